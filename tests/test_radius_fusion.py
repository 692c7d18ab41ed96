"""The pressures fused with the rolling radii (estimators/radius_fusion.py): against a second
implementation (stacked weighted least squares; scipy's minimizer of the posterior), honest σ in a
Monte Carlo through MF-Tyre 6.1's rolling radius, blind to a loss all tyres share, and bad input."""

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

from suvtwin.errors import InputError
from suvtwin.estimators.radius_fusion import RadiusModel, excess_operator, fuse_with_radii

GRID = np.arange(50.0, 452.0, 2.0)


def _rho(track=0.75, cross=0.15):
    rho = np.full((4, 4), cross)
    for f, r in ((0, 2), (1, 3)):
        rho[f, r] = rho[r, f] = track
    np.fill_diagonal(rho, 1.0)
    return rho


def _mf_model(loads_n=(5400.0, 5300.0, 4700.0, 4800.0)):
    """The SUV's tyre (its .tir file): ln R_e at each load on the grid."""
    from suvtwin.mjcf.tire import effective_rolling_radius, load_tire

    tp = load_tire().to_array()
    table = np.log([[effective_rolling_radius(fz, 1e3 * q, tp) for q in GRID] for fz in loads_n])
    return RadiusModel(pressure_kpa=GRID, log_radius=table)


