"""Road generators against ISO 8608, the analytic shape-filter process, and a direct sine sum."""

import numpy as np
import pytest
import scipy.fft
import scipy.signal
import scipy.stats
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import integrate

from suvtwin.roads.iso8608 import CLASSES, class_bounds, class_level, displacement_psd
from suvtwin.roads.profile import (
    SHAPE_FILTER_ALPHA,
    generate_road,
    isotropic_coherence,
    obstacle_profile,
    read_road,
    shape_filter_intensity,
    shape_filter_profile,
    superposition_profile,
    write_road,
)
from suvtwin.roads.roughness import classify_profile, fit_iso, profile_psd
from suvtwin.roads.spec import ObstacleSpec, RoadSpec, SegmentSpec

METHODS = ("shape-filter", "superposition", "gaussian")
N_SEEDS = 20


def _road(road_class="C", length=300.0, method="superposition", **kwargs):
    segment_keys = {"gd_n0", "waviness"}
    seg = {k: kwargs.pop(k) for k in list(kwargs) if k in segment_keys}
    return RoadSpec(
        segments=[SegmentSpec(length_m=length, road_class=road_class, **seg)], method=method, **kwargs
    )


def _target_variance(spec: RoadSpec) -> float:
    """Variance the generator is designed to produce, by quadrature of its target PSD (m^2)."""
    seg = spec.segments[0]
    if spec.method in ("superposition", "gaussian"):  # ISO PSD over the generated band
        value, _ = integrate.quad(
            lambda n: displacement_psd(n, gd_n0=seg.level, waviness=seg.waviness),
            spec.n_min,
            spec.n_max,
            limit=400,
        )
        return value
    # shape filter, eq. 5: G(Omega) = q / (alpha^2 + Omega^2) over Omega in [0, inf)
    q = shape_filter_intensity(seg.level)
    value, _ = integrate.quad(lambda w: q / (SHAPE_FILTER_ALPHA**2 + w**2), 0, np.inf)
    return value


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("letter", CLASSES)
def test_fitted_level_inside_class_and_std_matches_psd_integral(letter, method):
    spec = _road(letter, 300.0, method, spacing_m=0.02)
    lower, upper = class_bounds(letter)
    inside, waviness, stds = 0, [], []
    for seed in range(N_SEEDS):
        road = generate_road(spec, seed=1000 * CLASSES.index(letter) + seed)  # fresh seeds per class
        for track in (0, 1):
            fit = classify_profile(road.z[track], road.spacing_m)
            inside += lower <= fit.gd_n0 <= upper
            waviness.append(fit.waviness)
            stds.append(road.z[track].std())
    # acceptance: >= 19 of 20 inside the class bounds (here counted over both tracks: 38 of 40)
    assert inside >= 38
    if method == "superposition":
        assert np.all(np.abs(np.array(waviness) - 2.0) <= 0.25)
        assert np.mean(waviness) == pytest.approx(2.0, abs=0.05)
    # elevation std vs the integral of the target PSD: within 10 % on the mean over seeds
    assert np.mean(stds) == pytest.approx(np.sqrt(_target_variance(spec)), rel=0.10)


@pytest.mark.parametrize("waviness", [1.6, 2.5, 3.0])
def test_superposition_reproduces_other_waviness(waviness):
    spec = _road(None, 1000.0, gd_n0=3e-4, waviness=waviness)
    fits = [classify_profile(generate_road(spec, seed=s).z[0], 0.02) for s in range(5)]
    assert np.mean([f.waviness for f in fits]) == pytest.approx(waviness, abs=0.05)
    assert np.mean([f.gd_n0_free for f in fits]) == pytest.approx(3e-4, rel=0.10)


