"""The front→rear preview (suvtwin.estimators.preview) against things it does not compute itself.

(a) A time-domain simulation of the two corners (state space, scipy.signal.lsim) on an ISO road
    profile from suvtwin.roads, the rear wheel at the same track a wheelbase behind (the road read at
    x − L, not a phase), 0.5 m/s² accelerometer noise: the rear pressure given the true front's.
(b) The accumulated statistics against a direct per-segment computation written here, for any
    chunking, with forgetting and several memories.
(c) Bad input: InputError naming the field and its range.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.signal

from suvtwin.errors import InputError
from suvtwin.estimators.preview import PreviewConditional, PreviewConfig, PreviewTrack, fuse_track
from suvtwin.pipeline.estimation import corner_sprung_mass, linear_corner_model
from suvtwin.roads.profile import generate_road
from suvtwin.roads.spec import RoadSpec, SegmentSpec
from suvtwin.tire_stiffness import suv_tire_stiffness

DT = 1e-3
WHEELBASE = 2.818
NOISE = 0.5


def _models(load_kg: float = 100.0):
    return [linear_corner_model(c, corner_sprung_mass(c, load_kg)) for c in ("fl", "rl")]


def _unsprung_acc(ms: float, mu: float, ks: float, cs: float, kt: float, ct: float, zr, vr) -> np.ndarray:
    """Unsprung acceleration (m/s²) of a linear quarter car on road height zr and rate vr, from rest.

    m_s z̈_s = −k_s(z_s − z_u) − c_s(ż_s − ż_u);
    m_u z̈_u = k_s(z_s − z_u) + c_s(ż_s − ż_u) − k_t(z_u − z_r) − c_t(ż_u − ż_r)."""
    a = np.array([
        [0.0, 1.0, 0.0, 0.0],
        [-ks / ms, -cs / ms, ks / ms, cs / ms],
        [0.0, 0.0, 0.0, 1.0],
        [ks / mu, cs / mu, -(ks + kt) / mu, -(cs + ct) / mu],
    ])  # fmt: skip
    b = np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [kt / mu, ct / mu]])
    c = a[3:4]
    d = b[3:4]
    t = np.arange(zr.size) * DT
    _, y, _ = scipy.signal.lsim((a, b, c, d), np.stack([zr, vr], axis=1), t)
    return y


def _corner(qc, kt: float, zr, vr) -> np.ndarray:
    """The roll-plane corner's unsprung acceleration to its own track: half the heave quarter car's
    plus half the roll quarter car's (m_roll, k_s + 2 k_arb), the damping at its low-speed mean."""
    cs = max(qc.damping_range)
    heave = _unsprung_acc(qc.sprung_mass, qc.unsprung_mass, qc.spring_rate, cs, kt, qc.tire_damping, zr, vr)
    roll = _unsprung_acc(
        qc.roll_mass, qc.unsprung_mass, qc.spring_rate + 2 * qc.anti_roll, cs, kt, qc.tire_damping, zr, vr
    )
    return 0.5 * (heave + roll)


def _two_corners(p_front_kpa: float, p_rear_kpa, speed: float, duration_s: float, seed: int):
    """Front and rear unsprung accelerations (measured: with noise) on one track of an ISO road;
    `p_rear_kpa` a pressure, or (before, after, change time s): the rear's response at each pressure
    from the start, spliced at the change."""
    rng = np.random.default_rng(seed)
    tire = suv_tire_stiffness()
    length = speed * duration_s + WHEELBASE + 20.0
    # the profile's lines stop at 4 cycles/m (133 Hz at 120 km/h): none aliases into the band when the
    # road is read at the 1 kHz samples (a real tyre envelopes them too)
    spec = RoadSpec(segments=[SegmentSpec(length_m=length, gd_n0=64e-6)], spacing_m=0.01, n_max=4.0)
    road = generate_road(spec, seed=seed)
    x, z = road.x, road.z[0]
    slope = np.gradient(z, x)
    t = np.arange(int(round(duration_s / DT))) * DT
    front_x = WHEELBASE + 10.0 + speed * t  # the rear wheel is a wheelbase behind, on the same track
    qf, qr = _models()
    rear_x = front_x - WHEELBASE

    def response(qc, p, pos):
        kt = tire.kt0 * (1.0 + tire.pfz1 * (p * 1e3 - tire.p0) / tire.p0)  # Brancati & Tufano eq. 3–4
        return _corner(qc, kt, np.interp(pos, x, z), speed * np.interp(pos, x, slope))

    front = response(qf, p_front_kpa, front_x)
    if np.ndim(p_rear_kpa) == 0:
        rear = response(qr, p_rear_kpa, rear_x)
    else:
        before, after, t_change = p_rear_kpa
        rear = np.where(t < t_change, response(qr, before, rear_x), response(qr, after, rear_x))
    return [a + NOISE * rng.standard_normal(a.size) for a in (front, rear)]


