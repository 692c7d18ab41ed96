"""Tire-pressure estimators on quarter-car truth: the true-road oracle, the paper's IMM, inputs."""

import json

import numpy as np
import pytest

from suvtwin.errors import InputError
from suvtwin.estimators.tire_pressure import (
    PAPER_TABLE_3,
    EstimatorSettings,
    ModeBank,
    estimate_pressure,
    load_modes,
)
from suvtwin.pipeline.quarter_car_truth import SPEED_MPS, TEST_CORNER, TIMESTEP_S, quarter_car_runs

DT, SPEED = TIMESTEP_S, SPEED_MPS
MS, MUS, KS, CS = (TEST_CORNER.sprung_mass, TEST_CORNER.unsprung_mass, TEST_CORNER.spring_rate,
                   TEST_CORNER.damping)  # fmt: skip
LINEAR = ModeBank(("X",), np.array([CS]), np.array([0.0]), np.array([KS]), np.array([0.0]), "truth")


@pytest.fixture(scope="module")
def truth():
    runs = quarter_car_runs(20, 5000, seed=1)
    return runs.pressure, runs.road, runs.acc


def test_ukf_with_the_true_road_finds_the_pressure(truth):
    # correctness oracle: with the true road and the true quarter car, the UKF's pressure error is
    # within 10 kPa at 3 s (measured on three batches of 20: 20, 18 and 20 runs; the error's own
    # std is ~4.5 kPa, so the worst of 20 runs is a 2-3 sigma draw), unbiased, small afterwards
    pressure, roads, acc = truth
    est = estimate_pressure(
        acc[..., 0], acc[..., 1], DT, modes=LINEAR, sprung_mass=MS, unsprung_mass=MUS,
        road_input="true", road=roads, speed_mps=SPEED,
    )  # fmt: skip
    error = est.pressure_pa - pressure[:, None]
    after = est.t_s >= 3.0
    assert np.mean(np.abs(error[:, np.searchsorted(est.t_s, 3.0)]) <= 10e3) >= 0.9
    assert abs(error[:, after].mean()) < 3e3
    assert np.sqrt(np.mean(error[:, after] ** 2)) < 8e3
    # its sigma is honest: the 2-sigma band holds the truth in >= 90 % of samples after 3 s
    assert np.mean(np.abs(error[:, after]) <= 2 * est.pressure_sigma_pa[:, after]) >= 0.9
    assert est.repairs.sum() == 0


def test_forward_euler_of_eq_15_is_biased_low(truth):
    # the paper's forward Euler inflates the wheel-hop oscillation: k_t (and p) come out low
    pressure, roads, acc = truth
    kwargs = dict(
        modes=LINEAR, sprung_mass=MS, unsprung_mass=MUS, road_input="true", road=roads, speed_mps=SPEED
    )
    euler = estimate_pressure(
        acc[..., 0], acc[..., 1], DT, settings=EstimatorSettings(discretization="euler"), **kwargs
    )
    semi = estimate_pressure(acc[..., 0], acc[..., 1], DT, **kwargs)
    after = euler.t_s >= 3.0
    bias_euler = np.mean(euler.pressure_pa[:, after] - pressure[:, None])
    bias_semi = np.mean(semi.pressure_pa[:, after] - pressure[:, None])
    assert bias_euler < bias_semi - 2e3


@pytest.mark.parametrize("road_input", ["synthetic", "augmented"])
def test_paper_imm_runs_and_reports_per_mode(truth, road_input):
    pressure, _, acc = truth
    est = estimate_pressure(
        acc[:4, :2000, 0], acc[:4, :2000, 1], DT, modes=load_modes("paper"), sprung_mass=MS,
        unsprung_mass=MUS, road_input=road_input, speed_mps=SPEED, seed=3,
    )  # fmt: skip
    assert est.mode_probability.shape == (4, 2000, 4)
    np.testing.assert_allclose(est.mode_probability.sum(axis=-1), 1.0)
    assert est.mode_probability.min() >= 1e-4 * 0.99  # the floor
    assert np.all(np.isfinite(est.pressure_pa)) and np.all(est.pressure_sigma_pa > 0)
    assert est.info["road_input"] == road_input and est.classes == ("A", "B", "C", "D")
    single = estimate_pressure(
        acc[:4, :2000, 0], acc[:4, :2000, 1], DT, modes=load_modes("paper").subset(("A",)), sprung_mass=MS,
        unsprung_mass=MUS, road_input=road_input, speed_mps=SPEED, seed=3,
    )  # fmt: skip
    assert single.mode_probability is None and single.mode_stiffness.shape == (4, 2000, 1)


def test_mode_parameter_files(tmp_path):
    bank = load_modes("paper")
    assert bank.classes == ("A", "B", "C", "D") and bank.ks[1] == PAPER_TABLE_3["B"]["ks"]
    path = tmp_path / "params.json"
    path.write_text(json.dumps({"classes": {"A": {"cs": 1, "csnl": 2, "ks": 3, "ksnl": 4}}, "metadata": {}}))
    assert load_modes(path).cs.tolist() == [1.0]
    path.write_text(json.dumps({"classes": {"A": {"cs": 1}}}))
    with pytest.raises(InputError, match="cs, csnl, ks, ksnl"):
        load_modes(path)
    with pytest.raises(InputError, match="does not exist"):
        load_modes(tmp_path / "none.json")


def test_bad_measurements_are_refused():
    with pytest.raises(InputError, match="finite"):
        estimate_pressure([0.0, np.nan], [0.0, 0.0], DT, modes=LINEAR, sprung_mass=MS, unsprung_mass=MUS,
                          road_input="synthetic", speed_mps=SPEED)  # fmt: skip
    with pytest.raises(InputError, match="road input"):
        estimate_pressure([0.0, 0.0], [0.0, 0.0], DT, modes=LINEAR, sprung_mass=MS, unsprung_mass=MUS,
                          road_input="guess", speed_mps=SPEED)  # fmt: skip


def test_shipped_identified_parameters_are_the_default():
    from suvtwin.identification.quarter_car_fit import DEFAULT_BOUNDS

    bank = load_modes()
    assert bank.classes == ("A", "B", "C", "D") and "suv_fl_paper_scale.json" in bank.source
    for name in ("cs", "csnl", "ks", "ksnl"):
        low, high = DEFAULT_BOUNDS[name]
        assert np.all((getattr(bank, name) >= low) & (getattr(bank, name) <= high)), name
