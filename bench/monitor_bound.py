"""Cramér–Rao bounds of tyre pressure on the SUV: one corner, corners sharing the road, the preview,
the four corners of the full car.

Run: ``python bench/monitor_bound.py [record_s] [speeds_kmh]`` — prints JSON (default 10 s;
40, 60, 100 km/h).

Each bound is the pressure's standard deviation from the inverse Whittle Fisher information
:math:`I_{ij} = T\\sum_f \\mathrm{tr}(S^{-1}\\partial_i S\\, S^{-1}\\partial_j S)` of a Gaussian
ISO 8608 road (class C centre, w = 2) driving the SUV's linear front-left corner model
(:func:`suvtwin.pipeline.estimation.linear_corner_model`, damping at its range's middle), with
0.5 m/s² white accelerometer noise, on the band 0.05–1.5 cycles/m times the speed (≤ 30 Hz):

- ``one_corner``: the two accelerations of one corner (the joint estimator's and the
  monitor's model), with the level free and the slope fixed (w = 2) or free too;
- ``two_tracks_shared``: the front-left and front-right corners on independent tracks of one
  road, sharing its level (and slope): what tying the corners' level buys, at best;
- ``preview_track``: the front-left and rear-left corners on one track, the rear seeing the
  front's road a wheelbase/speed later (4 channels, one road, heave quarter cars without the
  pitch coupling): the bound of the front→rear preview, for an ideal linear vehicle;
- ``four_corner_30hz`` and ``four_corner_20hz_monitor`` (the band capped at 30 Hz, or at the
  monitor's 20 Hz): the linear full car (:func:`suvtwin.pipeline.estimation.full_car_model`
  without loads, all tyres at 200 kPa, its dampers: stiffer than the corner models' range
  middle, at which the joint bound about halves) on two independent tracks of one road, each
  rear wheel meeting its front wheel's road a wheelbase/speed later; eight channels (body above
  each corner and wheel, :func:`suvtwin.estimators.full_car.track_responses`),
  :math:`S = S_v G G^H + N I`. Lists of σ in the order fl, fr, rl, rr (``four_corner_order``):
  ``joint``: all eight channels, the level (and slope) shared by both tracks and the four
  pressures free; ``single_corner``: one corner's two channels (its 2×2 block of S), its own
  level (and slope) and its own pressure free, the other tyres known — what the monitor's
  per-corner fit can reach on this car (four corners each with its own level are the same
  bound: independent blocks share nothing); ``single_corner_projected``: the same with the two
  channels projected on the heave quarter car's road-driven direction u
  (:func:`suvtwin.estimators.joint.signal_direction`, the corner model at its damping range's
  middle): the monitor's likelihood; ``blocks_shared_level``: the four 2×2 blocks as if
  independent (the coherence between corners dropped) but sharing the level (and slope).

These bounds assume the model is exact; on the MuJoCo SUV the estimators stay above them
(docs/monitor.md, "Benchmarks").
"""

from __future__ import annotations

import json
import sys
from dataclasses import replace

import numpy as np

from suvtwin.estimators.full_car import track_responses
from suvtwin.estimators.joint import N0, corner_response, signal_direction, signal_gain
from suvtwin.estimators.quarter_car import sprung_mass_share, stiffness_from_pressure
from suvtwin.mjcf.vehicle import load_vehicle
from suvtwin.pipeline.estimation import full_car_model, linear_corner_model

LEVEL = np.sqrt(128e-6 * 512e-6)  # class C centre, m³
SIGMA = 0.5  # m/s²
DT = 1e-3
P_KPA = 200.0
CORNERS = ("fl", "fr", "rl", "rr")
MONITOR_MAX_HZ = 20.0  # the monitor's top frequency (TyreMonitor's max_frequency_hz)


