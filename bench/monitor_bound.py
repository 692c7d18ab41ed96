"""Cramér–Rao bounds of tyre pressure on the SUV: one corner, corners sharing the road, the preview.

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
  pitch coupling): the bound of the front→rear preview, for an ideal linear vehicle.

These bounds assume the model is exact; on the MuJoCo SUV the estimators stay above them
(README, "Benchmarks").
"""

from __future__ import annotations

import json
import sys
from dataclasses import replace

import numpy as np

from suvtwin.estimators.joint import N0, corner_response, signal_gain
from suvtwin.estimators.quarter_car import sprung_mass_share, stiffness_from_pressure
from suvtwin.mjcf.vehicle import load_vehicle
from suvtwin.pipeline.estimation import linear_corner_model

LEVEL = np.sqrt(128e-6 * 512e-6)  # class C centre, m³
SIGMA = 0.5  # m/s²
DT = 1e-3
P_KPA = 200.0


def _model(corner: str):
    vehicle = load_vehicle()
    front = corner.startswith("f")
    a_opposite = vehicle.chassis.a2 if front else vehicle.chassis.a1
    ms = sprung_mass_share(vehicle.chassis.mass, a_opposite=a_opposite, wheelbase=vehicle.wheelbase)
    qc = linear_corner_model(corner, ms)
    return replace(qc, damping=float(np.mean(qc.damping_range)), damping_range=None)


def _band(speed: float, record_s: float) -> np.ndarray:
    f = np.arange(1, int(record_s * 30.0) + 1) / record_s
    return f[(f >= 0.05 * speed) & (f <= min(1.5 * speed, 30.0))]


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
    }


def main() -> None:
    record_s = float(sys.argv[1]) if len(sys.argv) > 1 else 10.0
    speeds = [float(s) for s in sys.argv[2].split(",")] if len(sys.argv) > 2 else [40.0, 60.0, 100.0]
    print(json.dumps({"record_s": record_s, "level_m3": LEVEL, "pressure_kpa": P_KPA, "noise_mps2": SIGMA,
                      "bounds": [bounds(v, record_s) for v in speeds]}, indent=2))  # fmt: skip


if __name__ == "__main__":
    main()
