"""Writing output files so that a failure never leaves a partial file.

Usual call: ``atomic_write(path, lambda tmp: table_to_parquet(tmp))``.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from suvtwin.errors import InputError

if TYPE_CHECKING:
    import pyarrow as pa

__all__ = ["atomic_write", "package_versions", "read_parquet_table", "save_figure"]


def atomic_write(path: str | os.PathLike, write: Callable[[str], object]) -> None:
    """Call ``write(tmp_path)`` on a temporary file beside `path`, then rename it onto `path`.

    The rename is atomic on one file system: readers see the old file or the
    whole new one. If `write` raises, the temporary file is removed, `path` is
    untouched, and the exception propagates.
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=f".tmp{path.suffix}")
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp creates 0600; give the file the usual permissions
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def read_parquet_table(path: str | os.PathLike, *, what: str) -> pa.Table:
    """Read a Parquet file, or raise InputError naming `what` (e.g. "road file") and the problem."""
    import pyarrow as pa  # here: suvtwin.files is imported by commands that never touch Parquet
    import pyarrow.parquet as pq

    path = Path(path)
    if not path.is_file():
        raise InputError(f"{what} {str(path)!r} does not exist")
    try:
        return pq.read_table(path)
    except (pa.ArrowException, OSError) as error:
        raise InputError(f"{what} {str(path)!r} is not a readable Parquet file ({error})") from None


def save_figure(fig, path: str | os.PathLike, *, dpi: int = 100) -> None:
    """Save a matplotlib figure as PNG atomically, then close it (also on failure)."""
    import matplotlib.pyplot as plt

    try:
        atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=dpi, format="png"))
    finally:
        plt.close(fig)


def package_versions(names: tuple[str, ...]) -> dict[str, str]:
    """Installed version of each package in `names` ("unknown" if absent), for output metadata."""
    from importlib import metadata

    out = {}
    for name in names:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "unknown"
    return out
