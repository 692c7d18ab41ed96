"""The monitor with the force closure: two tracks of linear quarter cars simulated in the time domain
(scipy.signal.lsim), each rear car driven by its front car's road a wheelbase/speed later, the
monitor told nothing of the roads; the closure against the monitor without it on the same data."""

import math

import numpy as np
import pytest
import scipy.signal

from suvtwin.errors import InputError
from suvtwin.estimators.joint import LinearQuarterCar
from suvtwin.estimators.monitor import MonitorConfig, MonitorUpdate, TyreMonitor
from suvtwin.estimators.quarter_car import stiffness_from_pressure
from suvtwin.suspension_law import SuspensionLaw

DT = 1e-3
G = 9.81
SPEED = 20.0
WHEELBASE = 2.826
FRONT = dict(m_s=470.0, m_u=61.0, k_s=32_000.0, c_s=2_500.0)
REAR = dict(m_s=430.0, m_u=53.0, k_s=38_000.0, c_s=2_600.0)
PRESSURES_KPA = (215.0, 160.0, 190.0, 235.0)  # fl, fr, rl, rr


def _road(n: int, delay: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A Gaussian road under the wheel in time (m) and its rate (m/s), `delay` s late: Fourier
    coefficients drawn on a 2¹⁶-sample period, amplitudes ∝ 1/f over 0.3–40 Hz (a displacement PSD
    ∝ f⁻², an ISO road of waviness 2 at constant speed), the delay a phase; the first `n` samples."""
    rng = np.random.default_rng(seed)
    size = 1 << 16
    f = np.fft.rfftfreq(size, DT)
    amp = np.where((f > 0.3) & (f < 40.0), 2e-3 / np.maximum(f, 1e-9), 0.0) * math.sqrt(size / DT) / size
    coef = amp * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size))
    coef *= np.exp(-2j * np.pi * f * delay)
    z = np.fft.irfft(coef, n=size) * size
    v = np.fft.irfft(2j * np.pi * f * coef, n=size) * size
    return z[:n], v[:n]


def _car(z_r, v_r, *, m_s, m_u, k_s, c_s, k_t, c_t=200.0):
    a = np.array([[0, 0, 1, 0], [0, 0, 0, 1],
                  [-k_s / m_s, k_s / m_s, -c_s / m_s, c_s / m_s],
                  [k_s / m_u, -(k_s + k_t) / m_u, c_s / m_u, -(c_s + c_t) / m_u]])  # fmt: skip
    b = np.array([[0, 0], [0, 0], [0, 0], [k_t / m_u, c_t / m_u]])
    t = np.arange(z_r.size) * DT
    _, y, _ = scipy.signal.lsim((a, b, a[2:], b[2:]), np.column_stack([z_r, v_r]), t)
    return y[:, 0], y[:, 1]


def _model(m_s, m_u, k_s, c_s) -> LinearQuarterCar:
    law = SuspensionLaw(spring_rate=k_s, compression_low=c_s, compression_high=c_s, rebound_low=c_s,
                        rebound_high=c_s)  # fmt: skip
    return LinearQuarterCar(m_s, m_u, k_s, c_s, tire_damping=200.0, suspension=law, static_travel=0.0,
                            static_load=(m_s + m_u) * G)  # fmt: skip


@pytest.fixture(scope="module")
def drive():
    n = 48_000
    t = np.arange(n) * DT
    delay = WHEELBASE / SPEED
    rng = np.random.default_rng(7)
    a_s, a_u = np.empty((n, 4)), np.empty((n, 4))
    for side, seed in ((0, 21), (1, 22)):  # left track: fl, rl; right: fr, rr
        for corner, lag, car in ((side, 0.0, FRONT), (side + 2, delay, REAR)):
            z, v = _road(n, lag, seed)
            k_t = float(stiffness_from_pressure(PRESSURES_KPA[corner] * 1e3))
            body, wheel = _car(z, v, k_t=k_t, **car)
            a_s[:, corner] = body + 0.3 * rng.standard_normal(n)
            a_u[:, corner] = wheel + 0.3 * rng.standard_normal(n)
    return t, a_s, a_u


def _run(drive, **config) -> tuple[TyreMonitor, MonitorUpdate]:
    t, a_s, a_u = drive
    models = [_model(**FRONT), _model(**FRONT), _model(**REAR), _model(**REAR)]
    monitor = TyreMonitor(models, dt=DT, config=MonitorConfig(sigma_accel=0.3, **config),
                          tracks=((0, 2), (1, 3)), wheelbase_m=WHEELBASE)  # fmt: skip
    step = 5_000
    v = np.full(t.size, SPEED)
    parts = [monitor.update(t[i : i + step], v[i : i + step], a_s[i : i + step], a_u[i : i + step])
             for i in range(0, t.size, step)]  # fmt: skip
    return monitor, MonitorUpdate.concatenate(parts)


def test_the_closure_sharpens_each_tyre_and_keeps_its_sigma_honest(drive):
    truth = np.array(PRESSURES_KPA)
    with_it, out = _run(drive)
    _, alone = _run(drive, force_closure=False)
    assert with_it.counts["closure_windows"].min() >= 15
    # the road cancels in the closure: each tyre within a few kPa and its σ, far tighter than the
    # spectra alone
    error = out.pressure_pa[-1] / 1e3 - truth
    assert np.all(np.abs(error) <= np.minimum(6.0, 3.0 * out.pressure_sigma_pa[-1] / 1e3)), error
    sigma, sigma_alone = out.pressure_sigma_pa[-1], alone.pressure_sigma_pa[-1]
    assert np.all(sigma < 0.7 * sigma_alone), (sigma, sigma_alone)
    # the output's σ never below the closure's model-error floor once the closure carries the estimate
    assert np.all(sigma / 1e3 >= 0.9 * MonitorConfig().closure_floor_kpa)


def test_the_closure_is_off_without_two_tracks_or_suspension_laws(drive):
    t, a_s, a_u = drive
    plain = [LinearQuarterCar(**{"sprung_mass": 470.0, "unsprung_mass": 61.0, "spring_rate": 32e3,
                                 "damping": 2500.0})] * 4  # fmt: skip
    monitor = TyreMonitor(plain, dt=DT, tracks=((0, 2), (1, 3)), wheelbase_m=WHEELBASE)
    monitor.update(t[:10_000], np.full(10_000, SPEED), a_s[:10_000], a_u[:10_000])
    assert monitor.counts["closure_windows"].sum() == 0


def test_a_disconnected_wheel_accelerometer_keeps_the_closure_out(drive):
    # the rear-right wheel's accelerometer reads its noise alone (unplugged): the monitor flags the
    # corner silent, and the closure, whose wheel forces need every corner, takes no window at all
    t, a_s, a_u = drive
    unplugged = a_u.copy()
    unplugged[:, 3] = 0.3 * np.random.default_rng(9).standard_normal(t.size)
    monitor, out = _run((t, a_s, unplugged))
    assert monitor.counts["silent"][3] > 0
    assert monitor.counts["closure_windows"].sum() == 0
    # the other track keeps the estimate its spectra give, within 3σ
    error = out.pressure_pa[-1, [0, 2]] / 1e3 - np.array(PRESSURES_KPA)[[0, 2]]
    assert np.all(np.abs(error) <= 3.0 * out.pressure_sigma_pa[-1, [0, 2]] / 1e3), error


def test_tempering_divides_the_closures_information(drive):
    # a power likelihood ℓ/κ: for a Gaussian likelihood its precision is 1/κ times, whatever the prior
    # it meets (each update adds 1/σ²_after − 1/σ²_before = the likelihood's precision), so the
    # information the closure gave each tyre over the drive scales by 1/κ
    # (updates every 4 s; with the default 8 s the ratios read 0.84–1.17 × 1/4: twice the windows per
    # update, a sharper likelihood on the 1 kPa grid)
    plain, _ = _run(drive, closure_tempering=1.0, update_s=4.0)
    tempered, _ = _run(drive, closure_tempering=4.0, update_s=4.0)
    ratio = tempered._state.closure_info / plain._state.closure_info
    # within 15 %: the pressure grid's posteriors are near-Gaussian, not Gaussian (0.88–0.99 × 1/4 here)
    assert np.all(np.abs(4.0 * ratio - 1.0) <= 0.15), ratio


def test_tempering_below_one_is_refused():
    with pytest.raises(InputError, match="closure_tempering"):
        MonitorConfig(closure_tempering=0.5)
