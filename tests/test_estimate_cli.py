"""suvtwin estimate / score: files in and out, and one clear message for bad input."""

import json

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from suvtwin.pipeline.cli import main


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("run") / "run.parquet"
    argv = ["simulate", "--road-class", "B", "--speed", "60", "--pressure", "180", "--duration", "2",
            "--seed", "2", "--out", str(path), "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    return path


@pytest.mark.parametrize("estimator, road_input", [("imm", "synthetic"), ("ukf", "augmented")])
def test_estimate_and_score(run_file, tmp_path, capsys, estimator, road_input):
    out = tmp_path / "est.parquet"
    argv = ["estimate", str(run_file), "--corner", "rl", "--estimator", estimator, "--road-input", road_input,
            "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    table = pq.read_table(out)
    names = table.column_names
    assert names[:5] == ["t_s", "pressure_hat_kpa", "pressure_sigma_kpa", "tire_stiffness_hat_npm",
                         "tire_stiffness_sigma_npm"]  # fmt: skip
    assert ("mode_prob_A" in names) == (estimator == "imm")
    assert table.num_rows == 2000
    meta = json.loads(table.schema.metadata[b"suvtwin.estimate"])
    assert meta["corner"] == "rl" and meta["road_input"] == road_input
    assert meta["sprung_mass_kg"] == pytest.approx(0.5 * 1788 * 1.347 / 2.818)  # eq. 2, rear corner
    capsys.readouterr()
    assert main(["score", str(out), str(run_file), "--json"]) == 0
    metrics = json.loads(capsys.readouterr().out)
    assert metrics["true_pressure_end_kpa"] == 180.0
    assert {"rmse_kpa", "inside_2sigma", "time_to_converge_s"} <= set(metrics)


def _write(path, **columns):
    pq.write_table(pa.table(columns), path)


def _columns(n=100):
    t = np.arange(n) * 1e-3
    return {"t_s": t, "speed_mps": np.full(n, 16.7), "fl_accel_sprung_mps2": np.zeros(n),
            "fl_accel_unsprung_mps2": np.zeros(n)}  # fmt: skip


@pytest.mark.parametrize(
    "change, argv_extra, message",
    [
        ({"fl_accel_unsprung_mps2": None}, [], "lacks column(s) fl_accel_unsprung_mps2"),
        ({"fl_accel_sprung_mps2": np.r_[np.nan, np.zeros(99)]}, ["--estimator", "imm"], "NaN"),
        ({"t_s": np.r_[0.0, np.arange(99) * 1e-3]}, [], "strictly increasing"),
        ({}, ["--corner", "xx"], "--corner must be one of fl, fr, rl, rr"),
        ({}, ["--estimator", "imm", "--params", "missing.json"], "does not exist"),
    ],
)
def test_bad_input_exits_2(tmp_path, capsys, change, argv_extra, message):
    columns = _columns()
    for key, value in change.items():
        if value is None:
            columns.pop(key)
        else:
            columns[key] = value
    path = tmp_path / "user.parquet"
    _write(path, **columns)
    out = tmp_path / "est.parquet"
    assert main(["estimate", str(path), "--out", str(out), *argv_extra]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_joint_estimate_through_the_cli(tmp_path, capsys):
    # a 10 s class C run at 170 kPa: the joint estimator (road level unknown) ends near the truth,
    # and its metadata (with the estimator's info) is valid JSON
    run = tmp_path / "run.parquet"
    argv = ["simulate", "--road-class", "C", "--speed", "60", "--pressure", "170", "--duration", "10",
            "--seed", "3", "--out", str(run), "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    out = tmp_path / "est.parquet"
    assert main(["estimate", str(run), "--estimator", "joint", "--out", str(out)]) == 0
    table = pq.read_table(out)
    assert "road_level_hat_m3" in table.column_names
    meta = json.loads(table.schema.metadata[b"suvtwin.estimate"])
    assert meta["estimator"] == "joint" and meta["road_input"] == "estimated level"
    capsys.readouterr()
    assert main(["score", str(out), str(run), "--json"]) == 0
    metrics = json.loads(capsys.readouterr().out)
    assert abs(metrics["estimate_end_kpa"] - 170.0) < 25.0  # measured 168.2 (sigma ~15 kPa at 10 s)


def test_online_estimate_takes_the_corner_load_of_the_run(tmp_path):
    # An off-centre load (300 kg behind the rear axle's centre, to the left): the axles share its roll
    # moment by their roll stiffness (springs, bars, tyres), which MuJoCo's tyre forces and suspension
    # travels confirm (within 1 % and 1 mm); splitting each axle's share by the load's lateral offset
    # misses the rear tyres by 6-8 % and their travel by 12-15 mm. The single-corner online estimator
    # takes that load, and the monitor's corner models that travel.
    from suvtwin.pipeline.estimation import static_travels
    from suvtwin.pipeline.monitoring import corner_models

    frames = {}
    for name, load in (("empty", ""), ("loaded", "load: [{mass_kg: 300, position_m: [-1.2, 0.5, 0.1]}]\n")):
        scenario = tmp_path / f"{name}.yaml"
        scenario.write_text("duration_s: 3.0\nseed: 4\nspeed_kmh: 40\nroad: flat\n" + load)
        run = tmp_path / f"{name}.parquet"
        assert main(["simulate", "--scenario", str(scenario), "--out", str(run), "--no-progress"]) == 0
        frames[name] = pq.read_table(run).to_pandas().iloc[-1000:].mean()
    loads = ((300.0, (-1.2, 0.5, 0.1)),)
    travel = static_travels(loads)
    models = corner_models(("fl", "fr", "rl", "rr"), loads=loads)
    for i, corner in enumerate(("fl", "fr", "rl", "rr")):
        true_travel = frames["loaded"][f"{corner}_susp_travel_m"] - frames["empty"][f"{corner}_susp_travel_m"]
        assert travel[i] == pytest.approx(true_travel, abs=1e-3)
        assert models[i].static_load == pytest.approx(frames["loaded"][f"{corner}_tire_fz_n"], rel=0.01)
    for corner in ("rl", "rr"):
        out = tmp_path / f"{corner}.parquet"
        argv = ["estimate", str(tmp_path / "loaded.parquet"), "--corner", corner, "--estimator", "online",
                "--out", str(out)]  # fmt: skip
        assert main(argv) == 0
        meta = json.loads(pq.read_table(out).schema.metadata[b"suvtwin.estimate"])
        assert meta["static_load_n"] == pytest.approx(frames["loaded"][f"{corner}_tire_fz_n"], rel=0.01)
        assert meta["config"]["sigma_accel"] == 0.5  # the run records 0.5 m/s², the monitor's floor
