"""The campaign's content-addressed cache: every unit of work is one file named by a hash.

Usual calls: ``key = digest({"scenario": ..., "model": model_fingerprint()})``; a unit of work is
written with ``write_cached(path, lambda tmp: ...)`` and reused only ``if verify_cached(path)``;
``with campaign_lock(out): ...`` holds the campaign folder for one process;
:func:`remove_stale_temporaries` deletes what a killed run left behind.

Integrity: :func:`write_cached` writes a file as :func:`suvtwin.files.atomic_write` does (a
temporary file renamed into place) and, before the rename, the SHA-256 of its bytes beside it in
``<name>.sha256`` (the ``sha256sum`` format: ``sha256sum -c`` checks it). :func:`verify_cached`
checks a file against that record before it is reused; a file without a record (written before
records were kept, or by code that writes its own files) is read in full instead and its hash then
recorded. A damaged file (truncated, bits flipped, unreadable) is reported on stderr in one line
naming it, removed with its record, and made again.

Locking: :func:`campaign_lock` takes an exclusive ``flock`` on ``<out>/.campaign.lock`` (which
holds the owner's process id) for the whole campaign, without waiting: a second process on the
same folder gets :class:`~suvtwin.errors.InputError` naming the folder and the owner. The kernel
releases the lock when the owner ends, also on SIGKILL, so a killed campaign never blocks the next.

A key hashes everything that determines a result: for a run its scenario, the code and model
files (:func:`source_digest` of :data:`SIMULATION_SOURCES`) and the library versions; for an
estimate its run file, estimator, parameter file, estimator code (:data:`ESTIMATION_SOURCES`)
and initial estimate; for a parameter file the identification settings and code. Results made
by other code get other keys, so an upgrade never reuses stale work.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from suvtwin.errors import InputError, RunError, cut
from suvtwin.files import atomic_write, package_versions

try:
    import fcntl
except ImportError:  # Windows: no flock; the campaign folder is not locked there
    fcntl = None  # type: ignore[assignment]

__all__ = [
    "ESTIMATION_SOURCES",
    "IDENTIFICATION_SOURCES",
    "LOCK_FILE",
    "PREMISE_SOURCES",
    "SIMULATION_SOURCES",
    "campaign_lock",
    "digest",
    "drop_inherited_lock",
    "file_sha256",
    "lock_identity",
    "model_fingerprint",
    "record_digest",
    "remove_stale_temporaries",
    "sidecar",
    "source_digest",
    "verify_cached",
    "write_cached",
]

LOCK_FILE = ".campaign.lock"
"""The lock file in a campaign folder (never deleted: deleting a lock file races with its next user)."""

SIMULATION_SOURCES = ("suvtwin.mjcf", "suvtwin.pipeline.simulator", "suvtwin.pipeline.scenario",
                      "suvtwin.roads.profile", "suvtwin.roads.spec", "suvtwin.roads.iso8608",
                      "suvtwin.tire_stiffness", "suvtwin.tir")  # fmt: skip
"""What a ground-truth run is made by (besides its scenario): modules and packages of suvtwin."""
IDENTIFICATION_SOURCES = (*SIMULATION_SOURCES, "suvtwin.identification",
                          "suvtwin.pipeline.identification_runs", "suvtwin.quarter_car_law")  # fmt: skip
"""What a parameter file is made by (besides its settings)."""
ESTIMATION_SOURCES = ("suvtwin.estimators", "suvtwin.pipeline.estimator_registry",
                      "suvtwin.pipeline.estimation", "suvtwin.pipeline.campaign",
                      "suvtwin.quarter_car_law", "suvtwin.tire_stiffness", "suvtwin.tir")  # fmt: skip
"""What an estimate is made by (besides its run, estimator and parameter file)."""
PREMISE_SOURCES = (*ESTIMATION_SOURCES, "suvtwin.pipeline.premise", "suvtwin.pipeline.scoring",
                   "suvtwin.roads")  # fmt: skip
"""What paper 000's premise check is made by (besides its runs per class and seed)."""


def digest(obj: object, n: int = 12) -> str:
    """First `n` hex digits of the SHA-256 of `obj` as sorted JSON."""
    return hashlib.sha256(json.dumps(obj, sort_keys=True, default=str).encode()).hexdigest()[:n]


