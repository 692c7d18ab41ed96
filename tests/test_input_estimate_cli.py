"""suvtwin input-estimate: a run file in, a Parquet of estimated and true force and torque out."""

import json

import numpy as np
import pyarrow.parquet as pq
import pytest

from suvtwin.pipeline.cli import main
from suvtwin.pipeline.input_estimation import estimate_run, obstacle_scenario, scores
from suvtwin.pipeline.simulator import read_run, simulate, write_run


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("run") / "bump.parquet"
    write_run(simulate(obstacle_scenario("sine_bump", speed_kmh=60, duration_s=1.0)), path)
    return path


@pytest.mark.parametrize(
    ("options", "label"), [([], "AWIE"), (["--method", "CIE", "--fading", "0.9"], "CIE f=0.9")]
)
def test_writes_estimate_and_truth(run_file, tmp_path, capsys, options, label):
    out = tmp_path / "inputs.parquet"
    assert main(["input-estimate", str(run_file), "--out", str(out), "--seed", "4", *options]) == 0
    assert "pitch torque" in capsys.readouterr().out
    table = pq.read_table(out)
    assert table.column_names[:3] == ["t_s", "force_hat_n", "torque_hat_nm"]
    assert {"force_true_n", "torque_true_nm", "suspension_force_true_n", "suspension_torque_true_nm"} <= set(
        table.column_names
    )
    meta = json.loads(table.schema.metadata[b"suvtwin.input_estimate"])
    assert meta["method"] == label and meta["seed"] == 4
    frame = table.to_pandas()
    run, _ = read_run(run_file)
    expected = estimate_run(run, method="AWIE" if label == "AWIE" else 0.9, measurement_std=1e-8, seed=4)
    assert frame["force_hat_n"].to_numpy() == pytest.approx(expected.estimate[0, :, 0])
    assert frame["torque_true_nm"].to_numpy() == pytest.approx(expected.truth_input[:, 1])
    u = frame[["force_true_n", "torque_true_nm"]].to_numpy()
    uh = frame[["force_hat_n", "torque_hat_nm"]].to_numpy()
    assert np.all(scores(u, uh)["aligned"] < (25.0 if label == "AWIE" else 80.0))


def test_a_run_without_suspension_forces_gives_estimates_only(run_file, tmp_path):
    table = pq.read_table(run_file)
    keep = [n for n in table.column_names if not n.endswith("_susp_force_n")]
    bare = tmp_path / "bare.parquet"
    pq.write_table(table.select(keep), bare)
    out = tmp_path / "inputs.parquet"
    assert main(["input-estimate", str(bare), "--out", str(out)]) == 0
    assert pq.read_table(out).column_names == [
        "t_s",
        "force_hat_n",
        "torque_hat_nm",
        "suspension_force_hat_n",
        "suspension_torque_hat_nm",
    ]


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (["--method", "KF"], "--method"),
        (["--fading", "0"], "--fading"),
        (["--heave-noise", "-1"], "--heave-noise"),
        (["--pitch-noise", "2"], "--pitch-noise"),
        (["--q", "0"], "--q"),
        (["--seed", "-1"], "--seed"),
    ],
)
def test_bad_options_exit_2_and_write_nothing(run_file, tmp_path, capsys, options, message):
    out = tmp_path / "inputs.parquet"
    assert main(["input-estimate", str(run_file), "--out", str(out), *options]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_missing_or_bad_run_file_exits_2(tmp_path, capsys):
    out = tmp_path / "inputs.parquet"
    assert main(["input-estimate", str(tmp_path / "none.parquet"), "--out", str(out)]) == 2
    pq.write_table(pq.read_table(_tiny_table(tmp_path)), tmp_path / "tiny.parquet")
    assert main(["input-estimate", str(tmp_path / "tiny.parquet"), "--out", str(out)]) == 2
    assert "pitch_rad" in capsys.readouterr().err
    assert not out.exists()


def _tiny_table(tmp_path):
    import pyarrow as pa

    path = tmp_path / "t.parquet"
    pq.write_table(pa.table({"t_s": [0.0, 0.001, 0.002, 0.003], "heave_m": [0.0] * 4}), path)
    return path
