"""The MME&KF readings of Wang et al. 2017, eq. 16–21, against independent checks.

- a known, time-varying model error injected into the body's acceleration (and so into the
  measured body acceleration), exact data: the MME's d recovers it step by step;
- a correct model (the filter's own, exact discretization) with its own noise: eq. 20's W
  against the KF's innovation covariance is the upper bound, and MME&KF is the KF;
- eq. 7's G as printed: D = 0, MME&KF is the KF whatever W;
- a true sprung-mass change (the quarter car of eq. 1 with m_b + Δm, not the filter's
  model), exact data: the ``mass`` reading's d is −Δm/(m_b + Δm);
- Table 2's simulation, class C, 3 seeds: the default MME&KF equals the KF at Δm = 0 and
  beats it at Δm = −180 kg.
"""

import numpy as np
import pytest

from suvtwin.estimators.road_estimation import (
    PAPER_QUARTER_CAR,
    covariance_constraint_weight,
    discretize,
    error_input_matrix,
    error_std_percent,
    iso_road_model,
    kalman_filter,
    mme_kalman_filter,
    simulate_quarter_car,
)
from suvtwin.roads.iso8608 import class_level
from suvtwin.roads.profile import superposition_profile

CAR = PAPER_QUARTER_CAR
SPEED = 40.0 / 3.6
DT = 1e-3
ROAD_C = iso_road_model(class_level("C"), speed=SPEED, n_low=0.011, n_high=2.83)


def _known_start(road):
    return np.diag([1e-12] * 5 + [road.intensity / (2.0 * road.a2)])


@pytest.mark.parametrize("order", ["same-step", "delayed"])
def test_feedthrough_mme_recovers_a_known_time_varying_body_error(order):
    """Truth: the filter's model plus d(t) on ẍ_b; the measured ẍ_b contains d(t) (y = Cx + Ed)."""
    model = discretize(CAR, ROAD_C, dt=DT)
    n = 3001
    t = np.arange(n) * DT
    d_true = 0.3 * np.sin(2 * np.pi * 1.3 * t) + 0.1  # m/s^2
    Gd = model.error_transition(error_input_matrix("body"))[:, 0]
    x = np.zeros((n, 6))
    x[0] = [0.0, 0.0, 0.0, 0.0, 0.005, 0.2]  # a deterministic road: the model's free response
    for k in range(1, n):
        x[k] = model.Phi @ x[k - 1] + Gd * d_true[k]
    y = x @ model.C.T
    y[:, 0] += d_true
    est = mme_kalman_filter(y, model, measurement_std=1e-3, weight=1e-12, error_input="body",
                            feedthrough=True, order=order, state_covariance0=np.diag([1e-14] * 5 + [1e-6]),
                            state0=x[0])
    if order == "same-step":  # d_k fitted to y_k is the d_k that made it
        np.testing.assert_allclose(est.model_errors[1:, 0], d_true[1:], rtol=1e-6, atol=1e-9)
        np.testing.assert_allclose(est.road, x[:, 4], atol=1e-9)
    else:  # d_k corrects step k+1: one step late; d follows within a few %, the level drifts a little
        np.testing.assert_allclose(est.model_errors[2:, 0], d_true[2:], atol=0.03)
        assert np.max(np.abs(est.road - x[:, 4])) < 1e-3
    # without the error the KF drifts (the test can fail)
    kf = kalman_filter(y, model, measurement_std=1e-3, state_covariance0=np.diag([1e-14] * 5 + [1e-6]),
                       state0=x[0])
    assert np.max(np.abs(kf.road - x[:, 4])) > 1e-3


def test_innovation_constraint_on_a_correct_model_gives_the_kalman_filter():
    """The model exact (the filter's own, exact discretization, its noise): the KF's one-step
    prediction errors already have the covariance S_k it expects, eq. 20 against S_k leaves
    W at the upper bound and d = 0; against R (as printed) it does not."""
    model = discretize(CAR, ROAD_C, dt=DT, method="exact")
    rng = np.random.default_rng(11)
    n, sigma = 3001, 0.02
    vals, vecs = np.linalg.eigh(model.Q)
    L = vecs * np.sqrt(np.clip(vals, 0.0, None))
    x = np.zeros((2, n, 6))
    for k in range(1, n):
        x[:, k] = x[:, k - 1] @ model.Phi.T + rng.standard_normal((2, 6)) @ L.T
    y = x @ model.C.T + sigma * rng.standard_normal((2, n, 2))
    P0 = np.diag([1e-12] * 6)
    w = covariance_constraint_weight(y, model, measurement_std=sigma, error_input="body", feedthrough=True,
                                     target="innovation", state_covariance0=P0, bounds=(1e-6, 1e10))
    assert w == pytest.approx(1e10)
    kf = kalman_filter(y, model, measurement_std=sigma, state_covariance0=P0)
    mme = mme_kalman_filter(y, model, measurement_std=sigma, weight=w, error_input="body", feedthrough=True,
                            state_covariance0=P0)
    np.testing.assert_allclose(mme.road, kf.road, atol=1e-6 * np.std(x[..., 4]))
    w_r = covariance_constraint_weight(y, model, measurement_std=sigma, error_input="all", target="R",
                                       feedthrough=False, state_covariance0=P0, bounds=(1e-6, 1e10))
    assert w_r < 1e4  # the road's own unpredictability is taken for model error


