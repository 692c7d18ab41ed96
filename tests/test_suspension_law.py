"""Suspension laws and their equivalent linearization, checked against the simulator's compiled
laws (a second implementation), numerical quadrature, and the MuJoCo SUV on a rough road."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from suvtwin.errors import InputError
from suvtwin.mjcf import kernel
from suvtwin.mjcf.vehicle import CORNERS, load_vehicle
from suvtwin.suspension_law import (
    SuspensionLaw,
    damper_even_slope,
    damper_force,
    damper_hermite,
    damper_residual_psd,
    equivalent_spring_rate,
    gaussian_damper_force,
    gaussian_spring_force,
    gaussian_spring_rate,
    rectified_psd,
    spring_force,
    spring_hermite,
    spring_rate,
    spring_residual_psd,
    static_travel,
)

VEHICLE = load_vehicle()
LAWS = [SuspensionLaw.of(VEHICLE.suspension, spring_rate=k) for k in VEHICLE.spring_rate]


def _vp() -> np.ndarray:
    """The simulator's packed suspension values (preload zero: forces beyond the preload)."""
    s = VEHICLE.suspension
    vp = np.zeros(kernel.N_VEHICLE)
    vp[kernel.V_SPRING : kernel.V_SPRING + 4] = VEHICLE.spring_rate
    vp[kernel.V_PROGRESSION] = s.spring_progression
    vp[kernel.V_BUMP_CLEAR], vp[kernel.V_BUMP_LIN], vp[kernel.V_BUMP_QUAD] = (
        s.bump_stop_clearance, s.bump_stop_linear, s.bump_stop_quadratic)  # fmt: skip
    vp[kernel.V_REB_CLEAR], vp[kernel.V_REB_LIN], vp[kernel.V_REB_QUAD] = (
        s.rebound_stop_clearance, s.rebound_stop_linear, s.rebound_stop_quadratic)  # fmt: skip
    vp[kernel.V_C_COMP_LOW], vp[kernel.V_C_COMP_HIGH] = s.damper_compression_low, s.damper_compression_high
    vp[kernel.V_C_REB_LOW], vp[kernel.V_C_REB_HIGH] = s.damper_rebound_low, s.damper_rebound_high
    vp[kernel.V_V_KNEE] = s.damper_knee_velocity
    return vp


VP = _vp()


@pytest.mark.parametrize("corner", [0, 2])
def test_laws_match_the_simulator(corner):
    s = np.linspace(-0.12, 0.12, 481)
    sim = np.array([kernel._spring(corner, x, VP) for x in s])
    np.testing.assert_allclose(spring_force(s, LAWS[corner]), sim, rtol=1e-12, atol=1e-9)
    v = np.linspace(-1.5, 1.5, 301)
    sim_d = np.array([kernel._damper(x, VP) for x in v])
    np.testing.assert_allclose(damper_force(v, LAWS[corner]), sim_d, rtol=1e-12, atol=1e-9)
    # the local rate is the simulator's force's derivative (central differences away from the kinks)
    h = 1e-6
    smooth = np.all(np.abs(s[:, None] - np.array([0.0, 0.06, -0.08])[None]) > 2e-3, axis=1)
    f = lambda x: kernel._spring(corner, x, VP)  # noqa: E731
    diff = np.array([f(x + h) - f(x - h) for x in s]) / (2 * h)
    np.testing.assert_allclose(spring_rate(s, LAWS[corner])[smooth], diff[smooth], rtol=1e-6)


def _gauss_expect(fun, mean, sigma):
    pdf = lambda x: math.exp(-0.5 * ((x - mean) / sigma) ** 2) / (sigma * math.sqrt(2 * math.pi))  # noqa: E731
    kinks = [mean - 8 * sigma, -0.08, 0.0, 0.06, mean + 8 * sigma]
    pts = sorted(k for k in kinks if mean - 8 * sigma <= k <= mean + 8 * sigma)
    return sum(integrate.quad(lambda x: fun(x) * pdf(x), a, b, epsabs=1e-12, epsrel=1e-11)[0]
               for a, b in zip(pts[:-1], pts[1:], strict=False))  # fmt: skip


