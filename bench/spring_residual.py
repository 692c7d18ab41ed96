"""The spring's statistical linearization against the MuJoCo SUV's simulated travel (why the monitor leaves
the bump stop's residual out).

Run: ``python bench/spring_residual.py [--set constant] [--runs-dir bench/_runs/<set>] [--runs 100]
[--road-class D]``; prints JSON. One process; the cached runs of ``bench/monitor_mujoco.py``'s set are
read (simulated first if missing).

Per run of the road class, 8 s window (from 4 s on, 4 s apart, as the monitor's) and corner, from the
simulator's true suspension travel ``{c}_susp_travel_m`` (compression > 0) and the corner's spring law
(:class:`suvtwin.suspension_law.SuspensionLaw`, stops included):

- the equivalent rate of a Gaussian travel of the window's mean and std
  (:func:`suvtwin.suspension_law.gaussian_spring_rate`, what the monitor's linearization uses) over the
  least-squares slope of the spring force on the simulated travel (the same linearization with the
  travel's actual distribution);
- the Gaussian (Mehler) spectrum of what that linearization leaves
  (:func:`suvtwin.suspension_law.spring_residual_psd`, from the window's travel PSD above 1 Hz and its
  mean) over the periodogram of the actual residual (force less its least-squares line), averaged
  over 2 Hz around 5, 10, 15 and 20 Hz.

Printed per corner, for all windows and for those with more than 3 % of the samples on the bump stop:
the ratios' medians and quartiles, the windows' median share on the stop and their count.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from suvtwin.mjcf.vehicle import CORNERS, load_vehicle
from suvtwin.pipeline.monitor_scenarios import scenario_set, simulate_cached
from suvtwin.suspension_law import SuspensionLaw, gaussian_spring_rate, spring_force, spring_residual_psd

AT_HZ = (5.0, 10.0, 15.0, 20.0)
WINDOW_S, HOP_S, START_S = 8.0, 4.0, 4.0
ON_STOP = 0.03  # windows with more than this share of samples on the bump stop


def window_ratios(travel: np.ndarray, dt: float, law: SuspensionLaw) -> tuple[float, np.ndarray, float]:
    """(Gaussian rate / least-squares slope, Gaussian residual PSD / periodogram at :data:`AT_HZ`,
    share of samples on the bump stop) of one window of travel (m)."""
    mean, x = float(travel.mean()), travel - travel.mean()
    force = spring_force(travel, law)
    slope = float((force - force.mean()) @ x / (x @ x))
    rate = float(gaussian_spring_rate(law, mean, x.std()))
    residual = force - force.mean() - slope * x
    n = x.size
    f = np.fft.rfftfreq(n, dt)
    scale = 2.0 * dt / n
    p_x = np.abs(np.fft.rfft(x)) ** 2 * scale
    p_r = np.abs(np.fft.rfft(residual)) ** 2 * scale
    df = f[1]
    keep = f >= 1.0
    at = np.searchsorted(f, AT_HZ)
    half = max(1, int(round(1.0 / df)))
    bins = np.full(keep.sum(), df)
    predicted = spring_residual_psd(law, mean, f[keep], p_x[keep], bins, f[at], max_lag_s=2.0)
    measured = np.array([p_r[k - half : k + half + 1].mean() for k in at])
    return rate / slope, predicted / measured, float(np.mean(travel > law.bump_clearance))


def _summary(values: list) -> dict:
    a = np.asarray(values)
    if a.size == 0:
        return {"n": 0}
    q = np.percentile(a, [25, 50, 75], axis=0)
    return {"n": int(a.shape[0]), "q25": np.round(q[0], 3).tolist(), "median": np.round(q[1], 3).tolist(),
            "q75": np.round(q[2], 3).tolist()}  # fmt: skip


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    add = parser.add_argument
    add("--set", default="constant")
    add("--runs", type=int, default=100)
    add("--runs-dir", default=None)
    add("--road-class", default="D")
    args = parser.parse_args(argv)
    import pyarrow.parquet as pq

    runs = scenario_set(args.set, args.runs)
    paths, _ = simulate_cached(runs, args.runs_dir or f"bench/_runs/{args.set}", jobs=1)
    vehicle = load_vehicle()
    laws = [SuspensionLaw.of(vehicle.suspension, spring_rate=k) for k in vehicle.spring_rate]
    per = {c: {"rate": [], "psd": [], "stop": []} for c in CORNERS}
    picked = [i for i, r in enumerate(runs) if r.info["road_class"] == args.road_class]
    for i in picked:
        table = pq.read_table(paths[i], columns=["t_s"] + [f"{c}_susp_travel_m" for c in CORNERS])
        t = table["t_s"].to_numpy()
        dt = float(np.median(np.diff(t)))
        for start in np.arange(START_S, t[-1] - WINDOW_S + 1e-9, HOP_S):
            inside = (t > start) & (t <= start + WINDOW_S)
            for k, c in enumerate(CORNERS):
                rate, psd, stop = window_ratios(table[f"{c}_susp_travel_m"].to_numpy()[inside], dt, laws[k])
                per[c]["rate"].append(rate)
                per[c]["psd"].append(psd)
                per[c]["stop"].append(stop)
    corners = {}
    for c in CORNERS:
        stop = np.asarray(per[c]["stop"])
        on = stop > ON_STOP
        rate, psd = np.asarray(per[c]["rate"]), np.asarray(per[c]["psd"])
        corners[c] = {
            "windows": int(stop.size),
            "windows_on_stop": int(on.sum()),
            "median_share_on_stop": round(float(np.median(stop)), 4) if stop.size else None,
            "gaussian_rate_over_slope": _summary(rate),
            "gaussian_rate_over_slope_on_stop": _summary(rate[on]),
            "gaussian_residual_psd_over_actual": _summary(psd),
            "gaussian_residual_psd_over_actual_on_stop": _summary(psd[on]),
        }
    out = {"bench": "spring_residual", "set": args.set, "road_class": args.road_class, "runs": len(picked),
           "at_hz": list(AT_HZ), "on_stop_share": ON_STOP, "corners": corners}  # fmt: skip
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main()
