"""Radius analysis (estimators/rolling_radius.py): the turn's kinematics against a rigid body's
velocities, the MuJoCo SUV's wheel speeds against MF-Tyre's effective rolling radius, streaming,
causality, changes, bad input."""

import math

import numpy as np
import pytest

from suvtwin.errors import InputError
from suvtwin.estimators.rolling_radius import RadiusConfig, RollingRadius, excess_of

# the SUV's wheel centres from the rear axle's centre (x forward, y left), m
L, TF, TR = 2.818, 1.606, 1.636
POS = np.array([[L, TF / 2], [L, -TF / 2], [0.0, TR / 2], [0.0, -TR / 2]])
R0 = 0.37


def _wheel_speeds(radii, v, yaw_rate):
    """Rigid car turning about a point on the rear axle's line: each wheel centre's speed
    |v_rear + ψ̇ × r_i| (a vector product, not the module's closed form) over its radius."""
    n = np.broadcast(v, yaw_rate).shape[0]
    vel = np.zeros((n, 4, 2))
    vel[..., 0] = v[:, None] - yaw_rate[:, None] * POS[None, :, 1]
    vel[..., 1] = yaw_rate[:, None] * POS[None, :, 0]
    return np.linalg.norm(vel, axis=-1) / radii


def test_excess_sums_to_zero_and_reads_one_wheel():
    d = np.array([0.0, 0.0, 0.0, -4e-3])
    e = excess_of(d)
    np.testing.assert_allclose(e, [4e-3 / 3, 4e-3 / 3, 4e-3 / 3, -4e-3])
    assert abs(e.sum()) < 1e-15


