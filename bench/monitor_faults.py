"""Sensor faults and the online monitor: what each fault costs in error, never a crash.

Run: ``python bench/monitor_faults.py [runs] [runs_dir]`` — prints JSON (default: the first 12 runs
of the ``constant`` set, from the cache ``python bench/monitor_mujoco.py --set constant`` fills,
``bench/_runs/constant``; simulated there if missing).

Each MuJoCo run is monitored clean and with one fault at a time, on all four corners:

- ``gaps``: a 1 s gap (NaN) every 10 s in every accelerometer;
- ``spikes``: a ±300 m/s² one-sample spike every 5 s in every unsprung accelerometer;
- ``clipping``: the front-left unsprung accelerometer saturated (clipped at the quantile that
  cuts 29 % of its samples);
- ``bias``: +2 m/s² offset on every accelerometer (a mounting or calibration error);
- ``dead``: the rear-left wheel accelerometer silent (NaN) over the whole run;
- ``disconnected``: the rear-left wheel accelerometer reading only white noise of the sensors'
  0.5 m/s² (a loose connector or a sensor off its mount: no road signal, every sample plausible);
- ``disconnected_body``: the same for the rear-left body (sprung) accelerometer;
- ``gain``: the rear-left wheel accelerometer reading 10 % high (a sensitivity error; data sheets
  of automotive MEMS accelerometers allow a few per cent): plausible, with the road's signal, so
  no check can take it for a fault;
- ``dead_yaw_rate``, ``dead_lat_accel``, ``dead_long_accel``: the body's yaw-rate sensor, lateral or
  longitudinal accelerometer silent over the whole run (only the radius analysis reads them: the
  ``fused`` numbers alone; the analysis takes the wheels' kinematics instead);
- ``dead_wheel_speed``: the rear-left wheel-speed sensor silent over the whole run (the radius
  analysis stops: the ``fused`` numbers are the vibration's where there is no pressure with the
  radii, as a user reads them; ``with_radii_share`` says how often there was one).

Printed per case: the error at 30 s (mean, std, over runs × tyres, and the mean per tyre, kPa), the
±2σ coverage after 2 s, the windows used and skipped by reason, and the difference of the error from
the clean case; and the same for the pressure with the wheels' radii (``fused``: the run file with the faulty
accelerometers through :func:`suvtwin.pipeline.monitoring.monitor_run`, whose radius analysis takes
each sample's tyre loads from them).
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

CORNERS = ("fl", "fr", "rl", "rr")


def _faults(acc_s: np.ndarray, acc_u: np.ndarray, t: np.ndarray) -> dict:
    cases = {"clean": (acc_s, acc_u)}
    s, u = acc_s.copy(), acc_u.copy()
    gap = (t % 10.0 >= 5.0) & (t % 10.0 < 6.0)
    s[gap], u[gap] = np.nan, np.nan
    cases["gaps"] = (s, u)
    u = acc_u.copy()
    spikes = np.flatnonzero(np.isclose(t % 5.0, 2.5, atol=0.5e-3))
    u[spikes] += 300.0 * np.where(np.arange(spikes.size) % 2, 1.0, -1.0)[:, None]
    cases["spikes"] = (acc_s, u)
    u = acc_u.copy()
    level = np.quantile(u[:, 0], 0.71)
    u[:, 0] = np.minimum(u[:, 0], level)
    cases["clipping"] = (acc_s, u)
    cases["bias"] = (acc_s + 2.0, acc_u + 2.0)
    u = acc_u.copy()
    u[:, 2] = np.nan
    cases["dead"] = (acc_s, u)
    u = acc_u.copy()
    u[:, 2] = np.random.default_rng(2026).normal(0.0, 0.5, t.size)  # the sensor's own noise, nothing else
    cases["disconnected"] = (acc_s, u)
    s = acc_s.copy()
    s[:, 2] = np.random.default_rng(2027).normal(0.0, 0.5, t.size)
    cases["disconnected_body"] = (s, acc_u)
    u = acc_u.copy()
    u[:, 2] *= 1.10
    cases["gain"] = (acc_s, u)
    return cases


FILE_FAULTS = {"dead_yaw_rate": "yaw_rate_radps", "dead_lat_accel": "lat_accel_mps2",
               "dead_long_accel": "long_accel_mps2", "dead_wheel_speed": "rl_wheel_speed_radps"}  # fmt: skip
"""Faults of the sensors only the radius analysis reads: the column NaN throughout the run file."""


def _fused_scores(path, t, truth):
    """The pressure the monitor reports (monitor_run on the file `path`: with the radii, or the
    vibration's where their analysis stopped): its errors at 30 s, whether each update after 2 s holds
    the truth within ±2σ and whether it had the radii."""
    from suvtwin.pipeline.monitoring import monitor_run

    res = monitor_run(path).table
    idx = np.searchsorted(t, res["t_s"].to_numpy())
    fused = res[[f"{c}_pressure_hat_kpa" for c in CORNERS]].to_numpy()
    fsig = res[[f"{c}_pressure_sigma_kpa" for c in CORNERS]].to_numpy()
    here = res[[f"{c}_with_radii" for c in CORNERS]].to_numpy()
    err = fused - truth[idx]
    k = int(np.searchsorted(res["t_s"].to_numpy(), 30.0 - 1e-6))
    at_30 = err[k].tolist() if k < len(res) else []
    after = res["t_s"].to_numpy() > 2.0
    return at_30, (np.abs(err[after]) <= 2 * fsig[after]).ravel().tolist(), here[after].ravel().tolist()


def _by_tyre(errors: np.ndarray) -> dict:
    """The mean error per tyre of errors listed run by run, tyre by tyre (kPa)."""
    per = np.asarray(errors).reshape(-1, len(CORNERS)).mean(axis=0)
    return {c: round(float(x), 1) for c, x in zip(CORNERS, per, strict=True)}


def main() -> None:
    from suvtwin.estimators.monitor import SKIP_REASONS
    from suvtwin.pipeline.estimation import run_loads
    from suvtwin.pipeline.monitor_scenarios import scenario_set, simulate_cached
    from suvtwin.pipeline.monitoring import monitor_signals

    n_runs = int(sys.argv[1]) if len(sys.argv) > 1 else 12
    folder = Path(sys.argv[2]) if len(sys.argv) > 2 else Path("bench/_runs/constant")
    # the set's first runs on the current simulator (the cache may hold runs of older ones)
    found, _ = simulate_cached(scenario_set("constant", n_runs), folder, jobs=1)
    paths = [p for p in found if p is not None]
    errors: dict = {}
    inside: dict = {}
    counts: dict = {}
    fused_errors: dict = {}
    fused_inside: dict = {}
    fused_here: dict = {}
    scratch = Path(tempfile.mkdtemp())

    def score_file(case, faulty, t, truth):
        """The run with a fault written into its file, through monitor_run (the pressure with the radii)."""
        tmp = scratch / f"{case}.parquet"
        pq.write_table(faulty, tmp)
        at_30, held, with_radii = _fused_scores(tmp, t, truth)
        fused_errors.setdefault(case, []).extend(at_30)
        fused_inside.setdefault(case, []).extend(held)
        fused_here.setdefault(case, []).extend(with_radii)

    for path in paths:
        arrow = pq.read_table(path)
        table = arrow.to_pandas()
        loads = run_loads(json.loads(pq.read_schema(path).metadata[b"suvtwin.run"]))
        t = table["t_s"].to_numpy()
        truth = table[[f"{c}_pressure_kpa" for c in CORNERS]].to_numpy()
        acc_s = table[[f"{c}_accel_sprung_mps2" for c in CORNERS]].to_numpy()
        acc_u = table[[f"{c}_accel_unsprung_mps2" for c in CORNERS]].to_numpy()
        for case, (s, u) in _faults(acc_s, acc_u, t).items():
            monitor, out = monitor_signals(t, table["speed_mps"].to_numpy(), s, u, loads=loads)
            idx = np.searchsorted(t, out.t_s)
            err = out.pressure_pa / 1e3 - truth[idx]
            sig = out.pressure_sigma_pa / 1e3
            k = int(np.searchsorted(out.t_s, 30.0 - 1e-6))
            if k < out.t_s.size:
                errors.setdefault(case, []).extend(err[k].tolist())
            after = out.t_s > 2.0
            inside.setdefault(case, []).extend((np.abs(err[after]) <= 2 * sig[after]).ravel().tolist())
            c = monitor.counts
            total = counts.setdefault(case, {})
            for reason in SKIP_REASONS:
                total[reason] = total.get(reason, 0) + int(np.sum(c[reason]))
            # the same faults in the run file: the monitor with the radii (their load gate reads them)
            faulty = arrow
            for i, corner in enumerate(CORNERS):
                for kind, values in (("sprung", s), ("unsprung", u)):
                    name = f"{corner}_accel_{kind}_mps2"
                    faulty = faulty.set_column(faulty.column_names.index(name), name, pa.array(values[:, i]))
            score_file(case, faulty, t, truth)
        for case, name in FILE_FAULTS.items():  # sensors the radius analysis alone reads
            faulty = arrow.set_column(arrow.column_names.index(name), name, pa.array(np.full(len(t), np.nan)))
            score_file(case, faulty, t, truth)
    clean = np.array(errors["clean"])
    fused_clean = np.array(fused_errors["clean"])
    result = {}
    for case in fused_errors:
        result[case] = {}
        if case in errors:  # an accelerometer fault: the vibration monitor too
            e = np.array(errors[case])
            result[case] = {
                "error_30s_mean_kpa": round(float(e.mean()), 2),
                "error_30s_std_kpa": round(float(e.std()), 2),
                "error_30s_mean_by_tyre_kpa": _by_tyre(e),
                "change_from_clean_rms_kpa": round(float(np.sqrt(np.mean((e - clean) ** 2))), 2),
                "inside_2sigma_after_2s": round(float(np.mean(inside[case])), 3),
                "windows": counts[case],
            }
        f = np.array(fused_errors[case])
        result[case]["fused"] = {
            "error_30s_mean_kpa": round(float(f.mean()), 2),
            "error_30s_std_kpa": round(float(f.std()), 2),
            "error_30s_mean_by_tyre_kpa": _by_tyre(f),
            "change_from_clean_rms_kpa": round(float(np.sqrt(np.mean((f - fused_clean) ** 2))), 2),
            "inside_2sigma_after_2s": round(float(np.mean(fused_inside[case])), 3),
            "with_radii_share": round(float(np.mean(fused_here[case])), 3),
        }
    print(json.dumps({"runs": len(paths), "tyres": len(CORNERS), "cases": result}, indent=2))


if __name__ == "__main__":
    main()
