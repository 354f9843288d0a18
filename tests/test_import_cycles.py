"""No import cycles between the project's modules and no import against the one direction of
auv_gym's rooms (`benchmarks.checks.import_cycles`), and the checker finds the ones it is shown."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from benchmarks.checks.import_cycles import (
    LAYERS,
    ROOT,
    find_cycles,
    import_graph,
    layer_of,
    main,
    upward_imports,
)


def test_the_project_has_no_import_cycles_and_no_upward_imports(capsys):
    assert main([]) == 0
    out = capsys.readouterr().out
    assert out.rstrip().endswith(" 0 upward imports, 0 cycles")


def test_every_module_of_auv_gym_lives_in_a_room_or_at_the_top():
    """The top of auv_gym holds only registration and the evaluation API; the rest is in rooms."""
    modules = import_graph(ROOT, ["auv_gym"])
    top = sorted(m for m in modules if layer_of(m) == "auv_gym")
    assert top == ["auv_gym", "auv_gym.metrics", "auv_gym.rollout"]
    rooms = {layer_of(m) for m in modules} - {"auv_gym"}
    assert rooms == {name for name in LAYERS if name.startswith("auv_gym.")}


def test_upward_imports_are_found_by_layer():
    graph = {
        "auv_gym.paths.shapes": {"auv_gym.support.validation"},  # down: allowed
        "auv_gym.vehicle.dynamics": {"auv_gym.paths.kernels", "auv_gym.ocean.waves"},  # peer
        "auv_gym.sim.config": {"auv_gym.sim.task", "auv_gym.envs.env"},  # own room; up
        "auv_gym.support.files": {"auv_gym"},  # the top of the package is above every room
        "auv_gym.rollout": {"auv_gym.sim.simulator", "controllers.base"},
        "controllers.base": {"auv_gym.rollout", "benchmarks.cli"},
        "benchmarks.cli": {"controllers", "auv_gym.envs.env"},
        "tests.test_x": {"benchmarks.cli"},  # outside every layer: not checked
    }
    assert layer_of("auv_gym.sim.config") == "auv_gym.sim"
    assert layer_of("auv_gym.metrics") == "auv_gym"
    assert layer_of("auv_gym.simplex") == "auv_gym"  # a name, not a prefix, of a room
    assert layer_of("tests.test_x") is None
    assert upward_imports(graph) == [
        ("auv_gym.rollout", "controllers.base"),
        ("auv_gym.sim.config", "auv_gym.envs.env"),
        ("auv_gym.support.files", "auv_gym"),
        ("auv_gym.vehicle.dynamics", "auv_gym.ocean.waves"),
        ("controllers.base", "benchmarks.cli"),
    ]


def test_deferred_and_parent_imports_count_and_type_checking_does_not(tmp_path: Path):
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("from pkg.a import A\n")
    (pkg / "a.py").write_text("A = 1\n\ndef f():\n    from pkg.b import B\n")
    (pkg / "b.py").write_text("from pkg import a\nB = 2\n")
    (pkg / "c.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg.d import D\n"
    )
    (pkg / "d.py").write_text("from . import c\nD = 3\n")
    graph = import_graph(tmp_path, ["pkg"])
    assert graph == {
        "pkg": {"pkg.a"},
        "pkg.a": {"pkg.b"},
        "pkg.b": {"pkg.a"},
        "pkg.c": set(),
        "pkg.d": {"pkg.c"},
    }
    assert find_cycles(graph) == [["pkg.a", "pkg.b"]]


def test_the_command_line_reports_no_cycles():
    done = subprocess.run(
        [sys.executable, "-m", "benchmarks.checks.import_cycles"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "0 upward imports, 0 cycles" in done.stdout
