"""suvtwin run under faults (issue 16, reliability): killed with SIGKILL at three stages, damaged
cache files, two processes on one folder, a configuration with nothing to run. Each campaign ends
with the metrics of an uninterrupted run, byte for byte (every number is seeded).

A tiny campaign (4 runs of 8 s, two estimators, a 2-class GA of 8 × 2) keeps each run to seconds.
The kills are timed by polling for the files a stage writes."""

import fcntl
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from suvtwin.errors import InputError
from suvtwin.pipeline.campaign import preset, run_campaign
from suvtwin.pipeline.campaign.cache import LOCK_FILE, campaign_lock, sidecar, verify_cached, write_cached
from suvtwin.pipeline.cli import main

TINY = dict(
    monte_carlo_runs=4,
    duration_s=8.0,
    scenarios=[],
    estimators=["imm_synthetic", "joint"],
    identification={"classes": "AB", "pop_size": 8, "n_gen": 2, "duration_s": 2.0},
    chunk_size=1,
    premise_runs_per_class=0,
    monitor_leak_runs=0,
    monitor_warning_runs=0,
    input_estimation_seeds=0,
)
RUNS, ESTIMATES = 4, 8
RESULTS = ("metrics.csv", "monte_carlo.csv")


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """An uninterrupted campaign, and its settings as a --config file."""
    folder = tmp_path_factory.mktemp("faults")
    config = folder / "tiny.json"
    config.write_text(json.dumps(TINY))
    run_campaign(preset("quick", **TINY), folder / "reference", jobs=1)
    return folder / "reference", config


def _argv(out: Path, config: Path, jobs: int = 1) -> list[str]:
    return ["run", "--out", str(out), "--config", str(config), "--jobs", str(jobs), "--no-progress"]


def _start(out: Path, config: Path, log: Path, jobs: int = 1) -> subprocess.Popen:
    """`suvtwin run` in a process group of its own (so that its workers can be killed with it)."""
    argv = [sys.executable, "-m", "suvtwin.pipeline.cli", *_argv(out, config, jobs)]
    with open(log, "wb") as sink:
        return subprocess.Popen(argv, start_new_session=True, stdout=sink, stderr=subprocess.STDOUT)


def _count(folder: Path, pattern: str) -> int:
    """Finished files only (pathlib's glob also matches a killed writer's hidden temporary)."""
    return sum(not p.name.startswith(".") for p in folder.glob(pattern))


def _wait_for(proc: subprocess.Popen, ready, log: Path, timeout: float = 240.0) -> None:
    end = time.monotonic() + timeout
    while not ready():
        if proc.poll() is not None:
            pytest.fail(f"suvtwin run ended ({proc.returncode}) before the stage: {log.read_text()[-2000:]}")
        if time.monotonic() > end:
            os.killpg(proc.pid, signal.SIGKILL)
            pytest.fail("the stage never came")
        time.sleep(0.005)


def _kill_group(proc: subprocess.Popen) -> None:
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait()


def _resume_and_compare(out: Path, config: Path, reference: Path, capsys, jobs: int = 1) -> dict:
    assert main(_argv(out, config, jobs)) == 0
    for name in RESULTS:
        assert (out / name).read_bytes() == (reference / name).read_bytes(), name
    assert not list(out.rglob(".*tmp*"))
    capsys.readouterr()
    return json.loads((out / "campaign.json").read_text())


def _seed_with(out: Path, reference: Path, *parts: str) -> None:
    """Start `out` with the reference's finished `parts` (identification, runs)."""
    for part in parts:
        shutil.copytree(reference / part, out / part)


def test_killed_during_identification(reference, tmp_path, capsys):
    ref, config = reference
    out = tmp_path / "out"
    proc = _start(out, config, tmp_path / "log")
    _wait_for(proc, lambda: _count(out, "identification/*/class_A.json") == 1, tmp_path / "log")
    _kill_group(proc)
    assert proc.returncode == -signal.SIGKILL
    assert _count(out, "identification/*/class_B.json") == 0
    assert _count(out, "identification/*/params.json") == 0
    summary = _resume_and_compare(out, config, ref, capsys)
    assert summary["identification"]["classes_run"] == ["B"]  # class A was finished: reused
    assert summary["timings"]["simulated_runs"] == RUNS


def test_killed_during_simulation(reference, tmp_path, capsys):
    ref, config = reference
    out = tmp_path / "out"
    _seed_with(out, ref, "identification")
    proc = _start(out, config, tmp_path / "log")
    _wait_for(proc, lambda: _count(out, "runs/*.parquet") >= 1, tmp_path / "log")
    _kill_group(proc)
    done = _count(out, "runs/*.parquet")
    assert 1 <= done < RUNS and _count(out, "estimates/*/*.parquet") == 0
    summary = _resume_and_compare(out, config, ref, capsys)
    assert summary["identification"]["cached"]
    assert summary["timings"]["simulated_runs"] == RUNS - done
    assert summary["timings"]["estimates_made"] == ESTIMATES


