"""Writing output files so that a failure never leaves a partial file.

Usual call: ``atomic_write(path, lambda tmp: table_to_parquet(tmp))``.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path

__all__ = ["atomic_write"]


def atomic_write(path: str | os.PathLike, write: Callable[[str], object]) -> None:
    """Call ``write(tmp_path)`` on a temporary file beside `path`, then rename it onto `path`.

    The rename is atomic on one file system: readers see the old file or the
    whole new one. If `write` raises, the temporary file is removed, `path` is
    untouched, and the exception propagates.
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise
