"""Writing results: atomic files and folders, JSON with non-finite numbers, the environment record.

Every file the project writes (trajectories, figures, tables, agents, learning curves) goes
through `write_atomic` or `write_folder_atomic`: readers, and a run restarted after a kill, see
the previous complete file or folder or the new one, never a partial write. `environment` is the
one record of what produced a result (package versions and the git commit of the code).

One output folder, one run: `output_lock` holds an exclusive lock on a folder for the run that
writes it (a second run is refused with the holder's pid) and removes the temporary files of
runs killed mid-write; `replace_outputs` removes the files a previous run with other arguments
wrote and this one did not (so no stale figure sits beside new tables).
"""

from __future__ import annotations

import contextlib
import functools
import json
import math
import os
import platform
import re
import shutil
import subprocess
import tempfile
import tomllib
import zipfile
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import asdict, is_dataclass
from importlib import metadata
from pathlib import Path
from typing import IO, Any, Literal

import numpy as np

__all__ = [
    "LOCK_FILE",
    "OUTPUTS_FILE",
    "FolderInUseError",
    "environment",
    "git_commit",
    "json_default",
    "jsonable",
    "machine",
    "numpy_dispatch",
    "output_lock",
    "parse_toml",
    "process_alive",
    "read_toml",
    "remove_temporaries",
    "replace_outputs",
    "temporary_prefix",
    "versions",
    "write_atomic",
    "write_folder_atomic",
    "write_json",
    "write_text",
    "zip_is_whole",
]

# Distributions whose versions determine a result (Python is added).
PACKAGES = ("auv-gym", "numpy", "numba", "gymnasium", "stable-baselines3", "torch")
_ROOT = Path(__file__).resolve().parents[2]  # the checkout holding the auv_gym package
LOCK_FILE = ".lock"  # in an output folder: its run's pid, flock-ed while the run lasts
OUTPUTS_FILE = ".outputs.json"  # in an output folder: the files its last run wrote
# Temporary names of the atomic writers (`temporary_prefix`, then mkstemp's 8 random characters
# and ".tmp") and of the folder `write_folder_atomic` sets aside while swapping: tagged, so that
# cleaning a killed run's leftovers can never take a user's ".notes.abcdefgh.tmp" or ".x.old2".
TEMPORARY_TAG = "auv-gym"
TEMPORARY = re.compile(
    rf"\..+\.{TEMPORARY_TAG}\.[A-Za-z0-9_]{{8}}\.tmp|\..+\.{TEMPORARY_TAG}-old\d+"
)
TEMPORARY_DEPTH = 4  # folder levels searched: OUT/episodes/<scenario>/<policy>/ is 3


def temporary_prefix(target: str | os.PathLike) -> str:
    """The ``prefix`` of ``tempfile.mkstemp(prefix=..., suffix=".tmp", dir=target's folder)``
    for a temporary that becomes ``target``: `remove_temporaries` knows it by its tag."""
    return f".{Path(target).name}.{TEMPORARY_TAG}."


