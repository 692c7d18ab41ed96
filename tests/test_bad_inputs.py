"""Bad inputs end with one message and exit 2, fast and in bounded memory, writing nothing (issue 16).

Each case runs the installed command line in a child process that reports its own peak memory
(``VmHWM`` of ``/proc/self/status``), so a case that allocates or expands without bound shows up as time or
memory, not as a hung test.
"""

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

_CHILD = """
import sys
from suvtwin.pipeline.cli import main
code = main(sys.argv[1:])
# this process's own peak (VmHWM is per address space; getrusage's maxrss would carry the parent's
# over fork and exec on Linux)
hwm = [line for line in open("/proc/self/status") if line.startswith("VmHWM")]
peak_mb = float(hwm[0].split()[1]) / 1024 if hwm else 0.0
print(f"PEAK_MB {peak_mb:.0f}", file=sys.stderr)
sys.exit(code)
"""


def _run(args: list[str], cwd: Path) -> tuple[int, str, float, float]:
    """Exit code, stderr (without the peak line), wall seconds and peak memory (MB) of `suvtwin args`
    (Linux; 0 where /proc is missing)."""
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", _CHILD, *args], cwd=cwd, capture_output=True, text=True,
                          timeout=60)  # fmt: skip
    wall = time.perf_counter() - start
    lines = done.stderr.splitlines()
    peak = float(next(x for x in lines if x.startswith("PEAK_MB")).split()[1])
    message = "\n".join(x for x in lines if not x.startswith("PEAK_MB"))
    return done.returncode, message, wall, peak


def _alias_bomb(path: Path) -> Path:
    """Nine levels of nine aliases: 9⁹ ≈ 387 million strings once expanded."""
    lines = ['a0: &a0 ["x","x","x","x","x","x","x","x","x"]']
    for level in range(1, 9):
        lines.append(f"a{level}: &a{level} [" + ",".join([f"*a{level - 1}"] * 9) + "]")
    path.write_text("\n".join(lines) + "\n")
    return path


def _unknown_keys(path: Path) -> Path:
    """A 6 MB JSON scenario of 100 000 unknown keys."""
    path.write_text(json.dumps({f"k{i}": "x" * 50 for i in range(100_000)}))
    return path


def _oversize(path: Path) -> Path:
    path.write_text("# padding\n" * 900_000)  # 9 MB
    return path


def _long_spec(path: Path) -> Path:
    path.write_text("segments:\n  - {length_m: 1.0e9, road_class: C}\n")
    return path


ISSUE_CASES = {"alias_bomb_scenario", "alias_bomb_road_spec", "road_length_1e9", "road_spec_length_1e9"}
"""The cases with issue 16's bound: peak memory under 300 MB. The others load the campaign or the whole
scenario validation (pydantic, MuJoCo's vehicle model; numba compiling on a fresh clone) first and
are held to 600 MB."""

