"""The compiled-function cache never serves machine code built from an older version of a callee.

numba's own cache key is the function's file and bytecode; a compiled callee or a constant
from another module is compiled in by value, so editing that module alone would otherwise
run stale code. Each case runs in fresh Python processes on a throw-away package (`pkg`: a
caller in pkg/main.py, what it compiles in from pkg/dep.py).
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from suvtwin.jit import compiled_inputs
from suvtwin.mjcf import kernel
from suvtwin.mjcf.vehicle import GRAVITY

DEP = """
from numba.extending import register_jitable

from suvtwin.jit import cached_njit

SCALE = {scale}
OFFSET = {offset}


@{decorator}
def scaled(x):
    return SCALE * x
"""

MAIN = """
from suvtwin.jit import cached_njit
from pkg.dep import OFFSET, scaled


@cached_njit
def f(x):
    return scaled(x) + OFFSET
"""

RUN = "from pkg.main import f; print(f(1.0), len(f.stats.cache_hits), len(f.stats.cache_misses))"


def _write_dep(folder: Path, scale: float, offset: float, stamp: int, decorator: str) -> None:
    path = folder / "pkg" / "dep.py"
    path.write_text(DEP.format(scale=scale, offset=offset, decorator=decorator))
    os.utime(path, (stamp, stamp))  # a distinct modification time, whatever the clock's resolution


def _run(folder: Path) -> tuple[float, int, int]:
    env = {**os.environ, "PYTHONPATH": str(folder), "PYTHONDONTWRITEBYTECODE": "1"}
    env.pop("NUMBA_CACHE_DIR", None)
    done = subprocess.run([sys.executable, "-c", RUN], cwd=folder, env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    value, hits, misses = done.stdout.split()
    return float(value), int(hits), int(misses)


@pytest.mark.parametrize(
    ("decorator", "change"),
    [
        ("cached_njit", {"scale": 5.0, "offset": 1.0}),  # a compiled callee's constant
        ("cached_njit", {"scale": 2.0, "offset": 7.0}),  # a constant the caller reads from another module
        ("register_jitable", {"scale": 5.0, "offset": 1.0}),  # a plain function numba compiles in
    ],
)
def test_changing_another_module_recompiles_the_caller(tmp_path, decorator, change):
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "__init__.py").write_text("")
    (tmp_path / "pkg" / "main.py").write_text(textwrap.dedent(MAIN))
    _write_dep(tmp_path, 2.0, 1.0, stamp=1_700_000_000, decorator=decorator)
    assert _run(tmp_path) == (3.0, 0, 1)  # compiled and saved
    assert _run(tmp_path) == (3.0, 1, 0)  # loaded from the cache
    _write_dep(tmp_path, change["scale"], change["offset"], stamp=1_700_000_100, decorator=decorator)
    value, hits, _ = _run(tmp_path)
    assert value == change["scale"] * 1.0 + change["offset"]
    assert hits == 0
    assert _run(tmp_path) == (value, 1, 0)  # the new code is cached in turn


def test_changing_a_callees_compile_options_recompiles_the_caller(tmp_path):
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "__init__.py").write_text("")
    (tmp_path / "pkg" / "main.py").write_text(textwrap.dedent(MAIN))
    _write_dep(tmp_path, 2.0, 1.0, stamp=1_700_000_000, decorator="cached_njit")
    assert _run(tmp_path) == (3.0, 0, 1)
    _write_dep(tmp_path, 2.0, 1.0, stamp=1_700_000_100, decorator='cached_njit(error_model="numpy")')
    assert _run(tmp_path) == (3.0, 0, 1)  # same code and constants, other options: compiled afresh


def test_the_kernel_key_covers_the_tyre_model_and_vehicle_constants():
    inputs = compiled_inputs(kernel.step_kernel)
    for callee in ("vertical_force", "vertical_stiffness", "tire_forces", "effective_rolling_radius"):
        assert f"suvtwin.mjcf.tire.{callee}" in inputs
    assert "suvtwin.mjcf.kernel._log_accelerations" in inputs
    assert inputs["suvtwin.mjcf.kernel._log_accelerations:GRAVITY"] == f"float:{GRAVITY!r}"


def test_the_key_is_the_same_in_every_process():
    """Set constants print in an order that depends on string hashing; the key must not."""
    code = (
        "from suvtwin.jit import compiled_inputs\n"
        "def f(x):\n"
        "    return x in {'alpha', 'beta', 'gamma', 'delta', 'epsilon'}\n"
        "print(sorted(compiled_inputs(f).items()))"
    )
    outputs = set()
    for seed in ("1", "2", "3"):
        env = {**os.environ, "PYTHONHASHSEED": seed}
        done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        outputs.add(done.stdout)
    assert len(outputs) == 1
