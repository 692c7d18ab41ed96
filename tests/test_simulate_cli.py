"""Scenario validation and the simulate / render commands: one clear message, exit 2, nothing written."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from suvtwin.errors import InputError
from suvtwin.mjcf.vehicle import CORNERS
from suvtwin.pipeline.cli import main
from suvtwin.pipeline.scenario import load_scenario, parse_scenario
from suvtwin.pipeline.simulator import OUTPUT_COLUMNS, read_run

SCENARIO_YAML = """\
duration_s: 2.0
timestep_s: 0.001
output_rate_hz: 500
seed: 3
speed_kmh: [[0, 50], [2, 60]]
road:
  segments:
    - {length_m: 30, road_class: B}
    - {length_m: 30, gd_n0: 3.0e-4}
  tracks: correlated
  obstacles:
    - {kind: sine_bump, position_m: 25, length_m: 1.0, height_m: 0.03, track: left}
pressure_kpa: {fl: 230, fr: 230, rl: 220, rr: 220}
pressure_events:
  - {tire: fl, start_s: 0.5, end_s: 1.5, target_kpa: 180}
load:
  - {mass_kg: 143, position_m: [0, 0, 0]}
noise: {accel_sprung_mps2: 0.5, accel_unsprung_mps2: 0.5}
"""


def test_scenario_file_runs_and_writes_every_column(tmp_path, capsys):
    spec = tmp_path / "s.yaml"
    spec.write_text(SCENARIO_YAML)
    out = tmp_path / "run.parquet"
    assert main(["simulate", "--scenario", str(spec), "--out", str(out), "--no-progress"]) == 0
    table, meta = read_run(out)
    assert tuple(table.columns) == OUTPUT_COLUMNS
    required = ["t_s", "speed_mps", "steer_rad", "lat_accel_mps2", "yaw_rate_radps", "heave_m", "pitch_rad"]
    for c in CORNERS:
        for field in ("accel_sprung_mps2", "accel_unsprung_mps2", "accel_sprung_true_mps2", "z_sprung_m",
                      "z_unsprung_m", "v_sprung_mps", "v_unsprung_mps", "road_z_m", "pressure_kpa",
                      "tire_stiffness_npm", "tire_fz_n", "susp_force_n", "wheel_speed_radps"):  # fmt: skip
            required.append(f"{c}_{field}")
    assert set(required) <= set(table.columns)
    assert len(table) == 1000  # 2 s at 500 Hz
    assert np.all(np.isfinite(table.to_numpy()))
    # the pressure event: 230 kPa until 0.5 s, a linear ramp, 180 kPa from 1.5 s
    t, p = table.t_s.to_numpy(), table.fl_pressure_kpa.to_numpy()
    assert np.all(p[t <= 0.5] == 230) and np.all(p[t >= 1.5] == pytest.approx(180))
    assert p[np.argmin(np.abs(t - 1.0))] == pytest.approx(205, abs=0.2)
    assert np.all(table.rl_pressure_kpa == 220)
    # sensor noise: measured minus true has the configured standard deviation
    assert np.std(table.fl_accel_sprung_mps2 - table.fl_accel_sprung_true_mps2) == pytest.approx(0.5, rel=0.1)
    assert meta["scenario"]["load"][0]["mass_kg"] == 143
    assert meta["total_mass_kg"] == pytest.approx(1788 + 2 * 61.14 + 2 * 52.75 + 143)
    assert "mujoco" in meta["versions"]


def test_short_form(tmp_path, capsys):
    out = tmp_path / "run.parquet"
    argv = ["simulate", "--road-class", "C", "--speed", "60", "--pressure", "180", "--duration", "1",
            "--seed", "1", "--out", str(out), "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    table, meta = read_run(out)
    assert np.all(table[[f"{c}_pressure_kpa" for c in CORNERS]].to_numpy() == 180)
    assert meta["scenario"]["road"]["segments"][0]["road_class"] == "C"
    assert "x real time" in capsys.readouterr().out


BAD_SHORT = [
    (["--road-class", "Z"], "--road-class must be one of A–H"),
    (["--speed", "-5"], "--speed must be in [0, 200] km/h"),
    (["--pressure", "20"], "--pressure must be in [80, 350] kPa"),
    (["--pressure", "500"], "--pressure must be in [80, 350] kPa"),
    (["--duration", "0"], "--duration must be in (0, 3600] s"),
    (["--timestep", "0.01"], "--timestep must be in [1e-4, 2e-3] s"),
]


@pytest.mark.parametrize("change, message", BAD_SHORT)
def test_bad_short_form_exits_2_without_output(tmp_path, capsys, change, message):
    args = {"--road-class": "C", "--speed": "60", "--pressure": "180", "--duration": "1"}
    args.update(dict(zip(change[::2], change[1::2], strict=True)))
    out = tmp_path / "run.parquet"
    argv = ["simulate", *[x for kv in args.items() for x in kv], "--out", str(out), "--no-progress"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


BAD_SCENARIOS = [
    ({"pressure_kpa": {"fl": 200, "fr": 200, "rl": 200, "xx": 200}}, "pressure_kpa"),
    ({"pressure_kpa": 400}, "pressure must be in [80, 350] kPa"),
    (
        {"pressure_events": [{"tire": "fq", "start_s": 0, "end_s": 1, "target_kpa": 180}]},
        "pressure_events[0].tire",
    ),
    (
        {"pressure_events": [{"tire": "fl", "start_s": 0, "end_s": 9, "target_kpa": 180}]},
        "after the run's end",
    ),
    ({"pressure_events": [{"tire": "fl", "start_s": 2, "end_s": 1, "target_kpa": 180}]}, "must not precede"),
    ({"speed_kmh": -10}, "speed must be in [0, 200] km/h"),
    (
        {"road": {"segments": [{"length_m": 100, "road_class": "Q"}]}},
        "road.segments[0].road_class: must be one of A–H",
    ),
    ({"duration_s": -1}, "duration_s"),
    ({"output_rate_hz": 300}, "must divide the step rate"),
    ({"bogus": 1}, "bogus: unknown field"),
]


@pytest.mark.parametrize("change, message", BAD_SCENARIOS)
def test_bad_scenario_names_the_field(tmp_path, capsys, change, message):
    base = {"duration_s": 2.0, "road": {"segments": [{"length_m": 100, "road_class": "B"}]}}
    with pytest.raises(InputError) as info:
        parse_scenario({**base, **change})
    assert message in str(info.value)
    path = tmp_path / "s.yaml"
    import yaml

    path.write_text(yaml.safe_dump({**base, **change}))
    out = tmp_path / "run.parquet"
    assert main(["simulate", "--scenario", str(path), "--out", str(out), "--no-progress"]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_road_too_short_for_the_run(tmp_path, capsys):
    path = tmp_path / "s.yaml"
    path.write_text("duration_s: 10\nspeed_kmh: 60\nroad:\n  segments: [{length_m: 100, road_class: B}]\n")
    assert (
        main(["simulate", "--scenario", str(path), "--out", str(tmp_path / "r.parquet"), "--no-progress"])
        == 2
    )
    assert "road is 100 m long but the run needs" in capsys.readouterr().err


def test_malformed_and_missing_scenario_files(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text("duration_s = [")
    assert main(["simulate", "--scenario", str(path), "--out", str(tmp_path / "r.parquet")]) == 2
    assert "malformed" in capsys.readouterr().err
    assert (
        main(["simulate", "--scenario", str(tmp_path / "none.yaml"), "--out", str(tmp_path / "r.parquet")])
        == 2
    )
    assert "does not exist" in capsys.readouterr().err
    with pytest.raises(InputError, match="must hold a mapping"):
        (tmp_path / "list.yaml").write_text("- 1\n- 2\n")
        load_scenario(tmp_path / "list.yaml")


def test_scenario_and_short_form_are_exclusive(tmp_path, capsys):
    path = tmp_path / "s.yaml"
    path.write_text(SCENARIO_YAML)
    argv = ["simulate", "--scenario", str(path), "--speed", "50", "--out", str(tmp_path / "r.parquet")]
    assert main(argv) == 2
    assert "not both" in capsys.readouterr().err


def _simulated_run(tmp_path) -> Path:
    run = tmp_path / "run.parquet"
    argv = ["simulate", "--road-class", "B", "--speed", "40", "--pressure", "220", "--duration", "1",
            "--out", str(run), "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    return run


def _offscreen_gl_missing(env: dict) -> str | None:
    """Why `suvtwin render` cannot work here (None if it can): what makes render.py raise
    RenderUnavailable — no offscreen OpenGL context for MuJoCo's Renderer, or no MP4 writer —
    probed in a fresh process, since MUJOCO_GL is read when mujoco is first imported."""
    probe = (
        "import mujoco, imageio.v2, imageio_ffmpeg; imageio_ffmpeg.get_ffmpeg_exe(); "
        "mujoco.Renderer(mujoco.MjModel.from_xml_string('<mujoco/>'), 64, 64).close()"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, timeout=120)
    if done.returncode == 0:
        return None
    lines = done.stderr.strip().splitlines()
    return lines[-1] if lines else f"exit status {done.returncode}"


def test_render_writes_a_video(tmp_path):
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    missing = _offscreen_gl_missing(env)
    if missing is not None:
        pytest.skip(f"no offscreen OpenGL context or MP4 writer (MUJOCO_GL={env['MUJOCO_GL']}): {missing}")
    run = _simulated_run(tmp_path)
    video = tmp_path / "run.mp4"
    code = "import sys; from suvtwin.pipeline.cli import main; sys.exit(main(sys.argv[1:]))"
    done = subprocess.run(
        [sys.executable, "-c", code, "render", str(run), "--out", str(video), "--fps", "10",
         "--width", "320", "--height", "192"],
        capture_output=True, text=True, env=env, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert video.stat().st_size > 1000
    import imageio.v2 as imageio

    frames = imageio.get_reader(str(video))
    first = frames.get_data(0)
    assert first.shape == (192, 320, 3) and first.std() > 5  # a picture, not a blank frame


def test_render_without_offscreen_gl_says_why_and_writes_nothing(tmp_path, capsys, monkeypatch):
    # whatever this machine has: MuJoCo's Renderer fails as it does where no GL context exists
    import mujoco

    def no_context(*args, **kwargs):
        raise RuntimeError("gladLoadGL error")

    run = _simulated_run(tmp_path)
    monkeypatch.setenv("MUJOCO_GL", "egl")
    monkeypatch.setattr(mujoco, "Renderer", no_context)
    video = tmp_path / "run.mp4"
    assert main(["render", str(run), "--out", str(video), "--width", "320", "--height", "192"]) == 1
    assert "OpenGL" in capsys.readouterr().err
    assert not video.exists() and not list(Path(tmp_path).glob(".run.mp4*"))


def test_a_wheel_beyond_the_road_strip_is_measured_and_said(tmp_path, capsys):
    # an open-loop steering series cannot be checked before the run: a steady 0.05 rad from 5 s on
    # a rough road turns the car off the straight 4 m strip (a 57 m circle); the share of samples with
    # a wheel centre beyond |y| = 2 m, from the chassis pose and the wheels' places, goes into the
    # metadata and the console warns. A lane-kept run stays on it.
    scenario = tmp_path / "s.yaml"
    road = "road: {segments: [{length_m: 300, road_class: C}]}\n"
    for steering, off in (("{mode: series, series: [[0, 0.0], [5, 0.0], [6, 0.05], [12, 0.05]]}", True),
                          ("{mode: lane, lane_y_m: 0.5}", False)):  # fmt: skip
        scenario.write_text(f"duration_s: 12\nseed: 5\nspeed_kmh: 60\n{road}steering: {steering}\n")
        out = tmp_path / "run.parquet"
        assert main(["simulate", "--scenario", str(scenario), "--out", str(out), "--no-progress"]) == 0
        table, metadata = read_run(out)
        share = metadata["off_road_share"]
        t, y, yaw = table["t_s"].to_numpy(), table["y_m"].to_numpy(), table["yaw_rad"].to_numpy()
        if off:
            # every wheel is within 1.5 m of the chassis centre: all off beyond 3.5 m, none within 0.5 m
            assert np.mean(np.abs(y) > 3.5) <= share <= np.mean(np.abs(y) > 0.5)
            assert share > 0.2 and "beyond the 4 m road strip" in capsys.readouterr().err
            # and the monitor, reading that run, says so beside its estimates
            assert main(["monitor", str(out), "--out", str(tmp_path / "m.parquet"), "--placard", "230"]) == 0
            assert f"beyond the simulated road strip on {100 * share:.1f} %" in capsys.readouterr().out
        else:
            assert share == 0.0 and np.abs(y).max() < 0.7 and np.abs(yaw).max() < 0.05 and t[-1] > 11.9
            assert "road strip" not in capsys.readouterr().err
