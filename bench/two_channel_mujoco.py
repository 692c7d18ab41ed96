"""One corner's two accelerations as a likelihood of its tyre's pressure, on the MuJoCo SUV with its
damper swapped: why the online monitor projects on the road-driven direction.

Run: ``python bench/two_channel_mujoco.py [--runs 40] [--seconds 30] [--jobs 2]`` — prints JSON.

The first `--runs` scenarios of the monitor's ``constant`` set (roads anywhere in classes A–D,
40–120 km/h, loads 0–300 kg, pressures 130–230 kPa) are simulated once per suspension variant
(cached in ``bench/_runs/two_channel_<variant>``): the SUV as it is (digressive damper, knee
0.13 m/s, rebound three times compression), its damper made symmetric (still digressive), and
linear dampers of 2200 N s/m (the SUV's low-speed mean) and 1300 N s/m (about the SUV's
equivalent damping on a class C–D road), both with a linear spring. For the front-left and
rear-left tyre of each run, over 2 s to `--seconds`, the Whittle likelihood of the corner's two
accelerations (body above the wheel, wheel) is maximized over its pressure (5 kPa grid), as well
as the model can be made right without knowing the road:

- the linear full car (:func:`suvtwin.pipeline.estimation.full_car_model`, the run's vehicle and
  loads) with the other three tyres at their true pressures;
- each corner's spring rate and tyre contact share as the online monitor analyses them
  (:func:`suvtwin.pipeline.monitoring.monitor_run`, mean over the run up to `--seconds`);
- each corner's damping at its statistically linearized value :math:`E[F_d'(v)]` for the
  relative velocity's σ measured from its own accelerations (1–40 Hz), and what the
  linearization leaves (:func:`suvtwin.suspension_law.damper_residual_psd`) as a force between
  body and wheel (:func:`suvtwin.estimators.full_car.suspension_force_responses`);
- the road an ISO 8608 track of waviness 2 (both tracks independent, the rear wheels re-running
  the fronts' road a wheelbase later), enveloped by the tyre, its level profiled;
- the cross-periodogram from 8 s segments overlapping by half, with a rectangular window (as the
  monitor) or a Hann window.

Beside it: the wheel's channel alone (same model). Also, per track, the front→rear preview's
likelihood of both pressures (:class:`suvtwin.estimators.preview.PreviewTrack`, band 8–40 Hz):
the rear given the true front, and the joint maximum over both.
"""

from __future__ import annotations

import argparse
import json
import math
import os
from dataclasses import replace
from multiprocessing import get_context
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
from scipy.signal import csd

from suvtwin.estimators.full_car import corner_spectrum, suspension_force_responses
from suvtwin.estimators.joint import N0, envelope_power
from suvtwin.estimators.preview import PreviewConfig, PreviewTrack
from suvtwin.mjcf.vehicle import CORNERS
from suvtwin.pipeline.estimation import full_car_model, run_load_and_tire, run_loads, run_vehicle
from suvtwin.pipeline.monitor_scenarios import scenario_set, simulate_cached
from suvtwin.pipeline.monitoring import corner_models, monitor_run
from suvtwin.suspension_law import SuspensionLaw, damper_hermite, damper_residual_psd
from suvtwin.tire_stiffness import stiffness_at_pressure_array, tire_stiffness_of

HERE = Path(__file__).resolve().parent
LINEAR = {"damper_knee_velocity": 10.0, "spring_progression": 0.0}
VARIANTS = {
    "suv": {},
    "digressive_symmetric": {"damper_compression_low": 2200.0, "damper_rebound_low": 2200.0,
                             "damper_compression_high": 875.0, "damper_rebound_high": 875.0},
    "linear_1300": {**LINEAR, **{k: 1300.0 for k in ("damper_compression_low", "damper_compression_high",
                                                   "damper_rebound_low", "damper_rebound_high")}},
    "linear_2200": {**LINEAR, **{k: 2200.0 for k in ("damper_compression_low", "damper_compression_high",
                                                   "damper_rebound_low", "damper_rebound_high")}},
}  # fmt: skip
PRESSURES = np.arange(100.0, 301.0, 5.0)
LOG_LEVELS = np.linspace(math.log(1e-7), math.log(1e-2), 80)  # road velocity level, profiled
SEGMENT_S, BAND_CYCLES_PER_M, MAX_HZ, TRAVEL_HZ = 8.0, (0.05, 3.0), 20.0, (1.0, 40.0)
STUDIED = (0, 2)  # fl, rl
TRACKS = ((0, 2), (1, 3))


def _periodograms(a_s, a_u, dt, window):
    """Welch cross-periodogram (f, S11, S22, S12) of 8 s segments overlapping by half."""
    n = int(round(SEGMENT_S / dt))
    kw = dict(fs=1.0 / dt, nperseg=n, detrend="linear", window=window)
    f, p11 = csd(a_s, a_s, **kw)
    _, p22 = csd(a_u, a_u, **kw)
    _, p12 = csd(a_s, a_u, **kw)
    return f, p11.real, p22.real, p12


