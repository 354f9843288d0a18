"""Choosing a schedule's seed on its agents as they ship (`benchmarks.training.shipped_selection`):
the score is the recorded validation episodes flown with the export stages on (checked against
the same episodes flown by hand), the lowest score wins, a resumed selection flies only what
changed, and an agent without recorded validation episodes is refused in one line."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from benchmarks.training import shipped_selection
from benchmarks.training.evaluation import evaluate_policy_on_seeds, score, summarize
from benchmarks.training.shipped_selection import SHIPPED_FILE, select_shipped, shipped_validation
from controllers.env_settings import policy_settings
from controllers.loader import load_policy

pytestmark = pytest.mark.rl

AGENTS = Path(__file__).resolve().parents[1] / "benchmarks" / "agents"
# A short version of the as-built agent's validation: two seeds of 110 s on each plant.
EPISODES = {
    "actuator": "realistic",
    "disturbance": "ocean",
    "sensors": "typical_kalman",
    "observation": "preview_integral",
    "path": {"families": ["helix", "line"], "radius": [15.0, 40.0]},
    "start_rotation": -1.5707963267948966,
    "surge_limit": "vehicle",
    "plant": ["5dof", "6dof"],
    "max_time": 110.0,
}
SEEDS = [100700, 100701]
FLOOR = {"name": "envelope_guard", "nose_up_command": -1.0}
FLOOR |= {"surge_floor_soft": 1.2, "surge_floor_hard": 0.9}


def _run_agent(tmp_path: Path, source: str, name: str) -> Path:
    """A copy of a shipped agent as a run keeps it: the bare network (no stages) with its
    validation episodes recorded."""
    agent = tmp_path / name
    shutil.copytree(AGENTS / source, agent)
    meta_file = agent / "metadata.json"
    metadata = json.loads(meta_file.read_text())
    metadata.pop("stages", None)
    metadata |= {"eval_env_kwargs": EPISODES, "eval_seeds": SEEDS}
    meta_file.write_text(json.dumps(metadata))
    return agent


def _same(a: dict, b: dict) -> bool:
    """Equal records (a failed episode's NaN equal to itself)."""
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def test_the_score_is_the_validation_flown_with_the_stages_on(tmp_path):
    agent = _run_agent(tmp_path, "ppo_as_built", "best")
    record = shipped_validation(agent, [FLOOR])
    by_hand = []
    for plant in ("5dof", "6dof"):
        episodes = {**EPISODES, "plant": plant}
        policy = load_policy(agent, base_kwargs=policy_settings(episodes), stages=[FLOOR])
        assert [s.name for s in policy.stages] == ["envelope_guard"]
        rows = evaluate_policy_on_seeds(policy, SEEDS, **episodes)
        by_hand += [{**row, "variant": plant} for row in rows]
    assert record["summary"] == summarize(by_hand)
    assert record["score"] == list(score(summarize(by_hand)))
    assert record["summary"]["n_episodes"] == 4 and record["eval_seeds"] == SEEDS
    assert record["stages"][0]["surge_floor_soft"] == 1.2  # checked and filled in
    assert record["stages"][0]["pitch_soft_deg"] == 35.0
    bare = shipped_validation(agent, [])  # the network alone flies other commands
    assert bare["stages"] == []
    assert bare["summary"]["rms_distance_mean"] != record["summary"]["rms_distance_mean"]


def test_the_lowest_score_as_shipped_is_chosen_and_a_resumed_selection_flies_only_changes(
    tmp_path, monkeypatch
):
    entries = [
        {"seed": 3, "agent": str(_run_agent(tmp_path, "ppo_as_built", "a"))},
        {"seed": 8, "agent": str(_run_agent(tmp_path, "ppo_generalist", "b"))},
    ]
    lines: list[str] = []
    chosen, record = select_shipped(tmp_path, entries, [FLOOR], lines.append)
    scores = {int(s): tuple(r["score"]) for s, r in record["seeds"].items()}
    assert scores[3] != scores[8]
    assert chosen == min(scores, key=lambda s: (*scores[s], s)) == record["selected_seed"]
    assert len(lines) == 2 and lines[0].startswith("seed 3 as shipped: ")
    assert scores[8][0] == 4 and chosen == 3  # the paper actuator's agent leaves the corridor
    assert _same(json.loads((tmp_path / SHIPPED_FILE).read_text()), record)

    flown: list[str] = []
    real = shipped_validation

    def counting(agent, stages):
        flown.append(Path(agent).name)
        return real(agent, stages)

    monkeypatch.setattr(shipped_selection, "shipped_validation", counting)
    assert _same(select_shipped(tmp_path, entries, [FLOOR])[1], record)  # nothing flown again
    assert flown == []
    other = [{**FLOOR, "surge_floor_soft": 1.4, "surge_floor_hard": 1.1}]
    again = select_shipped(tmp_path, entries, other)[1]  # other stages: every seed again
    assert flown == ["a", "b"] and again["seeds"]["3"]["stages"][0]["surge_floor_soft"] == 1.4
    (tmp_path / SHIPPED_FILE).write_text("{not json")  # damaged: flown again, never trusted
    flown.clear()
    assert _same(select_shipped(tmp_path, entries, other)[1], again)
    assert flown == ["a", "b"]


def test_an_agent_without_recorded_validation_episodes_is_refused(tmp_path):
    agent = _run_agent(tmp_path, "ppo_as_built", "best")
    metadata = json.loads((agent / "metadata.json").read_text())
    del metadata["eval_seeds"]
    (agent / "metadata.json").write_text(json.dumps(metadata))
    with pytest.raises(ValueError, match=r"best/metadata.json: records no validation episodes"):
        shipped_validation(agent, [FLOOR])
