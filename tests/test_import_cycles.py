"""No import cycles between the project's modules (`benchmarks.checks.import_cycles`), and the
checker finds the ones it is shown."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from benchmarks.checks.import_cycles import ROOT, find_cycles, import_graph, main


def test_the_project_has_no_import_cycles(capsys):
    assert main([]) == 0
    out = capsys.readouterr().out
    assert out.rstrip().endswith(" 0 cycles")


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
    assert "0 cycles" in done.stdout
