"""The reference generalist (`benchmarks/agents/ppo_generalist`) runs under the env it carries
and follows the paper's helix at the accuracy docs/results.md reports for it."""

from __future__ import annotations

from pathlib import Path

import pytest

pytestmark = pytest.mark.rl
pytest.importorskip("stable_baselines3")

AGENT = Path(__file__).resolve().parents[1] / "benchmarks" / "agents" / "ppo_generalist"
FBSM_PAPER_RMS = 0.064  # [m] FBSM on the paper scenario (docs/results.md)


def test_the_reference_generalist_follows_the_paper_helix_under_its_own_env() -> None:
    import controllers
    from auv_gym.rollout import evaluate
    from benchmarks.catalog.policies import agent_run

    _, env_id, agent_env = agent_run("test", AGENT)
    assert env_id == "AUVPath3DPreview-v0"
    assert agent_env["observation"]["integral_errors"] == "xyz"
    policy = controllers.make("agent", path=str(AGENT))
    results = evaluate(policy, [0, 1], max_time=200.0, surge_limit="vehicle", **agent_env)
    assert [r["termination_reason"] for r in results] == ["time_limit"] * 2
    # Suite IQM on `paper`: 0.0427 m over ten seeds against FBSM's 0.0641 m.
    assert max(r["rms_distance"] for r in results) < 0.8 * FBSM_PAPER_RMS


def test_an_agent_runs_under_the_env_it_carries_unless_told_otherwise() -> None:
    """`evaluate(agent, seeds)` needs no env arguments: the agent's id and observation are its
    defaults (it once failed with "observation must have shape (49,)"); given ones win."""
    import controllers
    from auv_gym.rollout import evaluate

    policy = controllers.make("agent", path=str(AGENT))
    assert policy.env_kwargs["observation"]["integral_limit"] == 1.0
    (result,) = evaluate(policy, [0], max_time=120.0)
    assert result["termination_reason"] == "time_limit"
    assert result["rms_distance"] < FBSM_PAPER_RMS
    (calm,) = evaluate(policy, [0], max_time=120.0, disturbance="none")
    assert calm["rms_distance"] < result["rms_distance"]
