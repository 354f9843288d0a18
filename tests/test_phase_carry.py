"""A schedule's selection across phases (`benchmarks.training.phase_carry`, ``keep_earlier``).

A seed keeps the agent its phase started from when that agent scored strictly lower on the same
validation episodes, by the same rule; its entry then names the phase it was kept from and the
choice among seeds is made again. Agents validated on other episodes, or without a record of
them, are never compared."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from benchmarks.training.phase_carry import keep_earlier

VALIDATION = {
    "eval_env_kwargs": {"path": "helix", "random_current": 0.2},
    "eval_seeds": [100_200, 100_201],
    "options": {"eval_duration": 200.0},
    "config": {"selection": {"failures_allowed": 1, "across_variants": "geometric"}},
}


def entry(tmp_path: Path, name: str, seed: int, score: list, **changes) -> dict:
    """A phase summary's entry for ``seed`` whose agent folder records ``VALIDATION`` with
    ``changes``."""
    agent = tmp_path / name / f"seed_{seed}" / "best"
    agent.mkdir(parents=True)
    (agent / "metadata.json").write_text(json.dumps({**VALIDATION, **changes}))
    return {"seed": seed, "agent": str(agent), "validation_score": score, "test_summary": {}}


def test_a_seed_keeps_the_earlier_agent_that_validated_better_and_the_choice_is_made_again(
    tmp_path,
):
    base = {
        "seeds": [
            entry(tmp_path, "base", 0, [0, 0.130]),
            entry(tmp_path, "base", 1, [0, 0.128]),
        ],
        "selected_seed": 1,
    }
    precision = {
        "seeds": [
            entry(tmp_path, "precision", 0, [0, 0.125]),  # better than its start: its own
            entry(tmp_path, "precision", 1, [3, 0.201]),  # three failures beyond the allowance
        ],
        "selected_seed": 0,
    }
    kept = keep_earlier(base, precision, "base")
    own, carried = kept["seeds"]
    assert own == precision["seeds"][0] and "kept_from" not in own
    assert carried == {**base["seeds"][1], "kept_from": "base"}
    assert kept["selected_seed"] == 0  # (0, 0.125) beats the kept (0, 0.128)
    # a later phase keeps the name of the phase the agent came from
    later = {"seeds": [entry(tmp_path, "later", 1, [0, 0.2])], "selected_seed": 1}
    again = keep_earlier({"seeds": [carried]}, later, "precision")
    assert again["seeds"][0]["kept_from"] == "base"
    assert again["seeds"][0]["agent"] == base["seeds"][1]["agent"]


def test_a_tie_keeps_the_phases_own_agent(tmp_path):
    base = {"seeds": [entry(tmp_path, "base", 0, [0, 0.1])], "selected_seed": 0}
    fine = {"seeds": [entry(tmp_path, "fine", 0, [0, 0.1])], "selected_seed": 0}
    assert keep_earlier(base, fine, "base")["seeds"][0]["agent"] == fine["seeds"][0]["agent"]


@pytest.mark.parametrize(
    "changes",
    [
        {"eval_seeds": [100_200]},  # other episodes
        {"eval_env_kwargs": {"path": "helix", "random_current": 0.5}},  # other ocean
        {"options": {"eval_duration": 300.0}},
        {"config": {}},  # another rule (the default)
        {"eval_seeds": None},  # no record of its validation
    ],
)
def test_agents_validated_otherwise_are_never_compared(tmp_path, changes):
    base = {"seeds": [entry(tmp_path, "base", 0, [0, 0.05])], "selected_seed": 0}
    fine = {"seeds": [entry(tmp_path, "fine", 0, [2, 0.3], **changes)], "selected_seed": 0}
    assert keep_earlier(base, fine, "base")["seeds"] == fine["seeds"]


def test_an_agent_without_metadata_is_not_compared(tmp_path):
    base = {"seeds": [entry(tmp_path, "base", 0, [0, 0.05])], "selected_seed": 0}
    fine = {"seeds": [entry(tmp_path, "fine", 0, [2, 0.3])], "selected_seed": 0}
    (Path(base["seeds"][0]["agent"]) / "metadata.json").unlink()
    assert keep_earlier(base, fine, "base")["seeds"] == fine["seeds"]