def write_atomic(path: str | os.PathLike, write: Callable[[IO[bytes]], Any]) -> Path:
    """Call ``write(file)`` on a temporary file beside ``path``, then rename it over ``path``.

    Readers see the old file or the complete new one, never a partial write; the temporary
    file is removed if ``write`` fails. Permissions follow the umask, as for `open`.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=temporary_prefix(target), suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, target)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return target


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def zip_is_whole(path: str | os.PathLike, members: Iterable[str] = ()) -> bool:
    """Whether ``path`` is a zip archive holding ``members`` whose every member reads back
    with its checksum. A file cut short by a full disk or a copy is not, though its tail may
    be a whole zip stored inside it (torch's .pth files in an SB3 model.zip): name a member
    of the outer archive in ``members``."""
    try:
        with zipfile.ZipFile(path) as archive:
            return set(members) <= set(archive.namelist()) and archive.testzip() is None
    except (OSError, EOFError, zipfile.BadZipFile, ValueError):
        return False


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write UTF-8 text atomically (`write_atomic`)."""
    return write_atomic(path, lambda fh: fh.write(text.encode("utf-8")))


def write_folder_atomic(path: str | os.PathLike, fill: Callable[[Path], Any]) -> Path:
    """Call ``fill(folder)`` on an empty temporary folder beside ``path``, then swap it in.

    The swap is two renames (old folder aside, new folder in place) and the old folder is
    deleted afterwards, so readers see the previous complete folder or the new one. The
    temporary folder is removed if ``fill`` fails.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=temporary_prefix(target), suffix=".tmp", dir=target.parent))
    try:
        os.chmod(tmp, 0o777 & ~_umask())  # as `mkdir` would (mkdtemp makes it private)
        fill(tmp)
        old = target.with_name(f".{target.name}.{TEMPORARY_TAG}-old{os.getpid()}")
        if target.exists():
            os.replace(target, old)
        os.replace(tmp, target)
        shutil.rmtree(old, ignore_errors=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return target


def json_default(obj: Any) -> Any:
    """``json.dumps(default=...)``: dataclasses as dicts, numpy as Python, paths by their data.

    An `auv_gym.paths.Path` becomes {"type", "data"}, a file path its string; anything else its
    repr, so a record of keyword arguments never fails to serialise.
    """
    if is_dataclass(obj) and not isinstance(obj, type):
        return {"type": type(obj).__name__, **asdict(obj)}
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    if hasattr(obj, "data") and hasattr(obj, "kind"):  # an auv_gym.paths.Path
        return {"type": type(obj).__name__, "data": np.asarray(obj.data).tolist()}
    return repr(obj)


def jsonable(value: Any, non_finite: Literal["null", "text"] = "null") -> Any:
    """A copy of ``value`` that strict JSON can hold: numpy scalars as Python numbers, mappings
    and sequences converted item by item, and non-finite floats (which JSON lacks) replaced.

    ``non_finite="null"``: NaN and ±inf become null. ``"text"``: NaN becomes null and ±inf
    "inf" / "-inf", which ``float()`` reads back.
    """
    if isinstance(value, Mapping):
        return {k: jsonable(v, non_finite) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v, non_finite) for v in value]
    if isinstance(value, (np.integer, np.bool_)):
        return value.item()
    if isinstance(value, (float, np.floating)):
        value = float(value)
        if math.isfinite(value):
            return value
        if non_finite == "text" and math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return None
    return value


def write_json(
    path: str | os.PathLike, data: Any, indent: int | None = 1, sort_keys: bool = False
) -> Path:
    """Write ``data`` as JSON (objects JSON lacks through `json_default`) atomically.

    Non-finite floats are written as Python's json writes them (NaN, Infinity: read back by
    `json.loads`); convert with `jsonable` first for strict JSON.
    """
    text = json.dumps(data, indent=indent, sort_keys=sort_keys, default=json_default)
    return write_text(path, text + "\n")


@functools.cache
def versions() -> dict[str, str]:
    """Python's version and those of the packages that determine a result (or "not installed")."""
    found = {"python": platform.python_version()}
    for name in PACKAGES:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = "not installed"
    return found