def _velocity_psd(f, p11, p22, p12, noise):
    """The suspension velocity's PSD from the relative acceleration, on TRAVEL_HZ, (m/s)²/Hz."""
    keep = (f >= TRAVEL_HZ[0]) & (f <= TRAVEL_HZ[1])
    rel = p11 + p22 - 2.0 * p12.real - 2.0 * noise
    return f[keep], rel[keep] / (2.0 * np.pi * f[keep]) ** 2


def _fit(f, P, model, extra, noise):
    """Pressure-grid argmax of the Whittle log-likelihood, two channels and the wheel's alone, the
    road level profiled: `model` (G, F, 2, 2) per unit level, `extra` (G, F, 2, 2) known power."""
    best2 = np.full(model.shape[0], -np.inf)
    best1 = np.full(model.shape[0], -np.inf)
    eye = noise * np.eye(2)
    for lam in np.exp(LOG_LEVELS):
        S = lam * model + extra + eye
        det = (S[..., 0, 0] * S[..., 1, 1] - S[..., 0, 1] * S[..., 1, 0]).real
        tr = (S[..., 1, 1] * P[:, 0, 0] + S[..., 0, 0] * P[:, 1, 1]
              - S[..., 0, 1] * P[:, 1, 0] - S[..., 1, 0] * P[:, 0, 1]).real / det  # fmt: skip
        best2 = np.maximum(best2, -np.sum(np.log(det) + tr, axis=-1))
        s22 = S[..., 1, 1].real
        best1 = np.maximum(best1, -np.sum(np.log(s22) + P[:, 1, 1].real / s22, axis=-1))
    return PRESSURES[np.argmax(best2)], PRESSURES[np.argmax(best1)]


