"""`pip install .` gives a working `auv-gym` command that runs from any folder.

The package is installed from a copy of the repository into a temporary virtual environment
that also sees this interpreter's site-packages (a `.pth` file of plain path lines, after the
venv's own; nothing is downloaded, and the editable install of the checkout stays inactive
because the `.pth` files of those folders are not run), without the rl and video extras' modules
(an import hook makes importing them fail, as on a base install). The command runs in a
temporary folder outside the repository.
"""

from __future__ import annotations

import csv
import os
import re
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

from benchmarks.cli import COMMANDS, SPEED

ROOT = Path(__file__).resolve().parents[1]
# Modules only the optional extras install: the base install must not need them.
EXTRA_MODULES = ("stable_baselines3", "torch", "yaml", "rich", "tensorboard", "moviepy", "ray")
BLOCKER = f"""
import importlib.abc, sys
class _BlockExtras(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in {EXTRA_MODULES!r}:
            raise ModuleNotFoundError(f"No module named {{name!r}} (base install)", name=name)
sys.meta_path.insert(0, _BlockExtras())
"""


def _run(args: list[str], cwd: Path, env: dict[str, str], timeout: float = 600):
    return subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, str]]:
    """(the venv's bin folder, environment) after installing a copy of the repository."""
    base = tmp_path_factory.mktemp("install")
    source = base / "source"
    skip = shutil.ignore_patterns(
        ".git",
        ".venv",
        "out",
        "runs",
        "build",
        "*.egg-info",
        "__pycache__",
        ".*_cache",
        "results",
        ".hypothesis",
    )
    shutil.copytree(ROOT, source, ignore=skip)
    venv = base / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    bin_dir = venv / "bin"
    python = str(bin_dir / "python")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PATH"] = f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"
    where = "import sysconfig; print(sysconfig.get_path('purelib'))"
    site = Path(_run([python, "-c", where], base, env).stdout.strip())
    shared = {sysconfig.get_path("purelib"), sysconfig.get_path("platlib")}
    (site / "zz_shared_site_packages.pth").write_text("\n".join(sorted(shared)) + "\n")
    # This interpreter's pip and setuptools install into the venv (``pip --python``).
    pip = _run(
        [
            sys.executable,
            "-m",
            "pip",
            "--python",
            python,
            "install",
            "-q",
            "--no-deps",
            "--no-build-isolation",
            "--no-index",
            str(source),
        ],
        base,
        env,
    )
    assert pip.returncode == 0, pip.stderr[-3000:]
    shutil.rmtree(source)  # the installed package must not lean on the source tree
    (site / "_block_extras.py").write_text(BLOCKER)
    (site / "zz_block_extras.pth").write_text("import _block_extras\n")
    return bin_dir, env


@pytest.mark.integration
def test_packages_and_data_come_from_the_install(installed, tmp_path: Path) -> None:
    bin_dir, env = installed
    code = (
        "import auv_gym, benchmarks, controllers\n"
        "from benchmarks.catalog.policies import AGENTS_DIR\n"
        "from benchmarks.catalog.scenarios import SCENARIOS_FILE\n"
        "from benchmarks.training.train import TrainOptions\n"
        "print(auv_gym.__file__, benchmarks.__file__, controllers.__file__,\n"
        "      AGENTS_DIR / 'ppo_generalist' / 'model.zip', SCENARIOS_FILE,\n"
        "      TrainOptions().config, sep='\\n')"
    )
    out = _run([str(bin_dir / "python"), "-c", code], tmp_path, env)
    assert out.returncode == 0, out.stderr[-2000:]
    files = [Path(line) for line in out.stdout.split()]
    venv = bin_dir.parent.resolve()
    for file in files:
        assert venv in file.resolve().parents, f"{file} is not inside the installed package"
        assert file.is_file(), file
    blocked = _run([str(bin_dir / "python"), "-c", "import stable_baselines3"], tmp_path, env)
    assert "base install" in blocked.stderr  # the extras really are out of reach