@pytest.mark.parametrize(
    ("mean", "sigma"), [(0.0, 0.005), (0.02, 0.02), (0.045, 0.03), (-0.05, 0.025), (0.01, 1e-4)]
)
def test_gaussian_expectations_match_quadrature_of_the_simulator_law(mean, sigma):
    law = LAWS[2]
    force = _gauss_expect(lambda x: kernel._spring(2, x, VP), mean, sigma)
    assert gaussian_spring_force(law, mean, sigma) == pytest.approx(force, rel=1e-8, abs=1e-6)
    rate = _gauss_expect(lambda x: float(spring_rate(x, law)), mean, sigma)
    assert gaussian_spring_rate(law, mean, sigma) == pytest.approx(rate, rel=1e-8)
    # Stein's lemma: E[x F(m + x)] = σ² E[F'(m + x)], the statistical-linearization identity
    stein = _gauss_expect(lambda x: (x - mean) * kernel._spring(2, x, VP), mean, sigma) / sigma**2
    assert stein == pytest.approx(rate, rel=1e-6)
    sv = 20 * sigma
    damper = _gauss_expect(lambda v: kernel._damper(v, VP), 0.0, sv)
    assert gaussian_damper_force(law, sv) == pytest.approx(damper, rel=1e-8, abs=1e-8)


def test_linear_law_limits():
    law = SuspensionLaw(spring_rate=30000.0)
    m, k = equivalent_spring_rate(law, 0.01, 0.03)
    assert k == pytest.approx(30000.0) and m == pytest.approx(0.01)
    assert static_travel(law, 600.0) == pytest.approx(0.02)
    # the SUV's spring: +30 % rate at 50 mm bump (its design statement), stiffer on rough roads
    assert float(spring_rate(0.05, LAWS[0])) / LAWS[0].spring_rate == pytest.approx(1.3)
    _, k_rough = equivalent_spring_rate(LAWS[2], 0.02, np.array([0.002, 0.01, 0.02, 0.04]), 0.1)
    assert np.all(np.diff(k_rough) > 0) and k_rough[0] == pytest.approx(LAWS[2].spring_rate * 1.05, rel=0.02)


def test_mean_balances_the_static_load():
    law = LAWS[2]
    s0 = float(static_travel(law, 900.0))
    assert float(spring_force(s0, law)) == pytest.approx(900.0)
    m, _ = equivalent_spring_rate(law, s0, 0.02, 0.3)
    balance = gaussian_spring_force(law, m, 0.02) + gaussian_damper_force(law, 0.3)
    assert balance == pytest.approx(900.0, rel=1e-9)
    assert gaussian_damper_force(law, 0.3) < 0.0  # rebound stiffer: the body is pulled down


def test_bad_law_is_refused():
    with pytest.raises(InputError, match="spring_rate"):
        SuspensionLaw(spring_rate=0.0)
    with pytest.raises(InputError, match="bump_clearance"):
        SuspensionLaw(spring_rate=1.0, bump_clearance=-0.01)


