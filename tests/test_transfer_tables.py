"""The transfer tables (`benchmarks.analysis.transfer`) from the committed suites on both plants:
the means of transfer.csv are those of the committed table, and re-tabling one group keeps the
other group's rows (it lost them before)."""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import pytest

from benchmarks.analysis import transfer

COMMITTED = Path(__file__).resolve().parents[1] / "benchmarks" / "results" / "transfer"


def _rows(path: Path) -> dict[tuple[str, str, str], dict[str, str]]:
    with path.open(newline="") as handle:
        return {(r["group"], r["policy"], r["set"]): r for r in csv.DictReader(handle)}


@pytest.fixture
def suites(tmp_path: Path) -> Path:
    for folder in COMMITTED.iterdir():
        if folder.is_dir():
            shutil.copytree(folder, tmp_path / folder.name)
    return tmp_path


def test_one_group_retabled_keeps_the_other_groups_rows(suites):
    transfer.main(["--tables-only", "--groups", "as_built", "--out", str(suites), "--reps", "100"])
    new, old = _rows(suites / "transfer.csv"), _rows(COMMITTED / "transfer.csv")
    assert sorted(new) == sorted(old)
    assert {group for group, _, _ in new} == {"paper", "as_built"}
    for key, row in old.items():  # the means do not depend on the bootstrap
        for column in ("mean_5dof", "mean_6dof", "failures_6dof", "episodes_6dof", "ratio"):
            assert float(new[key][column]) == pytest.approx(float(row[column]), rel=1e-12), key
    text = (suites / "transfer.md").read_text()
    assert "| paper | best classical | fbsm_colos |" in text
    assert "| as_built | best classical | pid_as_built_climb_soft_pitch |" in text


def test_a_group_without_its_suites_is_left_out_unless_named(suites):
    shutil.rmtree(suites / "paper_6dof")
    transfer.main(["--tables-only", "--groups", "as_built", "--out", str(suites), "--reps", "100"])
    assert {group for group, _, _ in _rows(suites / "transfer.csv")} == {"as_built"}
    assert transfer.table_groups(suites, ["paper", "as_built"]) == ["paper", "as_built"]
    with pytest.raises(SystemExit):  # a bootstrap too small to give an interval: refused
        transfer.main(["--tables-only", "--out", str(suites), "--reps", "50"])
    with pytest.raises(FileNotFoundError, match="paper_6dof"):
        transfer.main(["--tables-only", "--groups", "paper", "--out", str(suites), "--reps", "100"])
