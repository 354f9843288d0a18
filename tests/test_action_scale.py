"""Scaled agents (`controllers.action_scale`, `benchmarks.training.action_scale`): the command is
k ⊙ clip(y, −1, 1), the same in the training wrapper and in a loaded agent; the surge range it
is for; bad values and excluded combinations are named."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

import auv_gym  # noqa: F401 - registers the ids
from controllers.action_scale import apply_scale, check_action_scale

SURGE_SCALE = (0.15, 1.0, 1.0)


def speed_for_thrust(command: float, seconds: float = 80.0) -> float:
    """Surge speed [m/s] after ``seconds`` of a constant normalised surge command, calm water,
    no moments (the vehicle's top speed for that thrust)."""
    env = gym.make(
        "AUVPath3DPreview-v0", disturbance="none", max_time=seconds + 1.0, corridor=500.0
    )
    env.reset(seed=0)
    for _ in range(round(seconds / 0.05)):
        env.step(np.array([command, 0.0, 0.0]))
    return float(env.unwrapped.state[5])


def test_the_surge_range_an_agent_needs_is_a_few_percent_of_the_command():
    """1 m/s takes about 3 % of the ±50 N range, the 2.0 m/s limit 15 %: the scale's reason."""
    assert 0.9 < speed_for_thrust(0.03) < 1.0  # 1.5 N
    assert 1.85 < speed_for_thrust(0.12) < 2.0  # 6 N
    assert speed_for_thrust(0.15) > 1.99  # 7.5 N: at the limit
    assert speed_for_thrust(1.0) > 2.0  # the whole range: past it


def test_hand_computed_scaled_commands_clip_the_output_first():
    command = apply_scale(np.array([1.0, 0.5, -2.0]), SURGE_SCALE)
    np.testing.assert_array_equal(command, np.float32([0.15, 0.5, -1.0]))
    assert command.dtype == np.float32
    batch = apply_scale(np.array([[3.0, -0.25, 0.0], [-1.0, 1.0, 0.5]]), (0.5, 0.5, 1.0))
    np.testing.assert_array_equal(batch, np.float32([[0.5, -0.125, 0.0], [-0.5, 0.5, 0.5]]))


@pytest.mark.parametrize(
    "value",
    [
        (0.0, 1.0, 1.0),
        (1.5, 1.0, 1.0),
        (float("nan"), 1.0, 1.0),
        (0.1, 1.0),
        (True, 1.0, 1.0),
        "0.1",
        0.1,
        None,
    ],
)
def test_bad_scales_are_named(value):
    with pytest.raises(ValueError, match=r"cfg: action_scale must be three numbers in \(0, 1\]"):
        check_action_scale(value, "cfg")


@pytest.mark.rl
def test_the_training_wrapper_applies_the_scale_to_the_env_commands():
    from benchmarks.training.action_scale import ScaledActions
    from benchmarks.training.train import make_training_env

    venv = ScaledActions(
        make_training_env(
            2, 0, {"disturbance": "none"}, kind="dummy", env_id="AUVPath3DPreview-v0"
        ),
        SURGE_SCALE,
    )
    venv.reset()
    _, _, _, infos = venv.step(np.float32([[1.0, 0.5, -2.0], [-0.2, 0.0, 0.3]]))
    tau = np.array([info["tau"] for info in infos])  # the applied (X [N], M, N [N·m])
    np.testing.assert_allclose(tau, [[7.5, 5.0, -10.0], [-1.5, 0.0, 3.0]], rtol=1e-6)
    venv.close()


@pytest.mark.rl
def test_a_file_refuses_a_scale_with_a_box_an_increment_or_a_bad_value(tmp_path):
    import yaml

    from benchmarks.training.config import read_zoo_config

    base = {"n_envs": 2, "n_timesteps": 64, "policy": "MlpPolicy", "normalize": True}
    for extra, message in [
        (
            {"action_scale": [0.15, 1, 1], "action_bounds": [[-1, -1, -1], [1, 1, 1]]},
            "action_scale excludes residual, action_bounds and action_increment",
        ),
        (
            {"action_scale": [0.15, 1, 1], "action_increment": 0.1},
            "action_scale excludes residual, action_bounds and action_increment",
        ),
        ({"action_scale": [0.15, 1]}, "action_scale must be three numbers"),
    ]:
        config = tmp_path / "cfg.yml"
        config.write_text(yaml.safe_dump({"AUVPath3DPreview-v0": {**base, **extra}}))
        with pytest.raises(ValueError, match=message):
            read_zoo_config(config, "AUVPath3DPreview-v0", "ppo")


@pytest.mark.rl
def test_a_loaded_scaled_agent_commands_what_training_applied(tmp_path, train_tiny_preview_agent):
    from auv_gym.observation import ObservationConfig
    from controllers.action_scale import ScaledPolicy
    from controllers.ppo import load_policy

    train_tiny_preview_agent(tmp_path, action_scale=list(SURGE_SCALE))
    meta_file = tmp_path / "agent" / "metadata.json"
    assert json.loads(meta_file.read_text())["action_scale"] == list(SURGE_SCALE)
    policy = load_policy(tmp_path / "agent")
    assert isinstance(policy, ScaledPolicy) and policy.scale == SURGE_SCALE
    obs = (
        np.random.default_rng(1)
        .normal(0.0, 1.0, (64, len(ObservationConfig.from_spec("preview").names)))
        .astype(np.float32)
    )
    output, _ = policy.actor.predict(obs)
    command, _ = policy.predict(obs)
    np.testing.assert_array_equal(command, np.clip(output, -1, 1) * np.float32(SURGE_SCALE))
    assert np.abs(command[:, 0]).max() <= 0.15
    meta = json.loads(meta_file.read_text())
    meta["action_scale"] = [0.15, 2.0, 1.0]
    meta_file.write_text(json.dumps(meta))
    with pytest.raises(ValueError, match=r"metadata.json: action_scale must be three numbers"):
        load_policy(tmp_path / "agent")
    meta["action_scale"], meta["action_increment"] = list(SURGE_SCALE), 0.1
    meta_file.write_text(json.dumps(meta))
    with pytest.raises(ValueError, match=r"metadata.json: action_scale excludes"):
        load_policy(tmp_path / "agent")