def source_digest(sources: tuple[str, ...]) -> str:
    """Hash of the code and model files of `sources` (suvtwin modules or packages, with their
    package data): results made by other code get other keys, so an upgrade never reuses stale
    work. Works the same from a source checkout and from an installed wheel."""
    sha = hashlib.sha256()
    for source in sources:
        spec = importlib.util.find_spec(source)
        if spec is None or spec.origin is None:
            raise RunError(f"campaign: cannot find the code of {source}")
        if spec.submodule_search_locations:  # a package: every code and model file under it
            root = Path(next(iter(spec.submodule_search_locations)))
            files = sorted(f for f in root.rglob("*") if "__pycache__" not in f.relative_to(root).parts)
        else:
            root, files = Path(spec.origin).parent, [Path(spec.origin)]
        for f in files:
            if f.is_file() and f.suffix in (".py", ".toml", ".xml", ".tir"):
                sha.update(f"{source}/{f.relative_to(root).as_posix()}".encode())
                sha.update(f.read_bytes())
    return sha.hexdigest()[:16]


def model_fingerprint(sources: tuple[str, ...] = SIMULATION_SOURCES) -> dict:
    """What, besides a scenario, decides a result: the code and model files and the library versions."""
    return {"code": source_digest(sources), "versions": package_versions(("suvtwin", "mujoco", "numpy"))}


def remove_stale_temporaries(out: Path) -> None:
    """Delete temporary files a killed run left behind (finished files are never temporary). Only
    with the folder locked (:func:`campaign_lock`): another campaign's temporaries are live files."""
    for pattern in ("runs/.*.tmp*", "estimates/*/.*.tmp*", "identification/*/.*.tmp*", "premise/.*.tmp*",
                    "identification/.*.tmp*", "monitor/*/.*.tmp*", "road_estimation/.*.tmp*",
                    "lateral_detection/.*.tmp*", "lateral_detection/runs/*/.*.tmp*",
                    ".*.tmp*"):  # fmt: skip
        for path in out.glob(pattern):
            path.unlink(missing_ok=True)


# ---------------------------------------------------------------- integrity of cached files
def sidecar(path: str | os.PathLike) -> Path:
    """Where the SHA-256 of the cached file `path` is recorded: ``<name>.sha256`` beside it."""
    path = Path(path)
    return path.with_name(path.name + ".sha256")


def file_sha256(path: str | os.PathLike) -> str:
    """The SHA-256 of a file's bytes, as 64 hex digits."""
    sha = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            sha.update(block)
    return sha.hexdigest()


def _record(path: Path, hexdigest: str) -> None:
    text = f"{hexdigest}  {path.name}\n"
    atomic_write(sidecar(path), lambda tmp: Path(tmp).write_text(text, encoding="ascii"))


def record_digest(path: str | os.PathLike) -> None:
    """Record the SHA-256 of the finished file `path` beside it (for files written by other code)."""
    _record(Path(path), file_sha256(path))


def write_cached(path: str | os.PathLike, write: Callable[[str], object]) -> None:
    """Write a cached file as :func:`suvtwin.files.atomic_write` does (``write(tmp)`` on a temporary
    file, then a rename onto `path`), recording the SHA-256 of its bytes beside it *before* the
    rename: a file in place always has its record. A kill between the two leaves a record without a
    file, which is harmless (the file is made again and the record replaced)."""
    path = Path(path)

    def write_and_record(tmp: str) -> None:
        write(tmp)
        _record(path, file_sha256(tmp))

    atomic_write(path, write_and_record)


def _recorded_digest(path: Path) -> str | None:
    """The SHA-256 recorded for `path`: None without a record, "" for a malformed one."""
    try:
        fields = sidecar(path).read_bytes().decode("ascii").split()
    except FileNotFoundError:
        return None
    except (OSError, UnicodeDecodeError):
        return ""
    if len(fields) == 2 and fields[1] == path.name and len(fields[0]) == 64:
        if all(c in "0123456789abcdef" for c in fields[0]):
            return fields[0]
    return ""


