"""The residual policy's learned filter (``filter_max`` > 0, docs/design.md §3.10): six agent
outputs (c, g); zero output is the base bit for bit, g ≡ 1 is the low-pass baseline bit for bit,
|a| ≤ 1 for any output, the coefficient is 0 at episode starts, and saved agents keep the
six-value action."""

from __future__ import annotations

import json

import numpy as np
import pytest
from gymnasium.vector import AutoresetMode
from hypothesis import given, settings
from hypothesis import strategies as st

import controllers
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.rollout import rollouts
from benchmarks.training.residual import ResidualTraining
from benchmarks.training.residual_env import ResidualVectorEnv
from controllers.residual import (
    RESIDUAL_OBS_DIM,
    ResidualPolicy,
    ResidualSettings,
    agent_action_dim,
    residual_action,
)

ENV = {"disturbance": "paper", "max_time": 4.0}  # 80 control steps
STATE = ("x", "y", "z", "theta", "psi", "u", "v", "w", "q", "r")


class ConstantAgent:
    """Returns the same six outputs (c_X, c_M, c_N, g_X, g_M, g_N) for every row."""

    def __init__(self, value) -> None:
        self.value = np.asarray(value, np.float32)

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        assert observation.shape[1] == RESIDUAL_OBS_DIM
        return np.tile(self.value, (observation.shape[0], 1)), state


def test_action_dim_is_six_with_the_filter_and_three_without():
    assert agent_action_dim(0.0) == 3 and agent_action_dim(0.5) == 6
    assert ResidualSettings(filter_max=0.8).action_dim == 6
    assert ResidualSettings().action_dim == 3
    assert ResidualSettings.from_dict({"filter_max": 0.8}).to_dict()["filter_max"] == 0.8


def test_zero_output_is_the_base_bit_for_bit(assert_same_episodes):
    policy = controllers.make("residual", agent=ConstantAgent(np.zeros(6)), filter_max=0.8)
    got = rollouts(policy, [0, 1], **ENV)
    assert_same_episodes(got, rollouts(controllers.make("fbsm_colos"), [0, 1], **ENV))
    assert all(np.all(t.extras["filter_coefficient"] == 0.0) for t in got)


def test_full_filter_without_correction_is_the_lowpass_baseline_bit_for_bit(assert_same_episodes):
    agent = ConstantAgent([0.0, 0.0, 0.0, 1.0, 1.0, 1.0])
    policy = controllers.make("residual", agent=agent, filter_max=0.5)
    got = rollouts(policy, [0, 1], **ENV)
    assert_same_episodes(got, rollouts(controllers.make("fbsm_colos_lowpass"), [0, 1], **ENV))
    alpha = got[0].extras["filter_coefficient"]
    assert np.all(alpha[0] == 0.0) and np.all(alpha[1:] == 0.5)  # no history at the start


def test_hand_computed_filter_step():
    # α = 0.8 · clip(g) = (0, 0.4, 0.8); t = clip(b + β c): (0.2 + 0.25·1, 0.2, −0.9 − 0.5 → −1)
    b = np.array([[0.2, 0.2, -0.9]], np.float32)
    previous = np.array([[0.6, 0.6, 0.0]], np.float32)
    out = np.array([[1.0, 0.0, -1.0, -0.3, 0.5, 2.0]])
    a = residual_action(b, out, (0.25, 0.5, 0.5), 0.8, previous, np.array([True]))
    np.testing.assert_allclose(a[0], [0.45, 0.4 * 0.6 + 0.6 * 0.2, 0.2 * -1.0], rtol=1e-6)
    fresh = residual_action(b, out, (0.25, 0.5, 0.5), 0.8, previous, np.array([False]))
    np.testing.assert_allclose(fresh[0], [0.45, 0.2, -1.0], rtol=1e-6)  # α = 0 at a start


