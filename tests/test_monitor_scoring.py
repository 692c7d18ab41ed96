"""Scores of the tyre-pressure monitor bench (suvtwin.pipeline.monitor_scoring) on hand-made
arrays whose answers are worked out by hand in each test."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from suvtwin.errors import InputError
from suvtwin.pipeline.monitor_scoring import (
    MonitorTrace,
    change_tracking,
    coverage,
    driving_time,
    errors_at,
    false_warnings,
    issue_targets,
    low_speed_shares,
    monitor_trace,
    score_set,
    settle_time,
    truth_at,
    vibration_view,
    warning_detection,
    warning_times,
)


def _trace(t_s, truth, t_est, p_hat, sigma=1.0, observable=True, warning=False, speed=20.0):
    t_s = np.asarray(t_s, float)
    t_est = np.asarray(t_est, float)
    truth = np.broadcast_to(np.asarray(truth, float), (len(t_s), 4)).copy()  # a scalar or (T, 4)
    K = len(t_est)
    return MonitorTrace(
        t_s=t_s,
        truth_kpa=truth,
        speed_mps=np.broadcast_to(np.asarray(speed, float), t_s.shape).copy(),
        t_est=t_est,
        p_hat=np.broadcast_to(np.asarray(p_hat, float), (K, 4)).copy(),
        sigma=np.broadcast_to(np.asarray(sigma, float), (K, 4)).copy(),
        observable=np.broadcast_to(np.asarray(observable, bool), (K, 4)).copy(),
        warning=np.broadcast_to(np.asarray(warning, bool), (K, 4)).copy(),
    )


def test_truth_is_taken_at_the_last_sample_not_after_the_update():
    t_s = np.array([0.0, 1.0, 2.0, 3.0])
    truth = np.array([10.0, 11.0, 12.0, 13.0])
    assert truth_at(t_s, truth, np.array([0.5, 2.0, 2.9, -1.0, 9.0])).tolist() == [10, 12, 12, 10, 13]


def test_error_at_a_time_uses_the_last_update_before_it():
    t_s = np.arange(0.0, 12.0, 0.5)
    t_est = np.array([9.0, 10.0, 10.5])
    # run A: errors +1, -1, +3, -3 at 10 s; run B: +5 on every tyre; both have 99 at 10.5 s
    a = _trace(t_s, 200.0, t_est, np.array([[0, 0, 0, 0], [201, 199, 203, 197], [299] * 4]))
    b = _trace(t_s, 150.0, t_est, np.array([[0, 0, 0, 0], [155] * 4, [249] * 4]), observable=False)
    out = errors_at([a, b], 10.0)
    # mean (1 - 1 + 3 - 3 + 4·5)/8 = 2.5; mean square (1+1+9+9+100)/8 = 15, var 15 - 6.25 = 8.75
    assert out["mean_kpa"] == pytest.approx(2.5)
    assert out["std_kpa"] == pytest.approx(math.sqrt(8.75))
    assert out["max_abs_kpa"] == pytest.approx(5.0)
    assert (out["n"], out["n_missing"], out["unobservable"]) == (8, 0, 0.5)
    # one tyre: fl errors +1 (run A) and +5 (run B)
    assert errors_at([a, b], 10.0, tyre="fl")["mean_kpa"] == pytest.approx(3.0)
    assert errors_at([a, b], 10.0, tyre="rr")["std_kpa"] == pytest.approx(4.0)  # -3 and +5
    with pytest.raises(InputError, match="tyre"):
        errors_at([a], 10.0, tyre="front")
    # runs that end before the time, or have no update yet, count as missing
    assert errors_at([a], 30.0) == {"n": 0, "n_missing": 4}
    assert errors_at([a], 5.0)["n_missing"] == 4


def test_coverage_counts_nan_as_outside_and_skips_the_start():
    t_s = np.arange(0.0, 10.0, 0.1)
    t_est = np.array([1.0, 3.0, 4.0, 5.0, 6.0])
    # errors 50 (before 2 s, skipped), 0.5, 1.5, 2.5, NaN with σ = 1
    p_hat = 100.0 + np.array([50.0, 0.5, 1.5, 2.5, np.nan])[:, None]
    out = coverage([_trace(t_s, 100.0, t_est, p_hat)], k=2.0, after_s=2.0)
    assert out["inside"] == pytest.approx(0.5) and out["n"] == 16
    assert coverage([_trace(t_s, 100.0, t_est, p_hat)], k=3.0)["inside"] == pytest.approx(0.75)


def test_settle_time():
    t = np.arange(0.0, 21.0)
    err = np.where(t <= 8, 20.0, 5.0)
    err[9] = 13.0  # last sample outside 12.5 kPa is at 9 s: within from 10 s, 5 s after the end at 5 s
    assert settle_time(t, err, 5.0) == pytest.approx(5.0)
    assert settle_time(t, np.full(t.size, 1.0), 5.0) == 0.0
    err[-1] = 30.0
    assert settle_time(t, err, 5.0) == math.inf
    assert settle_time(t, np.full(t.size, 1.0), 25.0) == math.inf


def test_change_tracking_of_a_lagging_estimate():
    # fr ramps 230 -> 180 kPa between 10 and 11.5 s; the estimate follows 6 s late with σ = 10
    t_s = np.arange(0.0, 40.0, 0.01)
    ramp = lambda t: 230.0 - 50.0 * np.clip((t - 10.0) / 1.5, 0.0, 1.0)  # noqa: E731
    truth = np.full((t_s.size, 4), 230.0)
    truth[:, 1] = ramp(t_s)
    t_est = np.arange(0.0, 40.0, 0.5)
    p_hat = np.full((t_est.size, 4), 230.0)
    p_hat[:, 1] = ramp(t_est - 6.0)
    trace = MonitorTrace(t_s, truth, np.full(t_s.size, 20.0), t_est, p_hat, np.full((t_est.size, 4), 10.0),
                         np.ones((t_est.size, 4), bool), np.zeros((t_est.size, 4), bool))  # fmt: skip
    out = change_tracking([trace], [{"tire": "fr", "start_s": 10.0, "end_s": 11.5}])
    # estimate within 12.5 kPa once ramp(t - 6) <= 192.5, i.e. t - 6 >= 10 + 1.5·37.5/50 = 11.125 s,
    # so from the update at 17.5 s: 6 s after the end of the change
    assert out["settle_s_median"] == pytest.approx(6.0)
    assert out["share_settled_within"] == 1.0 and out["never_settled"] == 0
    # error ramp(t - 6) - ramp(t): 33.3·(t - 10) up to 11.5 s, 50 until 16 s, then 50 - 33.3·(t - 16):
    # outside ±20 kPa for t in (10.6, 16.9) s, the updates 11.0 ... 16.5 = 12 of the 60 from 10 s
    assert out["inside_2sigma_during_and_after"] == pytest.approx(48 / 60)
    assert out["inside_2sigma_other_tyres"] == 1.0
    assert out["not_settled"] == [] and out["not_settled_sigma_above_tol"] == 0
    # asked to settle within 5 s, the run is listed with the updates scored: from the last update at
    # or before 11.5 + 5 = 16.5 s, where the estimate is ramp(10.5) = 230 - 50/3 against 180 kPa
    for sigma, above in ((10.0, False), (20.0, True)):
        tr = replace(trace, sigma=np.full((t_est.size, 4), sigma))
        out = change_tracking([tr], [{"tire": "fr", "start_s": 10.0, "end_s": 11.5}], within_s=5.0,
                              names=["drop_7"], infos=[{"road_class": "D", "speed_kmh": 104.0}])  # fmt: skip
        (miss,) = out["not_settled"]
        assert (miss["run"], miss["road_class"], miss["tyre"]) == ("drop_7", "D", "fr")
        assert miss["speed_kmh"] == 104.0
        assert miss["settle_s"] == pytest.approx(6.0)
        assert miss["updates"][0] == [16.5, pytest.approx(50.0 - 50.0 / 3.0, abs=0.01), sigma]
        assert [u[0] for u in miss["updates"]] == list(t_est[t_est >= 16.5])
        assert miss["sigma_above_tol"] is above and out["not_settled_sigma_above_tol"] == int(above)
    # never settled: the estimate stays at 230 kPa; named by its index without names
    tr = replace(trace, p_hat=np.full((t_est.size, 4), 230.0))
    (miss,) = change_tracking([tr], [{"tire": "fr", "start_s": 10.0, "end_s": 11.5}])["not_settled"]
    assert miss["run"] == 0 and miss["settle_s"] is None and miss["road_class"] is None
    assert miss["updates"][0][0] == 26.5 and miss["updates"][-1] == [39.5, 50.0, 10.0]


def test_low_speed_shares():
    t_s = np.arange(0.0, 10.0, 0.1)
    t_est = np.array([3.0, 4.0])
    # per tyre: accurate (err 5, σ 10), flagged wide (err -100, σ 60), wrong and outside 3σ
    # (err 40, σ 5), observable but inside 3σ and outside tolerance (err 20, σ 10)
    err = np.array([5.0, -100.0, 40.0, 20.0])
    trace = _trace(t_s, 200.0, t_est, 200.0 + err, sigma=np.array([10.0, 60.0, 5.0, 10.0]),
                   observable=np.array([True, False, True, True]))  # fmt: skip
    out = low_speed_shares([trace])
    assert (out["accurate"], out["flagged"], out["wrong"]) == (0.25, 0.25, 0.5)
    assert out["outside_3sigma"] == 0.25 and out["outside_3sigma_observable"] == pytest.approx(1 / 3)


def test_warning_times_and_driving_time():
    t_est = np.array([0.0, 1.0, 2.0, 3.0])
    w = np.zeros((4, 4), bool)
    w[2:, 0] = True
    w[3, 3] = True
    assert np.array_equal(warning_times(t_est, w), [2.0, np.nan, np.nan, 3.0], equal_nan=True)
    t = np.arange(0.0, 100.0, 0.5)
    speed = np.where(t < 40.0, 0.0, 20.0)  # standing for 40 s
    assert driving_time(t, speed, 70.0) == pytest.approx(30.0)


def test_warning_detection_within_a_window_of_driving():
    t_s = np.arange(0.0, 60.0, 0.1)
    t_est = np.arange(0.0, 60.0, 1.0)
    warned_fl_at_30 = np.zeros((t_est.size, 4), bool)
    warned_fl_at_30[30:, 0] = True
    all_but_rr = np.zeros((t_est.size, 4), bool)
    all_but_rr[10:, :3] = True
    runs = [_trace(t_s, 180.0, t_est, 180.0, warning=warned_fl_at_30),
            _trace(t_s, 180.0, t_est, 180.0, warning=all_but_rr),
            _trace(t_s, 180.0, t_est, 180.0, warning=warned_fl_at_30)]  # fmt: skip
    out = warning_detection(runs, [["fl"], ["fl", "fr", "rl", "rr"], ["fr"]], window_s=60.0)
    assert out["detected"] == pytest.approx(1 / 3)
    assert out["one_tyre"] == {"runs": 2, "detected": 0.5}
    assert out["all_four"] == {"runs": 1, "detected": 0.0}
    assert out["time_to_warn_s_median"] == pytest.approx(30.0)
    assert out["warnings_on_inflated_tyres"] == 1  # run 3 warns fl, deflated is fr
    assert warning_detection(runs[:1], [["fl"]], window_s=20.0)["detected"] == 0.0
    # one telltale (FMVSS 138): the all-four run lights it with three tyres; run 3's lamp is a wrong tyre's
    assert out["telltale"]["all_four"] == {"runs": 1, "detected": 1.0}
    assert out["telltale"]["one_tyre"] == {"runs": 2, "detected": 0.5}
    early = warning_detection(runs[1:2], [["fl", "fr", "rl", "rr"]], window_s=5.0)
    assert early["telltale"]["detected"] == 0.0
    assert "two_tyres" not in out and "three_tyres" not in out
    # two and three tyres low: their own kinds; run 2 warns fl, fr, rl at 1 s, not rr
    some = warning_detection(runs[1:2] * 3, [["fl", "fr"], ["fl", "rr"], ["fl", "fr", "rl"]], window_s=60.0)
    assert some["two_tyres"] == {"runs": 2, "detected": 0.5}
    assert some["three_tyres"] == {"runs": 1, "detected": 1.0}
    assert some["one_tyre"] == {"runs": 0, "detected": None}
    assert some["telltale"]["two_tyres"] == {"runs": 2, "detected": 1.0}
    assert some["warnings_on_inflated_tyres"] == 1 + 2 + 0  # rl in run 1; fr and rl in run 2


def test_warning_detection_after_a_loss_counts_driving_from_its_end_and_early_warnings_as_false():
    t_s = np.arange(0.0, 300.0, 0.1)
    t_est = np.arange(0.0, 300.0, 4.0)
    speed = np.where(t_s < 220.0, 20.0, 0.0)  # parked from 220 s: no driving counted there
    def warned(at):
        w = np.zeros((t_est.size, 4), bool)
        w[t_est >= at, 0] = True
        return w
    runs = [_trace(t_s, 180.0, t_est, 180.0, warning=warned(a), speed=speed)
            for a in (192.0, 172.0, 100.0, 240.0)]  # fmt: skip
    # the loss from 150 s to 180 s; warned 12 s after its end, during it, before it, 40 s on (parked)
    out = warning_detection(runs, [["fl"]] * 4, window_s=10.0, from_s=[180.0] * 4, loss_start_s=[150.0] * 4)
    assert out["detected"] == 0.25  # only the warning during the leak (0 s after its end)
    assert out["warnings_before_loss"] == 1 and out["warnings_on_inflated_tyres"] == 0
    out = warning_detection(runs, [["fl"]] * 4, window_s=40.0, from_s=[180.0] * 4, loss_start_s=[150.0] * 4)
    assert out["detected"] == 0.75  # 12 s and, parked after 220 s, 40 s of driving at 240 s
    assert out["time_to_warn_s_median"] == pytest.approx(12.0)


def test_warning_detection_explains_each_miss():
    """Each missed run names its cause from what its unwarned low tyres showed within the window of
    driving only (a probability reached after 60 s of driving does not count)."""
    t_s = np.arange(0.0, 80.0, 0.1)
    t_est = np.arange(0.0, 80.0, 4.0)
    K = t_est.size

    def prob(peak_at=None, peak=0.97, late=None):
        p = np.full((K, 4), 0.2)
        if peak_at is not None:
            p[peak_at, 0] = peak
        if late is not None:
            p[t_est > 60.0, 0] = late
        return p

    warned = np.zeros((K, 4), bool)
    warned[5:, 0] = True
    unobservable = np.ones((K, 4), bool)
    unobservable[:, 0] = False
    runs = [
        _trace(t_s, 180.0, t_est, 185.0, warning=warned),  # detected
        _trace(t_s, 180.0, t_est, 240.0, sigma=80.0, observable=unobservable),
        _trace(t_s, 180.0, t_est, 190.0, sigma=9.0),
        _trace(t_s, 180.0, t_est, 196.0, sigma=12.0),
    ]
    probabilities = [prob(), prob(), prob(peak_at=7), prob(late=0.99)]
    runs = [replace(r, loss_probability=p) for r, p in zip(runs, probabilities, strict=True)]
    out = warning_detection(runs, [["fl"]] * 4, window_s=60.0, names=["a", "b", "c", "d"],
                            classes=["A", "D", "B", "B"])  # fmt: skip
    assert out["detected"] == pytest.approx(0.25)
    assert out["by_class"] == {"A": {"runs": 1, "detected": 1.0}, "B": {"runs": 2, "detected": 0.0},
                               "D": {"runs": 1, "detected": 0.0}}  # fmt: skip
    causes = {"never_observable": 1, "probability_reached_once": 1, "probability_below": 1}
    assert out["missed_causes"] == causes
    missed = {m["run"]: m for m in out["missed"]}
    assert set(missed) == {"b", "c", "d"}
    assert missed["b"]["cause"] == "never_observable" and missed["b"]["road_class"] == "D"
    assert missed["b"]["tyres"]["fl"]["observable_share"] == 0.0
    assert missed["c"]["cause"] == "probability_reached_once"
    assert missed["c"]["tyres"]["fl"]["max_probability"] == pytest.approx(0.97)
    d = missed["d"]["tyres"]["fl"]
    assert missed["d"]["cause"] == "probability_below" and d["max_probability"] == pytest.approx(0.2)
    assert d["estimate_minus_truth_kpa"] == pytest.approx(16.0) and d["sigma_kpa"] == pytest.approx(12.0)
    # without probabilities a miss of an observable tyre is counted below
    plain = warning_detection([replace(runs[2], loss_probability=None)], [["fl"]], window_s=60.0)
    assert plain["missed_causes"]["probability_below"] == 1
    assert "max_probability" not in plain["missed"][0]["tyres"]["fl"]


def test_false_warnings_margin_is_the_probability_held_on_consecutive_observable_updates():
    t_s = np.arange(0.0, 40.0, 0.1)
    t_est = np.arange(0.0, 40.0, 4.0)
    K = t_est.size
    a = np.zeros((K, 4))
    a[3:5, 1] = [0.7, 0.6]  # held 0.6 over two updates
    a[7, 2] = 0.99  # a single update: not held
    b = np.zeros((K, 4))
    b[5:7, 3] = [0.8, 0.9]  # held 0.8, but the first of them is unobservable
    obs = np.ones((K, 4), bool)
    obs[5, 3] = False
    runs = [replace(_trace(t_s, 200.0, t_est, 200.0), loss_probability=a),
            replace(_trace(t_s, 200.0, t_est, 200.0, observable=obs), loss_probability=b)]  # fmt: skip
    best = false_warnings(runs, ["a", "b"])["max_held_probability"]
    assert best == {"probability": pytest.approx(0.6), "run": "a", "tyre": "fr", "t_s": 16.0}
    assert false_warnings(runs, held_updates=1)["max_held_probability"]["probability"] == pytest.approx(0.99)
    assert "max_held_probability" not in false_warnings([_trace(t_s, 200.0, t_est, 200.0)])


def test_false_warnings_count_onsets_per_simulated_minute():
    t_s = np.arange(0.0, 120.0, 0.1)  # 2 min each
    t_est = np.arange(0.0, 120.0, 30.0)
    flicker = np.zeros((4, 4), bool)
    flicker[[1, 3], 2] = True  # two onsets on rl
    runs = [_trace(t_s, 230.0, t_est, 230.0), _trace(t_s, 230.0, t_est, 230.0, warning=flicker)]
    out = false_warnings(runs)
    assert out["false_warnings"] == 2 and out["runs_with_false_warning"] == 1
    assert out["simulated_min"] == pytest.approx(2 * 119.9 / 60)
    assert out["per_simulated_min"] == pytest.approx(2 / (2 * 119.9 / 60))


def test_monitor_trace_from_tables():
    run = {"t_s": [0.0, 1.0], "speed_mps": [10.0, 10.0]}
    run |= {f"{c}_pressure_kpa": [200.0, 200.0] for c in ("fl", "fr", "rl", "rr")}
    mon = {"t_s": [0.5]}
    for c in ("fl", "fr", "rl", "rr"):
        mon |= {f"{c}_pressure_hat_kpa": [201.0], f"{c}_pressure_sigma_kpa": [2.0],
                f"{c}_observable": [True], f"{c}_warning": [False]}  # fmt: skip
    trace = monitor_trace(run, mon)
    assert trace.error.tolist() == [[1.0] * 4]
    del mon["rr_warning"]
    with pytest.raises(InputError, match="rr_warning"):
        monitor_trace(run, mon)


def test_score_set_names_the_set_criteria():
    t_s = np.arange(0.0, 40.0, 0.1)
    t_est = np.arange(0.0, 40.0, 1.0)
    trace = _trace(t_s, 200.0, t_est, 201.0, sigma=1.0)
    out = score_set(
        "drop", [trace], [{"road_class": "B", "change": {"tire": "fl", "start_s": 10, "end_s": 11.5}}]
    )
    assert out["error_at"]["10s"]["mean_kpa"] == pytest.approx(1.0)
    assert out["coverage"]["inside"] == 1.0 and out["by_class"]["B"]["runs"] == 1
    assert out["change"]["settle_s_median"] == 0.0
    with pytest.raises(InputError):
        score_set("drop", [trace], [])


def test_score_set_gives_warning_detection_within_the_longer_windows_the_runs_last():
    t_s = np.arange(0.0, 130.0, 0.1)
    t_est = np.arange(0.0, 130.0, 4.0)
    late = np.zeros((t_est.size, 4), bool)
    late[t_est >= 100.0, 0] = True  # warned after 100 s of driving
    trace = _trace(t_s, 180.0, t_est, 180.0, warning=late)
    out = score_set("warning", [trace], [{"road_class": "C", "deflated": ["fl"], "name": "w"}])
    assert out["warning"]["detected"] == 0.0
    by = out["warning_by_window"]
    assert set(by) == {"60s", "90s", "120s"}  # the run lasts 130 s
    assert by["90s"]["detected"] == 0.0 and by["120s"]["detected"] == 1.0
    assert by["120s"]["one_tyre"] == {"runs": 1, "detected": 1.0}


def test_false_warnings_margin_of_the_common_loss():
    # the car's common-loss probability held over two consecutive updates where it was taken (NaN:
    # not taken, which breaks a run)
    t_s = np.arange(0.0, 40.0, 0.1)
    t_est = np.arange(0.0, 40.0, 4.0)
    common = np.full(t_est.size, np.nan)
    common[2:4] = [0.5, 0.4]  # held 0.4
    common[6] = 0.97  # alone
    common[8] = 0.9  # next to a NaN: not held
    run = replace(_trace(t_s, 200.0, t_est, 200.0), common_probability=common)
    best = false_warnings([run], ["a"])["max_held_common_probability"]
    assert best == {"probability": pytest.approx(0.4), "run": "a", "t_s": 12.0}
    assert "max_held_common_probability" not in false_warnings([_trace(t_s, 200.0, t_est, 200.0)])


def test_the_scores_are_the_reported_estimate_s_and_the_vibration_s_own_beside():
    # the monitor reports its best estimate (with the radii) and writes the vibration's own beside it:
    # the set's scores and targets are the reported one's, vibration_only the vibration's
    run = {"t_s": [0.0, 10.0, 30.0], "speed_mps": [20.0] * 3}
    run |= {f"{c}_pressure_kpa": [200.0] * 3 for c in ("fl", "fr", "rl", "rr")}
    mon = {"t_s": [10.0, 30.0]}
    for c in ("fl", "fr", "rl", "rr"):
        mon |= {f"{c}_pressure_hat_kpa": [202.0, 201.0], f"{c}_pressure_sigma_kpa": [2.0, 1.0],
                f"{c}_observable": [True, True], f"{c}_warning": [False, False],
                f"{c}_fused_pressure_kpa": [202.0, 201.0], f"{c}_fused_sigma_kpa": [2.0, 1.0],
                f"{c}_vibration_pressure_kpa": [220.0, 190.0], f"{c}_vibration_sigma_kpa": [30.0, 4.0],
                f"{c}_vibration_observable": [False, True]}  # fmt: skip
    trace = monitor_trace(run, mon)
    own = vibration_view(trace)
    assert own.p_hat[:, 0].tolist() == [220.0, 190.0] and own.observable[:, 0].tolist() == [False, True]
    out = score_set("constant", [trace], [{"road_class": "B"}])
    assert out["error_at"]["10s"]["mean_kpa"] == pytest.approx(2.0)
    assert out["vibration_only"]["error_at"]["10s"]["mean_kpa"] == pytest.approx(20.0)
    assert out["vibration_only"]["error_at"]["30s"]["mean_kpa"] == pytest.approx(-10.0)
    targets = issue_targets("constant", out)
    assert targets["abs_mean_error_10s_kpa"]["met"]
    assert not targets["vibration_only"]["abs_mean_error_10s_kpa"]["met"]
    # a table without the vibration's columns (a monitor run without the radii): no vibration_only block
    plain = {k: v for k, v in mon.items() if "vibration" not in k}
    assert "vibration_only" not in score_set("constant", [monitor_trace(run, plain)], [{"road_class": "B"}])
