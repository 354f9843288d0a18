"""Where numba keeps this project's compiled kernels, and how it knows they are current.

numba judges a cached kernel by the file that defines it only, but the kernels here inline
functions from other modules (``inline="always"``): after an edit of `vehicle/dynamics.py` alone,
`sim/simulator.py`'s cached kernel would keep running the old physics, silently. So the files of a
registered package, in its folder and every sub-package below it, get their own numba cache
locator, whose source stamp is a digest of *all* the numba sources of the package tree and of the
package trees it inlines from. numba compares that stamp when it first loads a kernel and
recompiles on a mismatch; nothing is ever deleted, so processes that share a cache never pull a
file from under each other.

Nothing happens at import beyond definitions: registering a package records its folders, and the
digest is computed the first time numba loads or saves one of its kernels (once per process and
package). numba itself probes the cache directory when a ``cache=True`` kernel is defined; the
locator does that once per folder instead of once per kernel.

A kernel's cache lives in the ``__pycache__`` of the folder that defines it, as numba's own would;
if that is not writable (a read-only install), in ``NUMBA_CACHE_DIR`` or numba's per-user cache
directory; if none of those is writable either, in a private temporary directory per package
removed at exit, with a `NumbaCacheWarning`: the kernels then compile in every new process
(up to about 2 min on 2 cores) but nothing fails. ``NUMBA_CACHE_DIR``, when set, is used first,
as numba does.
"""

from __future__ import annotations

import atexit
import hashlib
import os
import shutil
import sys
import tempfile
import warnings
from pathlib import Path

from numba.core import caching, config

__all__ = [
    "NumbaCacheWarning",
    "cache_directory",
    "kernels_are_cached",
    "mark_kernels_cached",
    "register_package",
    "sources_digest",
]

NUMBA_MARKER = b"numba"  # files without it cannot hold a kernel


class NumbaCacheWarning(UserWarning):
    """No writable directory for the on-disk kernel cache: kernels compile in every process."""


def _sources(directory: Path) -> list[Path]:
    """The `.py` files of a package tree: its folder and every folder below it, sorted by their
    path inside the tree (bytecode caches are not sources)."""
    found = (p for p in directory.rglob("*.py") if "__pycache__" not in p.parts)
    return sorted(found, key=lambda p: p.relative_to(directory).parts)


def sources_digest(*source_dirs: str | Path, containing: bytes = b"") -> str:
    """SHA-256 over the names and contents of the `.py` files of the package trees `source_dirs`
    (sub-packages included; only the files whose text contains ``containing``, if given)."""
    digest = hashlib.sha256()
    for directory in map(Path, source_dirs):
        for path in _sources(directory):
            text = path.read_bytes()
            if containing in text:
                name = "/".join((directory.name, *path.relative_to(directory).parts))
                digest.update(f"{name}\0".encode())
                digest.update(text)
    return digest.hexdigest()


# Registered packages: folder -> the package trees its kernels may inline from (itself first).
_PACKAGES: dict[Path, tuple[Path, ...]] = {}
_DIGESTS: dict[tuple[Path, ...], str] = {}  # computed lazily, once per process
_DIRECTORIES: dict[Path, str] = {}  # folder -> chosen cache directory
_TEMPORARY: dict[Path, Path] = {}  # package -> its private temporary cache (no writable one)


def register_package(package_dir: str | Path, *inlined_from: str | Path) -> None:
    """Cache the kernels defined in `package_dir` and its sub-packages with a stamp over the numba
    sources of its tree and those of `inlined_from`. Must run before the package's first kernel
    is defined (its ``__init__``)."""
    package = Path(package_dir).resolve()
    _PACKAGES[package] = (package, *(Path(d).resolve() for d in inlined_from))


def _package_of(folder: Path) -> Path | None:
    """The registered package whose tree holds ``folder`` (the innermost one), or None."""
    return next((p for p in (folder, *folder.parents) if p in _PACKAGES), None)


def cache_directory(folder: str | Path) -> str | None:
    """The directory holding the kernel cache of the modules in ``folder`` (a registered package
    or one of its sub-packages), or None before its first kernel."""
    return _DIRECTORIES.get(Path(folder).resolve())


def _digest(folders: tuple[Path, ...]) -> str:
    if folders not in _DIGESTS:
        _DIGESTS[folders] = sources_digest(*folders, containing=NUMBA_MARKER)
    return _DIGESTS[folders]