@settings(max_examples=300, deadline=None)
@given(
    base=st.lists(st.floats(-1.0, 1.0, width=32), min_size=3, max_size=3),
    previous=st.lists(st.floats(-1.0, 1.0, width=32), min_size=3, max_size=3),
    output=st.lists(st.floats(-1e30, 1e30), min_size=6, max_size=6),
    filter_max=st.floats(0.01, 0.99),
)
def test_filtered_action_stays_in_range_for_any_output(base, previous, output, filter_max):
    b, p = np.array([base], np.float32), np.array([previous], np.float32)
    a = residual_action(b, np.array([output]), (0.25, 0.5, 0.5), filter_max, p, np.array([True]))
    assert a.dtype == np.float32 and np.all(np.abs(a) <= 1.0)


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_filter_output_is_an_error(bad):
    agent = ConstantAgent([0.0, 0.0, 0.0, 0.0, bad, 0.0])
    policy = controllers.make("residual", agent=agent, filter_max=0.5)
    with pytest.raises(ValueError, match=r"non-finite correction .* \(row 0\)"):
        rollouts(policy, [0], **ENV)


@pytest.mark.parametrize("value", [-0.1, 1.0, float("nan"), "0.5"])
def test_bad_filter_max_is_named(value):
    with pytest.raises(ValueError, match=r"filter_max must be a number in \[0, 0.99\]"):
        ResidualSettings(filter_max=value)


def test_wrapper_with_filter_takes_six_values_and_matches_the_policy():
    n, steps = 3, 79
    core = AUVPath3DVectorEnv(n, autoreset_mode=AutoresetMode.SAME_STEP, **ENV)
    env = ResidualVectorEnv(core, ResidualTraining(filter_max=0.5))
    assert env.single_action_space.shape == (6,) and env.action_space.shape == (n, 6)
    env.reset(seed=5)
    with pytest.raises(ValueError, match=r"action must have shape \(3, 6\), got \(3, 3\)"):
        env.step(np.zeros((n, 3)))
    full = np.tile([0.0, 0.0, 0.0, 1.0, 1.0, 1.0], (n, 1))
    states = []
    for _ in range(steps):
        states.append(env.core.sim.state[:, :10].copy())
        env.step(full)
    reference = rollouts(controllers.make("fbsm_colos_lowpass"), [5, 6, 7], **ENV)
    for i, ref in enumerate(reference):
        expected = np.stack([ref.samples[f] for f in STATE], 1)[:steps]
        np.testing.assert_array_equal(np.array(states)[:, i], expected)


@pytest.mark.rl
def test_saved_filter_agent_reloads_with_six_actions(
    tmp_path, save_tiny_residual_agent, assert_same_episodes
):
    from benchmarks.training.callbacks import policy_from_model
    from controllers.agent import check_agent
    from controllers.loader import load_policy

    residual = ResidualTraining(filter_max=0.6)
    model, venv = save_tiny_residual_agent(residual, tmp_path / "agent", 3, ENV)
    loaded = load_policy(tmp_path / "agent")
    assert isinstance(loaded, ResidualPolicy) and loaded.filter_max == 0.6
    episodes = rollouts(loaded, [0], **ENV)
    assert_same_episodes(episodes, rollouts(policy_from_model(model, venv, residual), [0], **ENV))
    alpha = episodes[0].extras["filter_coefficient"]
    assert alpha.max() > 0.0 and alpha.max() <= 0.6  # the untrained agent filters somewhere
    with pytest.raises(ValueError, match=r"trained with filter_max 0\.6, not 0\.3"):
        controllers.make("residual", agent=str(tmp_path / "agent"), filter_max=0.3)
    meta_file = tmp_path / "agent" / "metadata.json"
    data = json.loads(meta_file.read_text())
    data["action_shape"] = [3]
    meta_file.write_text(json.dumps(data))
    with pytest.raises(ValueError, match=r"action_shape is \[3\], expected \[6\]"):
        check_agent(tmp_path / "agent")
    del data["action_shape"]
    data["residual"]["filter_max"] = 0.0  # the zip's (6,) action space no longer matches
    meta_file.write_text(json.dumps(data))
    with pytest.raises(ValueError, match=r"action space shape \(6,\), expected \(3,\)"):
        check_agent(tmp_path / "agent")