def one_run(item: tuple[str, str, float]) -> dict[str, list[float]]:
    """Errors (estimate − truth, kPa) of one run: per axle (its left tyre), window and channels,
    and per track the preview's."""
    path, variant, seconds = item
    table = pq.read_table(path)
    meta = json.loads(table.schema.metadata[b"suvtwin.run"])
    d = table.to_pandas()
    vehicle = run_vehicle(meta)
    loads = run_loads(meta)
    _, tire_file = run_load_and_tire(meta, path)
    tire = tire_stiffness_of(tire_file)
    dt = float(np.median(np.diff(d.t_s)))
    s0, s1 = int(round(2.0 / dt)), int(round(seconds / dt))
    v = float(d.speed_mps.iloc[s0:s1].mean())
    noise = 2.0 * meta["scenario"]["noise"]["accel_sprung_mps2"] ** 2 * dt
    truth = [float(d[f"{c}_pressure_kpa"].iloc[0]) for c in CORNERS]
    kt_true = [float(stiffness_at_pressure_array(p * 1e3, tire.kt0, tire.p0, tire.pfz1)) for p in truth]
    mon = monitor_run(path, preview=False).table
    mon = mon[mon.t_s <= seconds + 1e-6]
    rates = [float(np.nanmean(mon[f"{c}_spring_rate_npm"])) for c in CORNERS]
    touch = [float(np.nanmean(mon[f"{c}_tyre_contact"])) for c in CORNERS]
    acc = {c: (d[f"{c}_accel_sprung_mps2"].to_numpy()[s0:s1], d[f"{c}_accel_unsprung_mps2"].to_numpy()[s0:s1])
           for c in CORNERS}  # fmt: skip
    laws = [SuspensionLaw.of(vehicle.suspension, spring_rate=float(vehicle.spring_rate[i])) for i in range(4)]
    out: dict[str, list[float]] = {}
    for window in ("boxcar", "hann"):
        spectra = [_periodograms(*acc[c], dt, window) for c in CORNERS]
        c_eq = []
        for i, (f_all, p11, p22, p12) in enumerate(spectra):
            fv, vel = _velocity_psd(f_all, p11, p22, p12, noise)
            sigma_v = math.sqrt(max(float(np.sum(vel) * (fv[1] - fv[0])), 1e-12))
            c_eq.append(float(damper_hermite(laws[i], sigma_v, 1)[0][1] / sigma_v))
        car = full_car_model(vehicle, loads, tire_file=tire_file)
        contact_damping = tuple(t * x for t, x in zip(touch, car.tire_damping, strict=True))
        car = replace(car, spring_rate=tuple(rates), damping=tuple(c_eq), tire_damping=contact_damping)
        for c in STUDIED:
            f_all, p11, p22, p12 = spectra[c]
            low, high = max(BAND_CYCLES_PER_M[0] * v, 0.8), min(BAND_CYCLES_PER_M[1] * v, MAX_HZ)
            band = (f_all >= low) & (f_all <= high)
            f = f_all[band]
            P = np.empty((f.size, 2, 2), dtype=complex)
            P[:, 0, 0], P[:, 1, 1] = p11[band], p22[band]
            P[:, 0, 1] = np.conj(p12[band])
            P[:, 1, 0] = p12[band]
            fv, vel = _velocity_psd(f_all, p11, p22, p12, noise)
            df = fv[1] - fv[0]
            residual = np.maximum(damper_residual_psd(laws[c], fv, vel, np.full(fv.size, df), f,
                                                      max_lag_s=0.45 / df), 0.0)  # fmt: skip
            road = 4.0 * np.pi**2 * N0**2 * v * envelope_power(f / v, vehicle.tire.envelope_half_length)
            model = np.empty((PRESSURES.size, f.size, 2, 2), dtype=complex)
            extra = np.empty_like(model)
            for g, p in enumerate(PRESSURES):
                kt = list(kt_true)
                kt[c] = float(stiffness_at_pressure_array(p * 1e3, tire.kt0, tire.p0, tire.pfz1))
                car_p = replace(car, tire_stiffness=tuple(t * k for t, k in zip(touch, kt, strict=True)))
                model[g] = corner_spectrum(f, v, car_p, c) * road[:, None, None]
                h = suspension_force_responses(f, car_p, c)
                extra[g] = residual[:, None, None] * h[:, :, None] * np.conj(h[:, None, :])
            p2, p1 = _fit(f, P, model, extra, noise)
            axle = "front" if c < 2 else "rear"
            out[f"{axle}_{window}_two_channel"] = [float(p2 - truth[c])]
            out[f"{axle}_{window}_wheel"] = [float(p1 - truth[c])]
    # the preview's two-pressure likelihood on 8–40 Hz, per track
    models = corner_models(CORNERS, loads=loads, tire_file=tire_file, vehicle=vehicle)
    step = int(round(1.0 / dt))
    for front, rear in TRACKS:
        track = PreviewTrack(models[front], models[rear], tire, tire, dt, float(vehicle.wheelbase),
                             PreviewConfig(band_hz=(8.0, 40.0)))  # fmt: skip
        for s in range(0, s1, step):
            sl = slice(s, min(s + step, s1))
            wheel = [d[f"{CORNERS[w]}_accel_unsprung_mps2"].to_numpy()[sl] for w in (front, rear)]
            body = [d[f"{CORNERS[w]}_accel_sprung_mps2"].to_numpy()[sl] for w in (front, rear)]
            track.add(*wheel, d.speed_mps.to_numpy()[sl], acc_s_front=body[0], acc_s_rear=body[1])
        ll = track.loglik(PRESSURES[:, None], PRESSURES[None, :])
        i, j = np.unravel_index(np.argmax(ll), ll.shape)
        given = ll[np.argmin(np.abs(PRESSURES - truth[front]))]
        for key, value in (("preview_joint_front", PRESSURES[i] - truth[front]),
                           ("preview_joint_rear", PRESSURES[j] - truth[rear]),
                           ("preview_rear_given_true_front", PRESSURES[np.argmax(given)] - truth[rear])):
            out.setdefault(key, []).append(float(value))
    return out


def _stats(e) -> dict:
    e = np.asarray(e, dtype=float)
    return {"mean_kpa": round(float(e.mean()), 1), "std_kpa": round(float(e.std()), 1),
            "median_abs_kpa": round(float(np.median(np.abs(e))), 1)}  # fmt: skip


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=40)
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1))
    parser.add_argument("--variants", default=",".join(VARIANTS))
    args = parser.parse_args(argv)
    report = {"bench": "two_channel_mujoco", "runs": args.runs, "seconds": args.seconds,
              "pressure_grid_kpa": 5.0, "variants": {}}  # fmt: skip
    base = scenario_set("constant", args.runs)
    for name in args.variants.split(","):
        over = {"suspension": VARIANTS[name]} if VARIANTS[name] else {}
        runs = [replace(r, scenario=r.scenario.model_copy(update={"vehicle": over})) for r in base]
        paths, _ = simulate_cached(runs, HERE / "_runs" / f"two_channel_{name}", jobs=args.jobs)
        items = [(str(p), name, args.seconds) for p in paths if p is not None]
        with get_context("forkserver").Pool(args.jobs) as pool:
            rows = pool.map(one_run, items)
        entry = {"suspension_overrides": VARIANTS[name], "runs": len(rows)}
        for key in sorted({k for r in rows for k in r}):
            entry[key] = _stats([x for r in rows for x in r.get(key, [])])
        report["variants"][name] = entry
    print(json.dumps(report, indent=1))
    return report


if __name__ == "__main__":
    main()
