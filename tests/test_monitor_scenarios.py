"""The monitor bench's scenario sets (suvtwin.pipeline.monitor_scenarios): what each set must hold by
issue 12, seeds apart from the tests', and the simulation cache with a stand-in monitor."""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
import pytest

from suvtwin.errors import InputError
from suvtwin.pipeline.monitor_scenarios import SEED_BASE, SETS, monitor_traces, scenario_set, simulate_cached
from suvtwin.pipeline.monitor_scoring import errors_at, score_set
from suvtwin.roads.iso8608 import class_bounds, class_level

CORNERS = ("fl", "fr", "rl", "rr")


def _pressures(scenario) -> dict:
    p = scenario.pressure_kpa
    return {c: p for c in CORNERS} if isinstance(p, float) else dict(p)


def test_sets_are_deterministic_prefix_stable_and_seeded_apart_from_tests():
    for name in SETS:
        a, b = scenario_set(name, 6), scenario_set(name, 3)
        assert [r.scenario for r in a[:3]] == [r.scenario for r in b]
        assert all(r.scenario.seed >= SEED_BASE for r in a)
    seeds = [r.scenario.seed for name in SETS for r in scenario_set(name, 5)]
    assert len(set(seeds)) == len(seeds)


def test_constant_set_spans_its_ranges_with_levels_anywhere_in_the_band():
    runs = scenario_set("constant", 100)
    assert all(r.scenario.duration_s == 40.0 for r in runs)
    p = np.array([[_pressures(r.scenario)[c] for c in CORNERS] for r in runs])
    assert 130.0 <= p.min() < 140.0 and 220.0 < p.max() <= 230.0
    assert np.std(p[:, 0] - p[:, 1]) > 20.0  # drawn per tyre, not one value per car
    v = np.array([r.scenario.speed_kmh for r in runs])
    assert 40.0 <= v.min() < 50.0 and 110.0 < v.max() <= 120.0
    assert {r.info["road_class"] for r in runs} == set("ABCD")
    # Gaussian roads: the default random-phase ones have a spectrum that flatters the monitor
    assert all(r.scenario.road.method == "gaussian" for r in runs)
    assert all(r.scenario.road.method == "gaussian" for r in scenario_set("nominal_long", 4))
    offsets = []
    for r in runs:
        level = r.scenario.road.segments[0].gd_n0
        lower, upper = class_bounds(r.info["road_class"])
        assert lower <= level <= upper and level == r.info["gd_n0_m3"]
        offsets.append(np.log(level / class_level(r.info["road_class"])) / np.log(2.0))
    assert min(offsets) < -0.7 and max(offsets) > 0.7  # both ends of the ×/÷2 band are reached
    loads = np.array([r.info["load_kg"] for r in runs])
    assert loads.min() < 30.0 and 270.0 < loads.max() <= 300.0
    for r in runs:  # every load inside the car: between the bumpers, within the body's width
        for ld in r.scenario.load:
            x, y, z = ld.position_m
            assert -2.3 < x < 1.5 and abs(y) < 0.9 and -0.3 < z < 0.6
        assert r.scenario.road.length_m >= 10.0 + r.scenario.distance_m() + 15.0


def test_change_sets():
    for r in scenario_set("slow_leak", 8):
        (event,) = r.scenario.pressure_events
        p0 = _pressures(r.scenario)[event.tire]
        assert (event.start_s, event.end_s, r.scenario.duration_s) == (10.0, 40.0, 60.0)
        assert event.target_kpa == pytest.approx(0.8 * p0, abs=1e-3)
        assert r.info["change"] == {"tire": event.tire, "start_s": 10.0, "end_s": 40.0}
    tyres = set()
    for r in scenario_set("drop", 40):
        (event,) = r.scenario.pressure_events
        assert _pressures(r.scenario) == dict.fromkeys(CORNERS, 230.0)
        assert (event.start_s, event.end_s, event.target_kpa, r.scenario.duration_s) == (
            10.0,
            11.5,
            180.0,
            40.0,
        )
        tyres.add(event.tire)
    assert tyres == set(CORNERS)
    v = [r.scenario.speed_kmh for r in scenario_set("low_speed", 20)]
    assert 20.0 <= min(v) and max(v) <= 35.0


def test_warning_set_deflates_each_tyre_and_all_four_by_the_loss():
    runs = scenario_set("warning", 10, loss=0.25)
    assert [len(r.info["deflated"]) for r in runs] == [1, 1, 1, 1, 4] * 2
    assert {r.info["deflated"][0] for r in runs if len(r.info["deflated"]) == 1} == set(CORNERS)
    for r in runs:
        p = _pressures(r.scenario)
        for c in CORNERS:
            want = r.placard_kpa * (0.75 if c in r.info["deflated"] else 1.0)
            assert p[c] == pytest.approx(want, abs=1e-3)
        assert r.scenario.pressure_events == [] and r.scenario.duration_s == 60.0


def test_warning_multi_set_deflates_every_pair_and_every_three():
    runs = scenario_set("warning_multi", 10)
    low = [frozenset(r.info["deflated"]) for r in runs]
    pairs = {frozenset(p) for p in itertools.combinations(CORNERS, 2)}
    threes = {frozenset(p) for p in itertools.combinations(CORNERS, 3)}
    assert set(low) == pairs | threes and len(set(low)) == 10
    for r in runs:
        p = _pressures(r.scenario)
        for c in CORNERS:
            assert p[c] == pytest.approx(r.placard_kpa * (0.8 if c in r.info["deflated"] else 1.0), abs=1e-3)
    # its own seeds: no run repeats a `warning` run's road
    seeds = {r.scenario.seed for r in scenario_set("warning", 10)}
    assert not seeds & {r.scenario.seed for r in runs}