def test_linear_model_gives_the_stacked_weighted_least_squares_solution():
    rng = np.random.default_rng(3)
    gain = np.array([0.09, 0.08, 0.10, 0.085]) * 1e-3  # ln R per kPa
    offset = rng.normal(0.0, 1e-3, 4)
    model = RadiusModel(pressure_kpa=GRID, log_radius=offset[:, None] + gain[:, None] * (GRID - 200.0))
    p_hat = np.array([[205.0, 190.0, 170.0, 230.0]])
    sd = np.array([[12.0, 8.0, 20.0, 15.0]])
    excess = np.array([[0.4e-3, -0.2e-3, 0.3e-3, -0.5e-3]])
    se = np.array([[0.2e-3, 0.3e-3, 0.25e-3, 0.2e-3]])
    spread = 0.8
    rho = _rho()
    fused = fuse_with_radii(p_hat, sd, rho, excess, se, model, spread_permille=spread)
    # the same as one stacked linear system: z = [p̂; e − A(offset − 200 G)] = [I; A G] p + noise,
    # whitened by the Cholesky factor of blockdiag(Σ_v, R) and solved by least squares
    a = excess_operator(4)[:-1]
    wheel = np.sqrt(se[0] ** 2 * 0.75 + (1e-3 * spread) ** 2)
    r = (a * wheel**2) @ a.T
    sigma_v = rho * np.outer(sd[0], sd[0])
    h = np.vstack([np.eye(4), a * gain])
    z = np.concatenate([p_hat[0], excess[0, :-1] - a @ (offset - 200.0 * gain)])
    cov = scipy.linalg.block_diag(sigma_v, r)
    w = np.linalg.inv(np.linalg.cholesky(cov))
    sol, *_ = scipy.linalg.lstsq(w @ h, w @ z)
    post = np.linalg.inv((w @ h).T @ (w @ h))
    np.testing.assert_allclose(fused.pressure_kpa[0], sol, atol=1e-6)
    np.testing.assert_allclose(fused.cov_kpa2[0], post, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(fused.sigma_kpa[0], np.sqrt(np.diag(post)), rtol=1e-8)


def test_mf_tyre_model_gives_the_posterior_maximum():
    model = _mf_model()
    p_true = np.array([230.0, 150.0, 200.0, 140.0])
    f, _ = model.evaluate(p_true)
    a_full = excess_operator(4)
    excess = a_full @ f
    p_hat = np.array([[215.0, 175.0, 190.0, 160.0]])
    sd = np.array([[20.0, 20.0, 25.0, 25.0]])
    se = np.full((1, 4), 0.15e-3)
    rho = _rho()
    fused = fuse_with_radii(p_hat, sd, rho, excess[None], se, model, spread_permille=1.0)
    # an independent optimizer on the same posterior
    a = a_full[:-1]
    wheel = np.sqrt(se[0] ** 2 * 0.75 + 1e-6)
    r_inv = np.linalg.inv((a * wheel**2) @ a.T)
    v_inv = np.linalg.inv(rho * np.outer(sd[0], sd[0]))

    def cost(p):
        d = p - p_hat[0]
        y = excess[:-1] - a @ model.evaluate(p)[0]
        return d @ v_inv @ d + y @ r_inv @ y

    best = scipy.optimize.minimize(cost, p_hat[0], method="Nelder-Mead",
                                   options={"xatol": 1e-6, "fatol": 1e-12, "maxiter": 20000})  # fmt: skip
    np.testing.assert_allclose(fused.pressure_kpa[0], best.x, atol=0.02)


def test_monte_carlo_through_mf_tyre_is_honest_and_sharpens_the_contrasts():
    rng = np.random.default_rng(21)
    model = _mf_model()
    rho = _rho()
    chol = np.linalg.cholesky(rho)
    a = excess_operator(4)
    n = 600
    truth = rng.uniform(130.0, 230.0, (n, 4))
    sd = rng.uniform(8.0, 30.0, (n, 4))
    p_hat = truth + sd * (rng.standard_normal((n, 4)) @ chol.T)
    se = rng.uniform(0.1e-3, 0.5e-3, (n, 4))
    offsets = 1e-3 * rng.standard_normal((n, 4))  # the tyres' own radii, σ 1 ‰
    noise = se * np.sqrt(0.75) * rng.standard_normal((n, 4))
    excess = (model.evaluate(truth)[0] + offsets + noise) @ a.T
    fused = fuse_with_radii(p_hat, sd, rho, excess, se, model, spread_permille=1.0)
    z = (fused.pressure_kpa - truth) / fused.sigma_kpa
    assert np.all(np.abs(z.mean(axis=0)) < 0.12) and np.all(np.abs(z.std(axis=0) - 1.0) < 0.08)
    assert np.mean(np.abs(z) <= 2.0) > 0.93
    # each tyre against the others: the radii sharpen it well beyond the vibration's
    contrast = lambda x: x @ a.T  # noqa: E731
    rms = lambda x: float(np.sqrt(np.mean(x**2)))  # noqa: E731
    assert rms(contrast(fused.pressure_kpa - truth)) < 0.6 * rms(contrast(p_hat - truth))
    # the four's mean stays the vibration's (the radii cannot see it)
    assert abs(rms((fused.pressure_kpa - truth).mean(axis=1)) / rms((p_hat - truth).mean(axis=1)) - 1) < 0.15


def test_a_loss_all_four_share_leaves_the_vibration_estimate():
    model = _mf_model(loads_n=(5000.0,) * 4)
    p_hat = np.full((1, 4), 180.0)
    excess = np.zeros((1, 4))  # four equal tyres at equal loads
    fused = fuse_with_radii(p_hat, np.full((1, 4), 15.0), _rho(), excess, np.full((1, 4), 0.2e-3), model)
    np.testing.assert_allclose(fused.pressure_kpa, p_hat, atol=1e-6)
    assert np.all(fused.sigma_kpa < 15.0)


def test_rows_without_an_input_are_nan_and_bad_input_is_named():
    model = _mf_model()
    p = np.array([[200.0] * 4, [200.0, np.nan, 200.0, 200.0]])
    e = np.array([[np.nan] * 4, [0.0] * 4])
    fused = fuse_with_radii(p, np.full((2, 4), 10.0), _rho(), e, np.full((2, 4), 1e-4), model)
    assert np.isnan(fused.pressure_kpa).all() and np.isnan(fused.sigma_kpa).all()
    with pytest.raises(InputError, match="spread"):
        fuse_with_radii(p, np.full((2, 4), 10.0), _rho(), e, np.full((2, 4), 1e-4), model, spread_permille=-1)
    with pytest.raises(InputError, match="rho"):
        fuse_with_radii(p, np.full((2, 4), 10.0), np.eye(3), e, np.full((2, 4), 1e-4), model)
    with pytest.raises(InputError, match="increasing grid"):
        RadiusModel(pressure_kpa=GRID[::-1], log_radius=np.zeros((4, GRID.size)))


def test_vibration_lag_reads_the_changed_tyre_and_decays():
    from suvtwin.estimators.radius_fusion import vibration_lag_kpa
    from suvtwin.estimators.rolling_radius import excess_of

    gain = np.array([0.09, 0.085, 0.08, 0.085]) * 1e-3
    t_b = np.arange(1, 11) * 4.0
    delta = np.zeros((10, 4))
    delta[5:, 3] = -4e-3  # the rear right's radius 4 ‰ smaller from the sixth block (24 s) on
    excess = excess_of(delta)
    changes = np.zeros((10, 4), bool)
    changes[5, 3] = True
    t_r = np.arange(0.0, 44.0, 2.0)
    lag = vibration_lag_kpa(t_b, excess, changes, gain, t_r, tau_s=30.0)
    step = 4e-3 / gain[3]  # kPa: the tyre's step, the others unchanged
    expect = np.where(t_r >= 24.0, step * np.exp(-(t_r - 24.0) / 30.0), 0.0)
    np.testing.assert_allclose(lag[:, 3], expect, rtol=1e-12)
    np.testing.assert_allclose(lag[:, :3], 0.0, atol=1e-9)
    # a block held as a possible change (its step in `held`): the change it would be, while held
    held = np.zeros((10, 4))
    held[4, 3] = excess[5, 3] - excess[4, 3]
    lag_h = vibration_lag_kpa(t_b, excess, changes, gain, t_r, tau_s=30.0, held=held)
    during = (t_r >= 20.0) & (t_r < 24.0)
    np.testing.assert_allclose(lag_h[during, 3], step, rtol=1e-12)
    np.testing.assert_allclose(lag_h[~during], lag[~during], atol=1e-12)


def test_the_lags_of_two_changes_add_and_no_block_yet_gives_none():
    from suvtwin.estimators.radius_fusion import vibration_lag_kpa
    from suvtwin.estimators.rolling_radius import excess_of

    gain = np.array([0.09, 0.085, 0.08, 0.085]) * 1e-3
    t_b = np.arange(1, 21) * 4.0
    delta = np.zeros((20, 4))
    delta[5:, 3] = -4e-3  # the rear right 4 ‰ smaller from 24 s on
    delta[12:, 0] = -2e-3  # then the front left 2 ‰ smaller from 52 s on
    changes = np.zeros((20, 4), bool)
    changes[5, 3] = changes[12, 0] = True
    t_r = np.arange(0.0, 84.0, 2.0)
    lag = vibration_lag_kpa(t_b, excess_of(delta), changes, gain, t_r, tau_s=30.0)
    def decayed(step_permille, tyre, t_c):  # the tyre's step, kPa, decaying from its change on
        return np.where(t_r >= t_c, step_permille * 1e-3 / gain[tyre] * np.exp(-(t_r - t_c) / 30.0), 0.0)

    np.testing.assert_allclose(lag[:, 3], decayed(4.0, 3, 24.0), rtol=1e-12)
    np.testing.assert_allclose(lag[:, 0], decayed(2.0, 0, 52.0), rtol=1e-12, atol=1e-9)
    none = vibration_lag_kpa(np.zeros(0), np.zeros((0, 4)), np.zeros((0, 4), bool), gain, t_r,
                             held=np.zeros((0, 4)), trend=np.zeros((0, 4)))  # fmt: skip
    np.testing.assert_array_equal(none, np.zeros((t_r.size, 4)))


def test_a_stale_vibration_estimate_with_its_lag_lets_the_radii_carry_a_drop():
    """Four tyres at 230 kPa, the rear right dropped to 180: the vibration still reads 230 ± 5 for all;
    with the lag the radii saw (50 kPa) the fused estimate follows the radii and covers the truth,
    without it the two sources split the difference at a σ that does not hold the truth."""
    model = _mf_model()
    truth = np.array([230.0, 230.0, 230.0, 180.0])
    excess = excess_operator(4) @ model.evaluate(truth)[0]
    p_hat, sd, se = np.full((1, 4), 230.0), np.full((1, 4), 5.0), np.full((1, 4), 0.2e-3)
    stale = fuse_with_radii(p_hat, sd, _rho(), excess[None], se, model, spread_permille=1.0)
    assert abs(stale.pressure_kpa[0, 3] - truth[3]) > 3 * stale.sigma_kpa[0, 3]
    lag = np.array([[0.0, 0.0, 0.0, 50.0]])
    fused = fuse_with_radii(p_hat, sd, _rho(), excess[None], se, model, spread_permille=1.0, lag_kpa=lag)
    assert abs(fused.pressure_kpa[0, 3] - truth[3]) < 1.0 * fused.sigma_kpa[0, 3]
    assert abs(fused.pressure_kpa[0, 3] - truth[3]) < 10.0


def test_a_ramp_lags_the_vibration_by_its_rate_times_the_time_constant():
    from suvtwin.estimators.radius_fusion import vibration_lag_kpa
    from suvtwin.estimators.rolling_radius import excess_of

    gain = np.full(4, 0.085e-3)
    t_b = np.arange(1, 6) * 4.0
    trend = np.zeros((5, 4))
    trend[3:] = excess_of(np.array([0.0, 0.0, 0.0, -0.1e-3]))  # the rear right's radius: −0.1 ‰/s
    lag = vibration_lag_kpa(t_b, np.zeros((5, 4)), np.zeros((5, 4), bool), gain, t_b, tau_s=30.0, trend=trend)
    np.testing.assert_allclose(lag[3:, 3], 30.0 * 0.1e-3 / gain[3], rtol=1e-12)  # 35 kPa
    np.testing.assert_allclose(lag[:3], 0.0, atol=1e-12)
    np.testing.assert_allclose(lag[:, :3], 0.0, atol=1e-9)


def test_the_lag_a_ramp_left_decays_as_a_first_order_lag_once_it_ends():
    """A ramp of the rear right's pressure followed for 300 s (ten time constants: the lag in its
    steady state r τ) ends at 300 s: the lag after it against scipy's simulation of the first-order
    lag itself (signal.lsim of 1/(τ s + 1) driven by the ramp that stops)."""
    from scipy import signal

    from suvtwin.estimators.radius_fusion import vibration_lag_kpa
    from suvtwin.estimators.rolling_radius import excess_of

    tau, gain = 30.0, np.full(4, 0.085e-3)
    t_b = np.arange(1, 101) * 4.0
    trend = np.zeros((100, 4))
    trend[t_b <= 300.0] = excess_of(np.array([0.0, 0.0, 0.0, -0.1e-3]))  # −0.1 ‰/s of radius
    rate = 0.1e-3 / gain[3]  # kPa/s
    t = np.linspace(0.0, 400.0, 40001)
    path = rate * np.minimum(t, 300.0)
    _, lagged, _ = signal.lsim(([1.0], [tau, 1.0]), path, t)
    after = np.arange(304.0, 400.0, 2.0)
    expect = np.interp(after, t, path - lagged)
    none = np.zeros((100, 4))
    lag = vibration_lag_kpa(t_b, none, none.astype(bool), gain, after, tau_s=tau, trend=trend)
    np.testing.assert_allclose(lag[:, 3], expect, rtol=2e-3)
    np.testing.assert_allclose(lag[:, :3], 0.0, atol=1e-9)


def test_a_wheel_without_an_excess_fuses_the_others_as_a_three_tyre_car():
    # A dead wheel-speed sensor: the radius analysis gives excesses over the other three wheels and
    # NaN for it. With that tyre's vibration error uncorrelated with the others', the three tyres'
    # fused pressures are those of the fusion built for three tyres alone (their model rows, their
    # ρ block), and the fourth keeps its vibration estimate and σ. A row with fewer than two excesses
    # has nothing to fuse (NaN), as a row without a pressure.
    model = _mf_model()
    rho = _rho(track=0.6, cross=0.2)
    rho[3, :3] = rho[:3, 3] = 0.0
    p_hat = np.array([[205.0, 190.0, 170.0, 230.0], [180.0, 200.0, 195.0, 160.0]])
    sd = np.array([[12.0, 8.0, 20.0, 15.0], [9.0, 11.0, 14.0, 10.0]])
    excess3 = np.array([[0.6e-3, -0.1e-3, -0.5e-3], [-0.2e-3, 0.5e-3, -0.3e-3]])  # over three wheels
    se3 = np.array([[0.2e-3, 0.3e-3, 0.25e-3], [0.3e-3, 0.2e-3, 0.2e-3]])
    nan = np.full((2, 1), np.nan)
    fused = fuse_with_radii(p_hat, sd, rho, np.hstack([excess3, nan]), np.hstack([se3, nan]), model,
                            spread_permille=0.8)  # fmt: skip
    three = fuse_with_radii(p_hat[:, :3], sd[:, :3], rho[:3, :3], excess3, se3,
                            RadiusModel(pressure_kpa=GRID, log_radius=model.log_radius[:3]),
                            spread_permille=0.8)  # fmt: skip
    np.testing.assert_allclose(fused.pressure_kpa[:, :3], three.pressure_kpa, rtol=1e-12)
    np.testing.assert_allclose(fused.cov_kpa2[:, :3, :3], three.cov_kpa2, rtol=1e-10)
    np.testing.assert_allclose(fused.pressure_kpa[:, 3], p_hat[:, 3], rtol=1e-12)
    np.testing.assert_allclose(fused.sigma_kpa[:, 3], sd[:, 3], rtol=1e-12)
    # the radii moved the three: not their vibration estimates
    assert np.max(np.abs(fused.pressure_kpa[:, :3] - p_hat[:, :3])) > 1.0
    # one excess only: nothing to compare it with
    lone = fuse_with_radii(p_hat, sd, rho, [[0.1e-3, np.nan, np.nan, np.nan]] * 2, [[0.2e-3, np.nan, np.nan,
                           np.nan]] * 2, model)  # fmt: skip
    assert np.isnan(lone.pressure_kpa).all()


def test_a_correlation_per_row_is_each_rows_own_fusion():
    # rho (K, C, C): each row fused as if alone with its own rho
    model = _mf_model()
    rng = np.random.default_rng(9)
    p_hat = 200.0 + rng.normal(0.0, 15.0, (3, 4))
    sd = np.full((3, 4), 12.0)
    excess = rng.normal(0.0, 0.5e-3, (3, 4))
    se = np.full((3, 4), 0.2e-3)
    rhos = np.stack([_rho(cross=c) for c in (0.15, 0.4, 0.7)])
    fused = fuse_with_radii(p_hat, sd, rhos, excess, se, model)
    for k in range(3):
        row = slice(k, k + 1)
        alone = fuse_with_radii(p_hat[row], sd[row], rhos[k], excess[row], se[row], model)
        np.testing.assert_allclose(fused.pressure_kpa[k], alone.pressure_kpa[0], rtol=1e-12)
        np.testing.assert_allclose(fused.cov_kpa2[k], alone.cov_kpa2[0], rtol=1e-12)
    with pytest.raises(InputError, match="rho must be"):
        fuse_with_radii(p_hat, sd, rhos[:2], excess, se, model)
