"""``cost_penalty`` w: training rewards charged w per unit of the env's safety cost (r − w·c),
the env itself unchanged; bad values are one line naming the key."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

pytestmark = pytest.mark.rl


def _pitching_envs(infos: str = "full"):
    from auv_gym.sb3 import make_sb3_vec_env

    return make_sb3_vec_env(4, seed=3, max_time=30.0, observation="preview", infos=infos)


def test_rewards_are_charged_the_safety_cost_and_nothing_else_changes():
    """Full nose-down pitch moment: the pitch passes the 45° soft limit within the episode; the
    charged reward is r − 2.5·c exactly (float32), observations and dones are the env's."""
    from benchmarks.training.cost_penalty import CostPenalty

    plain, charged = _pitching_envs(), CostPenalty(_pitching_envs("minimal"), 2.5)
    plain.reset()
    charged.reset()
    actions = np.tile(np.float32([0.3, -1.0, 0.0]), (4, 1))
    costly = 0
    ended = 0
    for _ in range(700):
        obs, rewards, dones, infos = plain.step(actions)
        obs2, rewards2, dones2, _ = charged.step(actions)
        cost = np.array([info["cost"] for info in infos])
        np.testing.assert_array_equal(obs2, obs)
        np.testing.assert_array_equal(dones2, dones)
        np.testing.assert_array_equal(rewards2, (rewards - 2.5 * cost).astype(np.float32))
        costly += int((cost > 0).sum())
        ended += int(dones.sum())
    assert costly > 0 and ended > 0  # the soft limit was crossed, and episodes ended


@pytest.mark.parametrize("value", [-1.0, float("nan"), "high", True, 2e6])
def test_a_bad_cost_penalty_is_one_line_naming_it(tmp_path, value):
    from benchmarks.training.config import read_zoo_config

    section = {
        "n_envs": 2,
        "n_timesteps": 64,
        "policy": "MlpPolicy",
        "normalize": True,
        "n_steps": 32,
        "batch_size": 32,
        "cost_penalty": value,
    }
    path = tmp_path / "c.yml"
    path.write_text(yaml.safe_dump({"AUVPath3DPreview-v0": section}))
    with pytest.raises(
        ValueError,
        match=r"AUVPath3DPreview-v0: cost_penalty must be a (real|finite) number in \[0, 1e\+06\]",
    ):
        read_zoo_config(path, "AUVPath3DPreview-v0", "ppo")
    section["cost_penalty"] = 4
    path.write_text(yaml.safe_dump({"AUVPath3DPreview-v0": section}))
    cfg = read_zoo_config(path, "AUVPath3DPreview-v0", "ppo")
    from benchmarks.training.agent_interface import wrap_rewards

    venv = _pitching_envs()
    assert cfg.cost_penalty == 4.0 and wrap_rewards(venv, cfg).weight == 4.0
    del section["cost_penalty"]
    path.write_text(yaml.safe_dump({"AUVPath3DPreview-v0": section}))
    assert wrap_rewards(venv, read_zoo_config(path, "AUVPath3DPreview-v0", "ppo")) is venv
