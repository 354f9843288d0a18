"""`benchmarks.analysis.suite_seeds`: a multi-seed policy on the test suite, seed by seed."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from benchmarks.analysis.suite_seeds import main, pool_suites, seed_table
from benchmarks.analysis.suite_stats import failure_matrices

SUITE = Path(__file__).resolve().parents[1] / "benchmarks" / "results" / "suite"


def test_a_seed_with_a_failed_episode_beats_nobody_and_the_counts_add_up() -> None:
    groups = ["a"] * 4 + ["b"] * 4
    good = np.full((1, 8), 0.05)
    runs = np.array([np.full(8, 0.04), np.r_[np.full(7, 0.03), 30.0]])  # run 1 failed once
    scores = {"agent": runs, "fbsm": good}
    failed = {"agent": runs >= 30.0, "fbsm": good >= 30.0}
    record = seed_table(
        scores, groups, {"agent": [3, 7], "fbsm": [0]}, failed, "agent", ["fbsm"], 100
    )
    assert record["runs"]["3"]["beats"] == {"fbsm": True}
    assert record["runs"]["3"]["iqm"][0] == pytest.approx(0.04)
    # run 7's IQM (0.03) is below FBSM's, but an episode failed: it does not beat it
    assert record["runs"]["7"]["iqm"][0] == pytest.approx(0.03)
    assert record["runs"]["7"]["failed_sets"] == ["b"]
    assert record["runs"]["7"]["beats"] == {"fbsm": False}
    assert record["beat_counts"] == {"fbsm": 1}
    assert (record["failed_episodes"], record["episodes"]) == (1, 16)
    with pytest.raises(ValueError, match="not in the evaluation: \\['sac'\\]"):
        seed_table(scores, groups, {"agent": [3, 7]}, failed, "agent", ["sac"], 100)


def test_failure_matrices_follow_the_score_columns() -> None:
    rows = [
        {"policy": "p", "run": 0, "set": s, "seed": k, "termination_reason": reason}
        for s, k, reason in [("b", 1, "corridor"), ("a", 0, "time_limit"), ("b", 0, "time_limit")]
    ]
    masks = failure_matrices(rows, ["a", "b"])
    np.testing.assert_array_equal(masks["p"], [[False, False, True]])


def test_the_committed_suite_seed_by_seed(tmp_path: Path) -> None:
    """The former generalist's five seeds (`ppo_cross_track_guard_alloc` in the committed
    suite): each beats FBSM's aggregate (0.0668 m) with no failed episode."""
    record = main(
        [
            "--suite",
            str(SUITE),
            "--policy",
            "ppo_cross_track_guard_alloc",
            "--out",
            str(tmp_path),
            "--reps",
            "100",
        ]
    )
    assert record["beat_counts"] == {"fbsm": 5, "fbsm_colos": 5}
    assert record["episodes_per_run"] == 130
    assert 0.035 < record["aggregate_iqm"][0] < 0.042
    assert json.loads((tmp_path / "suite_seeds.json").read_text())["policy"] == (
        "ppo_cross_track_guard_alloc"
    )
    assert "| 2 | 0.0350" in (tmp_path / "suite_seeds.md").read_text()


def _split_suite(tmp_path: Path, policy: str, parts: list[list[int]]) -> list[Path]:
    """The committed suite cut into one folder per part of ``policy``'s runs, each with the
    references' episodes too, as seeds flown in pairs would be."""
    header, *lines = (SUITE / "episodes.csv").read_text().splitlines()
    column = header.split(",")
    folders = []
    for k, runs in enumerate(parts):
        keep = [
            line
            for line in lines
            if (row := dict(zip(column, line.split(","), strict=True)))["policy"]
            in ("fbsm", "fbsm_colos")
            or (row["policy"] == policy and int(row["run"]) in runs)
        ]
        folder = tmp_path / f"part_{k}"
        folder.mkdir()
        (folder / "episodes.csv").write_text("\n".join([header, *keep]) + "\n")
        (folder / "suite.json").write_text((SUITE / "suite.json").read_text())
        folders.append(folder)
    return folders


def test_suites_flown_in_pairs_pool_to_the_whole(tmp_path: Path) -> None:
    """Five seeds cut into three evaluations, each with FBSM flown again: pooled, the table is
    the one-folder table (same runs, same aggregate, references counted once)."""
    policy = "ppo_cross_track_guard_alloc"
    folders = _split_suite(tmp_path, policy, [[0, 1], [2, 3], [4]])
    argv = ["--policy", policy, "--reps", "100", "--out"]
    whole = main(["--suite", str(SUITE), *argv, str(tmp_path / "whole")])
    pooled = main(["--suite", ",".join(map(str, folders)), *argv, str(tmp_path / "pooled")])
    assert pooled["suite"] == "part_0,part_1,part_2"
    assert pooled["runs"] == whole["runs"]
    assert pooled["aggregate_iqm"] == whole["aggregate_iqm"]
    assert pooled["references"] == whole["references"]
    assert pooled["episodes"] == 5 * 130


def test_pooling_refuses_an_episode_that_scored_differently(tmp_path: Path) -> None:
    """The same FBSM episode with another RMS in the second folder (another code version):
    refused, naming the episode and both folders."""
    first, second = _split_suite(tmp_path, "ppo_cross_track_guard_alloc", [[0], [1]])
    text = (second / "episodes.csv").read_text()
    row = next(line for line in text.splitlines() if line.startswith("fbsm,0,scenario:line,"))
    fields = row.split(",")
    fields[5] = str(float(fields[5]) + 1e-9)
    (second / "episodes.csv").write_text(text.replace(row, ",".join(fields)))
    with pytest.raises(ValueError, match=r"'fbsm' run 0, set 'scenario:line' seed .* in .*part_1"):
        pool_suites([first, second])


def test_pooling_refuses_a_set_defined_differently(tmp_path: Path) -> None:
    """The second evaluation flew `scenario:line` with another corridor: refused, naming the set
    and both folders, before any statistic."""
    first, second = _split_suite(tmp_path, "ppo_cross_track_guard_alloc", [[0], [1]])
    suite = json.loads((second / "suite.json").read_text())
    suite["sets"]["scenario:line"]["env"]["corridor"] = 3.0
    (second / "suite.json").write_text(json.dumps(suite))
    with pytest.raises(ValueError, match=r"set 'scenario:line' is defined differently in .*part_0"):
        pool_suites([first, second])


def test_a_folder_named_twice_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """`--suite A,A` would count every episode of A once and say nothing: a usage error."""
    with pytest.raises(SystemExit):
        main(["--suite", f"{SUITE},{SUITE}", "--policy", "fbsm", "--out", str(tmp_path)])
    assert "--suite names" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("flag", "value", "message"),
    [
        ("--sets", "scenario:line,scenario:line", "--sets names"),
        ("--sets", "scenario:line,", "--sets has an empty name"),
        ("--references", "fbsm,,fbsm_colos", "--references has an empty name"),
    ],
)
def test_a_set_or_reference_named_twice_or_empty_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture, flag: str, value: str, message: str
) -> None:
    """As for --suite: a repeated or empty name is a usage error, not silently dropped."""
    with pytest.raises(SystemExit):
        main(["--suite", str(SUITE), "--policy", "fbsm", flag, value, "--out", str(tmp_path)])
    assert message in capsys.readouterr().err