def test_linearization_predicts_the_mujoco_suv_on_a_rough_road():
    """On a class D road at 60 km/h without extra load, the mean travel and the equivalent rate
    predicted from the travel's and its velocity's standard deviations match the simulated ones
    (mean within 3 mm, rate within 5 % of E[F'(s)] over the simulated travel)."""
    from suvtwin.pipeline.scenario import parse_scenario
    from suvtwin.pipeline.simulator import simulate

    scenario = parse_scenario({
        "duration_s": 12.0, "seed": 4321, "speed_kmh": 60.0,
        "road": {"segments": [{"length_m": 260.0, "gd_n0": 1.0e-3}]},
    }, source="test")  # fmt: skip
    table = simulate(scenario).table.iloc[2000:]
    for i, c in enumerate(CORNERS):
        s = table[f"{c}_susp_travel_m"].to_numpy()
        v = np.gradient(s, 1e-3)
        m, k = equivalent_spring_rate(LAWS[i], 0.0, s.std(), v.std())
        assert float(m) == pytest.approx(s.mean(), abs=3e-3), c
        assert float(k) == pytest.approx(float(np.mean(spring_rate(s, LAWS[i]))), rel=0.05), c
        assert float(k) > 1.03 * LAWS[i].spring_rate, c  # the linear rate is too soft here


def test_damper_even_slope_against_a_sampled_regression():
    law = LAWS[0]
    below = damper_even_slope(law, 1e-3)
    assert below == pytest.approx(0.5 * (law.compression_low - law.rebound_low), rel=1e-6)
    symmetric = SuspensionLaw(spring_rate=4e4, compression_low=2000.0, rebound_low=2000.0,
                              compression_high=800.0, rebound_high=800.0, knee_velocity=0.13)  # fmt: skip
    assert damper_even_slope(symmetric, 0.3) == pytest.approx(0.0, abs=1e-9)
    rng = np.random.default_rng(2)
    for sigma in (0.1, 0.3):  # around and beyond the knee: least squares of the even part on |v|
        v = rng.normal(0.0, sigma, 2_000_000)
        even = 0.5 * (damper_force(v, law) + damper_force(-v, law))
        a = np.abs(v)
        slope = np.cov(even, a)[0, 1] / a.var()
        assert damper_even_slope(law, sigma) == pytest.approx(slope, rel=0.01)


def test_damper_even_slope_closed_form_against_adaptive_quadrature():
    # Cov(F_e, |v|)/Var|v| by scipy's adaptive quadrature over the half-normal density, split at the knee
    from scipy import integrate

    law = LAWS[0]

    def even(a):
        return 0.5 * (damper_force(a, law) + damper_force(-a, law))

    def moment(fn, sigma):
        def integrand(a):
            return fn(a) * 2.0 * np.exp(-0.5 * (a / sigma) ** 2) / (sigma * np.sqrt(2.0 * np.pi))

        parts = ((0.0, law.knee_velocity), (law.knee_velocity, np.inf))
        return sum(integrate.quad(integrand, lo, hi, epsabs=0.0, epsrel=1e-12)[0] for lo, hi in parts)

    for sigma in (0.02, 0.13, 0.4, 2.0):
        mean_a = moment(lambda a: a, sigma)
        cov = moment(lambda a: a * even(a), sigma) - mean_a * moment(even, sigma)
        slope = cov / (moment(lambda a: a * a, sigma) - mean_a**2)
        assert damper_even_slope(law, sigma) == pytest.approx(slope, rel=1e-8), sigma


def _body_and_hop_process(rng, fs: float, n: int, *, hop_hz: float, hop_width_hz: float) -> np.ndarray:
    """n samples at fs of a Gaussian process whose PSD has a hop-like peak (Gaussian, at hop_hz)
    and half as high a body-like one at 1.5 Hz: random-phase spectrum, inverse FFT."""
    f = np.fft.rfftfreq(n, 1 / fs)
    shape = np.exp(-0.5 * ((f - hop_hz) / hop_width_hz) ** 2) + 0.5 * np.exp(-0.5 * ((f - 1.5) / 0.4) ** 2)
    return np.fft.irfft((rng.normal(size=f.size) + 1j * rng.normal(size=f.size)) * np.sqrt(shape), n=n)


