"""`auv-gym compile`: the set-up compiles what the main job flies, ``--all`` every scenario."""

from __future__ import annotations

import re
from pathlib import Path

from benchmarks.catalog.scenarios import load_scenarios
from benchmarks.runner import compile_kernels

ROOT = Path(__file__).resolve().parents[1]


def test_the_set_up_scope_is_the_main_jobs_scenarios() -> None:
    main_job = (ROOT / "scripts" / "main.sh").read_text()
    (listed,) = re.findall(r"--scenarios (\S+)", main_job)
    assert tuple(listed.split(",")) == compile_kernels.MAIN_JOB_SCENARIOS
    assert set(compile_kernels.MAIN_JOB_SCENARIOS) <= set(load_scenarios())


def test_the_test_script_compiles_every_scenario_before_the_tests() -> None:
    script = (ROOT / "scripts" / "test.sh").read_text()
    assert script.index("compile_kernels --all") < script.index("python -m pytest")


def test_every_scope_has_its_marker(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(compile_kernels, "_scope_marker", lambda: tmp_path / ".compiled-all-x")
    assert compile_kernels._scope_marked(False)  # the main job's: the packages' own marker
    assert not compile_kernels._scope_marked(True)
    compile_kernels._mark_scope(True)
    assert compile_kernels._scope_marked(True)