def test_turn_kinematics_leave_only_the_radii():
    # a steady 40 m circle at 15 m/s and a 120 m one the other way: without the kinematic terms the
    # outer wheels' excess would be ±10–30 ‰; the radii's differences must come out exactly
    n = 4000
    radii = R0 * np.array([1.0, 1.001, 0.997, 1.0])
    v = np.full(n, 15.0)
    yaw = np.r_[np.full(n // 2, 15.0 / 40.0), np.full(n // 2, -15.0 / 120.0)]
    w = _wheel_speeds(radii, v, yaw)
    ra = RollingRadius(POS, 0.01, R0, RadiusConfig(max_lat_accel_mps2=10.0, floor_permille=0.0))
    rows = ra.update(np.arange(n) * 0.01, w, yaw, np.zeros(n), np.zeros(n))
    # ρ takes v from the wheels' speeds times R0, off by the radii's spread (3 ‰ here): at 5.6 m/s²
    # (beyond any limit a sample counts at) that is 2e-5 of a 30 ‰ term
    np.testing.assert_allclose(rows.excess[-1], excess_of(np.log(radii)), atol=3e-5)
    naive = excess_of(-np.log(w[:10]).mean(axis=0))
    assert np.max(np.abs(naive - excess_of(np.log(radii)))) > 5e-3


def test_blocks_in_hard_cornering_or_braking_and_samples_in_gaps_do_not_count():
    n = 3000  # three 10 s blocks
    w = _wheel_speeds(np.full(4, R0), np.full(n, 20.0), np.zeros(n))
    ay, ax = np.zeros(n), np.zeros(n)
    ay[:600] = 3.0  # RMS 2.3 m/s² over the first block (limit 2)
    ay[1000:1200] = 3.0  # RMS 1.3 over the second
    ax[1000:2000] = 3.0 * (-1) ** np.arange(1000)  # a rough road's scatter about a steady speed
    ax[2000:] = 0.7  # braking through the third (limit 0.5)
    w[1500:1510, 2] = np.nan
    ra = RollingRadius(POS, 0.01, R0, RadiusConfig(block_s=10.0))
    rows = ra.update(np.arange(n) * 0.01, w, np.zeros(n), ay, ax)
    assert rows.used.tolist() == [False, True, False]
    assert np.all(np.isnan(rows.excess[0])) and np.all(np.isfinite(rows.excess[1]))


def test_chunking_does_not_change_the_result_and_the_state_is_bounded():
    rng = np.random.default_rng(5)
    n = 12_345
    radii = R0 * (1 + np.array([0.0, 1e-3, -2e-3, 0.5e-3]))
    yaw = 0.05 * np.sin(np.arange(n) * 0.002)
    w = _wheel_speeds(radii, np.full(n, 25.0), yaw) * (1 + 3e-3 * rng.standard_normal((n, 4)))
    t = np.arange(n) * 0.01
    cfg = RadiusConfig(memory_blocks=5)
    whole = RollingRadius(POS, 0.01, R0, cfg).update(t, w, yaw, np.zeros(n), np.zeros(n))
    ra = RollingRadius(POS, 0.01, R0, cfg)
    parts = [ra.update(t[i : i + 777], w[i : i + 777], yaw[i : i + 777], np.zeros(777)[: min(777, n - i)],
                       np.zeros(777)[: min(777, n - i)]) for i in range(0, n, 777)]  # fmt: skip
    for name in ("t_s", "excess", "sigma", "blocks", "used", "changes", "held", "trend"):
        np.testing.assert_array_equal(np.concatenate([getattr(p, name) for p in parts]), getattr(whole, name))
    # the memory's 5 blocks and at most one block's raw samples (400 × (4 wheel speeds + 5 others))
    assert whole.blocks.max() == 5 and ra.state_nbytes <= 400 * 9 * 8 + 1000
    # causal: a record cut at a block's end gives that block's row
    z = np.zeros(4000)
    cut = RollingRadius(POS, 0.01, R0, cfg).update(t[:4000], w[:4000], yaw[:4000], z, z)
    np.testing.assert_array_equal(cut.excess, whole.excess[: cut.t_s.size])
    # σ: the blocks' scatter over √n (noise 3e-3 per sample, 400 samples per block, 4 wheels' excess),
    # the floor, and the share of the samples' scatter taken as systematic
    sample_sd = 3e-3 * np.sqrt(1 + 1 / 3)
    e_sd = sample_sd / np.sqrt(400)
    floor = np.hypot(cfg.floor_permille * 1e-3, cfg.roughness_share * sample_sd)
    expected = np.sqrt(e_sd**2 / 5 + floor**2)
    assert 0.5 * expected < np.median(whole.sigma[-10:]) < 2.0 * expected
    np.testing.assert_allclose(whole.excess[-1], excess_of(np.log(radii)), atol=4 * expected)


def test_a_drop_starts_the_memory_afresh():
    n = 8000
    radii = np.tile(np.full(4, R0), (n, 1))
    radii[4000:, 3] *= 1 - 4e-3  # the rear right loses pressure: 4 ‰ of radius
    rng = np.random.default_rng(1)
    w = _wheel_speeds(radii, np.full(n, 25.0), np.zeros(n)) * (1 + 1e-3 * rng.standard_normal((n, 4)))
    rows = RollingRadius(POS, 0.01, R0).update(np.arange(n) * 0.01, w, np.zeros(n), np.zeros(n), np.zeros(n))
    k = np.searchsorted(rows.t_s, 40.0)  # the first block after the drop: held
    assert not rows.changes[: k + 1].any() and abs(rows.excess[k, 3]) < 0.3e-3
    assert rows.changes[k + 1, 3] and rows.blocks[k + 1, 3] == 2  # confirmed by the next
    assert abs(rows.excess[k + 1, 3] + 4e-3) < 0.3e-3  # follows within two blocks


def test_a_drop_within_a_block_restarts_every_wheel_and_the_excesses_stay_consistent():
    """The rear right loses 4 ‰ of radius 2 s into a 4 s block: that block reads half the drop and is
    no change; the next is held (its step shown in `held`), the one after confirms it, and from then
    on every wheel reads the new radii (the others +4/3 ‰: one wheel's drop over three), the four
    excesses summing to 0 (with the changed wheel alone restarted, the others' memories averaged
    across the drop)."""
    n = 8000
    radii = np.tile(np.full(4, R0), (n, 1))
    radii[4200:, 3] *= 1 - 4e-3
    rng = np.random.default_rng(4)
    w = _wheel_speeds(radii, np.full(n, 25.0), np.zeros(n)) * (1 + 1e-3 * rng.standard_normal((n, 4)))
    rows = RollingRadius(POS, 0.01, R0).update(np.arange(n) * 0.01, w, np.zeros(n), np.zeros(n), np.zeros(n))
    k = np.searchsorted(rows.t_s, 43.0)  # the block 40–44 s, the drop at 42 s inside it
    truth = excess_of(np.log([1.0, 1.0, 1.0, 1 - 4e-3]))
    assert not rows.changes[: k + 2].any()
    # the block after it is held: the change it would be shows, beside an unchanged estimate
    assert abs(rows.held[k + 1, 3] - (truth[3] - rows.excess[k + 1, 3])) < 0.5e-3
    assert rows.changes[k + 2, 3] and np.all(rows.blocks[k + 2] == 2) and np.all(rows.held[k + 2] == 0.0)
    after = rows.excess[k + 2 :]
    np.testing.assert_allclose(after, np.tile(truth, (len(after), 1)), atol=0.3e-3)
    np.testing.assert_allclose(after.sum(axis=1), 0.0, atol=1e-12)


def test_a_ramp_is_followed_by_its_line_not_the_memory_mean():
    """The rear right's radius falls 0.12 ‰/s from 40 s to 70 s (a slow leak); no block is far
    enough from the others to be a change. The memory's mean would trail the ramp by half its six
    blocks (1.4 ‰); the straight line through them reads it at the newest block. At steady radii
    the slope is rarely taken (3σ)."""
    n = 10000
    t = np.arange(n) * 0.01
    radii = np.tile(np.full(4, R0), (n, 1))
    radii[:, 3] *= 1 - 0.12e-3 * np.clip(t - 40.0, 0.0, 30.0)
    rng = np.random.default_rng(6)
    w = _wheel_speeds(radii, np.full(n, 25.0), np.zeros(n)) * (1 + 1e-3 * rng.standard_normal((n, 4)))
    z = np.zeros(n)
    rows = RollingRadius(POS, 0.01, R0).update(t, w, z, z, z)
    truth = excess_of(np.log(radii[np.round(rows.t_s / 0.01).astype(int)] / R0))
    ramp = (rows.t_s >= 60.0) & (rows.t_s <= 70.0)
    assert not rows.changes.any() and np.all(rows.trend[ramp, 3] < 0)
    # the line at the newest block (its centre 2 s back: 0.24 ‰ of ramp) against a mean 6 s back
    np.testing.assert_allclose(rows.excess[ramp, 3], truth[ramp, 3], atol=0.5e-3)
    off = RollingRadius(POS, 0.01, R0, RadiusConfig(trend_z=None)).update(t, w, z, z, z)
    assert np.all(off.excess[ramp, 3] - truth[ramp, 3] > 1.0e-3) and not off.trend.any()
    steady = rows.t_s < 40.0
    assert np.mean(rows.trend[steady] != 0.0) < 0.1


def test_a_ramp_that_ended_is_not_carried_on():
    """The same ramp, ending at 70 s: in the two blocks after it the straight line through the memory
    would carry it on (0.25–0.28 ‰ past the truth, a block's worth of ramp); the ramp that ended
    (flat since its last block) reads the radius within 0.15 ‰, and the slope reported is 0."""
    n = 9000
    t = np.arange(n) * 0.01
    radii = np.tile(np.full(4, R0), (n, 1))
    radii[:, 3] *= 1 - 0.12e-3 * np.clip(t - 40.0, 0.0, 30.0)
    z = np.zeros(n)
    for seed in range(5):
        rng = np.random.default_rng(60 + seed)
        w = _wheel_speeds(radii, np.full(n, 25.0), np.zeros(n)) * (1 + 1e-3 * rng.standard_normal((n, 4)))
        rows = RollingRadius(POS, 0.01, R0).update(t, w, z, z, z)
        truth = excess_of(np.log(radii[np.round(rows.t_s / 0.01).astype(int)] / R0))
        after = (rows.t_s > 72.0) & (rows.t_s < 82.0)
        assert after.sum() == 2
        np.testing.assert_allclose(rows.excess[after], truth[after], atol=0.15e-3)
        assert np.all(rows.trend[after] == 0.0)


def test_one_block_apart_is_an_outlier_not_a_change():
    n = 8000
    radii = np.tile(np.full(4, R0), (n, 1))
    radii[4000:4400, 1] *= 1 - 11e-3  # one block: a wheel spinning on a rough stretch
    rng = np.random.default_rng(2)
    w = _wheel_speeds(radii, np.full(n, 25.0), np.zeros(n)) * (1 + 1e-3 * rng.standard_normal((n, 4)))
    rows = RollingRadius(POS, 0.01, R0).update(np.arange(n) * 0.01, w, np.zeros(n), np.zeros(n), np.zeros(n))
    assert not rows.changes.any()
    assert np.all(np.abs(rows.excess[~np.isnan(rows.excess[:, 0])]) < 0.3e-3)


def test_bad_input_names_the_field():
    with pytest.raises(InputError, match="memory_blocks"):
        RadiusConfig(memory_blocks=0)
    with pytest.raises(InputError, match="positions_m"):
        RollingRadius(np.zeros((4, 3)), 0.01, R0)
    ra = RollingRadius(POS, 0.01, R0)
    with pytest.raises(InputError, match="wheel speeds"):
        ra.update(np.arange(3.0), np.ones((3, 3)), np.zeros(3), np.zeros(3), np.zeros(3))
    ra.update(np.arange(3.0), np.ones((3, 4)), np.zeros(3), np.zeros(3), np.zeros(3))
    with pytest.raises(InputError, match="continue"):
        ra.update(np.arange(3.0), np.ones((3, 4)), np.zeros(3), np.zeros(3), np.zeros(3))


def test_mujoco_wheel_speeds_read_mf_tyre_rolling_radius():
    """Four pressures 230/200/170/140 kPa on a class C road at 90 km/h: each wheel's excess from its
    speed against MF-Tyre 6.1's R_e (the .tir file's) at the pressure and the wheel's mean load."""
    from suvtwin.mjcf.tire import effective_rolling_radius, load_tire
    from suvtwin.mjcf.vehicle import load_vehicle
    from suvtwin.pipeline.scenario import parse_scenario
    from suvtwin.pipeline.simulator import simulate

    sc = parse_scenario(
        {"duration_s": 24.0, "seed": 71, "speed_kmh": 90.0,
         "road": {"segments": [{"length_m": 700.0, "gd_n0": 80e-6}]},
         "pressure_kpa": {"fl": 230.0, "fr": 200.0, "rl": 170.0, "rr": 140.0}},
        source="test",
    )  # fmt: skip
    frame = simulate(sc).table
    corners = ("fl", "fr", "rl", "rr")
    from suvtwin.pipeline.monitoring import wheel_positions

    pos = wheel_positions(load_vehicle())
    t = frame["t_s"].to_numpy()
    keep = t >= 4.0  # after the start's speed-up
    w = frame[[f"{c}_wheel_speed_radps" for c in corners]].to_numpy()[keep]
    ra = RollingRadius(pos, float(np.median(np.diff(t))), 0.37)
    rows = ra.update(t[keep], w, *(frame[k].to_numpy()[keep] for k in ("yaw_rate_radps", "lat_accel_mps2",
                                                                         "long_accel_mps2")))  # fmt: skip
    tp = load_tire().to_array()
    fz = [frame[f"{c}_tire_fz_n"].to_numpy()[keep].mean() for c in corners]
    p = [frame[f"{c}_pressure_kpa"].to_numpy()[-1] * 1e3 for c in corners]
    expected = excess_of(np.log([effective_rolling_radius(f, q, tp) for f, q in zip(fz, p, strict=True)]))
    assert rows.used.all()
    # the 140 kPa tyre runs about 10 ‰ smaller than the 230 kPa one: each excess within 0.5 ‰
    assert expected[0] - expected[3] > 8e-3
    np.testing.assert_allclose(rows.excess[-1], expected, atol=0.5e-3)
    assert np.all(np.abs(rows.excess[-1] - expected) < 4 * rows.sigma[-1])


def _rough_run(seed: int, speed_kmh: float, gd_n0: float, length_m: float) -> dict:
    """A 28 s MuJoCo run on one class D road with four pressures, from 4 s on: the time, the four
    wheels' columns (wheel speed, accelerations, true tyre force), the yaw rate and accelerations the
    radius analysis reads, each sample's tyre load share from the accelerometers
    (:func:`load_share`), the static loads, the step and MF-Tyre's excess at the mean true loads."""
    from suvtwin.estimators.rolling_radius import load_share
    from suvtwin.mjcf.tire import effective_rolling_radius, load_tire
    from suvtwin.mjcf.vehicle import load_vehicle
    from suvtwin.pipeline.estimation import corner_sprung_mass, corner_static_load
    from suvtwin.pipeline.monitoring import wheel_positions
    from suvtwin.pipeline.scenario import parse_scenario
    from suvtwin.pipeline.simulator import simulate

    corners = ("fl", "fr", "rl", "rr")
    sc = parse_scenario(
        {"duration_s": 28.0, "seed": seed, "speed_kmh": speed_kmh,
         "road": {"segments": [{"length_m": length_m, "gd_n0": gd_n0}]},
         "pressure_kpa": {"fl": 230.0, "fr": 200.0, "rl": 170.0, "rr": 140.0}},
        source="test",
    )  # fmt: skip
    frame = simulate(sc).table
    vehicle = load_vehicle()
    t = frame["t_s"].to_numpy()
    keep = t >= 4.0
    names = ("wheel_speed_radps", "accel_sprung_mps2", "accel_unsprung_mps2", "tire_fz_n")
    col = {k: frame[[f"{c}_{k}" for c in corners]].to_numpy()[keep] for k in names}
    static = np.array([corner_static_load(c, vehicle=vehicle) for c in corners])
    sprung = [corner_sprung_mass(c, vehicle=vehicle) for c in corners]
    a_s, a_u = col["accel_sprung_mps2"], col["accel_unsprung_mps2"]
    share = load_share(a_s, a_u, sprung, vehicle.unsprung_mass, static)
    tp = load_tire().to_array()
    p = frame[[f"{c}_pressure_kpa" for c in corners]].to_numpy()[-1] * 1e3
    fz = col["tire_fz_n"].mean(axis=0)
    radii = [effective_rolling_radius(f, q, tp) for f, q in zip(fz, p, strict=True)]
    kinematics = ("yaw_rate_radps", "lat_accel_mps2", "long_accel_mps2")
    return {
        "t": t[keep], "col": col, "share": share, "static": static, "dt": float(np.median(np.diff(t))),
        "others": [frame[k].to_numpy()[keep] for k in kinematics],
        "positions": wheel_positions(vehicle), "expected": excess_of(np.log(radii)),
    }  # fmt: skip


@pytest.mark.parametrize("seed", [72, 73])
def test_on_a_rough_road_samples_with_a_wheel_off_the_ground_are_left_out(seed):
    """Class D (1.5e-3 m³) at 100 km/h, four pressures: the wheels leave the ground 3–13 % of the
    time, and a wheel in the air does not roll on its radius. The tyre loads from the two
    accelerometers (the quarter car's equations summed) against the simulator's true tyre force, and
    the excess with the samples where a wheel carries under 30 % of its static load left out, against
    MF-Tyre's R_e at the mean loads: within 0.5 ‰ (all samples: beyond 0.8 ‰ for some wheel)."""
    run = _rough_run(seed, 100.0, 1.5e-3, 900.0)
    share, static, fz = run["share"], run["static"], run["col"]["tire_fz_n"]
    assert np.all(np.mean(fz <= 1.0, axis=0) > 0.02)  # every wheel leaves the ground at times
    resid = np.sqrt(np.mean((share * static - fz) ** 2, axis=0))
    assert np.all(resid < 0.65 * fz.std(axis=0))
    for i in range(4):  # a wheel in the air reads under 30 % of its load
        assert np.mean(share[fz[:, i] <= 1.0, i] < 0.3) > 0.9
    args = (run["t"], run["col"]["wheel_speed_radps"], *run["others"])
    gated = RollingRadius(run["positions"], run["dt"], R0).update(*args, load_share=share)
    every = RollingRadius(run["positions"], run["dt"], R0).update(*args)
    assert np.max(np.abs(gated.excess[-1] - run["expected"])) < 0.5e-3
    assert np.max(np.abs(every.excess[-1] - run["expected"])) > 0.8e-3
    assert gated.used.sum() >= every.used.sum()


@pytest.mark.parametrize("seed", [74, 75])
def test_blocks_the_load_gate_thins_to_a_third_are_used_and_stay_accurate(seed):
    """Class D (1.2e-3 m³) at 112 km/h: the load gate keeps only 40–60 % of each block's samples.
    Blocks with at least 35 % kept are used (at half, most of them were skipped and a drop of pressure
    there went unseen for 28 s), and the excess from them is within 0.4 ‰ of MF-Tyre's R_e at the mean
    loads, inside 2σ."""
    from suvtwin.estimators.rolling_radius import RadiusConfig

    run = _rough_run(seed, 112.0, 1.2e-3, 1000.0)
    n = int(round(RadiusConfig().block_s / run["dt"]))
    kept = np.all(run["share"] >= RadiusConfig().min_load_share, axis=1)
    kept_share = kept[: kept.size // n * n].reshape(-1, n).mean(axis=1)
    assert np.all(kept_share < 0.65) and np.mean(kept_share < 0.5) >= 1 / 3  # the gate thins every block
    rows = RollingRadius(run["positions"], run["dt"], R0).update(
        run["t"], run["col"]["wheel_speed_radps"], *run["others"], load_share=run["share"])  # fmt: skip
    assert rows.used.sum() >= 5  # of 6
    assert rows.used[kept_share < 0.5].sum() >= 1  # blocks under half kept are among them
    error = rows.excess[-1] - run["expected"]
    assert np.max(np.abs(error)) < 0.4e-3
    assert np.all(np.abs(error) < 2.0 * rows.sigma[-1])


def test_load_share_is_the_quarter_cars_tyre_force_over_its_static_load():
    from suvtwin.estimators.rolling_radius import load_share

    # m_s a_s + m_us a_us = k_t (z_r − z_us): 400 kg × −2 m/s² + 50 kg × 30 m/s² = +700 N on 5000 N
    np.testing.assert_allclose(load_share(np.array([[-2.0]]), np.array([[30.0]]), [400.0], [50.0], [5000.0]),
                               [[1.14]])  # fmt: skip
    ra = RollingRadius(POS, 0.01, R0)
    with pytest.raises(InputError, match="load_share"):
        ra.update(np.arange(3.0), np.ones((3, 4)), *np.zeros((3, 3)), load_share=np.ones((3, 3)))


# ------------------------------------------------------------------ fused into the warning
def _evidence(n_k, excess, sigma, gain=0.1e-3, placard=None):
    """Radius evidence at `n_k` rows; with `placard` (kPa), a tyre model linear in the pressure with
    slope `gain` per kPa, equal at the placard for all four."""
    from suvtwin.estimators.deflation import RadiusEvidence
    from suvtwin.estimators.radius_fusion import RadiusModel

    model = None
    if placard is not None:
        grid = np.arange(50.0, 452.0, 2.0)
        model = RadiusModel(pressure_kpa=grid, log_radius=np.tile(gain * (grid - placard), (4, 1)))
    return RadiusEvidence(excess=np.tile(excess, (n_k, 1)), sigma=np.tile(sigma, (n_k, 1)),
                          gain_per_kpa=np.full(4, gain), model=model)  # fmt: skip


def test_fusion_reads_one_tyre_from_the_radii_where_the_others_are_known():
    from suvtwin.estimators.deflation import DeflationRule, deflation_warnings

    # three tyres known at the placard (σ 0.5 kPa), the fourth unknown to the vibration (σ 80 kPa,
    # read at 230); its radius 4 ‰ smaller than the model's at the placard: 40 kPa low at 0.1 ‰/kPa
    n_k = 3
    gain = 0.1e-3
    d = np.array([0.0, 0.0, 0.0, -40.0 * gain])
    excess = d - (d.sum() - d) / 3
    p = np.full((n_k, 4), 230.0)
    sig = np.tile([0.5, 0.5, 0.5, 80.0], (n_k, 1))
    rule = DeflationRule(radius_spread_permille=0.0, common_alpha=None)
    ev = _evidence(n_k, excess, np.full(4, 0.05e-3), gain, placard=230.0)
    obs = np.ones((n_k, 4), bool)
    w = deflation_warnings(np.arange(n_k) * 4.0, p, sig, obs, placard_kpa=230.0, rule=rule, radius=ev)
    np.testing.assert_allclose(w.fused_kpa[-1], [230, 230, 230, 190], atol=0.5)
    # σ of the fourth: its excess's σ over the gain, the others' σ adding little
    assert 0.4 < w.fused_sigma_kpa[-1, 3] < 1.2
    assert w.warning[-1].tolist() == [False, False, False, True]


def test_fusion_is_blind_to_a_loss_all_four_share_and_honest_in_monte_carlo():
    from suvtwin.estimators.deflation import DeflationRule, deflation_warnings

    rng = np.random.default_rng(11)
    rule = DeflationRule(radius_spread_permille=1.0, common_alpha=None)
    gain, sig_v, sig_e = 0.1e-3, 10.0, 0.2e-3
    tracks = ((0, 2), (1, 3))
    rho = np.full((4, 4), rule.cross_correlation)
    for f, r in tracks:
        rho[f, r] = rho[r, f] = rule.track_correlation
    np.fill_diagonal(rho, 1.0)
    chol = np.linalg.cholesky(rho * sig_v**2)
    a = (1 + 1 / 3) * np.eye(4) - np.full((4, 4), 1 / 3)
    z = []
    for _ in range(400):
        truth = 230.0 + rng.uniform(-60, 20, 4)
        p_hat = truth + chol @ rng.standard_normal(4)
        spread = 1e-3 * rng.standard_normal(4)  # the tyres' own radii about the model's
        # the wheels' own noise, σ_e·√(3/4) each, gives each excess σ_e
        excess = a @ (gain * (truth - 230.0) + spread + sig_e * np.sqrt(0.75) * rng.standard_normal(4))
        ev = _evidence(1, excess, np.full(4, sig_e), gain, placard=230.0)
        w = deflation_warnings([0.0], p_hat[None], np.full((1, 4), sig_v), np.ones((1, 4), bool),
                               placard_kpa=230.0, rule=rule, tracks=tracks, radius=ev)  # fmt: skip
        z.append((w.fused_kpa[0] - truth) / w.fused_sigma_kpa[0])
    z = np.array(z)
    assert np.all(np.abs(z.mean(axis=0)) < 0.15) and np.all(np.abs(z.std(axis=0) - 1.0) < 0.1)
    # a loss shared by all four: the radii say nothing, the fused mean stays the vibration's
    ev = _evidence(1, np.zeros(4), np.full(4, sig_e), gain, placard=230.0)
    w = deflation_warnings([0.0], np.full((1, 4), 180.0), np.full((1, 4), sig_v), np.ones((1, 4), bool),
                           placard_kpa=230.0, rule=rule, tracks=tracks, radius=ev)  # fmt: skip
    np.testing.assert_allclose(w.fused_kpa[0], 180.0, atol=1e-6)
    common_sd = math.sqrt(rho.sum()) * sig_v / 4  # the mean of four correlated estimates
    assert np.all(w.fused_sigma_kpa[0] >= common_sd - 1e-6) and np.all(w.fused_sigma_kpa[0] < sig_v)


def test_the_radii_let_the_common_loss_take_a_tyre_whose_windows_were_refused():
    from suvtwin.estimators.deflation import DeflationRule, deflation_warnings

    rule = DeflationRule(detect_fraction=0.125)  # the numbers below take a 12.5 % loss

    # all four 20 % below a 230 kPa placard (184 kPa); three read at 184 with σ 12 kPa, the rear
    # right's windows refused (not observable, at its prior 230 ± 80). Alone each observable tyre has
    # P = Φ(17.25/12) = 0.925, and the vibration's common fit needs every tyre observable
    n_k = 4
    t = np.arange(1, n_k + 1) * 4.0
    p = np.tile([184.0, 184.0, 184.0, 230.0], (n_k, 1))
    sig = np.tile([12.0, 12.0, 12.0, 80.0], (n_k, 1))
    obs = np.tile([True, True, True, False], (n_k, 1))
    tracks = ((0, 2), (1, 3))
    alone = deflation_warnings(t, p, sig, obs, placard_kpa=230.0, tracks=tracks, rule=rule)
    assert np.isnan(alone.warning_time_s).all()
    # the radii read all four alike (a shared loss leaves every excess 0): the fused estimates with
    # their covariance. The model is linear with one gain for all, so a common r moves no excess and
    # the common fit's estimate is the generalized least squares mean of the four vibration
    # estimates, the refused one at its σ (Aitken 1935): computed here from the vibration alone
    ev = _evidence(n_k, np.zeros(4), np.full(4, 0.2e-3), 0.1e-3, placard=230.0)
    w = deflation_warnings(t, p, sig, obs, placard_kpa=230.0, tracks=tracks, radius=ev, rule=rule)
    rho = np.full((4, 4), 0.15)
    rho[0, 2] = rho[2, 0] = rho[1, 3] = rho[3, 1] = 0.75
    np.fill_diagonal(rho, 1.0)
    info = np.linalg.inv(rho * np.outer(sig[0], sig[0]) / 230.0**2)
    r_hat = info.sum(axis=0) @ (p[0] / 230.0) / info.sum()
    expected = 0.5 * math.erfc(-(0.875 - r_hat) * math.sqrt(info.sum()) / math.sqrt(2.0))
    np.testing.assert_allclose(w.common_probability, expected, rtol=1e-6)
    assert expected > 0.95
    # all four warned on the second update, the refused one too (through the car's common loss)
    assert np.all(w.warning_time_s == t[1]) and w.warning_common[3]
    # one tyre low, the radii saying so: no common loss is taken
    d = np.array([-46.0e-4, 0.0, 0.0, 0.0])
    ev = _evidence(n_k, d - (d.sum() - d) / 3, np.full(4, 0.2e-3), 0.1e-3, placard=230.0)
    one = np.tile([184.0, 230.0, 230.0, 230.0], (n_k, 1))
    w = deflation_warnings(t, one, sig, obs, placard_kpa=230.0, tracks=tracks, radius=ev, rule=rule)
    assert np.isnan(w.common_probability).all() and np.isnan(w.warning_time_s[1:]).all()


def test_the_radii_keep_a_one_sided_loss_from_the_car_s_common_loss():
    from suvtwin.estimators.deflation import DeflationRule, deflation_warnings

    rule = DeflationRule(detect_fraction=0.125)  # the numbers below take a 12.5 % loss

    # the left front and rear 20 % below a 230 kPa placard (184 kPa), the right at it; the vibration
    # reads every tyre low (178 / 196 kPa, σ 12 kPa), as a shared error of a track would. Its own
    # common fit (tracks correlated 0.75) passes its χ² and the common loss's probability, 0.951,
    # would warn the two inflated tyres
    n_k = 4
    t = np.arange(1, n_k + 1) * 4.0
    p = np.tile([178.0, 196.0, 178.0, 196.0], (n_k, 1))
    sig, obs, tracks = np.full((n_k, 4), 12.0), np.ones((n_k, 4), bool), ((0, 2), (1, 3))
    alone = deflation_warnings(t, p, sig, obs, placard_kpa=230.0, tracks=tracks, rule=rule)
    assert np.all(alone.common_probability > 0.95) and np.isfinite(alone.warning_time_s).all()
    # the radii see the two left tyres 46 kPa below the right ones (0.1 ‰/kPa, σ 0.2 ‰ per wheel):
    # against their contrasts one relative pressure fails, and only the left tyres are warned
    d = np.array([-46.0e-4, 0.0, -46.0e-4, 0.0])
    ev = _evidence(n_k, d - (d.sum() - d) / 3, np.full(4, 0.2e-3), 0.1e-3, placard=230.0)
    w = deflation_warnings(t, p, sig, obs, placard_kpa=230.0, tracks=tracks, radius=ev, rule=rule)
    assert np.isnan(w.common_probability).all()
    assert np.isfinite(w.warning_time_s[[0, 2]]).all() and np.isnan(w.warning_time_s[[1, 3]]).all()
    # all four alike, the radii saying so: the common loss stands, as the vibration's fit has it
    even = np.full((n_k, 4), 184.0)
    ev = _evidence(n_k, np.zeros(4), np.full(4, 0.2e-3), 0.1e-3, placard=230.0)
    w = deflation_warnings(t, even, sig, obs, placard_kpa=230.0, tracks=tracks, radius=ev, rule=rule)
    by_vibration = deflation_warnings(t, even, sig, obs, placard_kpa=230.0, tracks=tracks, rule=rule)
    np.testing.assert_allclose(w.common_probability, by_vibration.common_probability, rtol=1e-12)
    assert np.all(w.common_probability > 0.95)


def test_learned_references_calibrate_the_radii_and_a_later_loss_warns_through_them():
    from suvtwin.estimators.deflation import DeflationRule, deflation_warnings

    # references learned at 64 s (60 s observable, σ 7 kPa each, from the vibration alone); from
    # 120 s the rear right is 46 kPa (20 %) low: its radius shows it at once, the vibration only
    # 30 kPa of it, at σ 10 kPa
    t = np.arange(1, 51) * 4.0
    gain = 0.1e-3
    d = np.where(t[:, None] >= 120.0, [0.0, 0.0, 0.0, -46.0 * gain], 0.0) + 0.7e-3  # a tyre offset
    excess = d - (d.sum(axis=1, keepdims=True) - d) / 3
    from suvtwin.estimators.deflation import RadiusEvidence

    ev = RadiusEvidence(excess=excess, sigma=np.full((t.size, 4), 0.2e-3), gain_per_kpa=np.full(4, gain))
    p, sig, obs = np.full((t.size, 4), 230.0), np.full((t.size, 4), 7.0), np.ones((t.size, 4), bool)
    p[t >= 120, 3], sig[t >= 120, 3] = 200.0, 10.0
    rule = DeflationRule(common_alpha=None)
    w = deflation_warnings(t, p, sig, obs, rule=rule, radius=ev)
    assert np.isnan(w.fused_kpa[t < 64]).all() and np.isfinite(w.fused_kpa[t >= 64]).all()
    # the offset the radii had at the reset is calibrated away: nothing apart before 120 s
    np.testing.assert_allclose(w.fused_kpa[(t >= 64) & (t < 120)], 230.0, atol=1e-6)
    after = t >= 120
    # the radii put the rear right 46 ± 2.8 kPa below the others, the vibration 30 ± ~11: the radii
    # dominate; the four's level is the vibration's (mean 222.5 kPa, weighted by σ and correlation),
    # which the radii cannot see
    np.testing.assert_allclose(w.fused_kpa[after, 3] - w.fused_kpa[after, :3].mean(axis=1), -46.0, atol=3.0)
    np.testing.assert_allclose(w.fused_kpa[after].mean(axis=1), 222.5, atol=8.0)
    assert w.warning_time_s[3] <= 124.0 and np.isnan(w.warning_time_s[:3]).all()
    # without the radii the vibration's 200 ± 10 against 230 ± 7 warns nothing
    assert np.isnan(deflation_warnings(t, p, sig, obs, rule=rule).warning_time_s).all()


def test_the_radii_warn_one_tyre_against_the_others_before_any_reference_is_learned():
    from suvtwin.estimators.deflation import DeflationRule, RadiusEvidence, deflation_warnings

    # the vibration never sharp enough to learn a reference (σ 15 kPa); the radii calibrated 20 s
    # after the reset; from 100 s the front left 20 % low, in another run all four
    t = np.arange(1, 41) * 4.0
    gain = 0.1e-3
    p, sig, obs = np.full((t.size, 4), 230.0), np.full((t.size, 4), 15.0), np.ones((t.size, 4), bool)
    sd = np.full((t.size, 4), 0.2e-3)
    one = np.where(t[:, None] >= 100.0, [-46.0 * gain, 0.0, 0.0, 0.0], 0.0)
    four = np.where(t[:, None] >= 100.0, -46.0 * gain, 0.0) + np.zeros((1, 4))
    rule = DeflationRule(common_alpha=None)
    gains = np.full(4, gain)
    w = deflation_warnings(t, p, sig, obs, rule=rule, radius=RadiusEvidence(excess_of(one), sd, gains))
    rel = w.relative_probability
    assert np.isnan(rel[t < 20]).all() and np.isfinite(rel[t >= 20]).all()
    assert np.isnan(w.reference_kpa).all()  # never learned
    assert w.warning_time_s[0] == 104.0 and np.isnan(w.warning_time_s[1:]).all()
    assert w.warning_relative[0] and w.relative_probability[-1, 0] > 0.999
    # all four alike: the radii see nothing
    w = deflation_warnings(t, p, sig, obs, rule=rule, radius=RadiusEvidence(excess_of(four), sd, gains))
    assert np.isnan(w.warning_time_s).all() and np.nanmax(w.relative_probability) < 1e-6


def test_a_dead_wheel_speed_sensor_leaves_the_analysis_on_the_other_three_and_is_taken_back():
    # A wheel-speed sensor that reads nothing while the others turn used to stop the analysis (every
    # excess needed all four). Now the analysis goes on over the wheels read: checked against an
    # analysis built for those three wheels alone on the same stream (a turn, one tyre 3 ‰ small, a
    # pressure change half way), and the sensor is taken back once it reads again.
    n = 9000  # 90 s at 100 Hz: 22 blocks of 4 s
    radii = np.tile(R0 * np.array([1.0, 1.0, 0.997, 1.0]), (n, 1))
    radii[n // 2 :, 1] *= 0.996  # the front right's tyre loses pressure
    v = 20.0 + 2.0 * np.sin(np.arange(n) * 0.001)
    yaw = 0.03 * np.sin(np.arange(n) * 0.002)
    w = _wheel_speeds(radii, v, yaw) * (1.0 + 2e-4 * np.random.default_rng(4).standard_normal((n, 4)))
    t, zero = np.arange(n) * 0.01, np.zeros(n)
    cfg = RadiusConfig(max_lat_accel_mps2=10.0)
    for dead_value in (np.nan, 0.0):
        broken = w.copy()
        broken[: 6 * 1000, 3] = dead_value  # rear right silent for 60 s, then back
        ra = RollingRadius(POS, 0.01, R0, cfg)
        rows = ra.update(t, broken, yaw, zero, zero)
        three = RollingRadius(POS[:3], 0.01, R0, cfg).update(t[:6000], w[:6000, :3], yaw[:6000], zero[:6000],
                                                                 zero[:6000])  # fmt: skip
        # the rows while the sensor is silent: the three-wheel analysis's, bit for bit; the dead wheel NaN
        np.testing.assert_array_equal(rows.excess[:15, :3], three.excess)
        np.testing.assert_array_equal(rows.sigma[:15, :3], three.sigma)
        assert np.isnan(rows.excess[:15, 3]).all()
        # the front right's change seen over three wheels: its excess over the other two falls by its
        # radius's 4 ‰ (within a block's share: the change fell inside a block the memory holds)
        assert rows.excess[14, 1] - rows.excess[9, 1] == pytest.approx(-4e-3, abs=5e-4)
        # back from the block after it read again: all four, the memory started afresh
        assert ra.alive.all() and np.isfinite(rows.excess[-1]).all()
        np.testing.assert_allclose(rows.excess[-1], excess_of(np.log(radii[-1])), atol=3e-4)
        assert ra.silent_wheel_samples.tolist() == [0, 0, 0, 6000]


def test_a_stopped_car_s_wheels_rocking_about_zero_are_not_silent_sensors():
    # At rest the wheels rock about zero (the brakes' hold, the suspension settling): a wheel reading
    # -0.01 rad/s while another reads +0.01 is not a dead sensor. Only a wheel that reads nothing
    # while another turns at TURNING_MPS or faster counts, and takes the analysis down to three wheels.
    n = 6000  # 60 s at 100 Hz: stopped for 30 s, then 20 m/s with the rear right's sensor dead
    rocking = 0.01 * np.random.default_rng(7).standard_normal((n // 2, 4))
    moving = _wheel_speeds(np.tile(R0 * np.ones(4), (n // 2, 1)), np.full(n // 2, 20.0), np.zeros(n // 2))
    moving[:, 3] = np.nan
    t, zero = np.arange(n) * 0.01, np.zeros(n)
    ra = RollingRadius(POS, 0.01, R0)
    ra.update(t[: n // 2], rocking, zero[: n // 2], zero[: n // 2], zero[: n // 2])
    assert ra.silent_wheel_samples.tolist() == [0, 0, 0, 0] and ra.alive.all()
    ra.update(t[n // 2 :], moving, zero[n // 2 :], zero[n // 2 :], zero[n // 2 :])
    assert ra.silent_wheel_samples.tolist() == [0, 0, 0, n // 2]
    assert ra.alive.tolist() == [True, True, True, False]


def test_a_fused_estimate_too_wide_to_be_observable_does_not_confirm_a_warning():
    from suvtwin.estimators.deflation import DeflationRule, deflation_warnings

    # the first update (half a window) reads every tyre 100 kPa below a 230 kPa placard at σ 40 kPa,
    # the next (the whole window, which holds the first one's data) 70 kPa below at σ 15, then the
    # data put them back at 230: the radii see the four alike (a shared error, not a loss). Fused,
    # the first update's σ is the four's common mode, above the monitor's 25 kPa observability
    # limit: it must not count as one of the two updates that confirm a warning
    t = np.array([4.0, 8.0, 12.0])
    p = np.array([[130.0] * 4, [160.0] * 4, [230.0] * 4])
    sig = np.array([[40.0] * 4, [15.0] * 4, [10.0] * 4])
    obs = sig <= 25.0
    tracks = ((0, 2), (1, 3))
    ev = _evidence(3, np.zeros(4), np.full(4, 0.2e-3), 0.1e-3, placard=230.0)
    w = deflation_warnings(t, p, sig, obs, placard_kpa=230.0, tracks=tracks, radius=ev)
    assert np.all(w.fused_sigma_kpa[0] > 25.0) and np.all(w.probability[:2] >= 0.95)
    assert np.isnan(w.warning_time_s).all()
    # counted at any σ (the limit set beyond it), the first two updates warn every tyre at 8 s
    loose = deflation_warnings(t, p, sig, obs, placard_kpa=230.0, tracks=tracks, radius=ev,
                               rule=DeflationRule(informed_sigma_kpa=1e3))  # fmt: skip
    assert np.all(loose.warning_time_s == 8.0)


def test_coherent_tracks_raise_the_cross_track_correlation_of_the_fusion():
    from dataclasses import replace

    from suvtwin.estimators.deflation import DeflationRule, deflation_warnings

    # the monitor's rows with the tracks' coherence γ: tyres on different tracks then correlate by
    # track_correlation·γ² (above cross_correlation), the same as a rule with that cross correlation
    rng = np.random.default_rng(4)
    n_k, tracks = 5, ((0, 2), (1, 3))
    t = np.arange(1, n_k + 1) * 4.0
    p = 200.0 + rng.normal(0.0, 10.0, (n_k, 4))
    sig = np.full((n_k, 4), 12.0)
    obs = np.ones((n_k, 4), bool)
    d = np.array([-20.0e-4, 0.0, 0.0, 0.0])
    ev = _evidence(n_k, d - (d.sum() - d) / 3, np.full(4, 0.2e-3), 0.1e-3, placard=230.0)
    rule = DeflationRule()
    gamma = 0.9
    coherent = deflation_warnings(t, p, sig, obs, placard_kpa=230.0, tracks=tracks, radius=ev, rule=rule,
                                  track_coherence=np.full(n_k, gamma))  # fmt: skip
    alike = replace(rule, cross_correlation=rule.track_correlation * gamma**2)
    told = deflation_warnings(t, p, sig, obs, placard_kpa=230.0, tracks=tracks, radius=ev, rule=alike)
    np.testing.assert_allclose(coherent.fused_sigma_kpa, told.fused_sigma_kpa, rtol=1e-12)
    np.testing.assert_allclose(coherent.fused_kpa, told.fused_kpa, rtol=1e-12)
    # the shared level is less known when the tracks are alike: the fused σ grows
    plain = deflation_warnings(t, p, sig, obs, placard_kpa=230.0, tracks=tracks, radius=ev, rule=rule)
    assert np.all(coherent.fused_sigma_kpa > plain.fused_sigma_kpa)
    # a coherence too small to raise it, or none read (NaN), changes nothing
    weak = deflation_warnings(t, p, sig, obs, placard_kpa=230.0, tracks=tracks, radius=ev, rule=rule,
                              track_coherence=np.r_[np.full(n_k - 1, 0.2), np.nan])  # fmt: skip
    np.testing.assert_array_equal(weak.fused_sigma_kpa, plain.fused_sigma_kpa)
    with pytest.raises(InputError, match="track_coherence must have shape"):
        deflation_warnings(t, p, sig, obs, placard_kpa=230.0, track_coherence=np.zeros(2))