@pytest.fixture(scope="module")
def linear_run():
    speed = 80 / 3.6
    front, rear = _two_corners(205.0, 165.0, speed, 30.0, seed=7)
    return front, rear, speed


def test_rear_given_true_front_on_linear_truth(linear_run):
    front, rear, speed = linear_run
    qf, qr = _models()
    tire = suv_tire_stiffness()
    track = PreviewTrack(qf, qr, tire, tire, DT, WHEELBASE)
    for i in range(0, front.size, 1000):
        track.add(front[i : i + 1000], rear[i : i + 1000], speed)
    assert track.counts["used"] == 29  # the first segment's front lies before the record
    out = track.conditional(205.0, 0.0)
    assert out.informative, out.reason
    # the 1 s segments' leakage biases it by about −1 kPa; the likelihood's own σ is ~1 kPa
    assert abs(out.mean_kpa - 165.0) < 3.0, out
    assert abs(out.mean_kpa - 165.0) <= 2.0 * out.sigma_kpa
    assert out.sigma_likelihood_kpa < 3.0
    assert np.isnan(out.dlc) and out.floor_kpa == track.config.rough_floor_kpa  # no sprung data given
    # the ridge: a higher front pressure asks for a higher rear one (the ratio k_t,r/k_t,f is what
    # is measured), and the front's σ enters through the slope
    assert 0.3 < out.ridge_slope < 2.0
    wide = track.conditional(205.0, 20.0, dlc=0.1)
    assert wide.floor_kpa == track.config.floor_kpa
    expected = np.sqrt(out.sigma_likelihood_kpa**2 + (out.ridge_slope * 20.0) ** 2 + 4.0**2)
    assert wide.sigma_kpa == pytest.approx(expected, rel=1e-9)
    shifted = track.conditional(215.0, 0.0)
    assert shifted.mean_kpa - out.mean_kpa == pytest.approx(10.0 * out.ridge_slope, abs=1.5)
    # the estimate is where the likelihood peaks
    grid = np.arange(out.mean_kpa - 3.0, out.mean_kpa + 3.01, 0.25)
    ll = track.loglik(205.0, grid)
    assert abs(grid[np.argmax(ll)] - out.mean_kpa) <= 0.25
    # ... and its curvature is the likelihood's σ (no forgetting: the sandwich factor is 1)
    lm, l0, lp = track.loglik(205.0, out.mean_kpa + np.array([-1.0, 0.0, 1.0]))
    h_rr = track.config.sigma_scale**2 / out.sigma_likelihood_kpa**2
    assert -(lp - 2 * l0 + lm) == pytest.approx(h_rr, rel=0.1)


def test_little_data_is_not_informative(linear_run):
    front, rear, speed = linear_run
    qf, qr = _models()
    tire = suv_tire_stiffness()
    track = PreviewTrack(qf, qr, tire, tire, DT, WHEELBASE)
    assert track.conditional(200.0, 5.0).reason == "no_segments"
    track.add(front[:2000], rear[:2000], speed)  # the first segment lacks its front: warm-up
    assert track.counts == {"used": 1, "gap": 0, "speed": 0, "warmup": 1}
    out = track.conditional(200.0, 5.0)
    assert not out.informative and out.reason == "few_segments"
    track.add(front[2000:4000], rear[2000:4000], speed)
    out = track.conditional(205.0, 0.0)  # 3 segments: a wide likelihood, not a spuriously sharp one
    assert out.informative and 0.5 < out.sigma_likelihood_kpa < 10.0, out
    assert abs(out.mean_kpa - 165.0) < 3.0 * out.sigma_likelihood_kpa
    slow = PreviewTrack(qf, qr, tire, tire, DT, WHEELBASE)
    slow.add(front[:5000], rear[:5000], 3.0)  # below min_speed_mps
    assert slow.counts["speed"] == 5 and slow.conditional(200.0, 5.0).reason == "no_segments"
    quiet = PreviewTrack(qf, qr, tire, tire, DT, WHEELBASE)
    rng = np.random.default_rng(1)
    quiet.add(NOISE * rng.standard_normal(8000), NOISE * rng.standard_normal(8000), speed)  # noise only
    assert quiet.conditional(200.0, 5.0).reason == "low_snr"