def test_printed_error_input_is_unobservable_and_changes_nothing():
    """Eq. 7's G times six equal d: G·1 = A·1 = [1, 0, 1, 0, 1, -a1-a2], a common shift of
    body, wheel and road, which no acceleration sees (D = T·C·A·1 = 0)."""
    model = discretize(CAR, ROAD_C, dt=DT)
    G = error_input_matrix("printed", model)
    np.testing.assert_allclose(G[:, 0], [1, 0, 1, 0, 1, -ROAD_C.a1 - ROAD_C.a2])
    np.testing.assert_allclose(model.C @ G, 0.0, atol=1e-9)
    rng = np.random.default_rng(3)
    y = 0.1 * rng.standard_normal((500, 2))
    kf = kalman_filter(y, model, measurement_std=0.02)
    mme = mme_kalman_filter(y, model, measurement_std=0.02, weight=1e-9, error_input="printed",
                            feedthrough=False)
    np.testing.assert_allclose(mme.states, kf.states, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("dm", [180.0, -180.0])
def test_mass_reading_recovers_the_sprung_mass_ratio_from_the_true_car(dm):
    """The true car of eq. 1 with m_b + Δm (first-order-hold exact simulation, not the filter's
    model), noise-free accelerations, Euler (eq. 7): d = m_b/(m_b + Δm) − 1 within 10 % (d
    also absorbs Euler's own error in the body acceleration)."""
    model = discretize(CAR, ROAD_C, dt=DT)
    z = superposition_profile(6001, SPEED * DT, gd_n0=class_level("C"), rng=np.random.default_rng(2),
                              n_min=0.011, n_max=2.83)[0]
    z = z - z[0]
    y = simulate_quarter_car(CAR.with_sprung_mass(CAR.sprung_mass + dm), z, dt=DT).accelerations[0]
    est = mme_kalman_filter(y, model, measurement_std=1e-3, weight=100.0, error_input="mass",
                            feedthrough=True, state_covariance0=_known_start(ROAD_C))
    d = est.model_errors[1000:, 0]
    s = np.abs(est.states[1000:-1] @ model.A[1])  # the body acceleration d multiplies
    d_mean = np.sum(d[1:] * s) / np.sum(s)  # weighted: d is ill-defined where A_2 x crosses 0
    assert d_mean == pytest.approx(-dm / (CAR.sprung_mass + dm), rel=0.1)


def test_default_mme_equals_kf_without_mass_change_and_beats_it_with_one():
    """Table 2's simulation (bench/road_estimation_paper.py's settings), class C, 3 seeds:
    the default reading (G = e2, feedthrough, eq. 20 against S_k on the first 2 s)."""
    gd = class_level("C")
    n, sigma = 10001, 0.02
    z = np.stack([superposition_profile(n, SPEED * DT, gd_n0=gd, rng=np.random.default_rng([s, 1, 1]),
                                        n_min=0.011, n_max=2.83)[0] for s in range(3)])
    z = z - z[:, :1]
    model = discretize(CAR, ROAD_C, dt=DT)
    P0 = _known_start(ROAD_C)
    err = {}
    for j, dm in enumerate((0.0, -180.0)):
        acc = simulate_quarter_car(CAR.with_sprung_mass(CAR.sprung_mass + dm), z, dt=DT).accelerations
        y = acc + sigma * np.stack([np.random.default_rng([s, 1, 2 * j, 2]).standard_normal((n, 2))
                                    for s in range(3)])
        w = covariance_constraint_weight(y[:, :2001], model, measurement_std=sigma, state_covariance0=P0,
                                         bounds=(1e-8, 1e12), iterations=16)
        kf = error_std_percent(z, kalman_filter(y, model, measurement_std=sigma, state_covariance0=P0).road)
        mme = error_std_percent(z, mme_kalman_filter(y, model, measurement_std=sigma, weight=w,
                                                     state_covariance0=P0).road)
        err[dm] = (kf.mean(), mme.mean())
    assert err[0.0][1] == pytest.approx(err[0.0][0], rel=0.05)
    assert err[-180.0][1] < 0.5 * err[-180.0][0]