def _model(corner: str):
    vehicle = load_vehicle()
    front = corner.startswith("f")
    a_opposite = vehicle.chassis.a2 if front else vehicle.chassis.a1
    ms = sprung_mass_share(vehicle.chassis.mass, a_opposite=a_opposite, wheelbase=vehicle.wheelbase)
    qc = linear_corner_model(corner, ms)
    return replace(qc, damping=float(np.mean(qc.damping_range)), damping_range=None)


def _band(speed: float, record_s: float, max_hz: float = 30.0) -> np.ndarray:
    """Fourier frequencies (Hz) of a `record_s` record in 0.05–1.5 cycles/m × `speed` (m/s), ≤ `max_hz`."""
    f = np.arange(1, int(record_s * max_hz) + 1) / record_s
    return f[(f >= 0.05 * speed) & (f <= min(1.5 * speed, max_hz))]


def _one_corner_information(qc, speed: float, record_s: float) -> np.ndarray:
    """Fisher information of (log level, slope β, p in kPa) for one corner's projected spectrum."""
    f = _band(speed, record_s)
    noise = 2.0 * SIGMA**2 * DT
    kt = stiffness_from_pressure(P_KPA * 1e3)
    dkt = stiffness_from_pressure((P_KPA + 1.0) * 1e3) - kt  # per kPa
    g = signal_gain(f, kt, qc) / noise
    dlog_g = (np.log(signal_gain(f, kt + 0.01 * dkt, qc) / noise) - np.log(g)) / 0.01
    r = 4.0 * np.pi**2 * N0**2 * LEVEL * speed * g
    q = r / (1.0 + r)
    d = np.stack([np.ones_like(f), np.log(f / (N0 * speed)), dlog_g])
    return (d * q * q) @ d.T


def _preview_information(front, rear, speed: float, record_s: float, wheelbase: float) -> np.ndarray:
    """Fisher information of (log level, p_front, p_rear) for one track's four accelerations."""
    f = _band(speed, record_s)
    noise = 2.0 * SIGMA**2 * DT
    heave_f, heave_r = replace(front, roll_mass=None), replace(rear, roll_mass=None)

    def spectrum(theta):
        lam, pf, pr = theta
        hf = np.stack(corner_response(f, stiffness_from_pressure(pf * 1e3), heave_f))
        hr = np.stack(corner_response(f, stiffness_from_pressure(pr * 1e3), heave_r))
        h = np.concatenate([hf, hr * np.exp(-2j * np.pi * f * wheelbase / speed)])
        sv = np.exp(lam) * 4.0 * np.pi**2 * N0**2 * speed
        return sv * np.einsum("if,jf->fij", h, h.conj()) + noise * np.eye(4)[None]

    theta = np.array([np.log(LEVEL), P_KPA, P_KPA])
    step = np.array([1e-3, 0.05, 0.05])
    inv = np.linalg.inv(spectrum(theta))
    grads = []
    for i in range(3):
        e = np.zeros(3)
        e[i] = step[i]
        grads.append((spectrum(theta + e) - spectrum(theta - e)) / (2.0 * step[i]))
    return np.array([[np.real(np.einsum("fij,fjk,fkl,fli->", inv, grads[i], inv, grads[j])) for j in range(3)]
                     for i in range(3)])  # fmt: skip


def _sd(info: np.ndarray, index: int) -> float:
    return float(np.sqrt(np.linalg.inv(info)[index, index]))


def _full_car():
    """The SUV's linear full car without loads, every tyre at P_KPA (dampers as full_car_model's)."""
    car = full_car_model(load_vehicle())
    return replace(car, tire_stiffness=(float(stiffness_from_pressure(P_KPA * 1e3)),) * 4)