def _line_powers(spacing, n_samples, gd_n0, w, n_min, n_max):
    """The generator's lines (index k, spacing dn) with A_k^2/2 from quadrature of the ISO PSD over
    each line's bin, and the number of lines of its grid (at least 8/n_min m, a fast FFT length)."""
    n_fft = scipy.fft.next_fast_len(max(n_samples, int(np.ceil(8.0 / (n_min * spacing)))), real=True)
    dn = 1.0 / (n_fft * spacing)
    lines = []
    for k in range(1, n_fft // 2 + 1):
        lo, hi = max(k * dn - dn / 2, n_min), min(k * dn + dn / 2, n_max)
        if hi <= lo or k >= n_fft / 2:
            continue
        power, _ = integrate.quad(lambda n: displacement_psd(n, gd_n0=gd_n0, waviness=w), lo, hi)
        lines.append((k, power))
    return lines, dn, n_fft // 2 + 1


def test_superposition_equals_a_direct_sum_of_sines():
    # Lin et al. 2021 eq. 31 summed term by term, with each A_i^2/2 from quadrature of the ISO
    # PSD over the line's bin, against the generator's single inverse FFT.
    spacing, n_samples, gd_n0, w, n_min, n_max = 0.05, 400, 2e-4, 2.3, 0.2, 5.0
    profile = superposition_profile(n_samples, spacing, gd_n0=gd_n0, waviness=w, n_min=n_min, n_max=n_max,
                                    rng=np.random.default_rng(5))[0]  # fmt: skip
    lines, dn, n_lines = _line_powers(spacing, n_samples, gd_n0, w, n_min, n_max)
    phases = np.random.default_rng(5).uniform(0.0, 2.0 * np.pi, size=(1, n_lines))[0]
    x = np.arange(n_samples) * spacing
    expected = np.zeros(n_samples)
    for k, power in lines:
        expected += np.sqrt(2 * power) * np.sin(2 * np.pi * k * dn * x - phases[k])
    assert profile.size == n_samples
    np.testing.assert_allclose(profile, expected, rtol=0, atol=1e-9 * np.abs(expected).max())


def test_gaussian_superposition_equals_rices_sum_of_random_cosines_and_sines():
    # Rice 1944: z = sum_i a_i cos(2 pi n_i x) + b_i sin(2 pi n_i x), a_i, b_i ~ N(0, A_i^2/2), summed
    # term by term against the generator's inverse FFT (its draws: a then b, one line each).
    spacing, n_samples, gd_n0, w, n_min, n_max = 0.05, 400, 2e-4, 2.3, 0.2, 5.0
    profile = superposition_profile(n_samples, spacing, gd_n0=gd_n0, waviness=w, n_min=n_min, n_max=n_max,
                                    rng=np.random.default_rng(5), random_amplitudes=True)[0]  # fmt: skip
    lines, dn, n_lines = _line_powers(spacing, n_samples, gd_n0, w, n_min, n_max)
    a, b = np.random.default_rng(5).standard_normal((2, 1, n_lines))[:, 0]
    x = np.arange(n_samples) * spacing
    expected = np.zeros(n_samples)
    for k, power in lines:
        s = np.sqrt(power)  # the std of a_k and b_k: A_k / sqrt(2), A_k^2 / 2 = power
        expected += s * (a[k] * np.cos(2 * np.pi * k * dn * x) + b[k] * np.sin(2 * np.pi * k * dn * x))
    np.testing.assert_allclose(profile, expected, rtol=0, atol=1e-9 * np.abs(expected).max())


def test_random_phase_lines_carry_their_power_exactly_and_gaussian_ones_exponentially():
    # Over the generator's whole period a random-phase road's periodogram is its PSD line for line;
    # a Gaussian road's line power is (a^2 + b^2)/2 of its mean: exponential, mean 1 (chi-square 2 / 2).
    spacing, n_min = 0.02, 0.05
    n = scipy.fft.next_fast_len(int(np.ceil(8.0 / (n_min * spacing))), real=True)  # no crop: one period
    lines = np.fft.rfftfreq(n, spacing)
    inside = (lines > n_min + 1 / (n * spacing)) & (lines < 9.9)
    dn = 1.0 / (n * spacing)
    lo, hi = lines[inside] - dn / 2, lines[inside] + dn / 2
    expected = 1e-4 * 0.1**2 * (1 / lo - 1 / hi)  # A_k^2 / 2: Gd(n0) (n/n0)^-2 integrated over the bin
    for random_amplitudes in (False, True):
        z = superposition_profile(n, spacing, gd_n0=1e-4, n_min=n_min, rng=np.random.default_rng(11),
                                  random_amplitudes=random_amplitudes)[0]  # fmt: skip
        power = 2.0 * np.abs(np.fft.rfft(z)[inside] / n) ** 2  # each line's variance A_k^2 / 2
        ratio = power / expected
        if not random_amplitudes:
            np.testing.assert_allclose(ratio, 1.0, rtol=1e-9)
        else:
            assert ratio.mean() == pytest.approx(1.0, abs=0.03)  # 1 / sqrt(~10^4 lines)
            assert scipy.stats.kstest(ratio, "expon").pvalue > 0.01


def test_a_random_phase_roads_spectrum_scatters_less_over_windows_than_a_gaussian_roads():
    # The spectrum an estimator reads: band means (0.025 cycles/m wide, 0.1-2 cycles/m) of the slope's
    # periodogram averaged over K consecutive 160 m windows (hop 80 m) of a 1200 m class C road, their
    # scatter about the mean over roads. On one window the three generators scatter alike; over more,
    # the random-phase road's converges to its PSD far faster than a Gaussian process's (its lines'
    # amplitudes are fixed); the two Gaussian generators (shape filter, random amplitudes) agree.
    def scatter(method, windows):
        means = []
        for seed in range(12):
            road = generate_road(_road(None, 1200.0, method, gd_n0=2.56e-4), seed=seed)
            slope = np.diff(road.z, axis=1) / road.spacing_m
            starts = np.arange(windows) * 4000
            segs = np.stack([slope[:, s : s + 8000] for s in starts], axis=1)
            power = np.abs(np.fft.rfft(segs - segs.mean(-1, keepdims=True))) ** 2
            n = np.fft.rfftfreq(8000, road.spacing_m)
            band = np.digitize(n, np.arange(0.1, 2.0, 0.025))
            avg = power.mean(1)
            means.extend(np.stack([avg[:, band == b].mean(-1) for b in range(1, 76)], axis=-1))
        means = np.array(means)
        return float((means / means.mean(0)).std())

    one = {m: scatter(m, 1) for m in METHODS}
    eight = {m: scatter(m, 8) for m in METHODS}
    assert one["superposition"] == pytest.approx(one["gaussian"], rel=0.2)
    assert eight["gaussian"] == pytest.approx(eight["shape-filter"], rel=0.2)
    assert eight["superposition"] < 0.75 * eight["gaussian"]
    assert scatter("superposition", 13) < 0.5 * scatter("gaussian", 13)


def test_shape_filter_autocovariance_is_the_analytic_exponential():
    # dz/dx = -alpha z + xi has autocovariance sigma^2 exp(-alpha |lag|), sigma^2 = pi q /(2 alpha)
    spacing, gd_n0 = 0.05, class_level("D")
    z = shape_filter_profile(400_000, spacing, gd_n0=gd_n0, rng=np.random.default_rng(2), n_tracks=4)
    sigma2 = np.pi * shape_filter_intensity(gd_n0) / (2 * SHAPE_FILTER_ALPHA)
    for lag_m in (0.0, 2.0, 5.0, 10.0):
        k = int(round(lag_m / spacing))
        cov = np.mean(z[:, : z.shape[1] - k] * z[:, k:])
        # 20 000 m per track / correlation length 7.9 m: ~2.5 % standard error on 4 tracks
        assert cov == pytest.approx(sigma2 * np.exp(-SHAPE_FILTER_ALPHA * lag_m), rel=0.08)


def test_shape_filter_hits_the_iso_level_where_the_paper_variance_does_not():
    # Calibrated: Welch PSD at Omega0 = 1 rad/m (n = 0.159 cycle/m) equals the ISO level.
    gd_n0 = class_level("B")
    z = shape_filter_profile(200_000, 0.02, gd_n0=gd_n0, rng=np.random.default_rng(8), n_tracks=8)
    n, psd = profile_psd(z, 0.02, segment_m=200.0)
    band = (n > 0.12) & (n < 0.21)
    measured = np.mean(psd[:, band]) / np.mean(displacement_psd(n[band], gd_n0=gd_n0))
    assert measured == pytest.approx(1.0, abs=0.08)
    # Brancati & Tufano 2022, eq. 5 with sigma^2 = 4 Gd(Omega0) as the paper states gives
    # G(Omega0) = 2 alpha 4 Gd / (pi (alpha^2 + 1)): a third of the class level.
    paper_ratio = 2 * SHAPE_FILTER_ALPHA * 4 / (np.pi * (SHAPE_FILTER_ALPHA**2 + 1))
    assert paper_ratio == pytest.approx(0.318, abs=0.002)
    assert measured / paper_ratio > 2.9


def test_same_seed_same_bytes_different_seed_different_road(tmp_path):
    spec = _road("D", 200.0, "shape-filter", tracks="correlated", track_correlation=0.7)
    write_road(generate_road(spec, seed=3), tmp_path / "a.parquet")
    write_road(generate_road(spec, seed=3), tmp_path / "b.parquet")
    write_road(generate_road(spec, seed=4), tmp_path / "c.parquet")
    assert (tmp_path / "a.parquet").read_bytes() == (tmp_path / "b.parquet").read_bytes()
    a, c = read_road(tmp_path / "a.parquet"), read_road(tmp_path / "c.parquet")
    assert not np.allclose(a.z, c.z)
    assert a.spec == spec and a.seed == 3


@pytest.mark.parametrize("method", METHODS)
def test_track_modes(method):
    n = 100_000  # 2 km
    for tracks, rho in (("independent", 0.0), ("identical", 1.0), ("correlated", 0.6)):
        road = generate_road(_road("C", 2000.0, method, tracks=tracks, track_correlation=0.6), seed=1)
        measured = np.corrcoef(road.z)[0, 1]
        if tracks == "identical":
            np.testing.assert_array_equal(road.z[0], road.z[1])
        else:
            # a 2 km road holds ~250 correlation lengths (shape filter): standard error ~0.06
            assert measured == pytest.approx(rho, abs=0.15)
        if tracks == "correlated":
            f, coh = scipy.signal.coherence(road.z[0], road.z[1], fs=50.0, nperseg=4096)
            band = (f > 0.1) & (f < 5)
            assert np.mean(coh[band]) == pytest.approx(rho**2, abs=0.06)
            assert road.z[1].std() == pytest.approx(road.z[0].std(), rel=0.2)
        assert road.x.size == n + 1


@pytest.mark.parametrize("method", METHODS)
def test_class_switch_segments_a_to_d(method):
    # Brancati & Tufano 2022 §5.4: the road switches from class A to class D.
    spec = RoadSpec(
        segments=[SegmentSpec(length_m=400, road_class="A"), SegmentSpec(length_m=400, road_class="D")],
        method=method,
        transition_m=2.0,
    )
    road = generate_road(spec, seed=9)
    half = road.x.size // 2
    first = classify_profile(road.z[0, : half - 100], 0.02)
    second = classify_profile(road.z[0, half + 100 :], 0.02)
    assert (first.road_class, second.road_class) == ("A", "D")
    # no step at the join: the largest sample-to-sample change near the join is no bigger than
    # the largest elsewhere on the rough segment
    dz = np.abs(np.diff(road.z[0]))
    join = slice(half - 100, half + 100)
    assert dz[join].max() <= dz[half + 100 :].max()
    assert road.z[0, half + 100 :].std() / road.z[0, : half - 100].std() == pytest.approx(8.0, rel=0.35)


def test_obstacles_have_their_analytic_shape():
    spec = RoadSpec(
        segments=[SegmentSpec(length_m=100, gd_n0=1e-12)],  # practically flat
        obstacles=[
            ObstacleSpec(kind="sine_bump", position_m=10, length_m=2.0, height_m=0.1, track="left"),
            ObstacleSpec(kind="cleat", position_m=30, length_m=0.5, height_m=0.02, track="right"),
            ObstacleSpec(kind="pothole", position_m=50, length_m=1.0, height_m=0.05, track="both"),
        ],
    )
    road = generate_road(spec, seed=0)
    x, (left, right) = road.x, road.z
    bump = (x >= 10) & (x <= 12)
    # Lin et al. 2021 eq. 23: peak h0 at mid-length, area 2 h0 D / pi
    assert left[np.argmin(np.abs(x - 11.0))] == pytest.approx(0.1, abs=1e-5)
    assert np.trapezoid(left[bump], x[bump]) == pytest.approx(2 * 0.1 * 2.0 / np.pi, rel=1e-3)
    assert np.abs(right[bump]).max() < 1e-5
    cleat = (x >= 30) & (x < 30.5)
    assert right[cleat] == pytest.approx(np.full(cleat.sum(), 0.02), abs=1e-5)
    assert np.abs(left[cleat]).max() < 1e-5
    hole = (x >= 50) & (x < 51)
    assert road.z[:, hole] == pytest.approx(np.full((2, hole.sum()), -0.05), abs=1e-5)
    assert obstacle_profile([9.99, 12.01], spec.obstacles[0]) == pytest.approx([0.0, 0.0])


@settings(max_examples=30, deadline=None)
@given(
    length=st.floats(20.0, 400.0),
    spacing=st.sampled_from([0.005, 0.01, 0.02, 0.025, 0.05]),
    letter=st.sampled_from(CLASSES),
    method=st.sampled_from(METHODS),
    seed=st.integers(0, 2**32 - 1),
)
def test_any_valid_spec_gives_a_finite_road_on_the_grid(length, spacing, letter, method, seed):
    road = generate_road(_road(letter, length, method, spacing_m=spacing), seed=seed)
    assert road.x[0] == 0.0
    assert road.x[-1] <= length + 1e-9 and road.x[-1] > length - spacing
    np.testing.assert_allclose(np.diff(road.x), spacing, rtol=1e-9)
    assert np.all(np.isfinite(road.z)) and road.z.shape == (2, road.x.size)
    assert road.z.std() < 20 * np.sqrt(class_level(letter))  # no blow-up: std ~ sqrt(Gd) scale


@settings(max_examples=25, deadline=None)
@given(gd_n0=st.floats(1e-6, 1e-2), waviness=st.floats(1.5, 3.0))
def test_fit_recovers_an_exact_power_law(gd_n0, waviness):
    # A PSD that *is* the power law (no estimation noise): the fit must return it exactly.
    n = np.linspace(0.0, 25.0, 20001)[1:]
    fit = fit_iso(n, displacement_psd(n, gd_n0=gd_n0, waviness=waviness))
    assert fit.waviness == pytest.approx(waviness, abs=2e-3)
    assert fit.gd_n0_free == pytest.approx(gd_n0, rel=5e-3)


@settings(max_examples=25, deadline=None)
@given(gd_n0=st.floats(1e-6, 1e-2))
def test_fixed_slope_fit_recovers_an_iso_power_law(gd_n0):
    # w = 2 exactly (an ISO class road): the w = 2 fit returns the level, the free fit w = 2
    n = np.linspace(0.0, 25.0, 20001)[1:]
    fit = fit_iso(n, displacement_psd(n, gd_n0=gd_n0))
    assert fit.gd_n0 == pytest.approx(gd_n0, rel=5e-3)
    assert fit.waviness == pytest.approx(2.0, abs=2e-3)


@pytest.mark.parametrize("waviness", [1.7, 2.0, 2.5])
def test_isotropic_coherence_is_the_isotropic_surfaces_integral(waviness):
    # the closed form (Watson's integral: a Matérn function of 2πnB) against the two-dimensional
    # spectrum (n² + m²)^−(w+1)/2 integrated across the road with and without the cos(2πmB) of two
    # lines B apart, by quadrature
    b, s = 1.62, 0.5 * (waviness + 1.0)
    for n in (0.02, 0.05, 0.1, 0.3, 0.8):
        spectrum = lambda m, n=n: (n * n + m * m) ** -s  # noqa: E731
        cross = integrate.quad(spectrum, 0.0, np.inf, weight="cos", wvar=2 * np.pi * b)[0]
        line = integrate.quad(spectrum, 0.0, np.inf)[0]
        assert isotropic_coherence(n, b, waviness) == pytest.approx(cross / line, rel=1e-6, abs=1e-9)
    assert isotropic_coherence(0.0, b, waviness) == 1.0
    assert np.all(np.diff(isotropic_coherence(np.linspace(0.0, 3.0, 50), b, waviness)) < 0)


@pytest.mark.parametrize("method", METHODS)
def test_isotropic_tracks_have_the_isotropic_coherence_and_each_its_psd(method):
    spec = _road("C", 4000.0, method, tracks="isotropic", track_spacing_m=1.62)
    road = generate_road(spec, seed=3)
    left, right = road.z
    f, pxy = scipy.signal.csd(left, right, fs=50.0, nperseg=4096)
    _, pxx = scipy.signal.welch(left, fs=50.0, nperseg=4096)
    _, pyy = scipy.signal.welch(right, fs=50.0, nperseg=4096)
    for lo, hi in ((0.03, 0.06), (0.08, 0.12), (0.2, 0.3), (0.5, 0.8)):
        band = (f >= lo) & (f < hi)
        measured = pxy[band].real.sum() / np.sqrt(pxx[band].sum() * pyy[band].sum())
        expected = np.average(isotropic_coherence(f[band], 1.62), weights=pxx[band])
        assert measured == pytest.approx(expected, abs=0.08)
    assert right.std() == pytest.approx(left.std(), rel=0.2)
    band = (f > 0.1) & (f < 5)
    assert np.median(pyy[band] / pxx[band]) == pytest.approx(1.0, rel=0.15)
