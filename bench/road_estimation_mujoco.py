"""Wang et al. 2017, Table 2 on the MuJoCo SUV: the road under the front-left tyre from its accelerations.

Usage: ``python bench/road_estimation_mujoco.py [n_seeds]`` (default 3 seeds; ~1 min per seed
on one core).

Prints JSON. The 18 cells of the paper's Table 2 (ISO class B, C, D × Δm 0, +180, −180 kg ×
KF, MME&KF) with the SUV as the truth:

- run: 12 s at 40 km/h, lane keeping on a single-class road (``superposition``, level at the
  class centre), 250 kPa, 1 kHz, accelerometer noise σ = 0.02 m/s² on both channels (as
  ``bench/road_estimation_paper.py``); the first 2 s (the car settling from its placement)
  are dropped, the filters run over the last 10 s;
- load: +180 kg is a scenario load at the chassis CoG; −180 kg lowers the chassis mass by
  180 kg (a scenario vehicle override; loads cannot be negative). The spring preload follows
  the chassis mass, so the −180 kg car rides at the design height and the +180 kg car
  1.4 cm lower. The front-left corner's share of ±180 kg is about ±47 kg (reported as
  measured: the change of its mean tyre load / g);
- filters: the SUV's front-left corner as a quarter car (``corner_quarter_car``: nominal
  mass share, linear wheel rate, mean low-speed damper rate, kt at 250 kPa), the road model
  at the class level, Euler (eq. 7). KF (eq. 10–15); MME&KF with G = I and eq. 20's W from
  the first 2 s of the filtered record (truth-free). Known start (the paper's eq. 10: x̂0 from
  the run's state at 2 s) and, as a variant, unknown start (stationary prior);
- truth: the heightfield under the tyre, raw (at the wheel centre) and enveloped (the tyre
  model's contact-patch mean), ``road_under_wheel``;
- error STD % = 100·std(x̂_r − x_r)/std(x_r) (the paper's, each about its own mean), and the
  same after a zero-phase high-pass at 0.05 cycles/m × speed (0.56 Hz) on both, labelled
  ``hp``; mean ± std over seeds;
- reference ``quarter_car``: the same KF on a linear quarter car (the filter's own, with the
  corner's share of Δm) driven by the same raw road, same noise: what is left when the
  SUV's extra dynamics (pitch, roll, non-linear damper, anti-roll bar, enveloping) are gone;
- classification: ``classify_profile`` (w = 2, band 0.05–5 cycles/m) of the estimated and
  of the true raw track over the wheel's x, class per seed.
"""

from __future__ import annotations

import json
import sys
import time

from suvtwin.pipeline.road_estimation import mujoco_study


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    seeds = list(range(int(argv[0]) if argv else 3))
    t0 = time.perf_counter()
    study = mujoco_study(seeds, variants=True)
    study.pop("example")
    study["bench_wall_s"] = round(time.perf_counter() - t0, 1)
    print(json.dumps(study, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
