"""`benchmarks.analysis.suite_seeds`: a multi-seed policy on the test suite, seed by seed."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from benchmarks.analysis.suite_seeds import main, seed_table
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
