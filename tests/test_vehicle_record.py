"""One vehicle record: the top speed of `AUVParams` is the speed-limited env ids' surge limit."""

from __future__ import annotations

import gymnasium as gym
import pytest

import auv_gym
from auv_gym.config import SimConfig
from auv_gym.rollout import rollout
from auv_gym.task import SURGE_LIMIT, VEHICLE_TOP_SPEED
from auv_gym.vehicle import AUVParams, remus100
from controllers.pid import PIDLOS


def test_the_speed_limited_ids_take_the_vehicles_top_speed() -> None:
    assert remus100().max_surge == SURGE_LIMIT == 2.0
    for env_id in (auv_gym.SPEED_LIMIT_ENV_ID, auv_gym.PREVIEW_ENV_ID):
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
        ({"surge_limit": "fast"}, ValueError,
         r"^surge_limit must be a speed in m/s, inf or 'vehicle' \(params.max_surge\), "
         r"got 'fast'$"),
        ({"params": {"max_surge": 0.0}}, ValueError, r"^AUVParams.max_surge must be positive"),
        ({"surge_limit": "vehicle", "params": {"max_surge": 0.9}}, ValueError,
         r"^surge_limit must be above u_desired = 1.0 m/s"),
    ],
)  # fmt: skip
def test_a_bad_top_speed_is_one_line(kwargs, error, message) -> None:
    with pytest.raises(error, match=message):
        SimConfig.from_kwargs(**kwargs)
    assert AUVParams().max_surge == 2.0