def test_killed_during_estimation_with_workers_left_behind(reference, tmp_path, capsys):
    ref, config = reference
    out = tmp_path / "out"
    _seed_with(out, ref, "identification", "runs")
    proc = _start(out, config, tmp_path / "log", jobs=2)
    _wait_for(proc, lambda: _count(out, "estimates/*/*.parquet") >= 1, tmp_path / "log")
    os.kill(proc.pid, signal.SIGKILL)  # the parent alone: its pool workers are orphaned
    proc.wait()
    try:
        # the kernel released the parent's lock, and no orphaned worker holds a copy of it
        with open(out / LOCK_FILE, "rb") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    finally:
        _kill_group(proc)
    done = _count(out, "estimates/*/*.parquet")
    assert 1 <= done < ESTIMATES
    summary = _resume_and_compare(out, config, ref, capsys, jobs=2)
    assert summary["timings"]["simulated_runs"] == 0
    assert summary["timings"]["estimates_made"] == ESTIMATES - done


def _flip_a_bit(path: Path) -> None:
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x04
    path.write_bytes(bytes(data))


def _truncate(path: Path) -> None:
    with open(path, "r+b") as f:
        f.truncate(path.stat().st_size // 2)


def test_damaged_cache_files_are_reported_removed_and_made_again(reference, tmp_path, capsys):
    ref, config = reference
    out = tmp_path / "out"
    shutil.copytree(ref, out)
    run = {i: next((out / "runs").glob(f"mc_000{i}-*.parquet")) for i in range(RUNS)}
    damaged = [run[0], run[2]]
    _truncate(run[0])  # with its record: the hash differs
    sidecar(run[1]).unlink()  # no record (as written before records were kept), intact: reused
    sidecar(run[2]).unlink()
    _truncate(run[2])  # no record and unreadable
    joint = next(out.glob("estimates/joint-*/mc_0003-*.parquet"))
    _flip_a_bit(joint)  # one bit: read without complaint before hashes were recorded
    imm = next(out.glob("estimates/imm_synthetic-*/mc_0001-*.parquet"))
    sidecar(imm).write_text("not a digest\n")  # a damaged record: the file cannot be trusted
    params = next(out.glob("identification/*/params.json"))
    _flip_a_bit(params)  # remade from the (intact) class files, without the GA
    damaged += [joint, imm, params]
    capsys.readouterr()
    assert main(_argv(out, config)) == 0
    warnings = [line for line in capsys.readouterr().err.splitlines() if "campaign cache" in line]
    assert len(warnings) == len(damaged)
    for path in damaged:
        assert sum(str(path) in line and "removed, making it again" in line for line in warnings) == 1
    for name in RESULTS:
        assert (out / name).read_bytes() == (ref / name).read_bytes(), name
    summary = json.loads((out / "campaign.json").read_text())
    assert summary["identification"]["classes_run"] == []
    assert summary["timings"]["simulated_runs"] == 2 and summary["timings"]["estimates_made"] == 2
    assert sidecar(run[1]).is_file()  # the intact file without a record now has one
    assert all(sidecar(p).is_file() for p in run.values())


def test_verify_cached_by_kind(tmp_path, capsys):
    csv = tmp_path / "table.csv"
    write_cached(csv, lambda tmp: Path(tmp).write_text("a,b\n1,2\n"))
    assert sidecar(csv).read_text().endswith("  table.csv\n") and verify_cached(csv)
    csv.write_text("a,b\n1,3\n")
    assert not verify_cached(csv) and not csv.exists() and not sidecar(csv).exists()
    assert "table.csv is damaged" in capsys.readouterr().err
    legacy = tmp_path / "old.json"
    legacy.write_text('{"parameters": {}}')
    assert verify_cached(legacy) and sidecar(legacy).is_file()
    broken = tmp_path / "broken.json"
    broken.write_text('{"parameters": {')
    assert not verify_cached(broken) and not broken.exists()
    assert "broken.json is damaged (unreadable" in capsys.readouterr().err
    assert not verify_cached(tmp_path / "missing.parquet") and capsys.readouterr().err == ""


def test_a_second_process_on_the_folder_is_refused(reference, tmp_path, capsys):
    ref, config = reference
    out = tmp_path / "out"
    _seed_with(out, ref, "identification")
    proc = _start(out, config, tmp_path / "log")
    try:
        lock = out / LOCK_FILE
        holds = str(proc.pid)
        _wait_for(proc, lambda: lock.is_file() and lock.read_text().strip() == holds, tmp_path / "log")
        capsys.readouterr()
        assert main(_argv(out, config)) == 2
        err = capsys.readouterr().err
        assert f"campaign folder {str(out)!r} is in use by process {proc.pid}" in err
        assert err.count("\n") == 1
        assert proc.wait(timeout=240) == 0, (tmp_path / "log").read_text()
    finally:
        _kill_group(proc)
    for name in RESULTS:
        assert (out / name).read_bytes() == (ref / name).read_bytes(), name
    # in one process too: the lock is per open file, not per process
    with campaign_lock(out), pytest.raises(InputError, match=f"in use by process {os.getpid()}"):
        run_campaign(preset("quick", **TINY), out)


def test_a_configuration_with_nothing_to_run_is_refused_up_front(tmp_path, capsys):
    for settings, message in (({"monte_carlo_runs": 0, "scenarios": []}, "nothing to run"),
                              ({"estimators": []}, "estimators is empty")):  # fmt: skip
        config = tmp_path / "config.json"
        config.write_text(json.dumps(settings))
        capsys.readouterr()
        assert main(["run", "--out", str(tmp_path / "out"), "--config", str(config), "--no-progress"]) == 2
        assert message in capsys.readouterr().err
        assert not (tmp_path / "out").exists()
