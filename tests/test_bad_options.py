"""Bad options and bad files for every subcommand: exit 2, one line naming the problem, nothing written.

A table of (subcommand arguments, words the message must hold), run in-process through
:func:`suvtwin.pipeline.cli.main` (the heavier cases, with time and memory bounds, are in
``tests/test_bad_inputs.py``). Every case starts in an empty folder holding only the inputs it
needs, and checks that no file appeared.
"""

from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from suvtwin.pipeline.cli import main


def _run_file(folder: Path, *, drop: str | None = None, name: str = "run.parquet") -> Path:
    """A small measurement file: 2 s at 1 kHz, four corners, white noise, a true pressure."""
    n = 2000
    rng = np.random.default_rng(0)
    cols = {"t_s": np.arange(n) * 1e-3, "speed_mps": np.full(n, 15.0)}
    for c in ("fl", "fr", "rl", "rr"):
        cols[f"{c}_accel_sprung_mps2"] = rng.normal(0.0, 1.0, n)
        cols[f"{c}_accel_unsprung_mps2"] = rng.normal(0.0, 10.0, n)
        cols[f"{c}_pressure_kpa"] = np.full(n, 230.0)
    if drop is not None:
        del cols[drop]
    path = folder / name
    pq.write_table(pa.table(cols), path)
    return path


def _road_file(folder: Path, *, drop: str | None = None) -> Path:
    x = np.arange(5000) * 0.02
    cols = {"x_m": x, "z_left_m": 0.01 * np.sin(x), "z_right_m": 0.01 * np.cos(x)}
    if drop is not None:
        del cols[drop]
    path = folder / "road.parquet"
    pq.write_table(pa.table(cols), path)
    return path


