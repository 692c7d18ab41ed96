"""suvtwin monitor and suvtwin estimate --estimator online: files in and out, gaps tolerated, and one
clear message for bad input."""

import json

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from suvtwin.estimators.monitor import MonitorConfig
from suvtwin.pipeline.cli import main


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("run") / "run.parquet"
    argv = ["simulate", "--road-class", "C", "--speed", "70", "--pressure", "180", "--duration", "20",
            "--seed", "3", "--out", str(path), "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    return path


def test_monitor_writes_every_tyre_and_warns_against_a_placard(run_file, tmp_path, capsys):
    out = tmp_path / "monitor.parquet"
    # 180 kPa in every tyre against a 250 kPa placard: 28 % low, all four (FMVSS 138's case)
    assert main(["monitor", str(run_file), "--out", str(out), "--placard", "250"]) == 0
    table = pq.read_table(out)
    frame = table.to_pandas()
    every = MonitorConfig().update_s  # one update every update_s over the 20 s run
    n_updates = int(round(20.0 / every))
    assert len(frame) == n_updates
    np.testing.assert_allclose(frame["t_s"], np.arange(1, n_updates + 1) * every - 1e-3)
    for c in ("fl", "fr", "rl", "rr"):
        for col in ("pressure_hat_kpa", "pressure_sigma_kpa", "pressure_lower_kpa", "pressure_upper_kpa",
                    "observable", "with_radii", "vibration_pressure_kpa", "vibration_sigma_kpa",
                    "vibration_lower_kpa", "vibration_upper_kpa", "vibration_observable", "status",
                    "reference_kpa", "loss_probability", "warning"):  # fmt: skip
            assert f"{c}_{col}" in frame
        # the 90 % interval holds the estimate, and is no wider than ±1.645 σ by much (a skirt narrows
        # the core; the grid's bounds can skew it)
        lower, hat, upper = (frame[f"{c}_pressure_{k}_kpa"] for k in ("lower", "hat", "upper"))
        assert (lower < hat).all() and (hat < upper).all()
        assert ((upper - lower) < 2 * 1.7 * frame[f"{c}_pressure_sigma_kpa"]).all()
        assert (frame[f"{c}_reference_kpa"] == 250.0).all()
        # four equal tyres: the radius analysis finds no tyre apart (the loads' own part, < 0.5 ‰, aside)
        assert (frame[f"{c}_radius_excess_permille"].abs() < 0.5).all()
        assert (frame[f"{c}_fused_sigma_kpa"] < frame[f"{c}_vibration_sigma_kpa"]).all()
        # the estimate reported is the best: fused with the radii where they are (every update here)
        assert frame[f"{c}_with_radii"].all()
        np.testing.assert_array_equal(frame[f"{c}_pressure_hat_kpa"], frame[f"{c}_fused_pressure_kpa"])
        np.testing.assert_array_equal(frame[f"{c}_pressure_sigma_kpa"], frame[f"{c}_fused_sigma_kpa"])
        # the vibration's own interval likewise holds its estimate
        lower, hat, upper = (frame[f"{c}_vibration_{k}"] for k in ("lower_kpa", "pressure_kpa", "upper_kpa"))
        assert (lower < hat).all() and (hat < upper).all()
    meta = json.loads(table.schema.metadata[b"suvtwin.monitor"])
    assert meta["placard_kpa"] == 250.0 and meta["segments"] == n_updates
    # the force closure ran: the simulator's half step told it as the damper's timing, windows counted
    closure = meta["force_closure"]
    assert closure["config"]["damper_lag_s"] == pytest.approx(0.5e-3)
    assert min(closure["windows"].values()) > 0
    warned = [meta["warnings"][c] for c in ("fl", "fr", "rl", "rr")]
    assert all(w is not None and w["loss_probability"] >= 0.95 for w in warned)
    assert "WARNING" in capsys.readouterr().out


def test_monitor_without_a_reference_fuses_the_radii_against_the_tyre_model(run_file, tmp_path):
    out = tmp_path / "monitor.parquet"
    assert main(["monitor", str(run_file), "--out", str(out)]) == 0
    frame = pq.read_table(out).to_pandas()
    for c in ("fl", "fr", "rl", "rr"):
        fused, sigma = frame[f"{c}_fused_pressure_kpa"], frame[f"{c}_fused_sigma_kpa"]
        # from the first radius block on (4 s): four equal tyres at 180 kPa, within 3σ
        assert np.isfinite(fused).all() and (sigma > 0).all()
        assert (np.abs(fused - 180.0) < 3 * sigma).all()
        assert frame[f"{c}_reference_kpa"].isna().all()  # 20 s: no reference learned, no warning


def test_online_estimate_tolerates_a_gap(run_file, tmp_path, capsys):
    frame = pq.read_table(run_file).to_pandas()
    frame.loc[3000:3500, "fl_accel_unsprung_mps2"] = np.nan
    gapped = tmp_path / "gapped.parquet"
    frame.to_parquet(gapped)
    out = tmp_path / "est.parquet"
    assert main(["estimate", str(gapped), "--estimator", "online", "--out", str(out)]) == 0
    est = pq.read_table(out)
    meta = json.loads(est.schema.metadata[b"suvtwin.estimate"])
    assert meta["estimator"] == "online" and meta["causal"]
    assert meta["windows_used"][0] < 5  # the windows holding the gap were skipped
    values = est.column("pressure_hat_kpa").to_numpy()
    assert est.num_rows == len(frame) and np.all(np.isfinite(values))
    # the default estimator (the most accurate on a recorded run: the joint one) refuses the gap
    assert main(["estimate", str(gapped), "--out", str(out)]) == 2
    assert "NaN" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv_extra, message",
    [
        (["--placard", "900"], "--placard must be a pressure within 50–500 kPa"),
        (["--placard", "230", "--reset-at", "0"], "not both"),
        (["--reset-at", "99"], "--reset-at must lie within the run"),
        (["--corners", "fl,xx"], "--corners must list distinct tyres"),
        (["--accel-noise", "0"], "--accel-noise must be an accelerometer noise σ within 0.05–50 m/s²"),
        (["--road-waviness", "smooth"], "--road-waviness must be one of iso, free"),
    ],
)
def test_bad_input_exits_2_and_writes_nothing(run_file, tmp_path, capsys, argv_extra, message):
    out = tmp_path / "m.parquet"
    assert main(["monitor", str(run_file), "--out", str(out), *argv_extra]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_monitor_models_the_run_s_own_vehicle(tmp_path, monkeypatch):
    # A run simulated with vehicle overrides is monitored with those overrides, not the parameter
    # file's car: the corner models get the run's anti-roll rate, spring rate and chassis mass.
    import suvtwin.pipeline.monitoring as monitoring
    from suvtwin.mjcf.vehicle import load_vehicle
    from suvtwin.pipeline.scenario import parse_scenario
    from suvtwin.pipeline.simulator import simulate, write_run

    overrides = {"suspension": {"anti_roll_front": 12000.0, "spring_rate_front": 36000.0},
                 "chassis": {"mass": 1700.0}}  # fmt: skip
    sc = parse_scenario({"duration_s": 12.0, "speed_kmh": 60, "seed": 4,
                         "road": {"segments": [{"length_m": 260.0, "gd_n0": 2.56e-4}]},
                         "vehicle": overrides})  # fmt: skip
    path = tmp_path / "run.parquet"
    write_run(simulate(sc), path)
    seen = []
    original = monitoring.corner_models

    def spy(*args, **kwargs):
        models = original(*args, **kwargs)
        seen.append(models)
        return models

    monkeypatch.setattr(monitoring, "corner_models", spy)
    monitoring.monitor_run(path, placard_kpa=250.0)
    fl = seen[0][0]
    default = load_vehicle()
    assert fl.anti_roll == 12000.0 != default.suspension.anti_roll_front
    assert fl.spring_rate == 36000.0
    # paper 000 eq. 2 with the overridden chassis mass: m·a2/(2L), independent of the parameter file
    assert fl.sprung_mass == pytest.approx(1700.0 * default.chassis.a2 / (2.0 * default.wheelbase), rel=1e-9)

    # `suvtwin estimate` (joint and online) builds the same run's car
    import suvtwin.pipeline.estimation as estimation

    built = []
    original_model = estimation.linear_corner_model

    def spy_model(*args, **kwargs):
        built.append(original_model(*args, **kwargs))
        return built[-1]

    monkeypatch.setattr(estimation, "linear_corner_model", spy_model)
    for name in ("joint", "online"):
        out = tmp_path / f"{name}.parquet"
        assert main(["estimate", str(path), "--corner", "fl", "--estimator", name, "--out", str(out)]) == 0
        assert built[-1].anti_roll == 12000.0 and built[-1].spring_rate == 36000.0


def test_after_a_reset_the_radii_warn_a_leaking_tyre_before_any_reference_is_learned(tmp_path):
    from suvtwin.pipeline.scenario import parse_scenario
    from suvtwin.pipeline.simulator import simulate, write_run

    # all at 230 kPa at the reset, the rear right losing 20 % from 25 s to 35 s; 64 s, class B
    sc = parse_scenario(
        {"duration_s": 64.0, "seed": 77, "speed_kmh": 80.0,
         "road": {"segments": [{"length_m": 1600.0, "gd_n0": 40e-6}]}, "pressure_kpa": 230.0,
         "pressure_events": [{"tire": "rr", "start_s": 25.0, "end_s": 35.0, "target_kpa": 184.0}]},
        source="test",
    )  # fmt: skip
    run = tmp_path / "leak.parquet"
    write_run(simulate(sc), run)
    out = tmp_path / "monitor.parquet"
    assert main(["monitor", str(run), "--out", str(out)]) == 0
    table = pq.read_table(out)
    meta = json.loads(table.schema.metadata[b"suvtwin.monitor"])
    warned = meta["warnings"]
    assert warned["fl"] is None and warned["fr"] is None and warned["rl"] is None
    # by the radii (the vibration has no reference yet: 60 s of driving and σ ≤ 8 kPa), within 25 s
    # of the leak's end: the radii's memory of six blocks follows a 10 s leak over about 20 s
    assert warned["rr"]["by"] == "radii against the others" and warned["rr"]["t_s"] <= 60.0
    assert warned["rr"]["reference_kpa"] is None
    frame = table.to_pandas()
    before = frame["t_s"] < 25.0  # nothing before the leak
    assert frame.loc[before, "rr_relative_loss_probability"].max() < 0.01


def test_monitor_assumes_the_noise_the_run_records_for_its_sensors(run_file, tmp_path):
    # The run re-noised at 3 m/s² per sample, its metadata saying so (as the simulator records its
    # sensors): the monitor and both previews assume 3 m/s²; --accel-noise overrides; the original
    # run (0.5 m/s² recorded) keeps the monitor's 0.5.
    import pyarrow as pa

    from suvtwin.estimators.monitor import MonitorConfig, TyreMonitor
    from suvtwin.pipeline.monitoring import corner_models, monitor_run

    table = pq.read_table(run_file)
    meta = json.loads(table.schema.metadata[b"suvtwin.run"])
    assert meta["scenario"]["noise"] == {"accel_sprung_mps2": 0.5, "accel_unsprung_mps2": 0.5}
    frame = table.to_pandas()
    rng = np.random.default_rng(11)
    for c in ("fl", "fr", "rl", "rr"):
        for w in ("sprung", "unsprung"):
            noise = 3.0 * rng.standard_normal(len(frame))
            frame[f"{c}_accel_{w}_mps2"] = frame[f"{c}_accel_{w}_true_mps2"] + noise
    meta["scenario"]["noise"] = {"accel_sprung_mps2": 3.0, "accel_unsprung_mps2": 3.0}
    noisy = tmp_path / "noisy.parquet"
    pq.write_table(pa.Table.from_pandas(frame, preserve_index=False)
                   .replace_schema_metadata({b"suvtwin.run": json.dumps(meta).encode()}), noisy)  # fmt: skip
    # the body channel above 100 Hz is the noise alone (the body's own motion there is ~1e-4 of it):
    # its one-sided PSD is 2 σ² dt
    from scipy.signal import welch

    f, psd = welch(frame["fl_accel_sprung_mps2"].to_numpy(), fs=1000.0, nperseg=1000)
    assert np.median(psd[(f > 100) & (f < 450)]) == pytest.approx(2 * 3.0**2 * 1e-3, rel=0.1)

    result = monitor_run(noisy, placard_kpa=250.0)
    noise = result.metadata["accel_noise"]
    assert noise == {"sigma_mps2": 3.0, "source": "the run's sensors", "recorded_mps2": 3.0}
    last = result.table.iloc[-1]
    for c in ("fl", "fr", "rl", "rr"):
        assert abs(last[f"{c}_pressure_hat_kpa"] - 180.0) < 3.0 * last[f"{c}_pressure_sigma_kpa"]
    # suvtwin estimate --estimator online (one corner) assumes the same figure
    from suvtwin.pipeline.estimation import estimate_run

    one = estimate_run(noisy, corner="fl", estimator="online", params="identified", road_input=None, seed=0)
    assert one.metadata["config"]["sigma_accel"] == 3.0
    assert one.metadata["accel_noise_source"] == "the run's sensors"
    end = one.table.iloc[-1]
    assert abs(end["pressure_hat_kpa"] - 180.0) < 3.0 * end["pressure_sigma_kpa"]
    given = monitor_run(noisy, placard_kpa=250.0, accel_noise_mps2=0.5)
    assert given.metadata["accel_noise"] == {"sigma_mps2": 0.5, "source": "given", "recorded_mps2": 3.0}
    plain = monitor_run(run_file, placard_kpa=250.0)
    assert plain.metadata["accel_noise"]["sigma_mps2"] == 0.5
    # one noise figure for all the accelerometers: the previews take the monitor's
    monitor = TyreMonitor(corner_models(("fl", "fr", "rl", "rr")), dt=1e-3,
                          config=MonitorConfig(sigma_accel=3.0), tracks=((0, 2), (1, 3)), wheelbase_m=2.8)
    assert [track.config.sigma_accel for track in monitor._previews] == [3.0, 3.0]


def test_monitor_takes_the_free_waviness_prior_by_name(run_file, tmp_path):
    out = tmp_path / "free.parquet"
    assert main(["monitor", str(run_file), "--out", str(out), "--road-waviness", "free"]) == 0
    meta = json.loads(pq.read_table(out).schema.metadata[b"suvtwin.monitor"])
    assert meta["road_waviness"] == "free"
    assert meta["config"]["waviness_iso_weight"] == 0.0 and meta["config"]["waviness_points"] == 7


def test_a_stop_reversing_and_speed_spikes_are_skipped_windows_not_a_refused_run(run_file, tmp_path):
    # A standing car's speed signal jitters about zero (the simulator's body velocity at rest dips to
    # −1e-5 m/s), a car may back up, and a faulty signal may spike: the monitor skips those windows and
    # counts them (issue 12: never fatal); the rest of the run is estimated as without them.
    frame = pq.read_table(run_file).to_pandas()
    v = frame["speed_mps"].to_numpy().copy()
    v[:3000] = np.where(np.arange(3000) % 2, -1e-5, 1e-5)  # 0–3 s: standing, jittering
    v[3000:5000] = -2.0  # 3–5 s: backing up
    v[[6000, 6001, 6500]] = 1e4  # three spikes (0.015 % of the samples)
    frame["speed_mps"] = v
    odd = tmp_path / "odd.parquet"
    frame.to_parquet(odd)
    out, ref = tmp_path / "m.parquet", tmp_path / "ref.parquet"
    assert main(["monitor", str(odd), "--out", str(out)]) == 0
    assert main(["monitor", str(run_file), "--out", str(ref)]) == 0
    got, base = pq.read_table(out), pq.read_table(ref).to_pandas()
    status = json.loads(got.schema.metadata[b"suvtwin.monitor"])["segment_status"]
    frame = got.to_pandas()
    # every window that holds the stop, the reversing or the spikes (0–6.5 s) is skipped for its speed
    cfg = MonitorConfig()
    ends = np.arange(1, int(round(20.0 / cfg.update_s)) + 1) * cfg.update_s
    skipped = int(np.sum(ends - cfg.segment_s < 6.5))
    assert 1 <= skipped < ends.size  # at least one window is clear of them
    assert all(status["speed"][c] == skipped for c in ("fl", "fr", "rl", "rr")), status
    assert (frame["fl_status"] == "speed").sum() == skipped
    for c in ("fl", "fr", "rl", "rr"):
        hat, sigma = frame[f"{c}_vibration_pressure_kpa"], frame[f"{c}_vibration_sigma_kpa"]
        assert np.isfinite(hat).all() and np.isfinite(sigma).all()
        # with one window of data, each tyre's vibration estimate holds the truth (180 kPa) within 3σ,
        # and is no better informed than with the whole run; so does the estimate with the radii
        assert abs(hat.iloc[-1] - 180.0) < 3 * sigma.iloc[-1]
        assert sigma.iloc[-1] >= base[f"{c}_vibration_sigma_kpa"].iloc[-1]
        best, best_sigma = frame[f"{c}_pressure_hat_kpa"].iloc[-1], frame[f"{c}_pressure_sigma_kpa"].iloc[-1]
        assert abs(best - 180.0) < 3 * best_sigma


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda v: np.where(np.arange(v.size) % 20 == 0, 1e4, v), "the wrong unit?"),  # 5 % beyond
        (lambda v: -v, "the wrong sign?"),  # backing up all along
    ],
)
def test_a_speed_in_the_wrong_unit_or_sign_is_refused(run_file, tmp_path, capsys, change, message):
    frame = pq.read_table(run_file).to_pandas()
    frame["speed_mps"] = change(frame["speed_mps"].to_numpy())
    bad, out = tmp_path / "bad.parquet", tmp_path / "m.parquet"
    frame.to_parquet(bad)
    assert main(["monitor", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "speed_mps" in err and message in err
    assert not out.exists()


def test_the_batch_estimators_take_a_standing_car_s_jitter_but_not_reversing(tmp_path):
    from suvtwin.errors import InputError
    from suvtwin.pipeline.estimation import check_signals

    v = np.r_[np.full(100, 1e-5), np.full(100, -1e-5), np.full(800, 20.0)]
    np.testing.assert_array_equal(check_signals(v, {}, "run.parquet", refuse_accel=True), v)
    with pytest.raises(InputError, match="no reversing"):
        check_signals(np.r_[v, -1.0], {}, "run.parquet", refuse_accel=True)
    with pytest.raises(InputError, match="no gaps"):
        check_signals(np.r_[v, np.nan], {}, "run.parquet", refuse_accel=True)
    # streamed: gaps and spikes kept as gaps, reversing kept
    odd = np.r_[v, np.nan, 1e4, -1.0]
    streamed = check_signals(odd, {}, "run.parquet", refuse_accel=False, speed_gaps=True)
    assert np.isnan(streamed[-3:-1]).all() and streamed[-1] == -1.0


def test_float32_or_jittered_timestamps_are_taken_and_a_missing_sample_is_refused(run_file, tmp_path, capsys):
    # A logger's time column may be float32 (rounded to 2e-6 s at 20 s) or jitter by a few percent of
    # a sample: the monitor reads the same data at the same rate; a sample left out (every later one a
    # whole interval off) is refused with one message, as it would shift the front→rear delay and the
    # spectra.
    frame = pq.read_table(run_file).to_pandas()
    ref = tmp_path / "ref.parquet"
    assert main(["monitor", str(run_file), "--out", str(ref)]) == 0
    base = pq.read_table(ref).to_pandas()
    jitter = np.random.default_rng(5).uniform(-0.05, 0.05, len(frame)) * 1e-3
    for name, t in (("f32", frame["t_s"].astype(np.float32)), ("jitter", frame["t_s"] + jitter)):
        odd, out = tmp_path / f"{name}.parquet", tmp_path / f"{name}_m.parquet"
        # the run's description kept (the simulator's step sets the damper's timing the closure takes)
        table = pa.Table.from_pandas(frame.assign(t_s=t), preserve_index=False)
        pq.write_table(table.replace_schema_metadata(pq.read_schema(run_file).metadata), odd)
        assert main(["monitor", str(odd), "--out", str(out)]) == 0, name
        got = pq.read_table(out).to_pandas()
        assert len(got) == len(base)
        for c in ("fl", "fr", "rl", "rr"):
            # the interval is the stamps' whole rate (1 kHz), so the same estimates (the time between
            # updates, from the stamps, moves the random walk's width in the last digits)
            for col in ("pressure_hat_kpa", "pressure_sigma_kpa", "fused_pressure_kpa"):
                np.testing.assert_allclose(got[f"{c}_{col}"], base[f"{c}_{col}"], rtol=1e-6, err_msg=name)
    gap, out = tmp_path / "gap.parquet", tmp_path / "gap_m.parquet"
    frame.drop(index=5000).to_parquet(gap)
    assert main(["monitor", str(gap), "--out", str(out)]) == 2
    assert "t_s must be uniformly sampled" in capsys.readouterr().err and not out.exists()


def test_one_dead_accelerometer_leaves_the_four_wheels_radius_analysis(run_file, tmp_path):
    # The radius analysis leaves out samples where a wheel is (nearly) off the ground, judged from its
    # accelerometers; a dead one says nothing of that, and used to stop the analysis of all four wheels.
    frame = pq.read_table(run_file).to_pandas()
    frame["rl_accel_unsprung_mps2"] = np.nan
    dead, out = tmp_path / "dead.parquet", tmp_path / "m.parquet"
    frame.to_parquet(dead)
    assert main(["monitor", str(dead), "--out", str(out)]) == 0
    got = pq.read_table(out).to_pandas()
    assert (got["rl_status"] == "gap").all() and not got["rl_vibration_observable"].any()
    for c in ("fl", "fr", "rl", "rr"):
        fused, sigma = got[f"{c}_fused_pressure_kpa"], got[f"{c}_fused_sigma_kpa"]
        assert np.isfinite(fused).all() and (np.abs(fused - 180.0) < 3 * sigma).all()
    # the dead tyre's pressure comes from the radii against the others: far narrower than its prior
    assert got["rl_fused_sigma_kpa"].iloc[-1] < 0.5 * got["rl_vibration_sigma_kpa"].iloc[-1]
    # and the estimate reported is that one
    assert got["rl_with_radii"].all()
    assert got["rl_pressure_sigma_kpa"].iloc[-1] == got["rl_fused_sigma_kpa"].iloc[-1]


def test_the_stream_s_interval_is_the_same_from_a_cut_record_and_the_whole_one():
    # causality (issue 12): the interval the monitor is built with may not depend on what follows t
    from suvtwin.pipeline.monitoring import stream_dt

    rng = np.random.default_rng(7)
    t = np.arange(60_000) * 1e-3
    for stamps in (t, t.astype(np.float32).astype(float), t + rng.uniform(-5e-5, 5e-5, t.size)):
        assert stream_dt(stamps[:4001]) == stream_dt(stamps) == 1e-3
    odd = np.arange(3000) * 3e-3 + 0.5  # 333.3 Hz: no whole rate, the median interval
    assert stream_dt(odd[:1500]) == stream_dt(odd) == pytest.approx(3e-3, rel=1e-12)


def test_the_run_file_is_streamed_and_its_row_groups_change_nothing(run_file, tmp_path):
    # suvtwin monitor reads the accelerometers and wheel speeds in chunks (memory bounded by a chunk,
    # not the drive's length); a Parquet batch ends early at a row group's end, so a file cut into odd
    # row groups feeds other chunks: the same result, to the bit, as the arrays in one go
    from suvtwin.pipeline.monitoring import monitor_run

    table = pq.read_table(run_file)
    odd = tmp_path / "groups.parquet"
    pq.write_table(table, odd, row_group_size=3333)
    assert pq.ParquetFile(odd).metadata.num_row_groups == 7
    one, many = monitor_run(run_file, placard_kpa=230), monitor_run(odd, placard_kpa=230)
    assert one.table.equals(many.table)
    assert np.isfinite(one.table["rr_fused_pressure_kpa"]).all()
    # the radius analysis of the whole record in one go (radius_evidence, the arrays' API) is the one
    # monitor_run fed in chunks
    from suvtwin.estimators.deflation import DeflationRule
    from suvtwin.pipeline.estimation import run_loads, run_vehicle
    from suvtwin.pipeline.monitoring import radius_evidence

    meta = json.loads(table.schema.metadata[b"suvtwin.run"])
    evidence, _ = radius_evidence(table.to_pandas(), one.table["t_s"].to_numpy(), loads=run_loads(meta),
                                  vehicle=run_vehicle(meta), tire_file=one.metadata["tire_file"],
                                  placard_kpa=230, rule=DeflationRule())  # fmt: skip
    for i, c in enumerate(("fl", "fr", "rl", "rr")):
        np.testing.assert_allclose(1e3 * evidence.excess[:, i], one.table[f"{c}_radius_excess_permille"],
                                   rtol=1e-9, atol=1e-12)  # fmt: skip


def test_the_time_axis_and_speed_checked_in_chunks_are_the_whole_record_checked():
    # suvtwin monitor checks the time axis and the speed in chunks (a record larger than memory): the
    # same interval, refusals and messages as the whole arrays at once, a fault in any chunk found
    from suvtwin.errors import InputError
    from suvtwin.pipeline.estimation import (
        check_signals,
        check_streamed_speed,
        check_time_axis,
        check_time_chunks,
    )

    rng = np.random.default_rng(11)
    t = 3.0 + np.arange(25_000) * 1e-3 + rng.uniform(-2e-5, 2e-5, 25_000)
    pieces = lambda x: lambda: iter(np.array_split(x, 7))  # noqa: E731
    axis = check_time_chunks(pieces(t), "r")
    assert axis.dt == check_time_axis(t, "r") and axis.n == t.size and (axis.t0, axis.t_end) == (t[0], t[-1])
    np.testing.assert_array_equal(axis.head_steps, np.diff(t[:10_001]))
    border = np.array_split(t, 7)[0].size
    faults = [(np.delete(t, 17_500), "uniformly"), (np.r_[t[:border], t[border - 1 :]], "increasing"),
              (np.r_[t[:20_000], np.nan, t[20_001:]], "NaN")]  # fmt: skip
    for bad, message in faults:
        with pytest.raises(InputError, match=message) as chunked:
            check_time_chunks(pieces(bad), "r")
        with pytest.raises(InputError, match=message) as whole:
            check_time_axis(bad, "r")
        assert str(chunked.value) == str(whole.value)
    v = np.full(t.size, 20.0)
    v[[5, 9_000, 24_000]] = 1e4  # spikes: gaps
    check_streamed_speed(np.array_split(v, 7), "r")
    np.testing.assert_array_equal(np.isnan(check_signals(v, {}, "r", refuse_accel=False, speed_gaps=True)),
                                  v > 100)  # fmt: skip
    v[:300] = 1e4  # 1.2 % beyond 100 m/s: the wrong unit, in chunks as whole
    with pytest.raises(InputError, match="wrong unit"):
        check_streamed_speed(np.array_split(v, 7), "r")


def test_a_dead_body_motion_sensor_leaves_the_radius_analysis_on_the_wheels_kinematics(run_file, tmp_path):
    # The radius analysis gates its blocks on the body's lateral and longitudinal acceleration; with
    # either sensor dead it used to count no sample (no tyre had a pressure with the radii). Now the
    # wheels' kinematics stand in: a_y = v ψ̇ and a_x = dv/dt. Checked against the sensors on a run
    # turning on a circle of 80 m while speeding up from 40 to 80 km/h, then on the monitor.
    import pyarrow as pa

    from suvtwin.estimators.rolling_radius import RollingRadius
    from suvtwin.mjcf.tire import load_tire
    from suvtwin.mjcf.vehicle import CORNERS, load_vehicle
    from suvtwin.pipeline.monitoring import wheel_positions
    from suvtwin.pipeline.scenario import parse_scenario
    from suvtwin.pipeline.simulator import simulate

    scenario = parse_scenario({"duration_s": 16.0, "seed": 5, "speed_kmh": [[0, 40], [16, 80]],
                               "road": "flat", "steering": {"mode": "circle", "radius_m": 80.0}},
                              source="test")  # fmt: skip  (a circle leaves a rough road's straight strip)
    frame = simulate(scenario).table
    t = frame["t_s"].to_numpy()
    wheels = frame[[f"{c}_wheel_speed_radps" for c in CORNERS]].to_numpy()
    yaw, lat, lon = (frame[k].to_numpy() for k in ("yaw_rate_radps", "lat_accel_mps2", "long_accel_mps2"))
    analysis = RollingRadius(wheel_positions(load_vehicle()), 1e-3, load_tire().unloaded_radius)
    dead = np.full(t.size, np.nan)
    _, k_lat, k_lon, _ = analysis._body_motion(t, wheels, yaw, dead, dead)
    blocks = lambda a: np.nanmean(a[:16000].reshape(4, 4000), axis=1)  # noqa: E731  (4 s blocks)
    # a_y 1.9–5.2 m/s² here: within 6 % (the sensor's body frame rolls); a_x 0.69 m/s² from the
    # speed profile: the kinematics' 0.72 (the unloaded radius, 3 % above the rolling one), the
    # sensor's 0.68–0.80 (its body frame pitches and turns)
    np.testing.assert_allclose(blocks(k_lat), blocks(lat), rtol=0.06)
    np.testing.assert_allclose(blocks(k_lon), blocks(lon), atol=0.1)
    assert analysis.substituted_samples == {"lat_accel": t.size, "long_accel": t.size - 1, "yaw_rate": 0}
    # a dead yaw-rate sensor: ψ̇ = a_y/v, within 8 % here (v from the unloaded radius, 3 % high)
    k_yaw, _, _, guessed = analysis._body_motion(t, wheels, dead, lat, lon)
    assert guessed[t > 1.0].all()
    np.testing.assert_allclose(blocks(k_yaw), blocks(yaw), rtol=0.08)

    table = pq.read_table(run_file)
    assert main(["monitor", str(run_file), "--out", str(tmp_path / "clean.parquet")]) == 0
    ref = pq.read_table(tmp_path / "clean.parquet").to_pandas()
    for name, key in (("lat_accel_mps2", "lat_accel"), ("long_accel_mps2", "long_accel"),
                      ("yaw_rate_radps", "yaw_rate")):  # fmt: skip
        column = pa.array(np.full(table.num_rows, np.nan))
        broken = table.set_column(table.schema.get_field_index(name), name, column)
        pq.write_table(broken, tmp_path / "dead.parquet")  # the run's metadata kept
        assert main(["monitor", str(tmp_path / "dead.parquet"), "--out", str(tmp_path / "m.parquet")]) == 0
        got = pq.read_table(tmp_path / "m.parquet")
        frame = got.to_pandas()
        for c in CORNERS:
            fused = f"{c}_fused_pressure_kpa"
            np.testing.assert_allclose(frame[fused], ref[fused], atol=0.5)
        substituted = json.loads(got.schema.metadata[b"suvtwin.monitor"])["radius"]["substituted_samples"]
        assert substituted[key] >= 0.9 * table.num_rows  # (the yaw rate: from 8 m/s on)
    # a file without the body's accelerations at all (wheel speeds and yaw rate only): the same
    pq.write_table(table.drop_columns(["lat_accel_mps2", "long_accel_mps2"]), tmp_path / "none.parquet")
    assert main(["monitor", str(tmp_path / "none.parquet"), "--out", str(tmp_path / "n.parquet")]) == 0
    frame = pq.read_table(tmp_path / "n.parquet").to_pandas()
    for c in CORNERS:
        assert np.isfinite(frame[f"{c}_fused_pressure_kpa"]).all()
        np.testing.assert_allclose(frame[f"{c}_fused_pressure_kpa"], ref[f"{c}_fused_pressure_kpa"], atol=0.5)


def test_a_dead_wheel_speed_sensor_leaves_the_radius_analysis_on_the_other_three_wheels(
    run_file, tmp_path, capsys
):
    # A wheel-speed sensor that reads nothing (NaN) or 0 while the car moves used to stop the radius
    # analysis (every excess compared one wheel with all the others): no tyre had a pressure with the
    # radii. Now the analysis runs over the other three wheels: their pressures with the radii stay
    # within a few kPa of the clean run's, the silent tyre keeps its vibration estimate (moved only by
    # its errors' correlation with the others'), the vibration estimates are the clean run's to the
    # bit, and the silent samples are counted per wheel in the output and said on the console.
    import pyarrow as pa

    assert main(["monitor", str(run_file), "--out", str(tmp_path / "clean.parquet")]) == 0
    ref = pq.read_table(tmp_path / "clean.parquet").to_pandas()
    table = pq.read_table(run_file)
    name = "rl_wheel_speed_radps"
    for dead in (np.full(table.num_rows, np.nan), np.zeros(table.num_rows)):
        broken = table.set_column(table.schema.get_field_index(name), name, pa.array(dead))
        pq.write_table(broken, tmp_path / "dead.parquet")
        capsys.readouterr()
        assert main(["monitor", str(tmp_path / "dead.parquet"), "--out", str(tmp_path / "m.parquet")]) == 0
        said = capsys.readouterr().out
        got = pq.read_table(tmp_path / "m.parquet")
        frame = got.to_pandas()
        for c in ("fl", "fr", "rl", "rr"):
            own = f"{c}_vibration_pressure_kpa"
            np.testing.assert_array_equal(frame[own], ref[own])
            assert np.isfinite(frame[f"{c}_fused_pressure_kpa"]).all()
            assert np.isnan(frame["rl_radius_excess_permille"]).all()
        for c in ("fl", "fr", "rr"):
            fused = f"{c}_fused_pressure_kpa"
            np.testing.assert_allclose(frame[fused], ref[fused], atol=3.0)
        # the silent tyre: no radius of its own, so its σ is about its vibration σ, not the fused one's
        assert np.all(frame["rl_fused_sigma_kpa"] >= 0.8 * frame["rl_vibration_sigma_kpa"])
        assert np.all(frame["rl_fused_sigma_kpa"] > ref["rl_fused_sigma_kpa"])
        silent = json.loads(got.schema.metadata[b"suvtwin.monitor"])["radius"]["silent_wheel_samples"]
        assert silent["rl"] >= 0.9 * table.num_rows and silent["fl"] == silent["fr"] == silent["rr"] == 0
        assert "wheel's speed missing (rl 100 %" in said
    # and on the clean run none is counted
    clean = json.loads(pq.read_table(tmp_path / "clean.parquet").schema.metadata[b"suvtwin.monitor"])
    assert clean["radius"]["silent_wheel_samples"] == {"fl": 0, "fr": 0, "rl": 0, "rr": 0}


def test_a_road_with_no_roughness_is_not_read_as_four_soft_tyres(tmp_path, capsys):
    # on a flat road the accelerometers hold their noise alone; the monitor read every tyre 80-87 kPa
    # and warned all four at 12 s (P = 1.000) before its windows checked for a road signal
    run = tmp_path / "flat.parquet"
    scenario = tmp_path / "flat.yaml"
    scenario.write_text("duration_s: 20\nseed: 3\nspeed_kmh: 80\nroad: flat\npressure_kpa: 230\n")
    assert main(["simulate", "--scenario", str(scenario), "--out", str(run), "--no-progress"]) == 0
    out = tmp_path / "monitor.parquet"
    assert main(["monitor", str(run), "--out", str(out), "--placard", "230"]) == 0
    frame = pq.read_table(out).to_pandas()
    for c in ("fl", "fr", "rl", "rr"):
        assert (frame[f"{c}_status"] == "smooth").all()
        assert not frame[f"{c}_observable"].any() and not frame[f"{c}_warning"].any()
    assert f"windows: {int(round(20.0 / MonitorConfig().update_s))} smooth" in capsys.readouterr().out


def test_the_update_interval_is_an_option_and_a_bad_one_is_named(run_file, tmp_path, capsys):
    out = tmp_path / "m4.parquet"
    assert main(["monitor", str(run_file), "--out", str(out), "--update-s", "4"]) == 0
    frame = pq.read_table(out).to_pandas()
    np.testing.assert_allclose(frame["t_s"], np.arange(1, 6) * 4.0 - 1e-3)  # 20 s: five updates
    meta = json.loads(pq.read_table(out).schema.metadata[b"suvtwin.monitor"])
    assert meta["config"]["update_s"] == 4.0
    capsys.readouterr()
    bad = tmp_path / "m3.parquet"
    assert main(["monitor", str(run_file), "--out", str(bad), "--update-s", "3"]) == 2
    said = capsys.readouterr().err
    assert "--update-s" in said and "segment_s a multiple of it" in said
    assert not bad.exists()


def test_the_reported_estimate_is_the_fused_one_where_there_is_one_else_the_vibration_s():
    # best_estimate: per update and tyre, the fusion with the radii where it has a value, else the
    # vibration's own; the fused estimate's 5 % / 95 % quantiles are the normal's, its observable flag
    # its σ within the limit
    from types import SimpleNamespace

    from suvtwin.pipeline.monitoring import best_estimate

    nan = np.nan
    update = SimpleNamespace(
        pressure_pa=np.array([[200e3, 210e3], [190e3, 205e3]]),
        pressure_sigma_pa=np.array([[40e3, 5e3], [8e3, 4e3]]),
        pressure_lower_pa=np.array([[150e3, 202e3], [178e3, 199e3]]),
        pressure_upper_pa=np.array([[260e3, 218e3], [203e3, 211e3]]),
        observable=np.array([[False, True], [True, True]]),
    )  # fmt: skip
    warn = SimpleNamespace(fused_kpa=np.array([[nan, 208.0], [185.0, nan]]),
                           fused_sigma_kpa=np.array([[nan, 3.0], [30.0, nan]]))  # fmt: skip
    best = best_estimate(update, warn, observable_sigma_kpa=25.0)
    assert best.with_radii.tolist() == [[False, True], [True, False]]
    np.testing.assert_array_equal(best.pressure_kpa, [[200.0, 208.0], [185.0, 205.0]])
    np.testing.assert_array_equal(best.sigma_kpa, [[40.0, 3.0], [30.0, 4.0]])
    z95 = 1.6448536  # the normal's 95 % point
    np.testing.assert_allclose(best.lower_kpa, [[150.0, 208.0 - z95 * 3.0], [185.0 - z95 * 30.0, 199.0]])
    np.testing.assert_allclose(best.upper_kpa, [[260.0, 208.0 + z95 * 3.0], [185.0 + z95 * 30.0, 211.0]])
    assert best.observable.tolist() == [[False, True], [False, True]]
    # no radius analysis: the vibration's own throughout
    alone = best_estimate(update, None)
    np.testing.assert_array_equal(alone.pressure_kpa, update.pressure_pa / 1e3)
    assert not alone.with_radii.any() and alone.observable.tolist() == update.observable.tolist()
