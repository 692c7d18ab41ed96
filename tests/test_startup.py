"""A fast command line: what each command imports, and the pieces that replaced slow imports.

Timings themselves are in ``bench/startup.py`` (they depend on the machine); here the
imports that made them slow are kept out, and the replacements are checked against the
libraries they stand in for.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.fft

from suvtwin.roads.profile import fast_fft_length


def _modules_after(code: str) -> set[str]:
    code += "\nimport json, sys; print(json.dumps(sorted(sys.modules)))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return set(json.loads(done.stdout.strip().splitlines()[-1]))


def test_help_loads_no_numerical_library():
    code = "from suvtwin.pipeline.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n    pass"
    loaded = _modules_after(code)
    for heavy in ("numpy", "pandas", "scipy", "matplotlib", "mujoco", "numba", "pyarrow", "pydantic", "rich"):
        assert heavy not in loaded, f"`suvtwin --help` imports {heavy}"


def test_simulate_loads_no_plotting_pandas_or_scipy_signal(tmp_path):
    out = tmp_path / "run.parquet"
    code = (
        "from suvtwin.pipeline.cli import main\n"
        f"assert main(['simulate', '--road-class', 'C', '--speed', '60', '--pressure', '200', '--duration', "
        f"'0.5', '--seed', '1', '--out', {str(out)!r}, '--no-progress']) == 0\n"
        "import os; assert os.environ.get('MUJOCO_GL') == GL, 'the command changed MUJOCO_GL'"
    )
    gl = os.environ.get("MUJOCO_GL")
    loaded = _modules_after(f"GL = {gl!r}\n" + code)
    assert out.is_file()
    for heavy in ("pandas", "matplotlib", "scipy.signal", "scipy.fft", "scipy.stats", "rich"):
        assert heavy not in loaded, f"`suvtwin simulate` imports {heavy}"
    if gl is None:  # MuJoCo imported without its OpenGL backends (GLFW's loader starts a subprocess)
        assert "glfw" not in loaded


def test_fast_fft_length_is_scipys_next_fast_len():
    sizes = [*range(1, 5000), 40_000, 40_001, 65_537, 99_999, 1_000_003, 2**24 + 1]
    assert [fast_fft_length(n) for n in sizes] == [scipy.fft.next_fast_len(n, real=True) for n in sizes]
    with pytest.raises(ValueError):
        fast_fft_length(0)


@pytest.mark.parametrize("n_fft", [1200, 40_000, 50_625, 102_400, 163_840])
def test_numpy_inverse_fft_is_scipys_bit_for_bit(n_fft):
    """Roads generated before the switch from scipy.fft to numpy.fft keep their bytes."""
    rng = np.random.default_rng(n_fft)
    spectrum = rng.standard_normal((2, n_fft // 2 + 1)) + 1j * rng.standard_normal((2, n_fft // 2 + 1))
    ours = np.fft.irfft(spectrum, n=n_fft, axis=-1)
    assert np.array_equal(ours, scipy.fft.irfft(spectrum, n=n_fft, axis=-1))
