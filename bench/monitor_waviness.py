"""The monitor on roads whose waviness is not ISO 8608's w = 2, with its two waviness priors.

Run: ``python bench/monitor_waviness.py [--runs 24] [--waviness 1.7,2,2.5] [--jobs 2]`` — prints JSON.

The first `--runs` scenarios of the ``constant`` set (:mod:`suvtwin.pipeline.monitor_scenarios`:
130–230 kPa, 40–120 km/h, classes A–D with levels anywhere in the band, 0–300 kg) with every road
segment's waviness w (the exponent of its displacement PSD, Gd(n) = Gd(n0) (n/n0)^−w) set to each
value of `--waviness`, simulated into ``bench/_runs/waviness_<w>/`` (reused on a second call) and
monitored (:func:`suvtwin.pipeline.monitoring.monitor_run`) with each prior of
:data:`suvtwin.pipeline.monitoring.ROAD_WAVINESS`: ``iso`` (the default, w = 2 with probability 0.8)
and ``free`` (uniform on 1.5–3). Printed per w and prior: the error at 10 s and 30 s (mean, std,
over all tyres) and the share of updates after 2 s within ±2σ, of the vibration estimate and of
the estimate fused with the wheels' radii (:func:`suvtwin.pipeline.monitor_scoring.score_set`); and
the would-be false warnings: tyres (all at a constant pressure) whose fused estimate put the
probability of being more than the rule's loss (10 %) below their true pressure at 0.95 or more on
two updates in a row (the deflation rule's threshold and confirmation,
:class:`suvtwin.estimators.deflation.DeflationRule`, with each tyre's reference its truth and the
fused estimate taken as Gaussian), and the highest such probability held on two updates.
"""

from __future__ import annotations

import argparse
import json
from functools import partial
from pathlib import Path

import numpy as np
from scipy.stats import norm

from suvtwin.estimators.deflation import DeflationRule
from suvtwin.pipeline.monitor_scenarios import BenchRun, monitor_traces, scenario_set, simulate_cached
from suvtwin.pipeline.monitor_scoring import score_set
from suvtwin.pipeline.monitoring import ROAD_WAVINESS, monitor_run
from suvtwin.pipeline.scenario import parse_scenario


def with_waviness(run: BenchRun, w: float) -> BenchRun:
    """The run with every road segment's waviness set to `w`."""
    data = run.scenario.model_dump(mode="json", exclude_none=True)
    for segment in data["road"]["segments"]:
        segment["waviness"] = w
    return BenchRun(run.name, run.set, parse_scenario(data, source=f"bench run {run.name}, w = {w:g}"),
                    {**run.info, "waviness": w})  # fmt: skip


def _summary(scores: dict) -> dict:
    out = {}
    # the monitor's estimate (with the radii where fused), and the vibration's own without them
    for label, part in (("fused", scores), ("vibration", scores.get("vibration_only"))):
        if part is None:
            continue
        out[label] = {
            **{at: {k: part["error_at"][at][k] for k in ("mean_kpa", "std_kpa", "max_abs_kpa")}
               for at in ("10s", "30s")},
            "inside_2sigma_after_2s": part["coverage"]["inside"],
        }  # fmt: skip
    return out


def would_be_false_warnings(traces) -> dict:
    """Tyres at their reference (their true, constant pressure) the deflation rule would warn on the
    fused estimate, and the highest loss probability held on its confirming updates."""
    rule = DeflationRule()
    keep = 1.0 - rule.detect_fraction
    warned = tyres = 0
    highest = 0.0
    for trace in traces:  # the monitor's estimate: with the radii where fused
        with np.errstate(invalid="ignore", divide="ignore"):
            prob = norm.cdf((keep * trace.truth_at_est - trace.p_hat) / trace.sigma)
        prob = np.nan_to_num(prob)
        n = rule.confirm_updates
        held = np.min(np.stack([prob[i : prob.shape[0] - n + 1 + i] for i in range(n)]), axis=0)
        warned += int(np.sum(np.any(held >= rule.probability, axis=0)))
        tyres += prob.shape[1]
        highest = max(highest, float(held.max()) if held.size else 0.0)
    return {"tyres": tyres, "warned": warned, "highest_held_probability": highest}


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=24, help="scenarios of the constant set (default 24)")
    parser.add_argument("--waviness", default="1.7,2,2.5", help="road waviness values (default 1.7,2,2.5)")
    parser.add_argument("--jobs", type=int, default=2, help="processes (default 2)")
    args = parser.parse_args(argv)
    values = [float(w) for w in args.waviness.split(",")]
    base = scenario_set("constant", args.runs)
    out: dict = {"bench": "monitor_waviness", "runs": args.runs, "results": {}}
    for w in values:
        runs = [with_waviness(r, w) for r in base]
        folder = Path(__file__).resolve().parent / "_runs" / f"waviness_{w:g}"
        paths, _ = simulate_cached(runs, folder, jobs=args.jobs)
        good = [i for i, p in enumerate(paths) if p is not None]
        runs, paths = [runs[i] for i in good], [paths[i] for i in good]
        for prior in ROAD_WAVINESS:
            traces, _, _ = monitor_traces(runs, paths, jobs=args.jobs,
                                          monitor=partial(monitor_run, road_waviness=prior))  # fmt: skip
            kept = [(r, t) for r, t in zip(runs, traces, strict=True) if t is not None]
            infos = [{**r.info, "name": r.name} for r, _ in kept]
            scores = score_set("constant", [t for _, t in kept], infos)
            out["results"].setdefault(f"w={w:g}", {})[prior] = {
                "runs": len(kept), **_summary(scores),
                "would_be_false_warnings": would_be_false_warnings([t for _, t in kept]),
            }  # fmt: skip
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main()
