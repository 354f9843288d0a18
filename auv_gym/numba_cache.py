"""Keep numba's on-disk kernel cache in step with every source file a kernel compiles in.

numba decides whether a cached kernel is stale from the modification time of the file that
defines it, but the kernels here inline functions from other modules (`inline="always"`): after
an edit of `dynamics.py` alone, `simulator.py`'s cached kernel would keep running the old physics,
silently. So each package records a digest of all its numba sources (and of the packages it
inlines from) beside numba's cache files, and deletes those files when the digest changes.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
from pathlib import Path

__all__ = ["refresh_numba_cache", "sources_digest"]

STAMP_NAME = "numba_sources.sha256"
NUMBA_MARKER = b"numba"  # files without it cannot hold a kernel


def sources_digest(*source_dirs: str | Path, containing: bytes = b"") -> str:
    """SHA-256 over the names and contents of the `.py` files in `source_dirs` (only those
    whose text contains ``containing``, if given)."""
    digest = hashlib.sha256()
    for directory in source_dirs:
        for path in sorted(Path(directory).glob("*.py")):
            text = path.read_bytes()
            if containing in text:
                digest.update(f"{Path(directory).name}/{path.name}\0".encode())
                digest.update(text)
    return digest.hexdigest()


def refresh_numba_cache(package_dir: str | Path, *inlined_from: str | Path) -> bool:
    """Delete `package_dir`'s numba cache files if its numba sources changed; True if deleted.

    Only the in-tree cache (`__pycache__/*.nbi`, `*.nbc`) is managed: a read-only install falls
    back to numba's user-wide cache, and reinstalling rewrites every file's time stamp anyway.
    """
    cache_dir = Path(package_dir) / "__pycache__"
    stamp = cache_dir / STAMP_NAME
    digest = sources_digest(package_dir, *inlined_from, containing=NUMBA_MARKER)
    try:
        if stamp.read_text() == digest:
            return False
    except OSError:
        pass
    deleted = False
    with contextlib.suppress(OSError):  # read-only or concurrently cleaned: nothing to keep
        for path in [*cache_dir.glob("*.nbi"), *cache_dir.glob("*.nbc")]:
            with contextlib.suppress(FileNotFoundError):
                path.unlink()
                deleted = True
        cache_dir.mkdir(exist_ok=True)
        tmp = cache_dir / f"{STAMP_NAME}.{os.getpid()}.tmp"
        tmp.write_text(digest)
        os.replace(tmp, stamp)
    return deleted
