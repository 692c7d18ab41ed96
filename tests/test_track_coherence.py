"""The left and right tracks' road coherence: the full car's spectra with coherent tracks, and the online
monitor's estimate of the coherence and of the pressures on roads whose tracks are alike."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from suvtwin.errors import InputError
from suvtwin.estimators.full_car import (
    TRACKS,
    axle_coherence_terms,
    blend_gain_at_delay,
    corner_spectrum,
    gain_at_delay,
    projected_cross_terms,
    projected_terms,
    track_responses,
    wheel_responses,
)
from suvtwin.estimators.joint import envelope_power, signal_direction
from suvtwin.estimators.monitor import MonitorConfig, TyreMonitor
from suvtwin.mjcf.vehicle import load_vehicle
from suvtwin.pipeline.monitoring import corner_models

CORNERS = ("fl", "fr", "rl", "rr")
MODELS = corner_models(CORNERS)
CAR = MODELS[0].full_car
F = np.linspace(0.5, 20.0, 40)


@pytest.mark.parametrize("gamma", [0.0, 0.4, 1.0])
@pytest.mark.parametrize("corner", [0, 3])
def test_projected_cross_terms_give_the_projected_spectrum_of_coherent_tracks(gamma, corner):
    # the decomposition A + γA' + 2 Re((B + γB') e^{iφ}) against u^H S u of the 2×2 spectrum built from
    # the tracks' covariance [[1, γ], [γ, 1]] (a second implementation: corner_spectrum's)
    speed = 17.0
    qc = MODELS[corner]
    h = wheel_responses(F, CAR, corner, [CAR.tire_stiffness[corner]])
    u1, u2 = signal_direction(F, qc)
    a0, b0 = projected_terms(h, u1, u2)
    a1, b1 = projected_cross_terms(h, u1, u2)
    delay = CAR.wheelbase / speed
    gain = gain_at_delay(a0 + gamma * a1, b0 + gamma * b1, F, delay)[0]
    spec = corner_spectrum(F, speed, CAR, corner, coherence=gamma)
    u = np.stack([u1, u2], axis=-1)
    direct = np.einsum("fi,fij,fj->f", np.conj(u), spec, u).real
    np.testing.assert_allclose(gain, direct, rtol=1e-9, atol=1e-12 * direct.max())


def test_identical_tracks_are_one_road_under_all_four_wheels():
    # coherence 1: both tracks are the same road, so each corner's response is that of one input under
    # all four wheels (the fronts at once, the rears a wheelbase later)
    speed = 25.0
    h = wheel_responses(F, CAR, 1, [CAR.tire_stiffness[1]])[0]  # (F, 2, 4)
    lag = np.exp(-2j * np.pi * F * CAR.wheelbase / speed)[:, None]
    g = h[:, :, 0] + h[:, :, 1] + (h[:, :, 2] + h[:, :, 3]) * lag
    np.testing.assert_allclose(corner_spectrum(F, speed, CAR, 1, coherence=1.0),
                               g[:, :, None] * np.conj(g[:, None, :]), rtol=1e-9, atol=1e-15)  # fmt: skip
    with pytest.raises(InputError, match="coherence must be in"):
        corner_spectrum(F, speed, CAR, 1, coherence=1.5)


@pytest.mark.parametrize("gamma", [0.0, 0.6])
def test_axle_coherence_terms_are_the_wheels_expected_spectra(gamma):
    delay = CAR.wheelbase / 20.0
    t0, t1, c0, c1 = axle_coherence_terms(F, CAR, delay)
    g = track_responses(F, CAR, delay)  # (F, 8, 2)
    cov = np.array([[1.0, gamma], [gamma, 1.0]])
    s = np.einsum("fit,tu,fju->fij", g, cov, np.conj(g))  # the eight channels' spectrum per unit S_v
    wheel = {c: 2 * i + 1 for i, c in enumerate(CORNERS)}
    autos = sum(s[:, wheel[c], wheel[c]].real for c in CORNERS)
    cross = s[:, wheel["fl"], wheel["fr"]].real + s[:, wheel["rl"], wheel["rr"]].real
    np.testing.assert_allclose(t0 + gamma * t1, autos, rtol=1e-10)
    np.testing.assert_allclose(c0 + gamma * c1, cross, rtol=1e-9, atol=1e-12 * autos.max())
    assert TRACKS == ((0, 2), (1, 3))


def _linear_car_drive(gamma: float, seconds: float = 48.0, speed: float = 20.0, seed: int = 5):
    """The linear full car (every tyre at its nominal pressure) driven at `speed` over two ISO 8608
    class C tracks (white road velocity, Gd(n0) = 64e-6 m³) of coherence `gamma`, the tyre's enveloping
    applied; all eight accelerations with 0.5 m/s² of white noise, sampled at 1 kHz."""
    dt = 1e-3
    n = int(round(seconds / dt))
    rng = np.random.default_rng(seed)
    s_v = 4.0 * np.pi**2 * 0.1**2 * speed * 64e-6  # one-sided road-velocity PSD, (m/s)²/Hz
    w = rng.standard_normal((2, n)) * np.sqrt(s_v / (2.0 * dt))
    road = np.stack([w[0], gamma * w[0] + np.sqrt(1.0 - gamma**2) * w[1]])  # velocity of each track
    f = np.fft.rfftfreq(n, dt)
    spectrum = np.fft.rfft(road, axis=-1)  # (2, F)
    spectrum *= np.sqrt(envelope_power(f / speed, MODELS[0].envelope_half_length))[None, :]
    g = np.zeros((f.size, 8, 2), dtype=complex)
    g[1:] = track_responses(f[1:], CAR, CAR.wheelbase / speed)  # per unit road velocity of each track
    acc = np.fft.irfft(np.einsum("fot,tf->of", g, spectrum), n=n, axis=-1).T  # (n, 8)
    acc += 0.5 * rng.standard_normal(acc.shape)
    return np.arange(n) * dt, np.full(n, speed), acc[:, 0::2], acc[:, 1::2]


def _monitor(config: MonitorConfig | None = None) -> TyreMonitor:
    # the spectra's coherence is under test: the force closure (which needs none) is off
    config = replace(config or MonitorConfig(), force_closure=False)
    return TyreMonitor(MODELS, dt=1e-3, config=config, names=CORNERS, tracks=TRACKS,
                       wheelbase_m=load_vehicle().wheelbase)  # fmt: skip


@pytest.fixture(scope="module")
def coherent_drives():
    return {gamma: _linear_car_drive(gamma) for gamma in (0.0, 0.9)}


def test_the_monitor_reads_the_tracks_coherence_and_the_pressures_on_coherent_roads(coherent_drives):
    # on its own model class: the coherence read within 0.1 by the end, the pressures as if it had been
    # given (and within 3σ of the truth), where taking the tracks as independent reads every tyre low
    truth = np.array([t.p0 / 1e3 for t in _monitor().tires])
    for gamma, (t, v, a_s, a_u) in coherent_drives.items():
        out = _monitor().update(t, v, a_s, a_u)
        assert out.track_coherence[-1] == pytest.approx(gamma, abs=0.1)
        error = out.pressure_pa[-1] / 1e3 - truth
        assert np.all(np.abs(error) < 3.0 * out.pressure_sigma_pa[-1] / 1e3)
        known = _monitor(MonitorConfig(track_coherence=gamma)).update(t, v, a_s, a_u)
        np.testing.assert_allclose(known.track_coherence, gamma, atol=1e-12)
        np.testing.assert_allclose(out.pressure_pa[-1] / 1e3, known.pressure_pa[-1] / 1e3, atol=5.0)
        independent = _monitor(MonitorConfig(track_coherence=0.0)).update(t, v, a_s, a_u)
        wrong = independent.pressure_pa[-1] / 1e3 - truth
        if gamma > 0:
            assert wrong.mean() < error.mean() - 20.0
        else:
            np.testing.assert_allclose(wrong, error, atol=2.0)


def test_track_coherence_config_is_checked():
    with pytest.raises(InputError, match="track_coherence"):
        MonitorConfig(track_coherence=1.2)
    with pytest.raises(InputError, match="coherence_memory_s"):
        MonitorConfig(coherence_memory_s=0.5)


def test_the_blend_with_the_tracks_cross_term_is_the_blend_of_the_coherent_gains():
    # the monitor's one-pass blend with γ per band against gain_at_delay of the tables A + γA', B + γB'
    # (γ spread over each band's frequencies), blended by hand
    rng = np.random.default_rng(7)
    f = np.linspace(0.5, 20.0, 40)
    a0, a1 = rng.random((2, 4, 3, 5, f.size))
    b0, b1 = rng.standard_normal((2, 4, 3, 5, f.size)) + 1j * rng.standard_normal((2, 4, 3, 5, f.size))
    start = np.array([0, 1, 2, 6, 10, 25, 39])
    gamma = rng.random(start.size)
    per_f = np.repeat(gamma, np.diff(np.r_[start, f.size]))
    banded = gain_at_delay(a0 + per_f * a1, b0 + per_f * b1, f, 0.21, band_start=start)  # (4, 3, 5, K)
    targets, tables = np.array([1, 0]), np.array([[3, 1], [2, 0]])
    weights = np.array([[0.4, 0.6], [1.0, 0.0]])
    out = rng.random((2, 3, 5, start.size))
    expected = out.copy()
    for i, t in enumerate(targets):
        for k in range(2):
            if weights[i, k] > 0:
                expected[t] += weights[i, k] * banded[tables[i, k]]
    blend_gain_at_delay(a0, b0, f, 0.21, start, targets, tables, weights, out, (a1, b1, gamma))
    np.testing.assert_allclose(out, expected, rtol=1e-12)
