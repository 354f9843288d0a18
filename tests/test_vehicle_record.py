"""One vehicle record: the top speed of `AUVParams` is the speed-limited env ids' surge limit."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import auv_gym
import controllers
from auv_gym.rollout import rollout
from auv_gym.sim.config import SimConfig
from auv_gym.sim.task import VEHICLE_TOP_SPEED
from auv_gym.vehicle import AUVParams, remus100
from controllers.pid import PIDLOS


def test_the_speed_limited_ids_take_the_vehicles_top_speed() -> None:
    assert remus100().max_surge == 2.0
    for env_id in (
        auv_gym.SPEED_LIMIT_ENV_ID,
        auv_gym.PREVIEW_ENV_ID,
    ):
        assert auv_gym.VARIANTS[env_id]["surge_limit"] == VEHICLE_TOP_SPEED == "vehicle"
        env = gym.make(env_id)
        assert env.unwrapped.config.limits.surge_limit == 2.0
        env.close()
        slow = gym.make(env_id, params=remus100().replace(max_surge=1.5))
        assert slow.unwrapped.config.limits.surge_limit == 1.5
        slow.close()
        explicit = gym.make(env_id, params={"max_surge": 1.5}, surge_limit=3.0)  # the override
        assert explicit.unwrapped.config.limits.surge_limit == 3.0
        explicit.close()
    assert SimConfig.from_kwargs().limits.surge_limit == float("inf")  # v0: no limit


def test_vehicle_is_the_same_episode_as_the_former_number(assert_same_episodes) -> None:
    """REMUS 100 with surge_limit="vehicle" is the former surge_limit=2.0, bit for bit."""
    kwargs = {"max_time": 40.0, "u_desired": 1.8, "randomize_start": True}
    by_name = rollout(PIDLOS(), 4, surge_limit="vehicle", **kwargs)
    by_number = rollout(PIDLOS(), 4, surge_limit=2.0, **kwargs)
    assert by_name.intervals["reward_overspeed"].min() < -1e-3  # the limit acts
    assert_same_episodes([by_name], [by_number])


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        (
            {"surge_limit": "fast"},
            ValueError,
            r"^surge_limit must be a speed in m/s, inf or 'vehicle' \(params.max_surge\), "
            r"got 'fast'$",
        ),
        ({"params": {"max_surge": 0.0}}, ValueError, r"^AUVParams.max_surge must be positive"),
        (
            {"surge_limit": "vehicle", "params": {"max_surge": 0.9}},
            ValueError,
            r"^surge_limit='vehicle' is the vehicle's top speed \(params.max_surge = 0.9 m/s\), "
            r"which must be above u_desired = 1 m/s and at most 10 m/s",
        ),
    ],
)
def test_a_bad_top_speed_is_one_line(kwargs, error, message) -> None:
    with pytest.raises(error, match=message):
        SimConfig.from_kwargs(**kwargs)
    assert AUVParams().max_surge == 2.0


def test_the_default_vehicles_observation_bounds_are_unchanged() -> None:
    """REMUS 100: speeds within ±10 m/s (u_p 20), ground speeds 30 m/s or 1.5·(10 + current)."""
    from auv_gym.sim.observation import OBS_HIGH, OBS_LOW, ObservationConfig, vehicle_speed_bound

    assert vehicle_speed_bound(remus100().max_surge) == 10.0
    for env_id in auv_gym.VARIANTS:
        env = gym.make(env_id)
        low, high = env.observation_space.low, env.observation_space.high
        np.testing.assert_array_equal(low[:15], OBS_LOW)
        np.testing.assert_array_equal(high[:15], OBS_HIGH)
        assert list(high[6:9]) == [10.0] * 3 and list(high[11:13]) == [10.0, 20.0]
        if len(high) > 15:
            assert list(high[15:18]) == [30.0] * 3
        env.close()
    preview = ObservationConfig.from_spec("preview")
    assert preview.bounds(12.0)[1][15] == np.float32(1.5 * (10.0 + 12.0))  # a strong current
    assert preview.bounds(3.0)[1][15] == 30.0


def test_the_shipped_agents_observation_spaces_are_the_envs() -> None:
    pytest.importorskip("stable_baselines3")
    from benchmarks.catalog.policies import REFERENCE_AGENTS, PolicySpec
    from controllers.agent import check_agent
    from controllers.residual import RESIDUAL_FEATURES, ResidualPolicy

    checked = 0
    for name in REFERENCE_AGENTS:
        folder = PolicySpec.parse(name).agent
        if folder is None or not folder.exists():
            continue
        policy = controllers.make("agent", path=str(folder))
        metadata = check_agent(folder).metadata  # an ensemble's: its first member's
        seen = {"observation": metadata["observation"]} if "observation" in metadata else {}
        env_id = auv_gym.resolve_env_id(metadata["env_id"])  # the env the agent carries
        env = gym.make(env_id, **{**metadata["env_kwargs"], **seen})
        low, high = env.observation_space.low, env.observation_space.high
        env.close()
        if isinstance(policy, ResidualPolicy):  # its actor reads the env's, then b and a_{k−1}
            ones = np.ones(len(RESIDUAL_FEATURES), np.float32)
            low, high = np.concatenate([low, -ones]), np.concatenate([high, ones])
            space = policy.agent.observation_space
        else:
            space = policy.observation_space
        np.testing.assert_array_equal(space.low, low, err_msg=name)
        np.testing.assert_array_equal(space.high, high, err_msg=name)
        checked += 1
    assert checked == len(REFERENCE_AGENTS) == 5


def test_a_faster_vehicle_is_observed_within_its_own_speed_bound() -> None:
    """A vehicle of X_max = 300 N reaches 13.6 m/s: REMUS 100's bounds end its episode at 10 m/s
    ("envelope"); with its top speed of 3 m/s the speed bound is 15 m/s and it keeps going."""
    from auv_gym.envs.env import AUVPath3DEnv

    speeds, reasons = {}, {}
    for top in (2.0, 3.0):
        vehicle = remus100().replace(X_max=300.0, max_surge=top)
        env = AUVPath3DEnv(
            path="line", u_desired=8.0, disturbance="none", max_time=12.0, params=vehicle
        )
        assert env.observation_space.high[6] == 5.0 * max(top, 2.0)
        env.reset(seed=0)
        u, info, done = [], {}, False
        while not done:
            obs, _, terminated, truncated, info = env.step(np.array([1.0, 0.0, 0.0], np.float32))
            u.append(obs[6])
            done = terminated or truncated
        speeds[top], reasons[top] = max(u), info.get("termination_reason", "")
    assert reasons[2.0] == "envelope" and 10.0 < speeds[2.0] < 10.5
    assert reasons[3.0] != "envelope" and speeds[3.0] > 13.0
    assert AUVPath3DEnv(params={"max_surge": 1.0}).observation_space.high[6] == 10.0  # ≥ 10
