"""The monitor on roads whose left and right tracks are correlated or identical, and on other roads.

Run: ``python bench/monitor_tracks.py [--runs 32] [--tracks independent,correlated:0.5,identical]
[--coherence estimated,0] [--jobs 2]`` — prints JSON.

The first `--runs` scenarios of the ``constant`` set (:mod:`suvtwin.pipeline.monitor_scenarios`:
130–230 kPa, 40–120 km/h, classes A–D with levels anywhere in the band, 0–300 kg) with the road's two
tracks as each value of `--tracks` gives (the simulator's ``tracks``: ``independent``, ``identical``,
``correlated:ρ``, the tracks correlated by ρ at every wavelength, or ``isotropic``, the two lines
1.62 m apart on a surface rough alike in every direction, coherent at long wavelengths,
:func:`suvtwin.roads.profile.isotropic_coherence`; or, tracks independent, the
road drawn by the first-order shape filter, ``shape-filter``, a Gaussian process, instead of by
sinusoid superposition, or with ``obstacles``: a 5 cm, 0.6 m pothole under the left track at 150 m
and an 8 cm, 3 m sine bump under both at 300 m; or any of the road's fields, ``key=value`` joined by
``+``, e.g. ``method=gaussian`` or ``n_max=25``), simulated into
``bench/_runs/tracks_<value>/`` (reused on a second call; ``independent`` is the ``constant`` set's
own cache) and monitored (:func:`suvtwin.pipeline.monitoring.monitor_run`) with each value of
`--coherence`: ``estimated`` (the default monitor: the tracks' coherence read online from the two
axles' wheels) or a fixed coherence (0: the tracks taken as independent, the monitor before
2026-12-04). Printed per tracks value and coherence: the error at 10 s and 30 s (mean, std, over all
tyres) and the share of updates after 2 s within ±2σ, of the vibration estimate and of the estimate
fused with the wheels' radii (:func:`suvtwin.pipeline.monitor_scoring.score_set`); the would-be false
warnings (tyres whose fused estimate held the deflation rule's probability of a 10 % loss below their
true, constant pressure on two updates in a row, ``bench/monitor_waviness.py``); and the coherence
the monitor used at 10 s and at the run's end (mean and std over runs).
"""

from __future__ import annotations

import argparse
import json
import sys
from functools import partial
from pathlib import Path

import numpy as np

from suvtwin.estimators.monitor import MonitorConfig
from suvtwin.pipeline.monitor_scenarios import BenchRun, monitor_traces, scenario_set, simulate_cached
from suvtwin.pipeline.monitor_scoring import score_set
from suvtwin.pipeline.monitoring import monitor_run
from suvtwin.pipeline.scenario import parse_scenario

sys.path.insert(0, str(Path(__file__).resolve().parent))
from monitor_waviness import _summary, would_be_false_warnings  # noqa: E402

OBSTACLES = [
    {"kind": "pothole", "position_m": 150.0, "length_m": 0.6, "height_m": 0.05, "track": "left"},
    {"kind": "sine_bump", "position_m": 300.0, "length_m": 3.0, "height_m": 0.08, "track": "both"},
]
"""The ``obstacles`` value's road obstacles."""


def road_of(value: str) -> dict:
    """The road's fields for a `--tracks` value."""
    if value in ("independent", "identical", "isotropic"):
        return {"tracks": value}
    if value == "shape-filter":
        return {"method": "shape-filter"}
    if value == "obstacles":
        return {"obstacles": OBSTACLES}
    if "=" in value:  # road fields, e.g. n_max=25 or method=shape-filter+n_max=10
        fields = dict(item.split("=", 1) for item in value.split("+"))
        return {k: v if k in ("method", "tracks") else float(v) for k, v in fields.items()}
    kind, _, rho = value.partition(":")
    if kind != "correlated" or not rho:
        raise SystemExit("--tracks values are independent, identical, isotropic, correlated:ρ, "
                         f"shape-filter, obstacles or road fields (n_max=25+method=gaussian), got {value!r}")
    return {"tracks": "correlated", "track_correlation": float(rho)}


def with_tracks(run: BenchRun, road: dict) -> BenchRun:
    """The run with its road's two tracks as `road` gives."""
    data = run.scenario.model_dump(mode="json", exclude_none=True)
    data["road"].update(road)
    return BenchRun(run.name, run.set, parse_scenario(data, source=f"bench run {run.name}, {road}"),
                    {**run.info, **road})  # fmt: skip


def coherence_at(traces, at_s: float | None) -> dict:
    """The coherence the monitor used at the last update at or before `at_s` (None: the run's end)."""
    values = []
    for trace in traces:
        t, c = trace.t_est, trace.track_coherence
        if c is None:
            continue
        k = t.size - 1 if at_s is None else int(np.searchsorted(t, at_s, side="right")) - 1
        if k >= 0 and np.isfinite(c[k]):
            values.append(c[k])
    return {"mean": float(np.mean(values)), "std": float(np.std(values)), "n": len(values)} if values else {}


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=32, help="scenarios of the constant set (default 32)")
    parser.add_argument("--tracks", default="independent,correlated:0.5,identical", help="road tracks values")
    parser.add_argument("--coherence", default="estimated,0", help="estimated and/or fixed values")
    parser.add_argument("--jobs", type=int, default=2, help="processes (default 2)")
    args = parser.parse_args(argv)
    base = scenario_set("constant", args.runs)
    here = Path(__file__).resolve().parent / "_runs"
    out: dict = {"bench": "monitor_tracks", "runs": args.runs, "results": {}}
    for value in args.tracks.split(","):
        road = road_of(value)
        runs = [with_tracks(r, road) for r in base]
        folder = here / ("constant" if value == "independent"
                         else "tracks_" + value.replace(":", "_").replace("=", "").replace("+", "_"))
        paths, _ = simulate_cached(runs, folder, jobs=args.jobs)
        good = [i for i, p in enumerate(paths) if p is not None]
        runs, paths = [runs[i] for i in good], [paths[i] for i in good]
        for coherence in args.coherence.split(","):
            config = MonitorConfig(track_coherence=None if coherence == "estimated" else float(coherence))
            monitor = partial(monitor_run, config=config)
            traces, _, _ = monitor_traces(runs, paths, jobs=args.jobs, monitor=monitor)
            kept = [(r, t) for r, t in zip(runs, traces, strict=True) if t is not None]
            infos = [{**r.info, "name": r.name} for r, _ in kept]
            scores = score_set("constant", [t for _, t in kept], infos)
            out["results"].setdefault(value, {})[f"coherence={coherence}"] = {
                "runs": len(kept), **_summary(scores),
                "would_be_false_warnings": would_be_false_warnings([t for _, t in kept]),
                "coherence_used": {"10s": coherence_at([t for _, t in kept], 10.0),
                                   "end": coherence_at([t for _, t in kept], None)},
            }  # fmt: skip
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main()