def _file(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


def _garbage(folder: Path, name: str = "run.parquet") -> Path:
    path = folder / name
    path.write_bytes(np.random.default_rng(1).bytes(4096))
    return path


def _params(folder: Path, road_class: str, name: str, value: float) -> Path:
    """The shipped mode-parameter file with one value changed."""
    import json

    from suvtwin.estimators.tire_pressure import IDENTIFIED_FILE

    data = json.loads(IDENTIFIED_FILE.read_text())
    data["classes"][road_class][name] = value
    path = folder / "params.json"
    path.write_text(json.dumps(data))  # NaN as JSON's NaN extension, as Python writes it
    return path


OUT = "out.parquet"
_SHORT = ["simulate", "--road-class", "C", "--speed", "60", "--pressure", "230", "--duration", "2"]

CASES = [
    # road
    ("road_unknown_class", lambda d: ["road", "--class", "Z", "--out", OUT], ["--class", "A–H"]),
    ("road_level_not_a_level", lambda d: ["road", "--gd-n0", "2", "--out", OUT], ["--gd-n0"]),
    ("road_level_outside_its_class", lambda d: ["road", "--class", "C", "--gd-n0", "1e-3", "--out", OUT],
     ["outside class C"]),
    ("road_waviness", lambda d: ["road", "--class", "C", "--waviness", "5", "--out", OUT], ["--waviness"]),
    ("road_coarse_spacing", lambda d: ["road", "--class", "C", "--spacing", "0.1", "--out", OUT], ["--spacing"]),
    ("road_correlation", lambda d: ["road", "--class", "C", "--track-correlation", "1.5", "--out", OUT],
     ["--track-correlation"]),
    ("road_out_suffix", lambda d: ["road", "--class", "C", "--out", "road.csv"], ["--out", ".parquet"]),
    ("road_plot_suffix", lambda d: ["road", "--class", "C", "--out", OUT, "--plot", "p.jpg"], ["--plot", ".png"]),
    ("road_out_folder_missing", lambda d: ["road", "--class", "C", "--out", "nowhere/road.parquet"],
     ["does not exist"]),
    ("road_spec_missing", lambda d: ["road", "--spec", "none.yaml", "--out", OUT], ["does not exist"]),
    ("road_spec_suffix", lambda d: ["road", "--spec", str(_file(d, "r.txt", "x")), "--out", OUT], [".yaml"]),
    ("road_spec_malformed", lambda d: ["road", "--spec", str(_file(d, "r.yaml", "segments: [")), "--out", OUT],
     ["malformed"]),
    ("road_spec_unknown_field", lambda d: ["road", "--spec", str(_file(d, "r.yaml", "segment: []\n")),
                                           "--out", OUT], ["unknown field"]),
    # classify
    ("classify_missing_file", lambda d: ["classify", "none.parquet"], ["none.parquet"]),
    ("classify_band", lambda d: ["classify", str(_road_file(d)), "--band-low", "5", "--band-high", "1"],
     ["fit band"]),
    ("classify_band_zero", lambda d: ["classify", str(_road_file(d)), "--band-low", "0"], ["fit band"]),
    ("classify_missing_column", lambda d: ["classify", str(_road_file(d, drop="z_right_m"))], ["z_right_m"]),
    ("classify_not_parquet", lambda d: ["classify", str(_garbage(d, "road.parquet"))], ["road.parquet"]),
    # simulate (short form and scenario files)
    ("simulate_short_form_incomplete", lambda d: ["simulate", "--road-class", "C", "--out", OUT],
     ["--scenario", "--duration"]),
    ("simulate_duration", lambda d: [*_SHORT, "--duration", "-1", "--out", OUT], ["--duration"]),
    ("simulate_speed", lambda d: [*_SHORT, "--speed", "500", "--out", OUT], ["--speed"]),
    ("simulate_pressure", lambda d: [*_SHORT, "--pressure", "10", "--out", OUT], ["--pressure"]),
    ("simulate_timestep", lambda d: [*_SHORT, "--timestep", "0.1", "--out", OUT], ["--timestep"]),
    ("simulate_class", lambda d: [*_SHORT, "--road-class", "Q", "--out", OUT], ["--road-class"]),
    ("simulate_scenario_missing", lambda d: ["simulate", "--scenario", "none.yaml", "--out", OUT],
     ["does not exist"]),
    ("simulate_scenario_not_a_mapping", lambda d: ["simulate", "--scenario", str(_file(d, "s.yaml", "- 1\n")),
                                                   "--out", OUT], ["mapping"]),
    ("simulate_scenario_duration_missing", lambda d: ["simulate", "--scenario",
                                                      str(_file(d, "s.yaml", "road: flat\n")), "--out", OUT],
     ["duration_s"]),
    ("simulate_tire_missing", lambda d: [*_SHORT, "--tire", "none.tir", "--out", OUT], ["none.tir"]),
    # render
    ("render_fps", lambda d: ["render", str(_run_file(d)), "--out", "v.mp4", "--fps", "0"], ["--fps"]),
    ("render_width", lambda d: ["render", str(_run_file(d)), "--out", "v.mp4", "--width", "10"], ["--width"]),
    ("render_camera", lambda d: ["render", str(_run_file(d)), "--out", "v.mp4", "--camera", "top"],
     ["--camera"]),
    ("render_out_suffix", lambda d: ["render", str(_run_file(d)), "--out", "v.avi"], ["--out", ".mp4"]),
    # estimate
    ("estimate_corner", lambda d: ["estimate", str(_run_file(d)), "--corner", "xx", "--out", OUT], ["--corner"]),
    ("estimate_params_missing", lambda d: ["estimate", str(_run_file(d)), "--corner", "fl", "--estimator", "imm",
                                           "--params", "none.json", "--out", OUT], ["--params"]),
    ("estimate_seed", lambda d: ["estimate", str(_run_file(d)), "--corner", "fl", "--seed", "-1", "--out", OUT],
     ["--seed"]),
    ("estimate_garbage_run", lambda d: ["estimate", str(_garbage(d)), "--corner", "fl", "--out", OUT],
     ["run.parquet"]),
    ("estimate_run_missing", lambda d: ["estimate", "none.parquet", "--corner", "fl", "--out", OUT],
     ["none.parquet"]),
    ("estimate_params_nan", lambda d: ["estimate", str(_run_file(d)), "--corner", "fl", "--estimator", "imm", "--params", str(_params(d, "B", "ks", float("nan"))), "--out", OUT], ["classes.B.ks", "finite"]),
    ("estimate_params_negative", lambda d: ["estimate", str(_run_file(d)), "--corner", "fl", "--estimator", "imm", "--params", str(_params(d, "C", "cs", -5.0)), "--out", OUT], ["classes.C.cs", "> 0"]),
    # monitor
    ("monitor_placard", lambda d: ["monitor", str(_run_file(d)), "--out", OUT, "--placard", "10"], ["--placard"]),
    ("monitor_placard_and_reset", lambda d: ["monitor", str(_run_file(d)), "--out", OUT, "--placard", "230",
                                             "--reset-at", "0"], ["--placard", "--reset-at"]),
    ("monitor_corners", lambda d: ["monitor", str(_run_file(d)), "--out", OUT, "--corners", "fl,zz"],
     ["--corners"]),
    ("monitor_reset_outside", lambda d: ["monitor", str(_run_file(d)), "--out", OUT, "--reset-at", "1e6"],
     ["--reset-at"]),
    ("monitor_radius_spread", lambda d: ["monitor", str(_run_file(d)), "--out", OUT, "--placard", "230",
                                         "--radius-spread", "-1"], ["--radius-spread"]),
    ("monitor_garbage_run", lambda d: ["monitor", str(_garbage(d)), "--out", OUT], ["run.parquet"]),
    # input-estimate
    ("input_fading", lambda d: ["input-estimate", str(_run_file(d)), "--out", OUT, "--method", "CIE",
                                "--fading", "1.5"], ["--fading"]),
    ("input_noise", lambda d: ["input-estimate", str(_run_file(d)), "--out", OUT, "--heave-noise", "-1"],
     ["--heave-noise"]),
    ("input_q", lambda d: ["input-estimate", str(_run_file(d)), "--out", OUT, "--q", "0"], ["--q"]),
    ("input_method", lambda d: ["input-estimate", str(_run_file(d)), "--out", OUT, "--method", "XYZ"],
     ["--method"]),
    ("input_missing_columns", lambda d: ["input-estimate", str(_run_file(d)), "--out", OUT], ["heave"]),
    # road-estimate
    ("road_estimate_class", lambda d: ["road-estimate", str(_run_file(d)), "--out", OUT, "--class", "Z"],
     ["--class"]),
    ("road_estimate_filter", lambda d: ["road-estimate", str(_run_file(d)), "--out", OUT, "--filter", "XX"],
     ["--filter"]),
    ("road_estimate_axle", lambda d: ["road-estimate", str(_run_file(d)), "--out", OUT, "--axle", "middle"],
     ["--axle"]),
    ("road_estimate_noise", lambda d: ["road-estimate", str(_run_file(d)), "--out", OUT,
                                       "--measurement-std", "-1"], ["--measurement-std"]),
    # score
    ("score_not_an_estimate", lambda d: ["score", str(_run_file(d, name="e.parquet")), str(_run_file(d))],
     ["suvtwin estimate"]),
    ("score_estimate_missing", lambda d: ["score", "none.parquet", str(_run_file(d))], ["none.parquet"]),
    # identify
    ("identify_classes", lambda d: ["identify", "--out", "p.json", "--classes", "Q"], ["--classes"]),
    ("identify_generations", lambda d: ["identify", "--out", "p.json", "--generations", "0"], ["--generations"]),
    ("identify_pop", lambda d: ["identify", "--out", "p.json", "--pop", "2"], ["--pop"]),
    ("identify_corner", lambda d: ["identify", "--out", "p.json", "--corner", "xx"], ["--corner"]),
    ("identify_out_suffix", lambda d: ["identify", "--out", "p.txt"], ["--out", ".json"]),
    ("identify_duration", lambda d: ["identify", "--out", "p.json", "--duration", "-5"], ["--duration"]),
    # run
    ("run_jobs", lambda d: ["run", "--quick", "--out", "results", "--jobs", "0"], ["--jobs"]),
    ("run_config_missing", lambda d: ["run", "--quick", "--out", "results", "--config", "none.yaml"],
     ["does not exist"]),
    ("run_config_unknown_key", lambda d: ["run", "--quick", "--out", "results", "--config",
                                          str(_file(d, "c.yaml", "monte_carlo: 3\n"))], ["monte_carlo"]),
    ("run_config_bad_value", lambda d: ["run", "--quick", "--out", "results", "--config",
                                        str(_file(d, "c.yaml", "monte_carlo_runs: -3\n"))], ["monte_carlo_runs"]),
    ("run_params_missing", lambda d: ["run", "--quick", "--out", "results", "--params", "none.json"],
     ["--params"]),
]  # fmt: skip


@pytest.mark.parametrize(("name", "build", "words"), CASES, ids=[c[0] for c in CASES])
def test_bad_option_or_file_exits_2_with_one_line_and_writes_nothing(tmp_path, monkeypatch, capsys, name, build,
                                                                     words):  # fmt: skip
    monkeypatch.chdir(tmp_path)
    args = build(tmp_path)
    before = set(tmp_path.rglob("*"))
    capsys.readouterr()
    code = main(args)
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert err.count("\n") == 0 or "Usage" in err, err  # typer's own usage errors print a short box
    for word in words:
        assert word in err, err
    assert set(tmp_path.rglob("*")) == before  # nothing written
