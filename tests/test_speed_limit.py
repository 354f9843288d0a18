"""Realistic speed (issue 14 item 3): the surge limit of AUVPath3DSpeedLimit-v0 and the speed
metrics."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import auv_gym  # noqa: F401  (registers the ids)
from auv_gym import AUVParams, AUVPath3DEnv
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.metrics import compute_metrics
from auv_gym.sim.task import RewardWeights
from auv_gym.sim.trajectory import INTERVAL_FIELDS, SAMPLE_FIELDS, Trajectory

FULL_THRUST = np.array([1.0, 0.0, 0.0])


def _sprint(env, steps: int = 400):
    """Full surge thrust from the paper's start: (surges, rewards, infos, terminated)."""
    env.reset(seed=3)
    surges, rewards, infos = [], [], []
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(FULL_THRUST)
        surges.append(float(obs[6]))
        rewards.append(reward)
        infos.append(info)
        if terminated or truncated:
            return np.array(surges), rewards, infos, terminated
    return np.array(surges), rewards, infos, False


def test_v0_has_no_surge_limit_and_its_reward_is_the_sum_without_the_overspeed_term():
    surges, rewards, infos, _ = _sprint(AUVPath3DEnv(), steps=200)
    assert surges.max() > 4.0  # the sprint the issue saw, not cut short
    assert all(info.get("termination_reason") != "overspeed" for info in infos)
    for reward, info in zip(rewards, infos, strict=True):
        assert info["reward_overspeed"] == 0.0 and math.copysign(1, info["reward_overspeed"]) < 0
        terms = [
            info[f"reward_{t}"]
            for t in ("progress", "tracking", "distance", "speed", "effort", "termination")
        ]
        assert reward == sum(terms)  # the v0 formula, bit for bit (adding −0.0 changes nothing)


def test_v1_terminates_above_the_surge_limit_with_the_failure_penalty():
    env = gym.make("AUVPath3DSpeedLimit-v0")
    assert env.unwrapped.config.limits.surge_limit == AUVParams().max_surge == 2.0
    surges, _, infos, terminated = _sprint(env)
    assert terminated and infos[-1]["termination_reason"] == "overspeed"
    assert surges[-1] > 2.0 and surges[:-1].max() <= 2.0  # the first step above the limit
    assert infos[-1]["reward_termination"] == -100.0
    assert infos[-1]["reward_overspeed"] == -1.0  # the ramp is saturated above u_max
    # On the ramp: −w·((u − u_D)/(u_max − u_D))² with u_D = 1 m/s, u_max = 2 m/s, w = 1.
    k = int(np.argmax(surges > 1.5))
    u = np.float32(surges[k])  # the term uses the float64 observation; compare to 1e-6
    assert infos[k]["reward_overspeed"] == pytest.approx(-((u - 1.0) ** 2), abs=1e-6)
    below = surges < 1.0
    assert all(infos[i]["reward_overspeed"] == 0.0 for i in np.flatnonzero(below))


def test_v1_vector_env_matches_the_single_env_and_weights_are_arguments():
    venv = gym.make_vec("AUVPath3DSpeedLimit-v0", num_envs=2)
    assert isinstance(venv, AUVPath3DVectorEnv) and venv.config.limits.surge_limit == 2.0
    env = AUVPath3DEnv(surge_limit=2.0, reward_weights=RewardWeights(overspeed=5.0))
    env.reset(seed=0)
    for _ in range(300):
        *_, terminated, _, info = env.step(FULL_THRUST)
        if terminated:
            break
    assert info["termination_reason"] == "overspeed" and info["reward_overspeed"] == -5.0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"surge_limit": 1.0}, r"surge_limit must be above u_desired = 1.0 m/s"),
        ({"surge_limit": 0.5}, r"surge_limit must be above u_desired"),
        ({"surge_limit": 11.0}, r"at most 10.0 m/s, or inf, got 11.0"),
        ({"surge_limit": -1.0}, r"surge_limit must be a positive speed"),
        ({"surge_limit": math.nan}, r"surge_limit must be a positive speed"),
        ({"surge_limit": 3.0, "u_desired": 3.5}, r"above u_desired = 3.5 m/s"),
    ],
)
def test_bad_surge_limits_are_named(kwargs, message):
    with pytest.raises(ValueError, match=message):
        AUVPath3DEnv(**kwargs)


def test_speed_metrics_by_hand():
    """u over 6 intervals of 0.5 s: two end samples above 2.0 m/s (2.5 and 2.01), 2.0 is not."""
    u = np.array([0.0, 1.0, 2.5, 2.0, 2.01, 1.5, 1.0])
    samples = {name: np.zeros(7) for name in SAMPLE_FIELDS}
    samples["u"] = u
    intervals = {name: np.zeros(6) for name in INTERVAL_FIELDS}
    tr = Trajectory(t=0.5 * np.arange(7), samples=samples, intervals=intervals, control_dt=0.5)
    m = compute_metrics(tr, transient=0.0)
    assert m["max_surge"] == 2.5
    assert m["overspeed_fraction"] == pytest.approx(2 / 6)
    tr0 = Trajectory(
        t=np.zeros(1),
        samples={n: np.zeros(1) for n in SAMPLE_FIELDS},
        intervals={n: np.zeros(0) for n in INTERVAL_FIELDS},
    )
    assert compute_metrics(tr0, transient=0.0)["overspeed_fraction"] == 0.0