@pytest.mark.integration
def test_help_lists_every_command_with_defaults(installed, tmp_path: Path) -> None:
    bin_dir, env = installed
    top = _run([str(bin_dir / "auv-gym"), "--help"], tmp_path, env)
    assert top.returncode == 0, top.stderr
    assert all(name in top.stdout for name in COMMANDS)
    speed = _run([str(bin_dir / "auv-gym"), "speed", "--help"], tmp_path, env)
    assert all(name in speed.stdout for name in SPEED)
    for command in ("compare", "paper-figures"):
        text = _run([str(bin_dir / "auv-gym"), command, "--help"], tmp_path, env)
        assert text.returncode == 0, text.stderr
        assert text.stdout.startswith(f"usage: auv-gym {command}")
        assert "(default: " in text.stdout
    help_train = _run([str(bin_dir / "auv-gym"), "train", "--help"], tmp_path, env)
    assert help_train.returncode == 0 and "--eval-duration" in help_train.stdout
    # Training itself needs the rl extra: one line that names it, not a traceback.
    train = _run(
        [str(bin_dir / "auv-gym"), "train", "--out", "run", "--n-timesteps", "64"], tmp_path, env
    )
    assert train.returncode == 2 and "pip install 'auv-gym[rl]'" in train.stderr
    assert "Traceback" not in train.stderr and not (tmp_path / "run").exists()


@pytest.mark.integration
@pytest.mark.slow  # compiles the numba kernels of the fresh install (30-90 s)
def test_compare_runs_from_another_folder_on_the_base_install(installed, tmp_path: Path) -> None:
    bin_dir, env = installed
    args = [
        str(bin_dir / "auv-gym"),
        "compare",
        "--policies",
        "backstepping",
        "--scenarios",
        "nominal",
        "--seeds",
        "1",
        "--duration",
        "4",
        "--workers",
        "1",
        "--out",
        "run",
        "--no-figures",
    ]
    result = _run(args, tmp_path, env)
    assert result.returncode == 0, result.stderr[-3000:]
    with open(tmp_path / "run" / "episodes.csv", newline="") as fh:
        (row,) = list(csv.DictReader(fh))
    assert row["policy"] == "backstepping" and row["scenario"] == "nominal"
    assert float(row["transient"]) == 2.0 and int(row["window_samples"]) == 41
    assert 0.0 < float(row["rms_distance"]) < 20.0  # the approach from 17.7 m away
    bad = _run([*args[:-1], "--transient", "3.99"], tmp_path, env)
    assert bad.returncode == 2 and "fewer than two samples" in bad.stderr
    assert len(bad.stderr.strip().splitlines()) == 1


HELP_COMMANDS = [
    ["compare"],
    ["suite"],
    ["paper-figures"],
    ["train"],
    ["train-seeds"],
    ["demos"],
    *(["speed", name] for name in SPEED),
    ["video"],
]


@pytest.mark.parametrize("argv", HELP_COMMANDS, ids=" ".join)
def test_every_option_shows_its_default(argv: list[str], capsys) -> None:
    """`auv-gym COMMAND --help`: every option after -h states its default (choices in braces)."""
    from benchmarks.cli import main

    with pytest.raises(SystemExit) as stop:
        main([*argv, "--help"])
    assert stop.value.code == 0
    text = capsys.readouterr().out
    assert text.startswith(f"usage: auv-gym {' '.join(argv)}")
    options = re.split(r"\n(?=  -)", text.split("\noptions:\n", 1)[1])
    assert options[0].lstrip().startswith("-h, --help")
    assert len(options) > 1
    for block in options[1:]:
        assert re.search(r"\(default:\s", block), f"no default shown for {block.split()[0]}"


@pytest.mark.integration
def test_compare_with_an_agent_on_the_base_install_exits_2_before_any_episode(
    installed, tmp_path: Path
) -> None:
    bin_dir, env = installed
    args = [
        str(bin_dir / "auv-gym"),
        "compare",
        "--policies",
        "fbsm,ppo_generalist",
        "--scenarios",
        "paper",
        "--seeds",
        "1",
        "--duration",
        "4",
        "--out",
        "run",
    ]
    result = _run(args, tmp_path, env)
    assert result.returncode == 2, result.stderr[-2000:]
    assert "from the 'rl' extra: pip install 'auv-gym[rl]'" in result.stderr
    assert "Traceback" not in result.stderr and not (tmp_path / "run" / "episodes").exists()


@pytest.mark.integration
def test_the_installed_command_finds_the_manual(installed, tmp_path: Path) -> None:
    bin_dir, env = installed
    result = _run([str(bin_dir / "auv-gym"), "docs"], tmp_path, env)
    assert result.returncode == 0, result.stderr
    folder = Path(result.stdout.splitlines()[0])
    assert bin_dir.parent in folder.parents  # installed with the package, not the source tree
    assert (folder / "model.md").is_file() and (folder.parent / "README.md").is_file()
    assert "model.md" in result.stdout and "usage.md" in result.stdout
