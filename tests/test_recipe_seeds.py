"""The ten-seed report of a recipe: per-seed verdicts against the classical policies, intervals."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from benchmarks.analysis import recipe_seeds

EPISODES = list(range(10))


def _results(rms: float, failed: int = 0) -> list[dict]:
    return [
        {
            "seed": s,
            "rms_distance": rms + 0.001 * s,
            "termination_reason": "corridor" if s < failed else "",
        }
        for s in EPISODES
    ]


def _run(folder: Path, seeds: dict[int, tuple[float, int]], scenario: str = "paper") -> Path:
    """A one-phase train-seeds run with the given seeds' test RMS and failed counts."""
    entries = []
    for seed, (rms, failed) in seeds.items():
        agent = folder / f"seed_{seed}" / "best"
        agent.mkdir(parents=True)
        held_out = {
            "scenario": scenario,
            "seeds": EPISODES,
            "duration_s": 200.0,
            "transient_s": 100.0,
            "results": _results(rms, failed),
        }
        (agent / "held_out_evaluation.json").write_text(json.dumps(held_out))
        entries.append(
            {"seed": seed, "agent": str(agent), "wall_time_s": 600.0, "num_timesteps": 3e6}
        )
    (folder / "summary.json").write_text(json.dumps({"seeds": entries}))
    return folder


@pytest.fixture
def classical(monkeypatch):
    fake = {"fbsm": _results(0.0660), "fbsm_colos": _results(0.0645)}
    monkeypatch.setattr(recipe_seeds, "classical_results", lambda *a, **k: fake)
    return fake


def test_each_seed_is_judged_against_the_classical_policies(tmp_path, classical) -> None:
    a = _run(tmp_path / "a", {0: (0.05, 0), 1: (0.065, 0)})
    b = _run(tmp_path / "b", {2: (0.04, 1)})  # better on the rest, but one episode failed
    record = recipe_seeds.main(["--runs", f"{a},{b}", "--out", str(tmp_path / "out")])
    seeds = record["seeds"]
    assert seeds["0"]["beats"] == {"fbsm": True, "fbsm_colos": True}
    assert seeds["1"]["beats"] == {"fbsm": True, "fbsm_colos": False}  # 0.0695 vs 0.0690
    assert seeds["2"]["failed"] == 1 and not any(seeds["2"]["beats"].values())
    assert seeds["2"]["rms_distance"] == pytest.approx(
        (30.0 + sum(0.04 + 0.001 * s for s in EPISODES[1:])) / 10
    )
    assert record["beat_counts"] == {"fbsm": 2, "fbsm_colos": 1}
    assert record["failed_episodes"] == 1 and record["episodes"] == 30
    iqm = record["intervals"]["iqm"]["recipe"]
    assert iqm[1] <= iqm[0] <= iqm[2]
    assert "Seeds beating FBSM: 2 of 3" in (tmp_path / "out" / "summary.md").read_text()


def test_seeds_of_other_episodes_or_twice_are_refused(tmp_path, classical) -> None:
    a = _run(tmp_path / "a", {0: (0.05, 0)})
    twice = _run(tmp_path / "b", {0: (0.05, 0)})
    other = _run(tmp_path / "c", {1: (0.05, 0)}, scenario="storm")
    with pytest.raises(ValueError, match="seed 0 appears in two runs"):
        recipe_seeds.seed_agents([a, twice])
    with pytest.raises(ValueError, match="other episodes"):
        recipe_seeds.seed_agents([a, other])
    with pytest.raises(ValueError, match=r"no summary\.json"):
        recipe_seeds.seed_agents([tmp_path])
