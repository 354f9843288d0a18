"""The kernel cache: stale when any inlined source changes, lazy at import, never fatal.

Each scenario runs in fresh interpreters (a cache is only read by a new process), on tiny
packages written to a temporary folder or on a read-only copy of the real ones.
"""

from __future__ import annotations

import json
import os
import pickle
import shutil
import stat
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

import auv_gym
import controllers
from auv_gym.support.numba_cache import NUMBA_MARKER, cache_directory, sources_digest

AUV_DIR = Path(auv_gym.__file__).parent
CTL_DIR = Path(controllers.__file__).parent

_REGISTER = "from pathlib import Path\nfrom auv_gym.support.numba_cache import register_package\n"
_PROBE = """
import json
from {module} import kernel
result = kernel(1.0)
stats = kernel.stats
print(json.dumps({{"result": result, "hits": sum(stats.cache_hits.values()),
                  "misses": sum(stats.cache_misses.values())}}))
"""


def _run(code: str, cwd: Path, env: dict[str, str] | None = None, user: list[str] | None = None):
    """Run ``code`` in a fresh interpreter in ``cwd``, which comes first on its path (then the
    project); ``user`` prefixes the command (e.g. to drop privileges)."""
    environment = {**os.environ, "PYTHONPATH": os.pathsep.join([str(cwd), str(AUV_DIR.parent)])}
    environment.pop("NUMBA_CACHE_DIR", None)
    environment.update(env or {})
    out = subprocess.run(
        [*(user or []), sys.executable, "-c", code],
        cwd=cwd,
        env=environment,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    return out


def _kernel_call(root: Path, module: str) -> dict:
    return json.loads(_run(_PROBE.format(module=module), root).stdout.strip().splitlines()[-1])


def _package(root: Path, name: str, register: str, files: dict[str, str]) -> Path:
    package = root / name
    package.mkdir()
    (package / "__init__.py").write_text(_REGISTER + register + "\n")
    for filename, text in files.items():
        path = package / filename
        for folder in reversed(path.relative_to(package).parents[:-1]):  # sub-packages
            (package / folder).mkdir(exist_ok=True)
            (package / folder / "__init__.py").touch()
        path.write_text(text)
    return package


def _helper(value: float) -> str:
    return (
        f"from numba import njit\n\n@njit(cache=True, inline='always')\n"
        f"def value():\n    return {value}\n"
    )


@pytest.mark.integration
def test_an_edit_of_an_inlined_module_recompiles_the_kernel(tmp_path: Path) -> None:
    kernels = (
        "from numba import njit\nfrom pkg.helpers import value\n\n"
        "@njit(cache=True)\ndef kernel(x):\n    return x + value()\n"
    )
    files = {"helpers.py": _helper(1.0), "kernels.py": kernels, "notes.py": "X = 1\n"}
    pkg = _package(tmp_path, "pkg", "register_package(Path(__file__).parent)", files)

    assert _kernel_call(tmp_path, "pkg.kernels") == {"result": 2.0, "hits": 0, "misses": 1}
    assert _kernel_call(tmp_path, "pkg.kernels") == {"result": 2.0, "hits": 1, "misses": 0}
    assert sorted(p.suffix for p in (pkg / "__pycache__").glob("kernels.*.nb*")) == [".nbc", ".nbi"]

    (pkg / "notes.py").write_text("X = 2  # no kernel in this file: the cache stays valid\n")
    assert _kernel_call(tmp_path, "pkg.kernels")["hits"] == 1

    # numba alone would load the cached kernel (kernels.py is unchanged) and return 2.0.
    (pkg / "helpers.py").write_text(_helper(5.0))
    assert _kernel_call(tmp_path, "pkg.kernels") == {"result": 6.0, "hits": 0, "misses": 1}
    assert _kernel_call(tmp_path, "pkg.kernels") == {"result": 6.0, "hits": 1, "misses": 0}


@pytest.mark.integration
def test_a_kernel_in_a_sub_package_is_cached_beside_it_and_stale_after_an_edit_in_another(
    tmp_path: Path,
) -> None:
    """The registered package's tree is one unit: a kernel of ``pkg/sim`` inlining a function of
    ``pkg/physics`` is recompiled after an edit there, and cached in ``pkg/sim/__pycache__``."""
    kernels = (
        "from numba import njit\nfrom pkg.physics.helpers import value\n\n"
        "@njit(cache=True)\ndef kernel(x):\n    return x + value()\n"
    )
    files = {
        "physics/helpers.py": _helper(1.0),
        "sim/kernels.py": kernels,
        "sim/notes.py": "X = 1\n",
    }
    pkg = _package(tmp_path, "pkg", "register_package(Path(__file__).parent)", files)

    assert _kernel_call(tmp_path, "pkg.sim.kernels") == {"result": 2.0, "hits": 0, "misses": 1}
    assert _kernel_call(tmp_path, "pkg.sim.kernels") == {"result": 2.0, "hits": 1, "misses": 0}
    cached = sorted(p.suffix for p in (pkg / "sim" / "__pycache__").glob("kernels.*.nb*"))
    assert cached == [".nbc", ".nbi"]
    assert not list((pkg / "__pycache__").glob("*.nb*"))

    (pkg / "sim" / "notes.py").write_text("X = 2  # no kernel here: the cache stays valid\n")
    assert _kernel_call(tmp_path, "pkg.sim.kernels")["hits"] == 1

    (pkg / "physics" / "helpers.py").write_text(_helper(5.0))
    assert _kernel_call(tmp_path, "pkg.sim.kernels") == {"result": 6.0, "hits": 0, "misses": 1}
    assert _kernel_call(tmp_path, "pkg.sim.kernels") == {"result": 6.0, "hits": 1, "misses": 0}


@pytest.mark.integration
def test_an_edit_in_a_package_inlined_from_recompiles_the_dependent_kernel(tmp_path: Path) -> None:
    base = _package(
        tmp_path, "base", "register_package(Path(__file__).parent)", {"helpers.py": _helper(1.0)}
    )
    kernels = (
        "from numba import njit\nfrom base.helpers import value\n\n"
        "@njit(cache=True)\ndef kernel(x):\n    return 10.0 * x + value()\n"
    )
    _package(
        tmp_path,
        "user",
        "import base\nregister_package(Path(__file__).parent, Path(base.__file__).parent)",
        {"kernels.py": kernels},
    )

    assert _kernel_call(tmp_path, "user.kernels")["result"] == 11.0
    assert _kernel_call(tmp_path, "user.kernels")["hits"] == 1
    (base / "helpers.py").write_text(_helper(3.0))
    assert _kernel_call(tmp_path, "user.kernels") == {"result": 13.0, "hits": 0, "misses": 1}


def test_import_is_lazy_and_touches_no_cache_file(tmp_path: Path) -> None:
    """Importing computes no digest and deletes or rewrites nothing; the first kernel call
    computes the digest once.

    On a private copy of the packages with a cache written beforehand: other test workers
    compile into the real packages' caches at the same time."""
    for package in (AUV_DIR, CTL_DIR):
        shutil.copytree(
            package, tmp_path / package.name, ignore=shutil.ignore_patterns("__pycache__")
        )
    _run("from auv_gym.paths.guidance import wrap_angle\nwrap_angle(1.0)\n", tmp_path)
    folders = {"AUV_DIR": str(tmp_path / "auv_gym"), "CTL_DIR": str(tmp_path / "controllers")}
    assert list((tmp_path / "auv_gym" / "paths" / "__pycache__").glob("guidance.*.nbi"))
    code = """
import json, os
from pathlib import Path
def listing():
    out = {}
    for folder in (Path(os.environ["AUV_DIR"]), Path(os.environ["CTL_DIR"])):
        for p in sorted(folder.rglob("__pycache__/*.nb*")):
            out[str(p)] = p.stat().st_mtime_ns
    return out
before = listing()
import auv_gym, controllers
from auv_gym.support import numba_cache
after_import = (len(numba_cache._DIGESTS), listing() == before)
from auv_gym.paths.guidance import wrap_angle
wrap_angle(4.0)
print(json.dumps([*after_import, len(numba_cache._DIGESTS)]))
"""
    out = _run(code, tmp_path, folders)
    assert json.loads(out.stdout.strip().splitlines()[-1]) == [0, True, 1]


def _index_stamp(cache_dir: Path, pattern: str) -> str:
    (index,) = cache_dir.glob(pattern)
    with index.open("rb") as f:
        pickle.load(f)  # numba version
        stamp, _ = pickle.loads(f.read())
    return stamp


def test_installed_kernels_are_stamped_with_their_package_digests() -> None:
    from auv_gym.paths.guidance import wrap_angle
    from controllers.los import loop_errors  # noqa: F401  (defines the controllers' kernels)

    wrap_angle(1.0)  # loads or writes its cache entry
    auv_cache = Path(cache_directory(AUV_DIR / "paths"))
    assert _index_stamp(auv_cache, "guidance.wrap_angle-*.nbi") == sources_digest(
        AUV_DIR, containing=NUMBA_MARKER
    )
    # Only the entry this process loaded or wrote is checked: entries of kernels not used since
    # the last edit keep their old stamp until their next use (and are then recompiled).
    assert cache_directory(CTL_DIR) is not None


def _read_only_copy() -> tuple[Path, list[str]]:
    """The two packages copied to a world-readable, nobody-writable folder, and the command
    prefix that runs a process without the right to write there (as root: user nobody)."""
    if os.geteuid() == 0:
        setpriv = shutil.which("setpriv")
        if setpriv is None:
            pytest.skip("running as root without setpriv: cannot drop the right to write")
        user = [setpriv, "--reuid=65534", "--regid=65534", "--clear-groups"]
        probe = subprocess.run(
            [*user, sys.executable, "-c", "import numba, gymnasium"],
            capture_output=True,
            text=True,
            timeout=300,
        )
        if probe.returncode != 0:  # e.g. a virtual environment inside a folder only root reads
            pytest.skip(
                f"user nobody cannot import this interpreter's packages: {probe.stderr[-200:]}"
            )
    else:
        user = []
    root = Path(tempfile.mkdtemp(prefix="auv_gym-read-only-"))
    for package in (AUV_DIR, CTL_DIR):
        shutil.copytree(package, root / package.name, ignore=shutil.ignore_patterns("__pycache__"))
    (root / "home").mkdir()
    for path in [root, *root.rglob("*")]:
        mode = stat.S_IRUSR | stat.S_IRGRP | stat.S_IROTH
        if path.is_dir():
            mode |= stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH
        path.chmod(mode)
    return root, user


def _run_read_only(code: str) -> tuple[subprocess.CompletedProcess, Path]:
    root, user = _read_only_copy()
    try:
        home = str(root / "home")  # numba's per-user cache folder is not writable either
        env = {
            "HOME": home,
            "XDG_CACHE_HOME": home,
            "TMPDIR": tempfile.gettempdir(),
            "MPLCONFIGDIR": tempfile.gettempdir(),
            "PYTHONPATH": str(root),
        }
        out = _run(code, root, env, user)
        written = [p for p in root.rglob("*") if p.name == "__pycache__" or p.suffix == ".nbi"]
    finally:
        for path in [root, *root.rglob("*")]:
            path.chmod(path.stat().st_mode | stat.S_IWUSR)
        shutil.rmtree(root)
    assert not written
    assert "no writable numba cache directory" in out.stderr
    return out, root


def test_a_read_only_install_imports_and_runs_kernels_without_a_disk_cache() -> None:
    code = """
import json
import auv_gym, controllers
from pathlib import Path
from auv_gym.paths.guidance import wrap_angle
from auv_gym.support.numba_cache import cache_directory
value = wrap_angle(4.0)
cache = cache_directory(Path(auv_gym.__file__).parent / "paths")
print(json.dumps([auv_gym.__file__, value, cache]))
"""
    out, root = _run_read_only(code)
    module, value, cache = json.loads(out.stdout.strip().splitlines()[-1])
    assert module == str(root / "auv_gym" / "__init__.py")
    assert value == pytest.approx(4.0 - 2.0 * 3.141592653589793)
    # one private folder for the package, a sub-folder per room with kernels
    assert Path(cache).name == "paths"
    assert Path(cache).parent.parent == Path(tempfile.gettempdir())


@pytest.mark.integration
@pytest.mark.slow
def test_a_read_only_install_steps_the_env() -> None:
    code = """
import gymnasium as gym, numpy as np
import auv_gym
env = gym.make("AUVPath3D-v0")
env.reset(seed=0)
obs, reward, terminated, truncated, _ = env.step(np.zeros(3, dtype=np.float32))
assert np.all(np.isfinite(obs)) and not terminated
print("stepped")
"""
    out, _ = _run_read_only(code)
    assert out.stdout.strip().splitlines()[-1] == "stepped"
