"""The arguments a policy takes from the env it drives: control period, vehicle, actuator model.

A controller models the plant it commands: its control period Δt_c, the vehicle record
(`auv_gym.vehicle.AUVParams`: the nominal hydrodynamics and the thrust and fin limits) and the
actuator model (docs/model.md §2.3, §2.6–2.7). All three are settings of the env
(`auv_gym.sim.config.SimConfig`), so ``controllers.make(name, env=env)`` reads them from there
instead of every caller restating them; an explicit keyword argument still wins.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from auv_gym.sim.config import SimConfig
from auv_gym.support.validation import ArgumentTypeError

__all__ = ["draws_actuator", "env_config", "policy_settings"]

# Drawn per episode: a policy built once cannot know which, so it keeps its own default ("paper").
_PER_EPISODE_ACTUATOR = "random"


def env_config(env: Any) -> SimConfig:
    """The `SimConfig` of ``env``: a `SimConfig`, the env keyword arguments (a mapping), an
    `AUVPath3DEnv` or `AUVPath3DVectorEnv` (wrapped or not) or the stable-baselines3 adapter of
    one (`auv_gym.envs.sb3`); TypeError naming the type otherwise."""
    if isinstance(env, SimConfig):
        return env
    if isinstance(env, Mapping):
        return SimConfig.from_kwargs(**env)
    for candidate in (env, getattr(env, "unwrapped", None), getattr(env, "core", None)):
        config = getattr(candidate, "config", None)
        if isinstance(config, SimConfig):
            return config
    raise ArgumentTypeError(
        "env must be an AUVPath3D env or vector env (wrapped or not), a SimConfig or a mapping "
        f"of env keyword arguments, got {type(env).__name__}"
    )


def draws_actuator(env: Any) -> bool:
    """Whether ``env`` (see `env_config`) draws each episode's actuator (``actuator="random"``)."""
    return env_config(env).actuator == _PER_EPISODE_ACTUATOR


def policy_settings(env: Any) -> dict[str, Any]:
    """The keyword arguments of a classical controller (`controllers.make`) that ``env``
    (see `env_config`) fixes: ``control_dt`` [s], ``params`` (the nominal vehicle; per-episode
    ``param_uncertainty`` stays unknown to the controller, as on a real vehicle) and, unless the
    env draws it per episode, ``actuator`` with its ``actuator_params``."""
    config = env_config(env)
    settings: dict[str, Any] = {"control_dt": config.control_dt, "params": config.params}
    if not draws_actuator(config):
        settings["actuator"] = config.actuator
        settings["actuator_params"] = config.actuator_params
    return settings
