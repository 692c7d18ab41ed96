"""The force closure against a second implementation: two linear quarter cars simulated in the time
domain (scipy.signal.lsim), the rear driven by the front's road a delay later."""

import math

import numpy as np
import pytest
import scipy.signal

from suvtwin.errors import InputError
from suvtwin.estimators.force_closure import CornerParts, closure_objective, corner_signals, integrate
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