def test_a_rear_off_the_fronts_track_is_incoherent_and_refused(linear_run):
    # the rear on the front's road: coherence near 1 (the noise removed); the rear on another road
    # of the same level (it does not follow the front's track): its least-squares ratio would be
    # attenuated by the coherence and read the rear soft, so the preview refuses it
    front, rear, speed = linear_run
    _, other = _two_corners(205.0, 165.0, speed, 30.0, seed=8)
    qf, qr = _models()
    tire = suv_tire_stiffness()
    same = PreviewTrack(qf, qr, tire, tire, DT, WHEELBASE)
    off = PreviewTrack(qf, qr, tire, tire, DT, WHEELBASE)
    same.add(front, rear, speed)
    off.add(front, other, speed)
    assert same.coherence() > 0.95
    assert off.coherence() < 0.2
    assert same.conditional(205.0, 0.0).informative
    refused = off.conditional(205.0, 0.0)
    assert not refused.informative and refused.reason == "incoherent" and refused.coherence < 0.2
    assert np.isnan(PreviewTrack(qf, qr, tire, tire, DT, WHEELBASE).coherence())  # no data


def test_a_short_memory_follows_a_pressure_change():
    """The rear drops 200 → 160 kPa at 12 s: at 24 s the memory forgetting with τ = 3 s is at the new
    pressure within its σ, the one that never forgets sits between the two."""
    speed = 60 / 3.6
    front, rear = _two_corners(200.0, (200.0, 160.0, 12.0), speed, 24.0, seed=21)
    qf, qr = _models()
    tire = suv_tire_stiffness()
    track = PreviewTrack(qf, qr, tire, tire, DT, WHEELBASE, memories=2)
    for i in range(0, front.size, 4000):  # the monitor's 4 s updates
        track.decay([np.exp(-4.0 / 3.0), 1.0])
        track.add(front[i : i + 4000], rear[i : i + 4000], speed)
    short, long = (track.conditional(200.0, 0.0, memory=m, dlc=0.1) for m in (0, 1))
    assert short.informative and long.informative
    assert abs(short.mean_kpa - 160.0) < min(2.0 * short.sigma_kpa, 6.0), short
    assert 165.0 < long.mean_kpa < 195.0, long
    assert short.segments < 8.0 < long.segments  # effective segments: (Σw)²/Σw²