def _text(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


_NAN_STEER = "duration_s: 2.0\nroad: flat\nsteering: {mode: series, series: [[0.0, 0.0], [1.0, .nan]]}\n"
_INF_LANE = "duration_s: 2.0\nroad: flat\nsteering: {lane_y_m: .inf}\n"
_NAN_LOAD = "duration_s: 2.0\nroad: flat\nload: [{mass_kg: 50, position_m: [0.0, .nan, 0.0]}]\n"
_NAN_VEHICLE = "duration_s: 2.0\nroad: flat\nvehicle: {chassis: {mass: .nan}}\n"
_OVERLAP = """duration_s: 10.0
road: flat
pressure_events:
  - {tire: fl, start_s: 1.0, end_s: 5.0, target_kpa: 200}
  - {tire: fr, start_s: 4.0, end_s: 6.0, target_kpa: 180}
  - {tire: fl, start_s: 4.0, end_s: 6.0, target_kpa: 180}
"""
_INF_SEGMENT = "segments:\n  - {length_m: .inf, road_class: C}\n"


def _run_file(path: Path, *, dt: float = 1e-3, speed: float = 15.0, spike: float | None = None,
              drop: str | None = None) -> Path:  # fmt: skip
    """A small measurement file of all four corners (2 s, white noise), with one fault."""
    import numpy as np
    import pyarrow as pa
    import pyarrow.parquet as pq

    n = 2000
    rng = np.random.default_rng(0)
    cols = {"t_s": np.arange(n) * dt, "speed_mps": np.full(n, speed)}
    for c in ("fl", "fr", "rl", "rr"):
        cols[f"{c}_accel_sprung_mps2"] = rng.normal(0.0, 1.0, n)
        cols[f"{c}_accel_unsprung_mps2"] = rng.normal(0.0, 10.0, n)
        cols[f"{c}_pressure_kpa"] = np.full(n, 230.0)
    if spike is not None:
        cols["fl_accel_unsprung_mps2"][100] = spike
    if drop is not None:
        del cols[drop]
    pq.write_table(pa.table(cols), path)
    return path


def _estimate(t: Path, **fault) -> list[str]:
    run = _run_file(t / "run.parquet", **fault)
    return ["estimate", str(run), "--corner", "fl", "--out", str(t / "e.parquet")]


def _monitor(t: Path, **fault) -> list[str]:
    return ["monitor", str(_run_file(t / "run.parquet", **fault)), "--out", str(t / "m.parquet")]


def _simulate(t: Path, text: str) -> list[str]:
    return ["simulate", "--scenario", str(_text(t / "s.yaml", text)), "--out", str(t / "out.parquet")]


def _folder(path: Path) -> Path:
    path.mkdir()
    return path


CASES = [
    # (id, argument builder (tmp -> args), words the message must hold)
    ("out_is_a_folder", lambda t: ["road", "--class", "C", "--out", str(_folder(t / "road.parquet"))],
     ["is a folder"]),
    ("out_under_proc", lambda t: ["road", "--class", "C", "--out", "/proc/self/road.parquet"],
     ["cannot write in folder", "/proc/self"]),
    ("campaign_out_is_a_file", lambda t: ["run", "--quick", "--out", str(_text(t / "results", "x"))],
     ["is a file"]),
    ("campaign_out_under_proc", lambda t: ["run", "--quick", "--out", "/proc/suvtwin-results"],
     ["cannot make folder"]),
    ("estimate_time_in_ms", lambda t: _estimate(t, dt=1.0), ["t_s", "time in ms"]),
    ("estimate_time_in_us", lambda t: _estimate(t, dt=1000.0), ["t_s", "time in ms or µs"]),
    ("estimate_negative_speed", lambda t: _estimate(t, speed=-15.0), ["speed_mps", "0–100 m/s"]),
    ("estimate_accel_1e30", lambda t: _estimate(t, spike=1e30), ["fl_accel_unsprung_mps2", "1000"]),
    ("estimate_missing_column", lambda t: _estimate(t, drop="fl_accel_sprung_mps2"),
     ["fl_accel_sprung_mps2"]),
    ("monitor_time_in_ms", lambda t: _monitor(t, dt=1.0), ["t_s", "time in ms"]),
    ("monitor_negative_speed", lambda t: _monitor(t, speed=-15.0), ["speed_mps"]),
    ("monitor_missing_column", lambda t: _monitor(t, drop="rr_accel_unsprung_mps2"),
     ["rr_accel_unsprung_mps2"]),
    ("scenario_nan_in_steering_series", lambda t: _simulate(t, _NAN_STEER),
     ["steering.series[1][1]", "finite"]),
    ("scenario_infinite_lane_offset", lambda t: _simulate(t, _INF_LANE), ["steering.lane_y_m", "finite"]),
    ("scenario_nan_load_position", lambda t: _simulate(t, _NAN_LOAD), ["load[0].position_m[1]", "finite"]),
    ("scenario_nan_vehicle_override", lambda t: _simulate(t, _NAN_VEHICLE), ["vehicle", "finite"]),
    ("scenario_overlapping_pressure_events", lambda t: _simulate(t, _OVERLAP),
     ["pressure_events[0] and [2]", "tyre fl"]),
    ("road_spec_infinite_segment", lambda t: ["road", "--spec", str(_text(t / "r.yaml", _INF_SEGMENT)),
                                              "--out", str(t / "out.parquet")],
     ["segments[0].length_m", "finite"]),
    ("alias_bomb_scenario", lambda t: ["simulate", "--scenario", str(_alias_bomb(t / "s.yaml")),
                                       "--out", str(t / "out.parquet")], ["alias"]),
    ("alias_bomb_road_spec", lambda t: ["road", "--spec", str(_alias_bomb(t / "r.yaml")),
                                        "--out", str(t / "out.parquet")], ["alias"]),
    ("alias_bomb_campaign", lambda t: ["run", "--config", str(_alias_bomb(t / "c.yaml")),
                                       "--out", str(t / "out")], ["alias"]),
    ("road_length_1e9", lambda t: ["road", "--class", "C", "--length", "1e9",
                                   "--out", str(t / "out.parquet")], ["--length", "200000"]),
    ("road_spacing_too_fine", lambda t: ["road", "--class", "C", "--length", "1000", "--spacing", "1e-9",
                                         "--out", str(t / "out.parquet")], ["grid points", "20,000,000"]),
    ("road_spec_length_1e9", lambda t: ["road", "--spec", str(_long_spec(t / "r.yaml")),
                                        "--out", str(t / "out.parquet")], ["total length", "200000"]),
    ("scenario_unknown_keys", lambda t: ["simulate", "--scenario", str(_unknown_keys(t / "s.json")),
                                         "--out", str(t / "out.parquet")],
     ["unknown field", "more problems"]),
    ("scenario_oversize", lambda t: ["simulate", "--scenario", str(_oversize(t / "s.yaml")),
                                     "--out", str(t / "out.parquet")], ["bytes", "8,000,000"]),
]  # fmt: skip


@pytest.mark.parametrize(("name", "build", "words"), CASES, ids=[c[0] for c in CASES])
def test_bad_input_is_refused_fast_in_bounded_memory_and_writes_nothing(tmp_path, name, build, words):
    args = build(tmp_path)
    before = set(tmp_path.iterdir())  # the inputs the case made
    code, message, wall, peak_mb = _run(args, tmp_path)
    assert code == 2, message
    assert message.startswith("suvtwin: error:") and message.count("\n") == 0, message
    for word in words:
        assert word in message, message
    assert len(message) < 2000  # a quoted value or a list of problems is cut
    assert wall < 10.0  # the issue asks < 2 s for the bomb and the length; start-up included here
    assert peak_mb < (300.0 if name in ISSUE_CASES else 600.0), peak_mb
    assert set(tmp_path.iterdir()) == before  # nothing written


_STEP_NAN = """
import sys, warnings
import mujoco, numpy as np
if sys.argv[1] == "suvtwin":
    import suvtwin.pipeline.simulator  # noqa: F401  (installs the warning handler)
xml = "<mujoco><worldbody><body><freejoint/><geom size='.1'/></body></worldbody></mujoco>"
m = mujoco.MjModel.from_xml_string(xml)
d = mujoco.MjData(m)
d.qpos[0] = np.nan
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    mujoco.mj_step(m, d)
print(len(caught))
"""


def test_mujoco_warnings_become_python_warnings_not_a_log_in_the_working_folder(tmp_path):
    # without suvtwin's handler MuJoCo writes MUJOCO_LOG.TXT into the working folder (the control)
    plain, ours = tmp_path / "plain", tmp_path / "ours"
    plain.mkdir()
    ours.mkdir()
    subprocess.run([sys.executable, "-c", _STEP_NAN, "plain"], cwd=plain, check=True, capture_output=True)
    assert (plain / "MUJOCO_LOG.TXT").exists()
    done = subprocess.run([sys.executable, "-c", _STEP_NAN, "suvtwin"], cwd=ours, check=True,
                          capture_output=True, text=True)  # fmt: skip
    assert int(done.stdout.strip()) >= 1  # the bad QPOS warning, as a Python warning
    assert not (ours / "MUJOCO_LOG.TXT").exists()


def test_score_never_counts_a_nan_estimate_as_converged(tmp_path):
    from suvtwin.pipeline.scoring import run_metrics

    t = np.arange(100) * 0.1
    m = run_metrics(t, np.full(100, 230.0), np.full(100, np.nan), np.full(100, 5.0), tolerance=12.5)
    assert np.isnan(m.time_to_converge_s) and m.inside_1sigma == 0.0 and m.inside_2sigma == 0.0
    # NaN at the end: not converged, even though the earlier samples were within the tolerance
    estimate = np.full(100, 231.0)
    estimate[-5:] = np.nan
    late_nan = run_metrics(t, np.full(100, 230.0), estimate, np.full(100, 5.0), tolerance=12.5)
    assert np.isnan(late_nan.time_to_converge_s)


def test_score_names_the_missing_columns_of_an_estimate_file(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    run = _run_file(tmp_path / "run.parquet")
    code, message, _, _ = _run(["estimate", str(run), "--corner", "fl", "--out", str(tmp_path / "e.parquet")],
                               tmp_path)  # fmt: skip
    assert code == 0, message
    table = pq.read_table(tmp_path / "e.parquet")
    pq.write_table(table.drop(["pressure_sigma_kpa"]).replace_schema_metadata(table.schema.metadata),
                   tmp_path / "bad.parquet")  # fmt: skip
    code, message, _, _ = _run(["score", str(tmp_path / "bad.parquet"), str(run)], tmp_path)
    assert code == 2 and "pressure_sigma_kpa" in message, message
    _ = pa  # pyarrow is needed to write the file


def test_a_write_that_fails_midway_is_one_message_and_keeps_the_earlier_file(tmp_path, monkeypatch, capsys):
    # a full disk while the Parquet file is written: exit 1, one line, the earlier road file untouched,
    # no temporary file left
    import errno

    import pyarrow.parquet as pq

    from suvtwin.pipeline.cli import main

    out = tmp_path / "road.parquet"
    assert main(["road", "--class", "C", "--length", "200", "--out", str(out)]) == 0
    before = out.read_bytes()
    real = pq.write_table

    def full_disk(table, where, *args, **kwargs):
        real(table.slice(0, 10), where, *args, **kwargs)  # part of it lands, then the disk is full
        raise OSError(errno.ENOSPC, "No space left on device", str(where))

    monkeypatch.setattr(pq, "write_table", full_disk)
    capsys.readouterr()
    assert main(["road", "--class", "C", "--length", "200", "--seed", "5", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.startswith("suvtwin: error: No space left on device") and err.count("\n") == 1, err
    assert out.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["road.parquet"]
