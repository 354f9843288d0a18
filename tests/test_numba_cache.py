"""The numba cache is dropped when any numba source a kernel may inline changes."""

from __future__ import annotations

from pathlib import Path

from auv_gym.numba_cache import NUMBA_MARKER, STAMP_NAME, refresh_numba_cache, sources_digest


def _package(root: Path, name: str, body: str) -> Path:
    package = root / name
    (package / "__pycache__").mkdir(parents=True)
    (package / "kernels.py").write_text(f"from numba import njit\n{body}\n")
    (package / "plots.py").write_text("import matplotlib\n")
    return package


def _cached(package: Path) -> list[str]:
    return sorted(p.name for p in (package / "__pycache__").glob("*.nb*"))


def _fake_cache(package: Path) -> None:
    for name in ("kernels.step-10.py311.nbi", "kernels.step-10.py311.1.nbc"):
        (package / "__pycache__" / name).write_bytes(b"compiled")


def test_cache_survives_until_a_numba_source_changes(tmp_path: Path) -> None:
    pkg = _package(tmp_path, "pkg", "X = 1")
    _fake_cache(pkg)
    assert refresh_numba_cache(pkg) is True  # no stamp yet: the cache's sources are unknown
    assert _cached(pkg) == []
    assert (pkg / "__pycache__" / STAMP_NAME).read_text() == sources_digest(
        pkg, containing=NUMBA_MARKER
    )

    _fake_cache(pkg)
    assert refresh_numba_cache(pkg) is False
    (pkg / "plots.py").write_text("import matplotlib  # edited, no kernels here\n")
    assert refresh_numba_cache(pkg) is False
    assert len(_cached(pkg)) == 2

    (pkg / "kernels.py").write_text("from numba import njit\nX = 2\n")
    assert refresh_numba_cache(pkg) is True
    assert _cached(pkg) == []


def test_an_edit_in_an_inlined_package_invalidates_the_dependent_cache(tmp_path: Path) -> None:
    base = _package(tmp_path, "base", "Y = 1")
    user = _package(tmp_path, "user", "Z = 1")
    refresh_numba_cache(user, base)
    _fake_cache(user)
    assert refresh_numba_cache(user, base) is False
    (base / "kernels.py").write_text("from numba import njit\nY = 3\n")
    assert refresh_numba_cache(user, base) is True
    assert _cached(user) == []


def test_installed_package_cache_stamps_match_their_sources() -> None:
    import auv_gym
    import controllers

    auv_dir = Path(auv_gym.__file__).parent
    stamp = auv_dir / "__pycache__" / STAMP_NAME
    if stamp.exists():  # absent only on a read-only install
        assert stamp.read_text() == sources_digest(auv_dir, containing=NUMBA_MARKER)
    ctl_dir = Path(controllers.__file__).parent
    ctl_stamp = ctl_dir / "__pycache__" / STAMP_NAME
    if ctl_stamp.exists():
        assert ctl_stamp.read_text() == sources_digest(ctl_dir, auv_dir, containing=NUMBA_MARKER)