def test_a_set_from_a_later_first_run_holds_those_runs_and_stays_in_its_seeds():
    late = scenario_set("constant", 3, first=5000)
    assert [r.name for r in late] == ["constant_5000", "constant_5001", "constant_5002"]
    assert [r.scenario.seed for r in late] == [SEED_BASE + 5000 + i for i in range(3)]
    # the same runs as a longer set from 0 would hold (each run's draws are its own seed's)
    again = scenario_set("constant", 2, first=5001)
    assert again[0].scenario.model_dump() == late[1].scenario.model_dump()
    for bad in (-1, 9999):  # 9999 + 3 runs would take seeds of the next set
        with pytest.raises(InputError, match="first"):
            scenario_set("constant", 3, first=bad)


def test_nominal_long_has_speed_changes_several_classes_and_weaves():
    runs = scenario_set("nominal_long", 8, duration_s=300.0, weave_every=4, weave_duration_s=30.0)
    lane = [r for r in runs if not r.info.get("weave")]
    weave = [r for r in runs if r.info.get("weave")]
    assert len(weave) == 2 and all(r.scenario.steering.mode == "path" for r in weave)
    for r in weave:  # the path's swing and lateral acceleration as drawn: a_y = swing·ω², within the strip
        x, y = r.scenario.steering.reference_path()
        assert np.max(np.abs(y)) == pytest.approx(r.info["weave"]["swing_m"], rel=0.02)
        assert r.info["weave"]["swing_m"] <= 0.7 and 1.0 <= r.info["weave"]["lateral_accel_mps2"] <= 4.0
        assert x[-1] >= r.scenario.distance_m()
    for r in runs:
        assert set(_pressures(r.scenario).values()) == {r.placard_kpa}
    for r in lane:
        profile = np.array(r.scenario.speed_kmh)
        assert len(profile) >= 3 and 30.0 <= profile[:, 1].min() and profile[:, 1].max() <= 130.0
        assert r.scenario.steering.mode == "lane" and r.scenario.duration_s == 300.0
        assert r.scenario.road.length_m >= 10.0 + r.scenario.distance_m() + 15.0
    assert len({c for r in lane for c in r.info["road_class"]}) >= 3


def test_bad_requests_name_the_field():
    with pytest.raises(InputError, match="set"):
        scenario_set("nope", 1)
    with pytest.raises(InputError, match="n_runs"):
        scenario_set("constant", 0)


def _stand_in_monitor(path, *, placard_kpa=None, reset_at_s=None):
    """Truth plus N(0, 2 kPa) noise every 0.5 s, σ = 2 kPa: a harness check, not a monitor."""
    from types import SimpleNamespace

    run = pd.read_parquet(path)
    rng = np.random.default_rng(0)
    k = np.arange(0, len(run), 500)
    out = {"t_s": run.t_s.to_numpy()[k]}
    for c in CORNERS:
        out[f"{c}_pressure_hat_kpa"] = run[f"{c}_pressure_kpa"].to_numpy()[k] + rng.normal(0.0, 2.0, k.size)
        out[f"{c}_pressure_sigma_kpa"] = np.full(k.size, 2.0)
        out[f"{c}_observable"] = np.ones(k.size, bool)
        out[f"{c}_warning"] = np.zeros(k.size, bool)
    out["road_level_hat_m3"] = np.full(k.size, 1e-4)
    out["waviness_hat"] = np.full(k.size, 2.0)
    return SimpleNamespace(table=pd.DataFrame(out))


def test_cache_simulates_once_and_the_harness_scores_a_stand_in(tmp_path):
    runs = scenario_set("drop", 1, duration_s=12.0)
    paths, cost = simulate_cached(runs, tmp_path, jobs=1)
    assert cost["simulated"] == 1 and paths[0].is_file() and cost["realtime_factor"] > 0
    again, cost = simulate_cached(runs, tmp_path, jobs=1)
    assert again == paths and cost["simulated"] == 0 and cost["reused"] == 1
    traces, extras, cost = monitor_traces(runs, paths, monitor=_stand_in_monitor, jobs=1)
    assert extras[0]["updates"] == 24 and extras[0]["road_level_hat_m3_at_end"] == 1e-4
    # the truth the harness pairs with the estimate is the run's: the drop is seen in it
    tyre = runs[0].info["change"]["tire"]
    assert traces[0].truth_at_est[-1, ("fl", "fr", "rl", "rr").index(tyre)] == pytest.approx(180.0)
    assert abs(errors_at(traces, 10.0)["mean_kpa"]) < 4.0
    out = score_set("drop", traces, [r.info for r in runs])
    assert out["change"]["runs"] == 1 and out["coverage"]["inside"] > 0.8

    def broken(path, **_):
        raise ValueError("no estimate")

    traces, extras, cost = monitor_traces(runs, paths, monitor=broken, jobs=1)
    assert traces == [None] and cost["failed"] == {"drop_0000": "ValueError: no estimate"}


def test_a_diverged_run_is_recorded_and_not_retried(tmp_path, monkeypatch):
    from suvtwin.pipeline import simulator

    calls = []

    def diverge(scenario, **_):
        calls.append(scenario.seed)
        raise simulator.SimulationError("simulation diverged before t = 1.000 s (MuJoCo: bad qacc)")

    monkeypatch.setattr(simulator, "simulate", diverge)
    runs = scenario_set("low_speed", 1, duration_s=2.0)
    for _ in range(2):
        paths, cost = simulate_cached(runs, tmp_path, jobs=1)
        assert paths == [None] and list(cost["failed"]) == ["low_speed_0000"]
        assert "diverged" in cost["failed"]["low_speed_0000"] and cost["realtime_factor"] is None
    assert len(calls) == 1 and list(tmp_path.glob("*.parquet")) == []
