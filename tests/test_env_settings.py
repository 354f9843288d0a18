"""Policies built from the env's configuration (`controllers.make(name, env=...)`)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import controllers
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.rollout import rollout
from auv_gym.sim.config import SimConfig
from auv_gym.vehicle import remus100
from auv_gym.vehicle.actuators import ActuatorParams
from controllers.env_settings import env_config, policy_settings

# A vehicle, control period and actuator model that are none of the defaults.
_VEHICLE = remus100().replace(X_max=40.0, M_max=8.0, N_max=9.0)
_ACTUATORS = ActuatorParams(fin_rate_max=0.9)


@pytest.mark.parametrize(
    ("name", "actuator", "control_dt"),
    [("fbsm", "fins", 0.1), ("backstepping", "realistic", 0.02), ("pid_los", "fins", 0.03)],
)
def test_a_policy_made_with_env_equals_one_made_with_the_explicit_arguments(
    name: str, actuator: str, control_dt: float, assert_same_episodes
) -> None:
    # the propeller and fin settings configure the realistic actuators only (others refuse them)
    own = {"actuator_params": _ACTUATORS} if actuator == "realistic" else {}
    kwargs = {
        "actuator": actuator,
        "control_dt": control_dt,
        "params": _VEHICLE,
        "max_time": 300 * control_dt,
        **own,
    }
    explicit = controllers.make(
        name, control_dt=control_dt, actuator=actuator, params=_VEHICLE, **own
    )
    config = SimConfig.from_kwargs(**kwargs)
    from_env = controllers.make(name, env=config)
    assert (from_env.control_dt, from_env.actuator) == (control_dt, actuator)
    assert from_env.params == _VEHICLE and from_env.actuator_params == config.actuator_params
    a, b = rollout(explicit, 3, **kwargs), rollout(from_env, 3, **kwargs)
    assert a.intervals["a_X"].shape == (300,) and np.ptp(a.intervals["a_M"]) > 0.1
    assert_same_episodes([a], [b])  # every action, state and reward, bit for bit


def test_env_settings_come_from_an_env_a_vector_env_a_config_or_kwargs() -> None:
    kwargs = {"control_dt": 0.1, "actuator": "fins"}
    env = gym.make("AUVPath3D-v0", **kwargs)  # wrapped: TimeLimit, OrderEnforcing, ...
    vector = AUVPath3DVectorEnv(2, **kwargs)
    expected = {
        "control_dt": 0.1,
        "params": remus100(),
        "actuator": "fins",
        "actuator_params": ActuatorParams(),
    }
    for source in (env, env.unwrapped, vector, SimConfig.from_kwargs(**kwargs), kwargs):
        assert policy_settings(source) == expected
    assert env_config(env) is env.unwrapped.config
    env.close()
    vector.close()


def test_explicit_keywords_override_the_env_and_a_random_actuator_is_not_passed() -> None:
    policy = controllers.make(
        "fbsm_colos", env={"control_dt": 0.1, "actuator": "fins"}, actuator="paper"
    )
    assert (policy.control_dt, policy.actuator) == (0.1, "paper")
    assert policy.gains.current_observer == 3.0  # the preset's
    assert "actuator" not in policy_settings({"actuator": "random"})
    lowpass = controllers.make("fbsm_colos_lowpass", env={"control_dt": 0.2})
    assert lowpass.base.control_dt == 0.2


def test_a_bad_env_is_one_line_naming_its_type() -> None:
    with pytest.raises(TypeError, match=r"^env must be an AUVPath3D env .* got list$"):
        controllers.make("fbsm", env=[0.05])


class _ZeroAgent:
    """A residual agent that never corrects its base."""

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        return np.zeros((np.shape(observation)[0], 3), dtype=np.float32), state


def test_a_residual_policys_base_takes_the_env_settings_without_recording_them() -> None:
    from controllers.residual import ResidualSettings

    env = {"control_dt": 0.1, "actuator": "fins", "params": _VEHICLE}
    policy = controllers.make("residual", agent=_ZeroAgent(), env=env, k_y=0.2)
    assert (policy.base.control_dt, policy.base.actuator, policy.base.params) == (
        0.1,
        "fins",
        _VEHICLE,
    )
    assert policy.settings.base_kwargs == {"k_y": 0.2}  # the env's settings are not the agent's
    with pytest.raises(ValueError, match=r"^base_kwargs must not set \['params'\]: the env"):
        ResidualSettings(base_kwargs={"params": _VEHICLE})
