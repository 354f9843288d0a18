"""Each leftover of the third hardening round, reproduced: refused in one line, before any work,
nothing run that the input asked for."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from gymnasium.error import ResetNeeded

import controllers
from auv_gym.envs.env import AUVPath3DEnv
from benchmarks.catalog.policies import AGENTS_DIR

ROOT = Path(__file__).resolve().parents[1]


def test_step_before_reset_is_refused_and_a_refused_reset_leaves_the_env_usable():
    env = AUVPath3DEnv()
    with pytest.raises(ResetNeeded, match=r"call reset\(\) before step\(\)"):
        env.step(np.zeros(3, np.float32))
    obs, _ = env.reset(seed=0)
    assert env.step(np.zeros(3, np.float32))[0].shape == obs.shape
    with pytest.raises(ValueError, match="takes no options"):
        env.reset(seed=1, options={"x": 1})
    with pytest.raises(ResetNeeded):  # was: an unrelated TypeError
        env.step(np.zeros(3, np.float32))
    env.reset(seed=1)
    assert np.isfinite(env.step(np.zeros(3, np.float32))[1])


def test_an_agent_path_of_the_wrong_type_is_named():
    with pytest.raises(
        TypeError, match=r"agent path must be a folder or model zip path .* int 123"
    ):
        controllers.make("agent", path=123)


@pytest.mark.rl
def test_non_finite_weights_are_named(tmp_path):
    from stable_baselines3 import PPO

    agent = tmp_path / "agent"
    shutil.copytree(AGENTS_DIR / "ppo_generalist", agent)
    model = PPO.load(agent / "model.zip", device="cpu")
    with __import__("torch").no_grad():
        model.policy.action_net.weight[0, 0] = float("nan")
    model.save(agent / "model.zip")
    with pytest.raises(ValueError, match=r"non-finite weights in \['action_net.weight'\]"):
        controllers.make("agent", path=str(agent))


def test_an_empty_out_is_refused_and_nothing_is_written(tmp_path, auv_gym_command):
    code, err = auv_gym_command("compare", "--policies", "fbsm", "--out", "", cwd=tmp_path)
    assert code == 2 and err.endswith(
        "argument --out: must name a file or folder, got an empty path"
    )
    assert list(tmp_path.iterdir()) == []


@pytest.mark.rl
def test_an_infinite_step_count_and_malformed_yaml_are_one_line(tmp_path, auv_gym_command):
    code, err = auv_gym_command(
        "train",
        "--config",
        str(ROOT / "benchmarks/hyperparams/ppo_helix.yml"),
        "--n-timesteps",
        "inf",
        "--out",
        str(tmp_path / "a"),
    )
    assert code == 2 and len(err.splitlines()) == 1 and "'inf' is not a whole number" in err
    bad = tmp_path / "bad.yml"
    bad.write_text("AUVPath3D-v0:\n  n_envs: [1,\n")
    for command in ("train", "train-seeds"):
        extra = ("--seeds", "1") if command == "train-seeds" else ()
        code, err = auv_gym_command(
            command, "--config", str(bad), *extra, "--out", str(tmp_path / "b")
        )
        assert code == 2 and len(err.splitlines()) == 1, err
        assert f"{bad}: cannot be read as YAML" in err
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


@pytest.mark.rl
def test_a_policy_kwargs_payload_never_runs(tmp_path):
    from benchmarks.training.config import read_zoo_config

    marker = tmp_path / "payload_ran"
    for payload in (
        f"__import__('os').system('touch {marker}')",
        f"dict(net_arch=().__class__.__base__.__subclasses__(), x=open('{marker}', 'w'))",
    ):
        config = tmp_path / "evil.yml"
        config.write_text(
            "AUVPath3D-v0:\n  n_timesteps: 1000\n  policy: MlpPolicy\n"
            f'  normalize: true\n  policy_kwargs: "{payload}"\n'
        )
        with pytest.raises(ValueError, match=r"evil.yml: policy_kwargs: .* is not a literal"):
            read_zoo_config(config, "AUVPath3D-v0", "ppo")
    assert not marker.exists()
    config.write_text(
        "AUVPath3D-v0:\n  n_timesteps: 1000\n  policy: MlpPolicy\n  normalize: true\n"
        '  policy_kwargs: "dict(net_arch=dict(pi=[32], vf=[32]), activation_fn=nn.ReLU)"\n'
    )
    import torch

    cfg = read_zoo_config(config, "AUVPath3D-v0", "ppo")
    assert cfg.policy_kwargs == {
        "net_arch": {"pi": [32], "vf": [32]},
        "activation_fn": torch.nn.ReLU,
    }


def test_an_agent_whose_stages_cannot_fly_a_scenario_is_refused_before_any_episode(
    tmp_path, auv_gym_command, tiny_paper_agent
):
    """Was: compare checked an agent's allocation only when its episodes came, after the other
    policies' had run. The agent observes the paper's 15 values: no previous action."""
    import json

    agent = tiny_paper_agent
    meta = json.loads((agent / "metadata.json").read_text())
    meta["stages"] = [{"name": "actuator_allocation", "commands": "paper"}]
    (agent / "metadata.json").write_text(json.dumps(meta))
    out = tmp_path / "run"
    episodes = "--scenarios paper,fins --seeds 1 --duration 20".split()
    code, err = auv_gym_command(
        "compare", "--policies", f"fbsm,agent:{agent}", *episodes, "--out", str(out)
    )
    assert code == 2 and len(err.splitlines()) == 1, err
    assert "scenario 'fins'" in err and "previous action" in err
    assert not out.exists()


@pytest.mark.parametrize(
    "bad_reset",
    [{"seed": -1}, {"seed": 0, "options": {"no_such_option": 1}}],
    ids=["negative seed", "unknown option"],
)
def test_a_refused_first_reset_leaves_the_made_env_usable(bad_reset) -> None:
    """Gymnasium 1.4's passive checker breaks the next step after a refused first reset (its
    own CartPole-v1 too); the ids are registered without it, and the env refuses, then flies."""
    import gymnasium as gym

    env = gym.make("AUVPath3D-v0")
    with pytest.raises((ValueError, TypeError, gym.error.Error)):
        env.reset(**bad_reset)
    obs, _ = env.reset(seed=0)
    obs2, reward, terminated, truncated, _ = env.step(np.zeros(3, dtype=np.float32))
    assert obs.shape == obs2.shape == (15,)
    assert np.isfinite(reward) and not terminated and not truncated
    env.close()