def _four_corner_spectrum(car, speed: float, record_s: float, max_hz: float):
    """The eight channels' spectrum and its derivatives on the band, (F, 8, 8) each.

    :math:`S = S_v(\\lambda, \\beta)\\,G G^H + N I` with G = :func:`track_responses` (F, 8, 2),
    :math:`S_v = e^\\lambda\\,4\\pi^2 n_0^2 v\\,(f / n_0 v)^\\beta` (m²/s²/Hz, β = 0: waviness 2) and
    N = 2σ²dt. Returns S and the derivatives w.r.t. (λ, β, p_fl, p_fr, p_rl, p_rr in kPa): λ and β
    analytic, each pressure by central differences of G with that tyre's stiffness moved."""
    f = _band(speed, record_s, max_hz)
    delay = car.wheelbase / speed
    step = 0.05  # kPa

    def responses(corner: int, p_kpa: float) -> np.ndarray:
        kt = list(car.tire_stiffness)
        kt[corner] = float(stiffness_from_pressure(p_kpa * 1e3))
        return track_responses(f, replace(car, tire_stiffness=tuple(kt)), delay)

    g = track_responses(f, car, delay)
    sv = LEVEL * 4.0 * np.pi**2 * N0**2 * speed
    signal = sv * np.einsum("fit,fjt->fij", g, g.conj())
    grads = [signal, np.log(f / (N0 * speed))[:, None, None] * signal]
    for c in range(4):
        dg = (responses(c, P_KPA + step) - responses(c, P_KPA - step)) / (2.0 * step)
        cross = sv * np.einsum("fit,fjt->fij", dg, g.conj())
        grads.append(cross + np.conj(np.swapaxes(cross, 1, 2)))
    noise = 2.0 * SIGMA**2 * DT
    return signal + noise * np.eye(8)[None], grads


def _projected_information(spectrum: np.ndarray, grads: list, corner: int, u: tuple, params) -> np.ndarray:
    """Whittle Fisher information of corner `corner`'s two channels projected on u = (u1, u2) (F,)
    each: the scalar spectrum :math:`s = u^H S u`,
    :math:`I_{ij} = \\sum_f \\partial_i s\\,\\partial_j s / s^2`."""
    vec = np.zeros((spectrum.shape[0], 8), dtype=complex)
    vec[:, 2 * corner], vec[:, 2 * corner + 1] = u
    quad = lambda m: np.einsum("fi,fij,fj->f", np.conj(vec), m, vec).real  # noqa: E731
    s = quad(spectrum)
    d = [quad(grads[k]) / s for k in params]
    return np.array([[np.sum(di * dj) for dj in d] for di in d])


def _whittle_information(spectrum: np.ndarray, grads: list, channels, params) -> np.ndarray:
    """Whittle Fisher information of the `channels` (indices into S's rows) for the parameters
    `params` (indices into `grads`): :math:`I_{ij} = \\sum_f \\mathrm{tr}(S^{-1}\\partial_i S\\,
    S^{-1}\\partial_j S)` over the band, the products :math:`S^{-1}\\partial S` by solves."""
    ch = np.asarray(channels)
    s = spectrum[:, ch[:, None], ch[None, :]]
    a = [np.linalg.solve(s, grads[k][:, ch[:, None], ch[None, :]]) for k in params]
    return np.array([[np.einsum("fab,fba->", ai, aj).real for aj in a] for ai in a])