class _PackageStamp:
    """The package digest, computed when numba first compares or stores it (not at import)."""

    def __init__(self, folders: tuple[Path, ...]) -> None:
        self._folders = folders

    def __str__(self) -> str:
        return _digest(self._folders)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, str) and other == str(self)

    def __ne__(self, other: object) -> bool:
        return not self == other

    __hash__ = None  # type: ignore[assignment]

    def __reduce__(self) -> tuple:
        return (str, (str(self),))  # stored in the index as the plain digest


def _writable(directory: str) -> bool:
    """Whether files can be created in `directory` (made if missing): numba's own probe."""
    try:
        os.makedirs(directory, exist_ok=True)
        tempfile.TemporaryFile(dir=directory).close()
    except OSError:
        return False
    return True


def _choose_directory(folder: Path) -> str:
    """The cache directory of the kernels defined in ``folder`` (chosen once per process)."""
    if folder in _DIRECTORIES:
        return _DIRECTORIES[folder]
    subpath = caching._CacheLocator.get_suitable_cache_subpath(str(folder / "__init__.py"))
    candidates = [str(folder / "__pycache__")]
    if config.CACHE_DIR:
        candidates.insert(0, os.path.join(config.CACHE_DIR, subpath))
    user_dir = caching.AppDirs(appname="numba", appauthor=False).user_cache_dir
    candidates.append(os.path.join(user_dir, subpath))
    chosen = next((d for d in candidates if _writable(d)), None)
    if chosen is None:
        package = _package_of(folder) or folder
        if package not in _TEMPORARY:
            _TEMPORARY[package] = Path(tempfile.mkdtemp(prefix=f"{package.name}-numba-cache-"))
            atexit.register(shutil.rmtree, _TEMPORARY[package], ignore_errors=True)
            warnings.warn(
                f"{package.name}: no writable numba cache directory (tried "
                f"{', '.join(candidates)}); compiled kernels are kept in {_TEMPORARY[package]} "
                "for this process only. Set NUMBA_CACHE_DIR to a writable folder to keep them.",
                NumbaCacheWarning,
                stacklevel=2,
            )
        chosen = str(_TEMPORARY[package].joinpath(*folder.relative_to(package).parts))
        os.makedirs(chosen, exist_ok=True)
    _DIRECTORIES[folder] = chosen
    return chosen


def _marker(package_dir: str | Path) -> Path | None:
    package = Path(package_dir).resolve()
    if package not in _PACKAGES:
        return None
    return Path(_choose_directory(package)) / f".compiled-{_digest(_PACKAGES[package])[:16]}"


def kernels_are_cached(*package_dirs: str | Path) -> bool:
    """True if a command already ran to its end with these packages' current sources, so their
    kernels load from the cache instead of compiling (up to about 2 min on 2 cores); a hint for a
    progress message, not a guarantee (a command may use kernels an earlier one did not)."""
    markers = [_marker(p) for p in package_dirs]
    return all(m is not None and m.is_file() for m in markers)


def mark_kernels_cached(*package_dirs: str | Path) -> None:
    """Record that a command ran to its end with the current sources (`kernels_are_cached`)."""
    for package in package_dirs:
        marker = _marker(package)
        if marker is not None:
            try:
                marker.parent.mkdir(parents=True, exist_ok=True)
                marker.touch()
            except OSError:  # a read-only cache: the message shows again, nothing fails
                pass


class _PackageCacheLocator(caching._CacheLocator):
    """numba cache locator for the files of a registered package (see the module docstring)."""

    def __init__(self, py_func, py_file: str, package: Path) -> None:
        self._lineno = py_func.__code__.co_firstlineno
        self._stamp = _PackageStamp(_PACKAGES[package])
        self._cache_path = _choose_directory(Path(py_file).resolve().parent)

    def ensure_cache_path(self) -> None:
        os.makedirs(self._cache_path, exist_ok=True)

    def get_cache_path(self) -> str:
        return self._cache_path

    def get_source_stamp(self) -> _PackageStamp:
        return self._stamp

    def get_disambiguator(self) -> str:
        return str(self._lineno)

    @classmethod
    def from_function(cls, py_func, py_file: str):
        package = _package_of(Path(py_file).resolve().parent)
        if package is None or getattr(sys, "frozen", False):
            return None  # not ours: numba's own locators decide
        return cls(py_func, py_file, package)


def _install() -> None:
    """Put the locator in front of numba's own (idempotent; affects registered packages only)."""
    locators = caching.CacheImpl._locator_classes  # the same list in numba 0.59 … 0.68
    if _PackageCacheLocator not in locators:
        locators.insert(0, _PackageCacheLocator)


_install()
register_package(Path(__file__).resolve().parents[1])  # auv_gym, with every room below it
