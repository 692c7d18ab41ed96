"""The suvtwin CLI: files written, one clear message and exit 2 on bad input, nothing half-written."""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from suvtwin.pipeline.cli import main
from suvtwin.roads.profile import read_road


def test_road_then_classify(tmp_path, capsys):
    out, png = tmp_path / "road.parquet", tmp_path / "road.png"
    argv = [
        "road",
        "--class",
        "C",
        "--length",
        "300",
        "--spacing",
        "0.02",
        "--seed",
        "7",
        "--out",
        str(out),
        "--plot",
        str(png),
    ]
    assert main(argv) == 0
    road = read_road(out)
    assert road.x.size == 15001 and road.spec.segments[0].road_class == "C" and road.seed == 7
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000
    assert pq.read_table(out).column_names == ["x_m", "z_left_m", "z_right_m"]
    capsys.readouterr()
    assert main(["classify", str(out), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["left"]["class"] == "C" and result["right"]["class"] == "C"
    assert 1.5 < result["left"]["waviness"] < 2.5


def test_gd_n0_and_waviness_reach_the_road(tmp_path, capsys):
    out = tmp_path / "r.parquet"
    assert (
        main(
            [
                "road",
                "--gd-n0",
                "3e-5",
                "--waviness",
                "2.4",
                "--length",
                "1000",
                "--seed",
                "1",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    seg = read_road(out).spec.segments[0]
    assert (seg.gd_n0, seg.waviness, seg.label) == (3e-5, 2.4, "A")
    capsys.readouterr()
    assert main(["classify", str(out), "--json"]) == 0
    fit = json.loads(capsys.readouterr().out)["left"]
    assert fit["waviness"] == pytest.approx(2.4, abs=0.15)


def test_road_method_gaussian_with_other_waviness_reaches_the_road(tmp_path, capsys):
    out = tmp_path / "g.parquet"
    argv = ["road", "--gd-n0", "3e-4", "--waviness", "2.4", "--method", "gaussian", "--length", "2000",
            "--seed", "3", "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    road = read_road(out)
    assert road.spec.method == "gaussian" and road.spec.segments[0].waviness == 2.4
    capsys.readouterr()
    assert main(["classify", str(out), "--json"]) == 0
    fit = json.loads(capsys.readouterr().out)["left"]
    assert fit["waviness"] == pytest.approx(2.4, abs=0.2)


def test_spec_file_with_segments_and_obstacles(tmp_path):
    spec = tmp_path / "road.yaml"
    spec.write_text(
        "segments:\n"
        "  - {length_m: 150, road_class: A}\n"
        "  - {length_m: 150, road_class: D}\n"
        "method: shape-filter\n"
        "tracks: identical\n"
        "obstacles:\n"
        "  - {kind: sine_bump, position_m: 20, length_m: 1.0, height_m: 0.08, track: left}\n"
    )
    out = tmp_path / "r.parquet"
    assert main(["road", "--spec", str(spec), "--seed", "2", "--out", str(out)]) == 0
    road = read_road(out)
    assert [s.road_class for s in road.spec.segments] == ["A", "D"]
    assert road.z[0, 1025] - road.z[1, 1025] == pytest.approx(0.08, abs=1e-6)  # x = 20.5 m


BAD_ROAD_ARGS = [
    (["--class", "Z"], "--class must be one of A–H, got 'Z'"),
    (["--class", "C", "--length", "0"], "--length must be in (0, 200000] m"),
    (["--class", "C", "--length", "-5"], "--length must be in (0, 200000] m"),
    (["--class", "C", "--spacing", "0"], "--spacing must be > 0 m"),
    (["--class", "C", "--spacing", "0.1"], "--spacing must be ≤ 0.05 m"),
    (["--class", "C", "--gd-n0", "1e-3"], "outside class C"),
    (["--class", "C", "--waviness", "5"], "--waviness must be in [1, 3.5]"),
    (["--class", "C", "--method", "shape-filter", "--waviness", "2.5"], "needs --method superposition or"),
    (["--class", "C", "--track-correlation", "1.5"], "--track-correlation must be in [0, 1]"),
    (["--class", "C", "--seed", "-1"], "--seed must be ≥ 0"),
    ([], "give --class"),
]


@pytest.mark.parametrize("extra, message", BAD_ROAD_ARGS)
def test_bad_road_input_exits_2_and_keeps_existing_output(tmp_path, capsys, extra, message):
    out = tmp_path / "road.parquet"
    out.write_bytes(b"previous result")
    assert main(["road", *extra, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and err.count("\n") == 1
    assert out.read_bytes() == b"previous result"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["road.parquet"]


def test_bad_spec_file_names_the_field(tmp_path, capsys):
    spec = tmp_path / "s.toml"
    spec.write_text('[[segments]]\nlength_m = 100\nroad_class = "Q"\n')
    assert main(["road", "--spec", str(spec), "--out", str(tmp_path / "r.parquet")]) == 2
    err = capsys.readouterr().err
    assert "segments[0].road_class" in err and "A–H" in err
    spec.write_text("segments = [")
    assert main(["road", "--spec", str(spec), "--out", str(tmp_path / "r.parquet")]) == 2
    assert "malformed" in capsys.readouterr().err
    assert not (tmp_path / "r.parquet").exists()


def test_short_road_warns_but_runs(tmp_path, capsys):
    assert main(["road", "--class", "B", "--length", "50", "--out", str(tmp_path / "r.parquet")]) == 0
    assert "0.01 cycle/m" in capsys.readouterr().err


def _write(path, **columns):
    pq.write_table(pa.table(columns), path)


@pytest.mark.parametrize(
    "columns, message",
    [
        ({"x_m": np.arange(100.0), "z_left_m": np.zeros(100)}, "lacks column(s) z_right_m"),
        (
            {"x_m": np.arange(100.0), "z_left_m": np.r_[np.nan, np.zeros(99)], "z_right_m": np.zeros(100)},
            "finite",
        ),
        (
            {"x_m": np.arange(100.0)[::-1], "z_left_m": np.zeros(100), "z_right_m": np.zeros(100)},
            "strictly increasing",
        ),
        (
            {
                "x_m": np.r_[np.arange(50.0), np.arange(50.0) * 2 + 50],
                "z_left_m": np.zeros(100),
                "z_right_m": np.zeros(100),
            },
            "uniformly spaced",
        ),
    ],
)
def test_classify_rejects_malformed_files(tmp_path, capsys, columns, message):
    path = tmp_path / "bad.parquet"
    _write(path, **columns)
    assert main(["classify", str(path)]) == 2
    assert message in capsys.readouterr().err


def test_classify_missing_and_non_parquet_file(tmp_path, capsys):
    assert main(["classify", str(tmp_path / "none.parquet")]) == 2
    assert "does not exist" in capsys.readouterr().err
    (tmp_path / "text.parquet").write_text("not parquet")
    assert main(["classify", str(tmp_path / "text.parquet")]) == 2
    assert "not a readable Parquet file" in capsys.readouterr().err


@pytest.mark.parametrize("command", [[], ["road"], ["classify"]])
def test_help_explains_units(command, capsys):
    assert main([*command, "--help"]) == 0
    text = capsys.readouterr().out
    assert "Usage" in text
    if command == ["road"]:
        for needle in ("cycles/m", "m³", "A–H", "0.05"):
            assert needle in text


def test_console_script_is_installed(tmp_path):
    beside_python = Path(sys.executable).with_name("suvtwin")
    exe = str(beside_python) if beside_python.exists() else shutil.which("suvtwin")
    done = subprocess.run(
        [exe, "road", "--class", "Q", "--out", str(tmp_path / "r.parquet")], capture_output=True, text=True
    )
    assert done.returncode == 2 and "--class must be one of A–H" in done.stderr