def test_rectified_psd_against_a_simulated_gaussian_process():
    # a process with a body-like and a hop-like peak; |v|'s Welch PSD against the formula from v's
    fs = 200.0
    v = _body_and_hop_process(np.random.default_rng(1), fs, 2**20, hop_hz=12.0, hop_width_hz=1.5)
    from scipy.signal import welch

    fw, pv = welch(v, fs=fs, nperseg=8192)
    fa, pa = welch(np.abs(v), fs=fs, nperseg=8192)
    at = np.array([41, 205, 410, 820, 984, 1230])  # 1, 5, 10, 20, 24, 30 Hz
    predicted = rectified_psd(fw[1:], pv[1:], np.full(fw.size - 1, fw[1]), fa[at], max_lag_s=4.0)
    measured = np.array([pa[k - 20 : k + 20].mean() for k in at])
    np.testing.assert_allclose(predicted, measured, rtol=0.1)
    assert predicted[4] > 2 * predicted[2]  # twice the 12 Hz peak: rectification's harmonic


def test_damper_hermite_coefficients_against_their_closed_forms():
    law = LAWS[0]
    rng = np.random.default_rng(3)
    for sigma in (0.05, 0.13, 0.4):
        coef, power = damper_hermite(law, sigma)
        # b1/σ = E[F'(v)] (Stein): the slopes weighted by the normal's mass in each piece
        knee = law.knee_velocity / sigma
        inner = 0.5 * math.erf(knee / math.sqrt(2.0))
        outer = 0.5 - inner
        slope = (inner * (law.compression_low + law.rebound_low)
                 + outer * (law.compression_high + law.rebound_high))  # fmt: skip
        assert coef[1] / sigma == pytest.approx(slope, rel=1e-4)
        # b0 = E[F] (the jacking force), and the orders sum towards E[F²]
        assert coef[0] == pytest.approx(float(gaussian_damper_force(law, sigma)), rel=1e-4)
        v = rng.normal(0.0, sigma, 2_000_000)
        assert power == pytest.approx(float(np.mean(damper_force(v, law) ** 2)), rel=0.01)
        assert np.sum(coef**2) <= power * (1 + 1e-9)
        assert np.sum(coef**2) > 0.995 * power  # the rest: orders above 40 (a kink)
    linear = SuspensionLaw(spring_rate=4e4, compression_low=2000.0, rebound_low=2000.0,
                           compression_high=2000.0, rebound_high=2000.0)  # fmt: skip
    coef, power = damper_hermite(linear, 0.2)
    assert coef[1] == pytest.approx(400.0, rel=1e-6)
    assert np.abs(np.delete(coef, 1)).max() < 1e-6 * 400.0


def test_damper_residual_psd_against_a_simulated_gaussian_process():
    # the residual F(v) − E[F] − c_eq v of the SUV's damper at a body-and-hop velocity process,
    # its Welch PSD against the formula from v's; a linear damper leaves nothing
    fs = 400.0
    v = _body_and_hop_process(np.random.default_rng(4), fs, 2**20, hop_hz=11.0, hop_width_hz=2.5)
    v *= 0.15 / v.std()  # around the knee (0.13 m/s)
    from scipy.signal import welch

    law = LAWS[0]
    coef, _ = damper_hermite(law, v.std())
    residual = damper_force(v, law) - coef[0] - coef[1] * v / v.std()
    fw, pv = welch(v, fs=fs, nperseg=8192)
    _, pr = welch(residual, fs=fs, nperseg=8192)
    at = np.searchsorted(fw, [2.0, 5.0, 11.0, 22.0, 35.0])
    predicted = damper_residual_psd(law, fw[1:], pv[1:], np.full(fw.size - 1, fw[1]), fw[at], max_lag_s=4.0)
    measured = np.array([pr[k - 20 : k + 20].mean() for k in at])
    np.testing.assert_allclose(predicted, measured, rtol=0.1)
    # the even part alone (rectified) is less than the whole residual: the knee's odd part adds
    bins = np.full(fw.size - 1, fw[1])
    even = damper_even_slope(law, v.std()) ** 2 * rectified_psd(fw[1:], pv[1:], bins, fw[at])
    assert np.all(predicted > even)
    linear = SuspensionLaw(spring_rate=4e4, compression_low=2000.0, rebound_low=2000.0,
                           compression_high=2000.0, rebound_high=2000.0)  # fmt: skip
    zero = damper_residual_psd(linear, fw[1:], pv[1:], np.full(fw.size - 1, fw[1]), fw[at])
    assert np.abs(zero).max() < 1e-9 * measured.max()


