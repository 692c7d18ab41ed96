"""How far the roll-plane corner model reads a tyre when the car is the linear full car.

Run: ``python bench/monitor_model_bias.py [gd_n0_m3] [pressure_kpa]`` — prints JSON.

The SUV as a linear full car (:func:`suvtwin.pipeline.estimation.full_car_model`, all tyres at
`pressure_kpa`, default 200) on two independent ISO tracks of level `gd_n0_m3` (default 64e-6,
class B's centre), the rear wheels re-running the front road. For each corner and speed the
expected periodogram (the full car's spectrum, projected on the heave quarter car's direction,
plus the monitor's accelerometer noise) is fitted, as the monitor fits a window (Whittle, 8 s,
0.05–1.5 cycles/m times the speed, at most 30 Hz; road level profiled, slope 2, the model's
low-speed damping), by (a) the roll-plane corner model and (b) the full car itself: the pressure
each reads with infinitely much data. (b) must give the truth (a check of the fit); (a)'s offset is
the roll-plane model's bias. Also (c): the full car with the other three tyres at the truth while
the same-side tyre of the other axle is 40 kPa low (the monitor models the other tyres at their
nominal stiffness); and, with a truth whose tyres envelope the road (the simulator's cos² mean
over ±0.12 m, :func:`suvtwin.estimators.joint.envelope_power`), the full car without (d) and
with (e) the enveloping.
"""

from __future__ import annotations

import json
import sys
from dataclasses import replace

import numpy as np

from suvtwin.estimators.full_car import corner_spectrum
from suvtwin.estimators.joint import envelope_power, signal_direction, signal_gain
from suvtwin.estimators.quarter_car import stiffness_from_pressure
from suvtwin.mjcf.vehicle import CORNERS, load_vehicle
from suvtwin.pipeline.estimation import corner_sprung_mass, full_car_model, linear_corner_model

SPEEDS_KMH = (36, 40, 60, 90, 120)
SIGMA_ACCEL, DT, SEGMENT_S = 0.5, 1e-3, 8.0


def _fit(p_grid, gain, proj, noise):
    """Pressure maximizing the expected Whittle likelihood, level profiled on a fine log grid."""
    lam = np.exp(np.linspace(np.log(1e-10), np.log(1e-1), 600))[:, None, None]
    s = lam * gain[None]
    ll = -(np.log(noise + s) + (noise + proj) / (noise + s)).sum(-1)
    return float(p_grid[np.argmax(ll.max(axis=0))])


def _with(car, corner, pressure_kpa):
    kt = list(car.tire_stiffness)
    kt[corner] = float(stiffness_from_pressure(pressure_kpa * 1e3))
    return replace(car, tire_stiffness=tuple(kt))


def main(gd: float = 64e-6, pressure_kpa: float = 200.0) -> dict:
    vehicle = load_vehicle()
    nominal = full_car_model(vehicle)
    truth = nominal
    for c in range(4):
        truth = _with(truth, c, pressure_kpa)
    noise = 2.0 * SIGMA_ACCEL**2 * DT
    p_grid = np.arange(60.0, 400.5, 1.0)
    out: dict = {"bench": "monitor_model_bias", "gd_n0_m3": gd, "pressure_kpa": pressure_kpa, "speeds": {}}
    for kmh in SPEEDS_KMH:
        v = kmh / 3.6
        f = np.arange(1, int(30 * SEGMENT_S) + 1) / SEGMENT_S
        f = f[(f >= 0.05 * v) & (f <= min(1.5 * v, 30.0))]
        sv = 4.0 * np.pi**2 * gd * 0.1**2 * v
        row = {}
        for i, name in enumerate(CORNERS):
            qc = linear_corner_model(name, corner_sprung_mass(name, vehicle=vehicle), vehicle=vehicle)
            u = np.stack(signal_direction(f, qc), axis=1)
            along = lambda spec, u=u: np.einsum("fi,fij,fj->f", np.conj(u), spec, u).real  # noqa: E731
            proj = sv * along(corner_spectrum(f, v, truth, i))
            other = (i + 2) % 4
            low_other = _with(truth, other, pressure_kpa - 40.0)
            proj_low = sv * along(corner_spectrum(f, v, low_other, i))
            kt = stiffness_from_pressure(p_grid * 1e3)
            roll_plane = signal_gain(f[None, :], kt[:, None], qc)
            full = np.stack([along(corner_spectrum(f, v, _with(nominal, i, p), i)) for p in p_grid])
            envelope = envelope_power(f / v, vehicle.tire.envelope_half_length)
            row[name] = {
                "roll_plane_kpa": _fit(p_grid, roll_plane, proj, noise),
                "full_car_kpa": _fit(p_grid, full, proj, noise),
                "full_car_other_axle_low_kpa": _fit(p_grid, full, proj_low, noise),
                "enveloping_truth_full_car_kpa": _fit(p_grid, full, proj * envelope, noise),
                "enveloping_truth_full_car_enveloping_kpa": _fit(p_grid, full * envelope, proj * envelope,
                                                                 noise),  # fmt: skip
            }
        out["speeds"][f"{kmh}"] = row
    return out


if __name__ == "__main__":
    args = [float(a) for a in sys.argv[1:3]]
    print(json.dumps(main(*args), indent=1))