def four_corner_bounds(speed: float, record_s: float, max_hz: float, car=None) -> dict:
    """σ (kPa) of each tyre's pressure (fl, fr, rl, rr) on the linear full car at `speed` (m/s).

    ``joint``: all eight channels, one road level (and slope) for both tracks, the four pressures
    free; ``single_corner``: corner c's two channels alone (its 2×2 block of S), its own level (and
    slope) and its own pressure free, the other tyres known; ``single_corner_projected``: the same
    on the two channels projected on the heave quarter car's road-driven direction (the monitor's
    likelihood); ``blocks_shared_level``: the four 2×2 blocks as if independent (the coherence
    between corners dropped) but sharing the level (and slope). ``spectrum_max_condition``: the
    largest condition number of the eight channels' S on the band (float64 solves are safe far
    below 1e12)."""
    car = car or _full_car()
    spectrum, grads = _four_corner_spectrum(car, speed, record_s, max_hz)
    f = _band(speed, record_s, max_hz)
    directions = [signal_direction(f, _model(name)) for name in CORNERS]
    sd = {}
    for slope, lead in (("fixed", [0]), ("free", [0, 1])):
        n = len(lead)
        joint = _whittle_information(spectrum, grads, range(8), [*lead, 2, 3, 4, 5])
        shared = np.zeros((n + 4, n + 4))
        single = []
        for c in range(4):
            block = _whittle_information(spectrum, grads, [2 * c, 2 * c + 1], [*lead, 2 + c])
            single.append(_sd(block, n))
            keep = [*range(n), n + c]
            shared[np.ix_(keep, keep)] += block
        sd["single_corner_projected", slope] = [
            _sd(_projected_information(spectrum, grads, c, directions[c], [*lead, 2 + c]), n)
            for c in range(4)
        ]
        sd["joint", slope] = [_sd(joint, n + c) for c in range(4)]
        sd["single_corner", slope] = single
        sd["blocks_shared_level", slope] = [_sd(shared, n + c) for c in range(4)]
    names = ("joint", "single_corner", "single_corner_projected", "blocks_shared_level")
    out = {f"{name}_slope_{slope}_kpa": [round(v, 2) for v in sd[name, slope]]
           for name in names for slope in ("fixed", "free")}  # fmt: skip
    out["spectrum_max_condition"] = float(f"{np.linalg.cond(spectrum).max():.3g}")
    return out


def bounds(speed_kmh: float, record_s: float) -> dict:
    speed = speed_kmh / 3.6
    vehicle = load_vehicle()
    fl, rl = _model("fl"), _model("rl")
    i1 = _one_corner_information(fl, speed, record_s)
    fixed = np.ix_([0, 2], [0, 2])
    # two corners on independent tracks sharing (level, slope): parameters (λ, β, p_a, p_b)
    shared = np.zeros((4, 4))
    shared[:2, :2] = 2.0 * i1[:2, :2]
    for k in (2, 3):
        shared[k, k] = i1[2, 2]
        shared[:2, k] = shared[k, :2] = i1[:2, 2]
    shared_fixed = shared[np.ix_([0, 2, 3], [0, 2, 3])]
    ip = _preview_information(fl, rl, speed, record_s, vehicle.wheelbase)
    return {
        "speed_kmh": speed_kmh,
        "one_corner_slope_fixed_kpa": round(_sd(i1[fixed], 1), 2),
        "one_corner_slope_free_kpa": round(_sd(i1, 2), 2),
        "one_corner_level_known_kpa": round(float(1.0 / np.sqrt(i1[2, 2])), 2),
        "two_tracks_shared_slope_fixed_kpa": round(_sd(shared_fixed, 1), 2),
        "two_tracks_shared_slope_free_kpa": round(_sd(shared, 2), 2),
        "preview_track_front_kpa": round(_sd(ip, 1), 2),
        "preview_track_rear_kpa": round(_sd(ip, 2), 2),
        "four_corner_30hz": four_corner_bounds(speed, record_s, 30.0),
        "four_corner_20hz_monitor": four_corner_bounds(speed, record_s, MONITOR_MAX_HZ),
    }


def main() -> None:
    record_s = float(sys.argv[1]) if len(sys.argv) > 1 else 10.0
    speeds = [float(s) for s in sys.argv[2].split(",")] if len(sys.argv) > 2 else [40.0, 60.0, 100.0]
    print(json.dumps({"record_s": record_s, "level_m3": LEVEL, "pressure_kpa": P_KPA, "noise_mps2": SIGMA,
                      "four_corner_order": list(CORNERS),
                      "bounds": [bounds(v, record_s) for v in speeds]}, indent=2))  # fmt: skip


if __name__ == "__main__":
    main()
