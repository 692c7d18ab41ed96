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
