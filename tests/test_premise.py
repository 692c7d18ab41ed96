"""Paper 000's premise check (suvtwin.pipeline.premise): the truth is what it says it is, and the
study gives finite scores in the campaign's format."""

import numpy as np
import pandas as pd
import pytest

from suvtwin.errors import InputError
from suvtwin.pipeline.premise import (
    CONTROLS,
    PAPER_PRESSURE_KPA,
    PAPER_SPEED_KMH,
    PREMISE_ESTIMATORS,
    premise_study,
    premise_summary,
    premise_truth,
)
from suvtwin.roads.iso8608 import class_bounds, class_level
from suvtwin.roads.roughness import classify_profile


@pytest.fixture(scope="module")
def truth():
    return premise_truth(3, seed=7)


def test_the_roads_are_at_the_class_centres_not_anywhere_in_the_band(truth):
    # the level fitted to each generated road by the ISO 8608 Welch fit (suvtwin.roads.roughness),
    # against the class's geometric-mean level; a road anywhere in the band would be up to 2x off
    for c in "ABCD":
        mine = truth.road_class == c
        assert mine.sum() == 3
        pairs = zip(truth.road[mine], truth.speed_mps[mine], strict=True)
        fitted = np.array([classify_profile(z, v * truth.dt).gd_n0 for z, v in pairs])
        ratio = fitted / class_level(c)
        assert np.all(np.abs(np.log(ratio)) < np.log(np.sqrt(2.0))), (c, ratio)  # inner half of the band
        assert abs(np.mean(np.log(ratio))) < np.log(1.15), (c, ratio)
        lower, upper = class_bounds(c)
        assert np.all((fitted > lower) & (fitted < upper))


def test_the_draws_follow_table_4_and_the_acceleration_grows_with_the_class(truth):
    low, high = PAPER_PRESSURE_KPA
    assert np.all((truth.pressure_kpa >= low) & (truth.pressure_kpa <= high))
    speed_kmh = truth.speed_mps * 3.6
    assert np.all((speed_kmh >= PAPER_SPEED_KMH[0]) & (speed_kmh <= PAPER_SPEED_KMH[1]))
    assert np.all(truth.road_seed != truth.estimator_seed)
    assert truth.acc.shape == (12, 10000, 2) and np.all(np.isfinite(truth.acc))
    # each class is 4x the level of the one before: the wheel's acceleration (rms) grows ~2x a class
    rms = {c: np.sqrt(np.mean(truth.acc[truth.road_class == c, :, 1] ** 2)) for c in "ABCD"}
    assert rms["A"] < rms["B"] < rms["C"] < rms["D"]
    # the same seed, the same runs; a larger study shares the smaller one's runs
    again = premise_truth(1, seed=7, duration_s=2.0)
    assert np.array_equal(again.pressure_kpa, truth.pressure_kpa[::3])
    assert np.array_equal(again.road, truth.road[::3, :2000])


def test_the_study_gives_finite_scores_and_the_true_road_control_finds_the_pressure(tmp_path):
    runs = premise_study(1, seed=7)
    names = (*PREMISE_ESTIMATORS, *CONTROLS)
    assert len(runs) == 4 * len(names) and set(runs.estimator) == set(names)
    for column in ("mean_error_kpa", "rmse_kpa", "inside_2sigma", "estimate_end_kpa", "sigma_end_kpa"):
        assert np.all(np.isfinite(runs[column])), column
    banks = runs[runs.estimator.str.startswith("imm")]
    total = banks[[f"mode_prob_{c}" for c in "ABCD"]].sum(axis=1)
    assert np.allclose(total, 1.0, atol=1e-6)
    # given the true road, the Table 3 quarter car of the class driven is the truth's model:
    # the IMM must find the pressure (an independent check of the truth and the filter together)
    control = runs[runs.estimator == "imm_true_road"]
    assert np.all(np.abs(control.estimate_end_kpa - control.pressure_kpa) < 25.0), control
    summary = premise_summary(runs)
    assert len(summary) == 4 * len(names)
    assert np.all(np.isfinite(summary[["mean_error_kpa", "rmse_kpa", "sigma_bound_kpa", "inside_2sigma"]]))
    assert np.all(np.isnan(summary.error_std_kpa))  # one run per class: no std (eq. 24, N - 1)
    single = summary[summary.estimator.str.startswith("ukf")]
    assert single.right_mode_probability.isna().all() and (single.most_probable_mode == "").all()
    # the same summary from the runs as the campaign stores them (a CSV file)
    stored = tmp_path / "runs.csv"
    runs.to_csv(stored, index=False)
    again = premise_summary(pd.read_csv(stored))
    assert (again.most_probable_mode.fillna("") == summary.most_probable_mode).all()
    assert np.allclose(again.rmse_kpa, summary.rmse_kpa)


def test_bad_study_input_is_one_clear_message():
    with pytest.raises(InputError, match="runs per class"):
        premise_truth(0, seed=1)
    with pytest.raises(InputError, match="premise estimator"):
        premise_study(1, estimators=("imm_nonsense",))
