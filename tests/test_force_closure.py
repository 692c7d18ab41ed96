"""The force closure against a second implementation: two linear quarter cars simulated in the time
domain (scipy.signal.lsim), the rear driven by the front's road a delay later."""

import math

import numpy as np
import pytest
import scipy.signal

from suvtwin.errors import InputError
from suvtwin.estimators.force_closure import (
    ClosureConfig,
    ClosureStream,
    CornerParts,
    closure_objective,
    closure_weights,
    corner_signals,
    integrate,
    objective_from_moments,
    objective_on_grid,
    windows_moments,
)
from suvtwin.suspension_law import SuspensionLaw

DT = 1e-3
G = 9.81


def _road(t: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A road under the wheel in time (m) and its rate (m/s): sinusoids at 0.3–40 Hz with amplitudes
    falling as 1/f (a displacement PSD ∝ f⁻², as an ISO road at constant speed), random phases."""
    f = np.linspace(0.3, 40.0, 400)
    amp = 2e-3 / f * math.sqrt(f[1] - f[0]) * rng.rayleigh(1.0, f.size)
    phase = rng.uniform(0.0, 2 * np.pi, f.size)
    arg = 2 * np.pi * f[None, :] * t[:, None] + phase
    return (np.sin(arg) @ amp), (np.cos(arg) @ (2 * np.pi * f * amp))


def _quarter_car(z_r, v_r, *, m_s, m_u, k_s, c_s, k_t, c_t):
    """Body and wheel accelerations (m/s²) of a linear quarter car driven by road height and rate."""
    # states: z_s, z_u, v_s, v_u; inputs: z_r, v_r
    a = np.array([[0, 0, 1, 0], [0, 0, 0, 1],
                  [-k_s / m_s, k_s / m_s, -c_s / m_s, c_s / m_s],
                  [k_s / m_u, -(k_s + k_t) / m_u, c_s / m_u, -(c_s + c_t) / m_u]])  # fmt: skip
    b = np.array([[0, 0], [0, 0], [0, 0], [k_t / m_u, c_t / m_u]])
    c, d = a[2:], b[2:]
    t = np.arange(z_r.size) * DT
    _, y, _ = scipy.signal.lsim((a, b, c, d), np.column_stack([z_r, v_r]), t)
    return y[:, 0], y[:, 1]


def _parts(m_s, m_u, k_s, c_s, **law) -> CornerParts:
    spring = SuspensionLaw(spring_rate=k_s, compression_low=c_s, compression_high=c_s, rebound_low=c_s,
                           rebound_high=c_s, **law)  # fmt: skip
    return CornerParts(unsprung_mass=m_u, law=spring, anti_roll=0.0, static_travel=0.0,
                       static_load=(m_s + m_u) * G)  # fmt: skip


@pytest.fixture(scope="module")
def track():
    rng = np.random.default_rng(12)
    n, delay = 24_000, 0.1413  # 24 s; 2.826 m at 20 m/s: a fractional number of samples
    t = np.arange(n) * DT
    zf, vf = _road(t, rng)
    # the same road a delay later under the rear: re-evaluate the sum at t - delay
    rng2 = np.random.default_rng(12)
    zr, vr = _road(t - delay, rng2)
    front = dict(m_s=470.0, m_u=61.0, k_s=32_000.0, c_s=2_500.0)
    rear = dict(m_s=430.0, m_u=53.0, k_s=38_000.0, c_s=2_600.0)
    acc_f = _quarter_car(zf, vf, k_t=235_000.0, c_t=200.0, **front)
    acc_r = _quarter_car(zr, vr, k_t=198_000.0, c_t=200.0, **rear)
    return dict(front=front, rear=rear, acc_f=acc_f, acc_r=acc_r, delay=delay, n=n)


def _fit(track, noise_sigma, rng, **law):
    zeros = np.zeros(track["n"])
    sigs = []
    for key in ("front", "rear"):
        body, wheel = track["acc_f" if key == "front" else "acc_r"]
        wheel = wheel + noise_sigma * rng.standard_normal(wheel.size)
        body = body + noise_sigma * rng.standard_normal(body.size)
        sigs.append(corner_signals(wheel, body, zeros, zeros, _parts(**track[key], **law), dt=DT))
    grid = np.linspace(150e3, 300e3, 301)  # 0.5 kN/m steps
    fit = closure_objective(sigs[0], sigs[1], delay_s=track["delay"], dt=DT, stiffness_grid=grid,
                            noise_sigma=max(noise_sigma, 1e-3))  # fmt: skip
    return fit, grid


def test_recovers_both_tyres_of_two_simulated_quarter_cars(track):
    # the road is in neither the estimator's input nor its model: only the two cars' accelerometers
    fit, grid = _fit(track, 0.05, np.random.default_rng(3))
    assert fit.windows_used == fit.windows > 8
    k_f, k_r = grid[fit.best[0]], grid[fit.best[1]]
    assert k_f == pytest.approx(235_000.0, rel=0.01)
    assert k_r == pytest.approx(198_000.0, rel=0.01)


def test_a_wrong_delay_or_swapped_wheels_do_not_close(track):
    fit, grid = _fit(track, 0.05, np.random.default_rng(3))
    zeros = np.zeros(track["n"])
    f = corner_signals(track["acc_f"][1], track["acc_f"][0], zeros, zeros, _parts(**track["front"]), dt=DT)
    r = corner_signals(track["acc_r"][1], track["acc_r"][0], zeros, zeros, _parts(**track["rear"]), dt=DT)
    late = closure_objective(f, r, delay_s=track["delay"] + 0.01, dt=DT, stiffness_grid=grid,
                             noise_sigma=0.05)  # fmt: skip
    # 10 ms off the wheelbase's delay: the road no longer matches, the residual is many times the noise
    assert late.objective.min() > 50 * fit.objective.min()


def test_the_dampers_timing_is_read_from_the_data(track):
    # the simulated dampers act without a lag: the closure's J is least at no lag (about the noise's
    # degrees of freedom), and grows with a lag of 1 ms, more with 2 ms
    zeros = np.zeros(track["n"])
    rng = np.random.default_rng(4)
    acc = {key: [a + 0.05 * rng.standard_normal(a.size) for a in track[f"acc_{key[0]}"]]
           for key in ("front", "rear")}  # fmt: skip
    grid = np.linspace(150e3, 300e3, 151)
    least = []
    for lag in (0.0, 1e-3, 2e-3):
        f, r = (corner_signals(acc[key][1], acc[key][0], zeros, zeros, _parts(**track[key]), dt=DT,
                               damper_lag_s=lag) for key in ("front", "rear"))  # fmt: skip
        least.append(closure_objective(f, r, delay_s=track["delay"], dt=DT, stiffness_grid=grid,
                                       noise_sigma=0.05).objective.min())  # fmt: skip
    assert least[0] < least[1] < least[2] and least[1] > 1.5 * least[0]


def test_windows_at_a_stop_are_left_out(track):
    # a bump-stop clearance the travel passes now and then: those windows are not used
    body, wheel = track["acc_r"]
    travel = integrate(wheel - body, DT, 2)
    clearance = float(np.quantile(travel, 0.9995))
    fit, grid = _fit(track, 0.05, np.random.default_rng(3), bump_clearance=clearance)
    assert 0 < fit.windows_used < fit.windows
    # the windows left still close on the true tyres
    assert grid[fit.best[1]] == pytest.approx(198_000.0, rel=0.02)


def test_integrate_is_the_inverse_of_differentiation_in_band():
    t = np.arange(20_000) * DT
    x = np.sin(2 * np.pi * 3.0 * t) + 0.5 * np.cos(2 * np.pi * 11.0 * t)
    acc = -(2 * np.pi * 3.0) ** 2 * np.sin(2 * np.pi * 3.0 * t) - 0.5 * (2 * np.pi * 11.0) ** 2 * np.cos(
        2 * np.pi * 11.0 * t)  # fmt: skip
    np.testing.assert_allclose(integrate(acc, DT, 2), x, atol=1e-6)


def test_bad_inputs_name_the_problem():
    parts = _parts(470.0, 61.0, 32_000.0, 2_500.0)
    a = np.zeros(100)
    with pytest.raises(InputError, match="finite"):
        corner_signals(np.full(100, np.nan), a, a, a, parts, dt=DT)
    with pytest.raises(InputError, match="one length"):
        corner_signals(a, a[:50], a, a, parts, dt=DT)
    s = corner_signals(a, a, a, a, parts, dt=DT)
    with pytest.raises(InputError, match="delay_s"):
        closure_objective(s, s, delay_s=0.0, dt=DT, stiffness_grid=[1e5, 2e5])
    with pytest.raises(InputError, match="stiffness_grid"):
        closure_objective(s, s, delay_s=0.1, dt=DT, stiffness_grid=[1e5])


def _noisy_signals(track, seed):
    """The front and rear corners' signals from the lsim cars' accelerations, 0.05 m/s² noise on the
    wheels'."""
    rng = np.random.default_rng(seed)
    zeros = np.zeros(track["n"])
    return tuple(corner_signals(w + 0.05 * rng.standard_normal(w.size), b, zeros, zeros, _parts(**track[key]),
                                dt=DT)
                 for key, (b, w) in (("front", track["acc_f"]), ("rear", track["acc_r"])))  # fmt: skip


def _direct_objective(f, r, grid, m, windows):
    """J on `grid` (both tyres) summed window by window from each window's residual: `windows` the
    (rear's first sample, delay s) pairs, `m` samples each, the delay's whole samples a shift and the
    rest a phase; the noise weights of :func:`closure_weights`."""
    freq = np.fft.rfftfreq(m, DT)
    band = (freq > 0.5) & (freq < 20.0)
    x_f, x_r, inv_var = closure_weights(f.parts, r.parts, grid, grid, m=m, dt=DT, noise_sigma=0.05)
    hann = np.hanning(m)
    direct = np.zeros((grid.size, grid.size))
    for at, delay in windows:
        back = int(round(delay / DT))
        phase = np.exp(-1j * 2 * np.pi * freq[band] * (delay - back * DT))
        rr, ff = slice(at, at + m), slice(at - back, at - back + m)
        dft = [np.fft.rfft((x - x @ hann / hann.sum()) * hann)[band]
               for x in (r.z_u[rr], r.force[rr], f.z_u[ff], f.force[ff])]  # fmt: skip
        for i in range(grid.size):
            for j in range(grid.size):
                res = dft[0] + x_r[j] * dft[1] - phase * (dft[2] + x_f[i] * dft[3])
                direct[i, j] += np.sum(np.abs(res) ** 2 * inv_var[i, j])
    return direct, (x_f, x_r, inv_var)


def test_the_moments_give_the_objective_of_the_windows_residuals(track):
    # J from the summed moments against J summed window by window from each window's residual
    f, r = _noisy_signals(track, 5)
    grid = np.array([180e3, 200e3, 235e3, 260e3])
    fit = closure_objective(f, r, delay_s=track["delay"], dt=DT, stiffness_grid=grid, noise_sigma=0.05)
    m, shift = 4000, int(round(track["delay"] / DT))
    direct, _ = _direct_objective(f, r, grid, m, [(at, track["delay"])
                                                  for at in range(shift, track["n"] - m + 1, m // 2)])
    np.testing.assert_allclose(fit.objective, direct, rtol=1e-9)


def test_windows_of_their_own_delays_give_the_objective_of_their_residuals(track):
    # the stream's form: windows of one pass, each its own delay (whole samples a shift, the rest a
    # phase), against J summed window by window from each window's residual at its delay
    f, r = _noisy_signals(track, 7)
    grid = np.array([180e3, 235e3, 260e3])
    m = 500
    delays = np.array([0.1413, 0.1389, 0.14462, 0.1413])
    rear_at = np.array([1000, 3000, 5250, 9000])
    shift = np.rint(delays / DT).astype(int)
    moments, used = windows_moments([f, f], [r, r], rear_at, rear_at - shift, delays - shift * DT, m, dt=DT)
    assert used.tolist() == [4, 4]
    direct, weights = _direct_objective(f, r, grid, m, list(zip(rear_at, delays, strict=True)))
    for k in range(2):
        np.testing.assert_allclose(objective_from_moments(moments[k], weights=weights), direct, rtol=1e-9)


def test_decimated_integrals_are_the_full_rate_ones_in_band():
    t = np.arange(12_345) * DT
    acc = np.sin(2 * np.pi * 2.0 * t) + 0.3 * np.sin(2 * np.pi * 17.0 * t + 1.0)
    full = integrate(acc, DT, (2, 1, 0), 0.3)
    every5 = integrate(acc, DT, (2, 1, 0), 0.3, step=5)
    for a, b in zip(full, every5, strict=True):
        assert b.size == -(-acc.size // 5)
        mid = slice(1000, -1000)
        np.testing.assert_allclose(b[mid.start // 5 : mid.stop // 5], a[::5][mid.start // 5 : mid.stop // 5],
                                   atol=2e-3 * np.abs(a).max())  # fmt: skip


def _stream_feed(track, chunks, noise=0.05, seed=3, nan_at=None, speed=None, config=None):
    """Two tracks of the lsim cars (the second the first's cars again) fed to a ClosureStream in
    chunks of the given sizes (repeated); the summed moments per track and the stream."""
    rng = np.random.default_rng(seed)
    bf, wf = (a + noise * rng.standard_normal(a.size) for a in track["acc_f"])
    br, wr = (a + noise * rng.standard_normal(a.size) for a in track["acc_r"])
    a_s = np.column_stack([bf, bf, br, br])
    a_u = np.column_stack([wf, wf, wr, wr])
    if nan_at is not None:
        a_u[nan_at, 0] = np.nan
    parts = [_parts(**track[key]) for key in ("front", "front", "rear", "rear")]
    wheelbase = 20.0 * track["delay"]
    stream = ClosureStream(parts, ((0, 2), (1, 3)), wheelbase, DT, config)
    v = np.full(track["n"], 20.0) if speed is None else speed
    total, windows, skipped, i, k = 0.0, 0, 0, 0, 0
    while i < track["n"]:
        n = chunks[k % len(chunks)]
        got = stream.add(v[i : i + n], a_s[i : i + n], a_u[i : i + n], np.ones(min(n, track["n"] - i), bool))
        total = total + got.moments
        windows, skipped = windows + got.windows, skipped + got.skipped
        i, k = i + n, k + 1
    return stream, total, windows, skipped


def test_the_stream_closes_both_tyres_whatever_its_chunks(track):
    grid = np.linspace(150e3, 300e3, 301)
    stream, total, windows, skipped = _stream_feed(track, [4000])
    lattice = ClosureConfig(spans="lattice", span_windows=4)
    _, fixed, fixed_windows, _ = _stream_feed(track, [4000], config=lattice)
    _, fixed2, fixed_windows2, _ = _stream_feed(track, [777, 2500, 13], config=lattice)
    # on the lattice, the same windows from the same spans whatever the chunks: the same moments
    np.testing.assert_array_equal(fixed_windows, fixed_windows2)
    np.testing.assert_allclose(fixed2, fixed, rtol=1e-9, atol=1e-12 * np.abs(fixed).max())
    # the windows ready at each call share a span (the default): the same windows whatever the chunks,
    # their moments from other spans (the integrals' drift near a span's tapered ends differs: J's floor
    # here 4.2e3 with 4 s chunks, 5.8e3 with the small ones), J's minimum at the same stiffnesses
    _, total2, windows2, _ = _stream_feed(track, [777, 2500, 13])
    np.testing.assert_array_equal(windows, windows2)
    assert np.all(fixed_windows <= windows) and np.all(fixed_windows >= windows - 4)  # the lattice waits
    w = stream.weights(0, 2, grid, grid, tyre_damping=200.0, noise_sigma=0.05)
    j1, j2 = objective_from_moments(total[0], weights=w), objective_from_moments(total2[0], weights=w)
    assert np.unravel_index(np.argmin(j2), j2.shape) == np.unravel_index(np.argmin(j1), j1.shape)
    assert j1.min() <= j2.min() < 1.5 * j1.min()
    # 24 s: windows every quarter second once the first has its margin and delay behind it
    assert windows[0] >= 80 and skipped[0] == 0
    j = j1
    best = np.unravel_index(np.argmin(j), j.shape)
    assert grid[best[0]] == pytest.approx(235_000.0, rel=0.015)
    assert grid[best[1]] == pytest.approx(198_000.0, rel=0.015)


def test_the_stream_restarts_after_a_bad_sample_and_skips_a_changing_speed(track):
    _, _, clean, _ = _stream_feed(track, [2000])
    _, _, after_gap, _ = _stream_feed(track, [2000], nan_at=12_000)
    # the windows holding the gap, and those whose margin or delay reach back over it, are lost
    assert 0 < after_gap[0] < clean[0] - 1
    speed = np.full(track["n"], 20.0)
    speed[10_000:] = 25.0  # a step: the windows across it span 22 % of their mean speed
    _, _, windows, skipped = _stream_feed(track, [2000], speed=speed)
    assert skipped[0] >= 2 and windows[0] + skipped[0] <= clean[0] + 1


def test_closure_config_names_the_bad_field():
    with pytest.raises(InputError, match="margin_s"):
        ClosureConfig(margin_s=-1.0)
    with pytest.raises(InputError, match="analysis_rate_hz"):
        ClosureConfig(analysis_rate_hz=30.0)
    with pytest.raises(InputError, match="two tracks"):
        ClosureStream([_parts(470.0, 61.0, 32_000.0, 2_500.0)] * 4, ((0, 2),), 2.8, DT)


def test_the_compiled_objective_is_the_objective(track):
    # J's compiled sums (the monitor's) against J summed in numpy from the moments
    stream, total, _, _ = _stream_feed(track, [4000])
    k_f, k_r = np.linspace(180e3, 280e3, 7), np.linspace(160e3, 240e3, 5)
    w = stream.weights(0, 2, k_f, k_r, tyre_damping=200.0, noise_sigma=0.05)
    direct = objective_from_moments(total[0], weights=w)
    fast = objective_on_grid(total[0], w)
    assert fast.shape == direct.shape == (7, 5)
    np.testing.assert_allclose(fast, direct, rtol=1e-10)


def test_a_track_whose_windows_mostly_reach_a_stop_is_read_in_short_windows(track):
    # the first track's rear reaches its bump stop 31 times in 24 s (its travel's 90 % quantile): most
    # 0.5 s spans have fewer than half their windows clear, and are read in 0.25 s windows instead,
    # which tile the same time (two in each window's hop) and still close on the true tyres; the other
    # track (the same cars, no stop) reads its 0.5 s windows as before, to the bit
    body, wheel = track["acc_r"]
    clearance = float(np.quantile(integrate(wheel - body, DT, 2), 0.9))
    rng = np.random.default_rng(3)
    bf, wf = (a + 0.05 * rng.standard_normal(a.size) for a in track["acc_f"])
    br, wr = (a + 0.05 * rng.standard_normal(a.size) for a in track["acc_r"])
    a_s, a_u = np.column_stack([bf, bf, br, br]), np.column_stack([wf, wf, wr, wr])
    parts = [_parts(**track["front"]), _parts(**track["front"]),
             _parts(**track["rear"], bump_clearance=clearance), _parts(**track["rear"])]  # fmt: skip
    grid = np.linspace(150e3, 300e3, 301)
    found = {}
    for name, config in (("default", None), ("none", ClosureConfig(short_window_s=None))):
        stream = ClosureStream(parts, ((0, 2), (1, 3)), 20.0 * track["delay"], DT, config)
        sums = None
        for i in range(0, track["n"], 4000):
            got = stream.add(np.full(4000, 20.0), a_s[i : i + 4000], a_u[i : i + 4000], np.ones(4000, bool))
            parts_of = [got.moments, got.windows, got.skipped, got.short_moments, got.short_windows,
                        got.short_skipped]
            sums = parts_of if sums is None else [a + b for a, b in zip(sums, parts_of, strict=True)]
        found[name] = (stream, sums)
    stream, (moments, windows, skipped, s_moments, s_windows, s_skipped) = found["default"]
    _, (moments_none, windows_none, skipped_none, _, none_short, _) = found["none"]
    assert not none_short.any()
    assert s_windows[0] > windows[0] and s_windows[1] == s_skipped[1] == 0
    # each span read one way: two short windows for each window's place
    assert 2 * (windows[0] + skipped[0]) + s_windows[0] + s_skipped[0] == 2 * (windows[1] + skipped[1])
    assert windows_none[0] + skipped_none[0] == windows[1] + skipped[1]
    np.testing.assert_array_equal(moments[1], moments_none[1])
    np.testing.assert_array_equal(windows[1], windows_none[1])
    w = stream.weights(0, 2, grid, grid, tyre_damping=200.0, noise_sigma=0.05, short=True)
    j = objective_from_moments(s_moments[0], weights=w)
    best = np.unravel_index(np.argmin(j), j.shape)
    assert grid[best[0]] == pytest.approx(235_000.0, rel=0.015)
    assert grid[best[1]] == pytest.approx(198_000.0, rel=0.015)


def test_short_windows_must_tile_the_windows_hop():
    parts = [_parts(470.0, 61.0, 32_000.0, 2_500.0)] * 4
    with pytest.raises(InputError, match="short_window_s"):
        ClosureStream(parts, ((0, 2), (1, 3)), 2.8, DT, ClosureConfig(short_window_s=0.2))
    with pytest.raises(InputError, match="short_window_s"):
        ClosureConfig(short_window_s=0.4)
    with pytest.raises(InputError, match="short_below"):
        ClosureConfig(short_below=1.5)
    stream = ClosureStream(parts, ((0, 2), (1, 3)), 2.8, DT, ClosureConfig(short_window_s=None))
    with pytest.raises(InputError, match="no short windows"):
        stream.weights(0, 2, [2e5], [2e5], tyre_damping=200.0, noise_sigma=0.05, short=True)
