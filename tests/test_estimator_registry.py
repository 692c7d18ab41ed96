"""The estimator registry: every estimator declared once, the command line's (family, road input)
pairs map one-to-one onto the campaign's names, and each runner writes the columns its entry
declares."""

import numpy as np
import pytest

from suvtwin.errors import InputError
from suvtwin.pipeline.estimator_registry import (
    COMMON_COLUMNS,
    ESTIMATORS,
    CornerSignals,
    estimate_columns,
    estimator_families,
    find_estimator,
    road_inputs,
)


def test_command_line_pairs_map_one_to_one_onto_campaign_names():
    assert estimator_families() == ("imm", "ukf", "joint", "online")
    assert road_inputs() == ("synthetic", "augmented")
    pairs = {(e.family, e.road_input): name for name, e in ESTIMATORS.items()}
    assert len(pairs) == len(ESTIMATORS)
    assert find_estimator("imm", "augmented").name == "imm_augmented"
    assert find_estimator("ukf", "synthetic").name == "ukf_synthetic"
    assert find_estimator("joint", "augmented").name == "joint"  # takes no road input
    assert find_estimator("online", None).name == "online"
    with pytest.raises(InputError, match="--estimator must be one of imm, ukf, joint, online"):
        find_estimator("kalman", "synthetic")
    with pytest.raises(InputError, match="--road-input"):
        find_estimator("imm", "true")


def test_entries_are_consistent():
    assert len({e.label for e in ESTIMATORS.values()}) == len(ESTIMATORS)
    assert len({e.color for e in ESTIMATORS.values()}) == len(ESTIMATORS)
    for name, e in ESTIMATORS.items():
        assert e.name == name
        if e.single_model_baseline is not None:
            assert e.mode_probabilities and e.single_model_baseline in ESTIMATORS


def test_each_runner_writes_the_columns_its_entry_declares():
    rng = np.random.default_rng(3)
    b, t = 2, 12000
    signals = CornerSignals(
        acc_sprung=rng.normal(size=(b, t)), acc_unsprung=5 * rng.normal(size=(b, t)), dt=1e-3,
        speed_mps=np.array([15.0, 18.0]), corner="fl", sprung_mass=430.0, unsprung_mass=61.0,
        params="paper", seeds=np.array([1, 2]), initial_pressure_kpa=np.array([200.0, 220.0]),
    )  # fmt: skip
    for name, entry in ESTIMATORS.items():
        batch = entry.run(signals)
        columns = estimate_columns(batch, 1, np.arange(t) * 1e-3)
        declared = [c.format(c=letter) for c in entry.columns for letter in "ABCD"]
        assert list(columns)[: len(COMMON_COLUMNS)] == list(COMMON_COLUMNS), name
        assert list(columns)[len(COMMON_COLUMNS) :] == list(dict.fromkeys(declared)), name
        assert all(v.shape == (t,) for v in columns.values()), name
        assert any(c.startswith("mode_prob_") for c in columns) == entry.mode_probabilities, name