@functools.cache
def git_commit() -> str | None:
    """The commit of the checkout this code runs from (None outside a git checkout).

    Read once per process: the code a run started from, even if the checkout moves on.
    """
    if not (_ROOT / ".git").exists():  # e.g. an installed copy: not the checkout's code
        return None
    try:
        done = subprocess.run(
            ["git", "-C", str(_ROOT), "rev-parse", "HEAD"],
            capture_output=True,
            text=True,
            timeout=10,
            check=False,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    commit = done.stdout.strip()
    return commit if done.returncode == 0 and commit else None


def numpy_dispatch() -> tuple[list[str], list[str]] | None:
    """(NumPy's dispatched SIMD levels, those this CPU runs and NUMPY_DISABLE_CPU_FEATURES left
    on), from NumPy's private tables (`numpy._core` from NumPy 2, `numpy.core` before); None
    where neither exists."""
    try:
        from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    except ImportError:
        try:
            from numpy.core._multiarray_umath import __cpu_dispatch__, __cpu_features__
        except ImportError:  # NumPy's private layout changed: say so rather than guess
            return None
    dispatched = list(__cpu_dispatch__)
    return dispatched, [name for name in dispatched if __cpu_features__.get(name)]


@functools.cache
def machine() -> dict[str, Any]:
    """The CPU choices a result's last digits depend on: {"numpy_simd": NumPy's dispatched SIMD
    levels in use (e.g. ["X86_V3", "X86_V4", "AVX512_ICL"]), "blas": OpenBLAS's kernel (e.g.
    "openblas SkylakeX")}; None where they cannot be read. NumPy's AVX-512 exp and pow and
    OpenBLAS's fused dot products round differently from their AVX2 forms, so the same seed
    reproduces bit for bit on the machine class that made a result (docs/design.md §4, the
    bullet on OpenBLAS kernels)."""
    dispatch = numpy_dispatch()
    simd = dispatch[1] if dispatch is not None else None
    blas = None
    try:
        from threadpoolctl import threadpool_info
    except ImportError:
        pass
    else:
        for library in threadpool_info():
            if library.get("internal_api") == "openblas":
                blas = f"openblas {library.get('architecture')}"
                break
    return {"numpy_simd": simd, "blas": blas}


def environment() -> dict[str, Any]:
    """The record stored with every result: {"versions": `versions()`, "git_commit": ...,
    "machine": `machine()`}."""
    return {"versions": dict(versions()), "git_commit": git_commit(), "machine": machine()}


class FolderInUseError(OSError):
    """Another live run holds the output folder's lock."""


@contextlib.contextmanager
def output_lock(folder: str | os.PathLike, flag: str = "--out") -> Iterator[Path]:
    """Hold ``folder`` (created if needed) for this run: an exclusive `fcntl.flock` on
    ``folder/.lock``, which holds the pid; the kernel releases it when the run ends, even by
    SIGKILL, so a killed run never blocks the next one.

    `FolderInUseError` (one line naming ``flag``, the folder and the holder's pid) while another
    run holds it. Once held, the temporary files of runs killed mid-write are removed
    (`remove_temporaries`): no live run can be writing them.
    """
    import fcntl  # POSIX; imported here so that auv_gym imports everywhere

    path = Path(folder)
    path.mkdir(parents=True, exist_ok=True)
    fd = os.open(path / LOCK_FILE, os.O_RDWR | os.O_CREAT, 0o666)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "unknown"
        os.close(fd)
        raise FolderInUseError(
            f"{flag} {str(path)!r} is in use by another run (pid {holder}); wait for it to end "
            f"or choose another {flag}"
        ) from None
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        remove_temporaries(path)
        yield path
    finally:
        os.close(fd)  # releases the lock


def remove_temporaries(folder: str | os.PathLike, depth: int = TEMPORARY_DEPTH) -> list[Path]:
    """Remove the temporary files and folders the atomic writers leave when killed
    (``.NAME.auv-gym.XXXXXXXX.tmp``, ``.NAME.auv-gym-old<pid>``; nothing else) in ``folder``
    and its subfolders down to ``depth`` levels; returns them. Call it only while holding
    `output_lock`."""
    removed = []
    level = [Path(folder)]
    for _ in range(depth):
        below = []
        for parent in level:
            try:
                entries = list(os.scandir(parent))
            except OSError:
                continue
            for entry in entries:
                if TEMPORARY.fullmatch(entry.name):
                    if entry.is_dir(follow_symlinks=False):
                        shutil.rmtree(entry.path, ignore_errors=True)
                    else:
                        Path(entry.path).unlink(missing_ok=True)
                    removed.append(Path(entry.path))
                elif entry.is_dir(follow_symlinks=False) and not entry.name.startswith("."):
                    below.append(Path(entry.path))
        level = below
    return removed


def replace_outputs(folder: str | os.PathLike, written: Iterable[str | os.PathLike]) -> list[Path]:
    """Record ``written`` (files this run wrote in ``folder``) in ``folder/.outputs.json`` and
    delete the files the previous record lists that this run did not write; returns them.

    Only files this project recorded are ever deleted, so an output folder may hold the
    user's own files too. Folders left empty by the deletion are removed.
    """
    root = Path(folder)
    record = root / OUTPUTS_FILE
    keep = sorted({Path(os.path.relpath(Path(f), root)).as_posix() for f in written})
    try:
        before = json.loads(record.read_text())["files"]
    except (OSError, ValueError, KeyError, TypeError):
        before = []
    removed = []
    for name in sorted(set(before) - set(keep)):
        stale = root / name
        if ".." in Path(name).parts or Path(name).is_absolute() or not stale.is_file():
            continue  # a hand-edited record names nothing outside the folder
        stale.unlink()
        removed.append(stale)
        if stale.parent != root:
            with contextlib.suppress(OSError):  # not empty: something else lives there
                stale.parent.rmdir()
    write_json(record, {"files": keep}, indent=1)
    return removed


def read_toml(path: str | os.PathLike, what: str) -> dict[str, Any]:
    """The TOML file at ``path`` parsed; ValueError "``what`` PATH: ..." naming the file when it
    cannot be read, is not UTF-8 or is not valid TOML (a user's scenario, task or report file)."""
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise ValueError(f"{what} {path}: cannot be read ({exc.strerror})") from None
    return parse_toml(data, f"{what} {path}")


def parse_toml(data: bytes, where: str) -> dict[str, Any]:
    """A TOML file's bytes parsed; ValueError "``where``: not valid TOML (...)" when they are not
    UTF-8 or not valid TOML."""
    try:
        return tomllib.loads(data.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise ValueError(f"{where}: not valid TOML (not UTF-8 text: {exc})") from None
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{where}: not valid TOML ({exc})") from None


def process_alive(pid: int) -> bool:
    """Whether process ``pid`` still runs (a temporary file named by it may be in use)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's live process
        return True
    return True