def _read_problem(path: Path) -> str | None:
    """Read a cached file in full by its kind: None if it reads, else what went wrong."""
    try:
        if path.suffix == ".parquet":
            import pyarrow as pa
            import pyarrow.parquet as pq

            try:
                pq.read_table(path)
            except pa.ArrowException as error:
                return cut(str(error).replace("\n", " "), 120)
        elif path.suffix == ".json":
            json.loads(path.read_text(encoding="utf-8"))
        elif path.suffix == ".csv":
            import pandas as pd

            pd.read_csv(path)
        else:
            return f"no way to check a {path.suffix or 'suffix-less'} file"
    except (OSError, ValueError) as error:  # json, pandas and UnicodeDecodeError are ValueErrors
        return cut(str(error).replace("\n", " "), 120)
    return None


def verify_cached(path: str | os.PathLike) -> bool:
    """Whether an intact cached file is at `path`, to be reused.

    With a recorded SHA-256 (:func:`write_cached`) the file's bytes must match it; without one the
    file must read in full (Parquet, JSON, CSV), and its hash is then recorded. A damaged file is
    reported on stderr (one line naming it), removed with its record, and False returned: the
    caller makes it again. Missing file: False, silently.
    """
    path = Path(path)
    if not path.is_file():
        return False
    recorded = _recorded_digest(path)
    if recorded is None:  # written before records were kept, or by code that writes its own files
        problem = _read_problem(path)
        if problem is None:
            record_digest(path)
            return True
        problem = f"unreadable: {problem}"
    elif not recorded:
        problem = f"its record {sidecar(path).name} is malformed"
    elif recorded == file_sha256(path):
        return True
    else:
        problem = "its SHA-256 differs from the one recorded when it was written"
    print(f"suvtwin: warning: campaign cache: {path} is damaged ({problem}); removed, making it again",
          file=sys.stderr, flush=True)  # fmt: skip
    path.unlink(missing_ok=True)
    sidecar(path).unlink(missing_ok=True)
    return False


# ---------------------------------------------------------------- one process per campaign folder
@contextmanager
def campaign_lock(out: str | os.PathLike) -> Iterator[int | None]:
    """Hold the campaign folder `out` (which must exist) for this process; yields the lock's file
    descriptor (None where there is no ``flock``: Windows).

    Non-blocking: if another process holds it, :class:`~suvtwin.errors.InputError` "campaign folder
    X is in use by process PID". The lock is an ``flock`` on ``out/.campaign.lock``: the kernel
    drops it when its holder ends, however it ends, so a lock left by a killed run does not block.
    Child processes forked while it is held share it: a pool worker should close its copy
    (:func:`drop_inherited_lock`), or a worker orphaned by a killed parent would keep the folder.
    """
    out = Path(out)
    path = out / LOCK_FILE
    if fcntl is None:
        yield None
        return
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    except OSError as error:
        problem = f"--out: cannot write in the campaign folder {str(out)!r} ({error.strerror})"
        raise InputError(problem) from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 32, 0).decode("ascii", errors="replace").strip()
            who = f"process {holder}" if holder.isdigit() else "another process"
            raise InputError(
                f"campaign folder {str(out)!r} is in use by {who} (another suvtwin run): "
                "wait for it to end, or give another --out"
            ) from None
        except OSError as error:
            raise RunError(f"cannot lock the campaign folder {str(out)!r} ({error.strerror})") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        try:
            yield fd
        finally:
            os.ftruncate(fd, 0)  # still held: nobody else reads a stale id
    finally:
        os.close(fd)  # releases the lock (with every forked copy closed)


def lock_identity(fd: int | None) -> tuple[int, int, int] | None:
    """What :func:`drop_inherited_lock` needs to find the lock in a forked child: fd, device, inode."""
    if fd is None:
        return None
    st = os.fstat(fd)
    return fd, st.st_dev, st.st_ino


def drop_inherited_lock(identity: tuple[int, int, int] | None) -> None:
    """In a forked pool worker: close the worker's copy of the campaign lock (the parent keeps the
    lock). Checks that the descriptor is still the lock file before closing it (a worker started by
    spawn or forkserver has no copy, and the number may be another file there)."""
    if identity is None:
        return
    fd, device, inode = identity
    try:
        st = os.fstat(fd)
    except OSError:
        return
    if (st.st_dev, st.st_ino) == (device, inode):
        os.close(fd)
