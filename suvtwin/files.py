"""Reading input files safely and writing output files so that a failure never leaves a partial file.

Usual calls: ``atomic_write(path, lambda tmp: table_to_parquet(tmp))``;
``data = read_settings(path, what="scenario file")``.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from suvtwin.errors import InputError, cut

if TYPE_CHECKING:
    import pyarrow as pa

__all__ = ["MAX_SETTINGS_BYTES", "atomic_write", "iter_parquet_batches", "package_versions",
           "read_parquet_schema", "read_parquet_table", "read_settings", "save_figure"]

MAX_SETTINGS_BYTES = 8_000_000
"""Largest settings file (scenario, road description, campaign configuration) read, bytes: a
scenario's longest series (a steering or speed table) at 1 kHz for an hour is well below."""


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


def read_parquet_table(path: str | os.PathLike, *, what: str, columns: list[str] | None = None) -> pa.Table:
    """Read a Parquet file (only `columns` if given, each of which it must have), or raise InputError
    naming `what` (e.g. "road file") and the problem."""
    import pyarrow as pa  # here: suvtwin.files is imported by commands that never touch Parquet
    import pyarrow.parquet as pq

    path = _parquet_path(path, what)
    try:
        return pq.read_table(path, columns=columns)
    except (pa.ArrowException, OSError) as error:
        raise InputError(f"{what} {str(path)!r} is not a readable Parquet file ({error})") from None


def read_parquet_schema(path: str | os.PathLike, *, what: str) -> pa.Schema:
    """A Parquet file's schema (column names, types and its key–value metadata) without its data, or
    raise InputError naming `what` and the problem."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    path = _parquet_path(path, what)
    try:
        return pq.read_schema(path)
    except (pa.ArrowException, OSError) as error:
        raise InputError(f"{what} {str(path)!r} is not a readable Parquet file ({error})") from None


def iter_parquet_batches(path: str | os.PathLike, *, what: str, columns: list[str], rows: int):
    """The `columns` of a Parquet file in consecutive record batches of at most `rows` rows (fewer at
    the end of a row group), in file order: a file larger than memory read in bounded memory. A
    file that cannot be read raises InputError naming `what` and the problem."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    path = _parquet_path(path, what)
    try:
        # without pre-buffering: with it (pyarrow 26) every range read stays cached until the file
        # closes, the whole file's columns in the end (measured: +1.5 kB a row of 15 columns)
        with pq.ParquetFile(path, pre_buffer=False) as file:
            yield from file.iter_batches(batch_size=rows, columns=columns, use_threads=False)
    except (pa.ArrowException, OSError) as error:
        raise InputError(f"{what} {str(path)!r} is not a readable Parquet file ({error})") from None


def _parquet_path(path: str | os.PathLike, what: str) -> Path:
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{what} {str(path)!r} does not exist")
    return path


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


def read_settings(path: str | os.PathLike, *, what: str) -> object:
    """The mapping in a settings file (.yaml, .yml, .toml or .json), for validation by the caller.

    Refused with :class:`InputError` naming `what` and the path: a missing file, one larger than
    :data:`MAX_SETTINGS_BYTES`, an unknown suffix, malformed text, and YAML aliases (``*name``):
    a settings file has no use for them, and nested ones expand exponentially ("billion laughs").
    Parser messages are cut to a readable length.
    """
    import json
    import tomllib

    import yaml

    path = Path(path)
    if not path.is_file():
        raise InputError(f"{what}: file {str(path)!r} does not exist")
    size = path.stat().st_size
    if size > MAX_SETTINGS_BYTES:
        raise InputError(f"{what}: {str(path)!r} is {size:,} bytes, more than {MAX_SETTINGS_BYTES:,}")
    suffix = path.suffix.lower()
    if suffix not in (".yaml", ".yml", ".toml", ".json"):
        raise InputError(f"{what}: file must be .yaml, .yml, .toml or .json, got {str(path)!r}")
    try:
        text = path.read_text(encoding="utf-8")
        if suffix == ".toml":
            return tomllib.loads(text)
        if suffix == ".json":
            return json.loads(text)
        return yaml.load(text, Loader=_no_alias_loader())  # noqa: S506 - a SafeLoader that refuses aliases
    except (tomllib.TOMLDecodeError, json.JSONDecodeError, yaml.YAMLError, UnicodeDecodeError) as error:
        message = cut(str(error).replace("\n", " "), 300)
        raise InputError(f"{what}: {str(path)!r} is malformed: {message}") from None


def _no_alias_loader():
    import yaml

    class NoAliasLoader(yaml.SafeLoader):
        """yaml's SafeLoader that raises on an alias instead of composing it."""

        def compose_node(self, parent, index):
            if self.check_event(yaml.AliasEvent):
                event = self.peek_event()
                line = event.start_mark.line + 1 if event.start_mark else "?"
                raise yaml.YAMLError(f"YAML aliases (*{event.anchor}, line {line}) are not accepted")
            return super().compose_node(parent, index)

    return NoAliasLoader
