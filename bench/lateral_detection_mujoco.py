"""Solmaz's 16-model deflation detector on the MuJoCo SUV: ISO 3888-1 double lane changes, Monte Carlo.

Run: ``python bench/lateral_detection_mujoco.py [--runs 150] [--jobs 2] [--runs-dir DIR] [--case C]
[--slip detector|tyre] [--rigid-steering]``
— prints JSON (:func:`suvtwin.pipeline.lateral_detection.monte_carlo_study`).

Two tyre cases: ``shipped`` (the SUV's .tir, whose cornering stiffness *rises* at low pressure,
PPY1 < 0) and ``softer_deflated`` (``mjcf/suv/suv_235_60R18_softer_deflated.tir``, a labelled
sensitivity case whose cornering stiffness falls 20 % from 250 to 150 kPa: paper 004's premise).
Per case the bank's arctan tyres are fitted from simulator runs (nominal 250 kPa, deflated
155 kPa), then ``--runs`` lane changes are drawn with ``numpy.random.default_rng(900000 + i)`` (the
same draws in both cases): speed uniform 80–120 km/h, direction left or right, the deflated tyre
FL, FR, RL, RR or none in turn (exactly 20 % none), its pressure uniform 130–180 kPa, an extra load
uniform 0–300 kg between boot and front seats (the detector's vehicle includes it). Runs are
simulated in ``--jobs`` processes into ``bench/_runs/lateral_detection/<case>/`` (one Parquet file
per run named by the hash of its scenario and the simulator's code: reused on a second call).

Detector variants (paper cost α 0, γ 1, λ 0; ESC noise σ 0.05 m/s², 0.2 °/s, seeded per run):
``esc_body`` — a_y as a body-fixed sensor reads it (roll's gravity component included), sideslip
by eq. 10; ``roll_compensated`` — the horizontal a_y, eq. 10; ``ideal_sideslip`` — the horizontal
a_y and the true sideslip. Scored per variant: confusion matrix (true model vs final pick; 1 RR,
2 RL, 4 FR, 8 FL, 16 none), correct rate, detection delay (steering onset — |δ| first at 10 % of
its peak — to the first sample from which the true model is selected to the end), false-alarm
rate (no-deflation runs ending on a deflated model). The per-run series are left out of the
printed JSON (``example`` keeps run 0's).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def main(argv: list[str] | None = None) -> dict:
    from suvtwin.pipeline.lateral_detection import CALIBRATION_SLIP, CASES, RIGID_STEERING, monte_carlo_study

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=150, help="lane changes per tyre case (default 150)")
    parser.add_argument("--jobs", type=int, default=2, help="processes (default 2)")
    default_dir = Path(__file__).parent / "_runs" / "lateral_detection"
    parser.add_argument("--runs-dir", type=Path, default=default_dir)
    parser.add_argument("--case", choices=CASES, action="append", help="default: both")
    parser.add_argument("--slip", choices=CALIBRATION_SLIP, default="detector",
                        help="bank fit: per-axle against the detector's slip angles (default) or one tyre "
                             "against the tyres' own")  # fmt: skip
    parser.add_argument("--rigid-steering", action="store_true",
                        help="the SUV without its compliance and bump steer (RIGID_STEERING), runs in "
                             "<runs-dir>/rigid_steering/")  # fmt: skip
    args = parser.parse_args(argv)
    if args.runs < 1 or args.jobs < 1:
        parser.error("--runs and --jobs must be >= 1")
    runs_dir = args.runs_dir / "rigid_steering" if args.rigid_steering else args.runs_dir
    vehicle = RIGID_STEERING if args.rigid_steering else None
    study = monte_carlo_study(args.runs, runs_dir, jobs=args.jobs, cases=tuple(args.case or CASES),
                              slip=args.slip, vehicle=vehicle)
    for case in study["cases"].values():
        if case["example"]:  # keep the printout short: no per-sample series
            for series in case["example"].values():
                if isinstance(series, dict) and "selected" in series:
                    series.pop("t_s")
                    series.pop("selected")
    return study


if __name__ == "__main__":
    json.dump(main(sys.argv[1:]), sys.stdout, indent=1)
    print()