@pytest.mark.parametrize("mean, sigma", [(0.0, 0.01), (0.035, 0.018), (-0.05, 0.02)])
def test_spring_hermite_coefficients_against_the_closed_forms(mean, sigma):
    # a0 = E[F_s], a1/σ = E[F_s'] (Stein) against the partial-moment closed forms; the orders sum to
    # E[F_s²] (Monte Carlo)
    law = LAWS[2]
    coef, power = spring_hermite(law, mean, sigma)
    assert coef[0] == pytest.approx(float(gaussian_spring_force(law, mean, sigma)), rel=1e-6, abs=1e-6)
    assert coef[1] / sigma == pytest.approx(float(gaussian_spring_rate(law, mean, sigma)), rel=1e-5)
    s = np.random.default_rng(5).normal(mean, sigma, 2_000_000)
    assert power == pytest.approx(float(np.mean(spring_force(s, law) ** 2)), rel=0.01)
    assert np.sum(coef**2) <= power * (1 + 1e-9)
    linear = SuspensionLaw(spring_rate=4e4)
    coef, power = spring_hermite(linear, mean, sigma)
    assert coef[1] == pytest.approx(4e4 * sigma, rel=1e-6)
    assert np.abs(coef[2:]).max() < 1e-6 * coef[1]


def test_spring_residual_psd_against_a_simulated_gaussian_process():
    # a loaded corner's travel on a rough road: 35 mm mean, 18 mm std, the bump stop at 60 mm
    # (touched 8 % of the time). The residual F_s(m + x) − E[F_s] − k_eq x, its Welch PSD against
    # the formula from x's; above the travel's own band the stop's pulses dominate
    fs = 400.0
    x = _body_and_hop_process(np.random.default_rng(6), fs, 2**20, hop_hz=11.0, hop_width_hz=2.5)
    x *= 0.018 / x.std()
    from scipy.signal import welch

    law, mean = LAWS[2], 0.035
    coef, _ = spring_hermite(law, mean, x.std())
    residual = spring_force(mean + x, law) - coef[0] - coef[1] * x / x.std()
    fw, px = welch(x, fs=fs, nperseg=8192)
    _, pr = welch(residual, fs=fs, nperseg=8192)
    at = np.searchsorted(fw, [2.0, 5.0, 11.0, 22.0, 35.0])
    bins = np.full(fw.size - 1, fw[1])
    predicted = spring_residual_psd(law, mean, fw[1:], px[1:], bins, fw[at], max_lag_s=4.0)
    measured = np.array([pr[k - 20 : k + 20].mean() for k in at])
    np.testing.assert_allclose(predicted, measured, rtol=0.1)
    # the residual's power against the linearized force's at 22 Hz: the stop's pulses reach where the
    # travel has little power of its own
    _, pl = welch(coef[1] * x / x.std(), fs=fs, nperseg=8192)
    assert predicted[3] > 0.05 * pl[at[3] - 20 : at[3] + 20].mean()
    # without stops and progression the residual vanishes; far from the stops only the progression's
    linear = SuspensionLaw(spring_rate=4e4)
    none = spring_residual_psd(linear, mean, fw[1:], px[1:], bins, fw[at])
    assert np.abs(none).max() < 1e-9 * measured.max()
    small = spring_residual_psd(law, 0.0, fw[1:], px[1:] * 0.1, bins, fw[at])
    assert small.max() < 1e-3 * measured.max()