def _direct_statistics(front, rear, speed, n, band, wheelbase):
    """A, B, C, K per segment of the rear's time axis, written out plainly (segments whose front
    starts before the record are left out)."""
    freqs = np.fft.rfftfreq(n, DT)
    sel = (freqs >= band[0]) & (freqs <= band[1])
    a = b = c = 0.0
    k = 0
    for j in range(rear.size // n):
        start = j * n
        tau = wheelbase / np.mean(speed[start : start + n])
        whole = int(np.floor(tau / DT))
        if start - whole < 0:
            continue
        x = np.fft.rfft(scipy.signal.detrend(front[start - whole : start - whole + n]))[sel]
        y = np.fft.rfft(scipy.signal.detrend(rear[start : start + n]))[sel]
        a = a + np.abs(x) ** 2
        b = b + np.abs(y) ** 2
        c = c + np.conj(x) * y * np.exp(2j * np.pi * freqs[sel] * (tau - whole * DT))
        k += 1
    return a, b, c, k


def test_statistics_match_a_direct_computation_for_any_chunking():
    rng = np.random.default_rng(3)
    size = 12_000
    front, rear = rng.standard_normal((2, size))
    speed = np.linspace(15.0, 17.0, size)  # τ changes from segment to segment
    s_front, s_rear = rng.standard_normal((2, size))
    qf, qr = _models()
    tire = suv_tire_stiffness()
    a, b, c, k = _direct_statistics(front, rear, speed, 1000, (20.0, 40.0), WHEELBASE)
    results = []
    for chunks in (
        [size],
        [1] * 7 + [333, 1000, 4001, 2] + [size - 5343],
        list(np.diff([0, 999, 1000, 1001, 6500, size])),
    ):
        track = PreviewTrack(qf, qr, tire, tire, DT, WHEELBASE)
        edges = np.concatenate([[0], np.cumsum(chunks)])
        for lo, hi in zip(edges[:-1], edges[1:], strict=True):
            track.add(
                front[lo:hi], rear[lo:hi], speed[lo:hi], acc_s_front=s_front[lo:hi], acc_s_rear=s_rear[lo:hi]
            )
        assert track.K[0] == k == track.counts["used"]
        np.testing.assert_allclose(track.A[0], a, rtol=1e-10)
        np.testing.assert_allclose(track.B[0], b, rtol=1e-10)
        np.testing.assert_allclose(track.C[0], c, rtol=1e-10, atol=1e-9 * np.abs(c).max())
        results.append((track.dlc(), track.conditional(200.0, 5.0, dlc=0.1)))
    for r in results[1:]:  # bit for bit
        np.testing.assert_equal(r[0], results[0][0])
        np.testing.assert_equal(dataclasses.astuple(r[1]), dataclasses.astuple(results[0][1]))
    # the DLC: the larger corner's std of m_s a_s + m_us a_us over (m_s + m_us) g, noise removed,
    # over the used segments' samples (the first is warm-up)
    used = slice(1000, size)
    dlc = []
    for qc, au, as_ in ((qf, front, s_front), (qr, rear, s_rear)):
        load = qc.sprung_mass * as_[used] + qc.unsprung_mass * au[used]
        var = load.var() - NOISE**2 * (qc.sprung_mass**2 + qc.unsprung_mass**2)
        dlc.append(np.sqrt(max(var, 0.0)) / ((qc.sprung_mass + qc.unsprung_mass) * 9.81))
    assert results[0][0] == pytest.approx(max(dlc), rel=1e-9)


def test_forgetting_and_memories_weight_the_segments():
    rng = np.random.default_rng(4)
    front, rear = rng.standard_normal((2, 6000))
    qf, qr = _models()
    tire = suv_tire_stiffness()
    one = PreviewTrack(qf, qr, tire, tire, DT, WHEELBASE)
    one.add(front[:3000], rear[:3000], 20.0)
    first = one.A[0].copy(), one.C[0].copy(), one.K[0]
    two = PreviewTrack(qf, qr, tire, tire, DT, WHEELBASE, memories=2)
    two.add(front[:3000], rear[:3000], 20.0, weight=[1.0, 0.5])
    two.decay([0.25, 1.0])
    two.add(front[3000:], rear[3000:], 20.0)
    one.add(front[3000:], rear[3000:], 20.0)
    later = one.A[0] - first[0], one.C[0] - first[1], one.K[0] - first[2]
    np.testing.assert_allclose(two.A[0], 0.25 * first[0] + later[0], rtol=1e-12)
    np.testing.assert_allclose(two.A[1], 0.5 * first[0] + later[0], rtol=1e-12)
    np.testing.assert_allclose(two.C[1], 0.5 * first[1] + later[1], rtol=1e-12)
    assert two.K.tolist() == pytest.approx([0.25 * first[2] + later[2], 0.5 * first[2] + later[2]])
    assert two.K2[0] == pytest.approx(0.25**2 * first[2] + later[2])
    assert two.state_nbytes < 40_000


def test_fusion_is_the_posterior_of_the_linearized_ridge():
    """fuse_track against the posterior moments of the product of the two Gaussians and the ridge's
    Gaussian likelihood exp(−(p_r − p_r*(p̂_f) − s (p_f − p̂_f))²/2R), summed on a grid."""
    cond = PreviewConditional(
        mean_kpa=171.0, sigma_kpa=float("nan"), informative=True, reason="", sigma_likelihood_kpa=1.5,
        ridge_slope=0.9, cov_front_rear_kpa2=float("nan"), floor_kpa=4.0, dlc=0.1, segments=30.0,
        bands_used=5,
    )  # fmt: skip
    mean, cov = fuse_track(200.0, 10.0, 185.0, 12.0, cond)
    pf, pr = np.meshgrid(np.arange(120.0, 280.0, 0.25), np.arange(100.0, 260.0, 0.25), indexing="ij")
    r = 1.5**2 + 4.0**2
    log_w = (
        -((pf - 200.0) ** 2) / 200.0
        - (pr - 185.0) ** 2 / 288.0
        - (pr - 171.0 - 0.9 * (pf - 200.0)) ** 2 / (2 * r)
    )
    w = np.exp(log_w - log_w.max())
    w /= w.sum()
    m = np.array([np.sum(w * pf), np.sum(w * pr)])
    d = np.stack([pf - m[0], pr - m[1]])
    c = np.einsum("iab,jab,ab->ij", d, d, w)
    np.testing.assert_allclose(mean, m, atol=1e-6)
    np.testing.assert_allclose(cov, c, atol=1e-4)
    # not informative: the prior back
    flat = dataclasses.replace(cond, informative=False, reason="few_segments")
    mean, cov = fuse_track(200.0, 10.0, 185.0, 12.0, flat)
    assert mean.tolist() == [200.0, 185.0] and cov.tolist() == [[100.0, 0.0], [0.0, 144.0]]
    with pytest.raises(InputError, match="sigma_rear_kpa"):
        fuse_track(200.0, 10.0, 185.0, 0.0, cond)


def test_fusion_with_correlated_estimates_on_a_grid():
    """fuse_track with correlated own estimates against the grid posterior of the correlated prior
    times the ridge's likelihood; the correlation narrows the front less (the ridge pins only
    p_r − s p_f, and a shared error moves both), and the limits are refused."""
    cond = PreviewConditional(
        mean_kpa=171.0, sigma_kpa=float("nan"), informative=True, reason="", sigma_likelihood_kpa=2.0,
        ridge_slope=1.05, cov_front_rear_kpa2=float("nan"), floor_kpa=4.0, dlc=0.1, segments=30.0,
        bands_used=5,
    )  # fmt: skip
    rho, sf, sr = 0.6, 10.0, 12.0
    mean, cov = fuse_track(200.0, sf, 185.0, sr, cond, correlation=rho)
    pf, pr = np.meshgrid(np.arange(130.0, 270.0, 0.25), np.arange(110.0, 260.0, 0.25), indexing="ij")
    prior = np.array([[sf**2, rho * sf * sr], [rho * sf * sr, sr**2]])
    d0 = np.stack([pf - 200.0, pr - 185.0])
    log_w = -0.5 * np.einsum("iab,ij,jab->ab", d0, np.linalg.inv(prior), d0)
    log_w -= (pr - 171.0 - 1.05 * (pf - 200.0)) ** 2 / (2 * (2.0**2 + 4.0**2))
    w = np.exp(log_w - log_w.max())
    w /= w.sum()
    m = np.array([np.sum(w * pf), np.sum(w * pr)])
    d = np.stack([pf - m[0], pr - m[1]])
    np.testing.assert_allclose(mean, m, atol=1e-6)
    np.testing.assert_allclose(cov, np.einsum("iab,jab,ab->ij", d, d, w), atol=1e-4)
    _, independent = fuse_track(200.0, sf, 185.0, sr, cond)
    assert independent[0, 0] < cov[0, 0] < sf**2
    with pytest.raises(InputError, match="correlation"):
        fuse_track(200.0, sf, 185.0, sr, cond, correlation=1.0)


@pytest.mark.parametrize(
    ("make", "field"),
    [
        (lambda: PreviewConfig(segment_s=-1.0), "segment_s"),
        (lambda: PreviewConfig(band_hz=(40.0, 20.0)), "band_hz"),
        (lambda: PreviewConfig(pressure_range_kpa=(300.0, 100.0)), "pressure_range_kpa"),
        (lambda: PreviewConfig(rough_dlc=0.0), "rough_dlc"),
        (
            lambda: PreviewTrack(*_models(), suv_tire_stiffness(), suv_tire_stiffness(), -1e-3, WHEELBASE),
            "dt",
        ),
        (
            lambda: PreviewTrack(*_models(), suv_tire_stiffness(), suv_tire_stiffness(), DT, 0.0),
            "wheelbase_m",
        ),
        (lambda: PreviewTrack(*_models(), suv_tire_stiffness(), None, DT, WHEELBASE), "tire_rear"),
        (
            lambda: PreviewTrack(
                *_models(),
                suv_tire_stiffness(),
                suv_tire_stiffness(),
                3e-3,
                WHEELBASE,
                PreviewConfig(segment_s=1.0001),
            ),
            "segment_s",
        ),  # fmt: skip
    ],
)
def test_bad_settings_name_the_field(make, field):
    with pytest.raises(InputError, match=field):
        make()


def test_bad_calls_name_the_field():
    track = PreviewTrack(*_models(), suv_tire_stiffness(), suv_tire_stiffness(), DT, WHEELBASE, memories=2)
    x = np.zeros(100)
    with pytest.raises(InputError, match="acc_u_rear"):
        track.add(x, np.zeros(99), 20.0)
    with pytest.raises(InputError, match="speed_mps"):
        track.add(x, x, np.zeros(3))
    with pytest.raises(InputError, match="weight"):
        track.add(x, x, 20.0, weight=-1.0)
    with pytest.raises(InputError, match="weight"):
        track.add(x, x, 20.0, weight=[1.0, 1.0, 1.0])
    with pytest.raises(InputError, match="acc_s_front and acc_s_rear"):
        track.add(x, x, 20.0, acc_s_front=x)
    with pytest.raises(InputError, match="decay factor"):
        track.decay(1.5)
    with pytest.raises(InputError, match="p_front_kpa"):
        track.conditional(1000.0, 5.0)
    with pytest.raises(InputError, match="sigma_front_kpa"):
        track.conditional(200.0, -1.0)
    with pytest.raises(InputError, match="memory"):
        track.conditional(200.0, 1.0, memory=2)
