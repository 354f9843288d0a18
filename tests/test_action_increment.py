"""Incremental agents (`controllers.action_increment`, `benchmarks.training.action_increment`):
the command is clip(a_prev + δ·Δ, −1, 1) with a_prev read from the observation, the same in
the training wrapper (also across autoresets) and in a loaded agent; bad values are named."""

from __future__ import annotations

import json

import numpy as np
import pytest

from auv_gym.observation import ObservationConfig
from controllers.action_increment import (
    apply_increment,
    check_increment,
    prev_action_index,
)

AGENT_NAMES = ObservationConfig.from_spec("preview").names


def test_hand_computed_increments_saturate_at_the_bounds():
    obs = np.zeros(len(AGENT_NAMES), np.float32)
    obs[prev_action_index(AGENT_NAMES)] = (0.5, -0.95, 0.0)
    command = apply_increment(obs, np.array([1.0, -1.0, 0.5]), 0.1, prev_action_index(AGENT_NAMES))
    np.testing.assert_allclose(command, [0.6, -1.0, 0.05], rtol=1e-6)
    assert command.dtype == np.float32
    batch = apply_increment(np.stack([obs, obs]), np.zeros((2, 3)), 0.1, [18, 19, 20])
    np.testing.assert_array_equal(batch, np.float32([[0.5, -0.95, 0.0]] * 2))


@pytest.mark.parametrize("value", [0.0, -0.1, 2.5, float("nan"), float("inf"), True, "0.1"])
def test_bad_increments_are_named(value):
    with pytest.raises(ValueError, match=r"cfg: action_increment must be a number in \(0, 2\]"):
        check_increment(value, "cfg")


def test_an_observation_without_the_previous_action_is_refused():
    with pytest.raises(ValueError, match=r"missing \['a_X_prev', 'a_M_prev', 'a_N_prev'\]"):
        prev_action_index(ObservationConfig.from_spec("paper").names)


@pytest.mark.rl
def test_the_training_wrapper_integrates_and_restarts_at_zero_after_an_autoreset():
    from benchmarks.training.action_increment import IncrementalActions
    from benchmarks.training.train import make_training_env

    venv = make_training_env(2, 0, {"max_time": 1.0}, env_id="AUVPath3DPreview-v0")
    wrapped = IncrementalActions(venv, 0.25, AGENT_NAMES)
    index = prev_action_index(AGENT_NAMES)
    obs = wrapped.reset()
    np.testing.assert_array_equal(obs[:, index], 0.0)
    seen = []
    for _ in range(21):  # 1 s = 20 steps of 0.05 s, then the autoreset
        obs, _, dones, infos = wrapped.step(np.tile(np.float32([1.0, -0.5, 0.0]), (2, 1)))
        seen.append(obs[0, index].copy())
        if dones[0]:
            terminal = infos[0]["terminal_observation"]
            np.testing.assert_array_equal(terminal[index], np.float32([1.0, -1.0, 0.0]))
            np.testing.assert_array_equal(obs[:, index], 0.0)  # the new episode's first
    np.testing.assert_allclose(seen[0], [0.25, -0.125, 0.0])
    np.testing.assert_allclose(seen[3], [1.0, -0.5, 0.0])  # saturated at 1 after 4 steps
    np.testing.assert_allclose(seen[8], [1.0, -1.0, 0.0])
    np.testing.assert_allclose(seen[20], [0.25, -0.125, 0.0])  # integrating again from 0
    venv.close()


@pytest.mark.rl
def test_a_loaded_incremental_agent_commands_what_training_applied(
    tmp_path, train_tiny_preview_agent
):
    from controllers.action_increment import IncrementPolicy
    from controllers.ppo import load_policy

    train_tiny_preview_agent(tmp_path, action_increment=0.2)
    policy = load_policy(tmp_path / "agent")
    assert isinstance(policy, IncrementPolicy) and policy.increment == 0.2
    rng = np.random.default_rng(1)
    obs = rng.normal(0.0, 1.0, (5, len(AGENT_NAMES))).astype(np.float32)
    obs[:, prev_action_index(AGENT_NAMES)] = rng.uniform(-1, 1, (5, 3))
    delta, _ = policy.actor.predict(obs)
    command, _ = policy.predict(obs)
    prev = obs[:, prev_action_index(AGENT_NAMES)]
    np.testing.assert_array_equal(command, np.clip(prev + np.float32(0.2) * delta, -1, 1))
    meta_file = tmp_path / "agent" / "metadata.json"
    meta = json.loads(meta_file.read_text())
    meta["action_increment"] = -1
    meta_file.write_text(json.dumps(meta))
    with pytest.raises(ValueError, match=r"metadata.json: action_increment must be a number"):
        load_policy(tmp_path / "agent")
