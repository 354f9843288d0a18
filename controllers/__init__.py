"""Policies for `AUVPath3D-v0`: the paper's FBSM, backstepping, a PID + LOS autopilot, saved
RL agents (PPO, SAC) and residual policies.

Every controller implements stable-baselines3's `predict` (`controllers.base.Policy`), so the
evaluation code treats FBSM, backstepping, a trained agent and a user's object alike.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

import auv_gym
from auv_gym.sim.integrator import ACTUATORS
from auv_gym.support.numba_cache import register_package

# Before the first kernel is defined: the controllers' kernels inline auv_gym's dynamics and
# guidance, so an edit there must also recompile them (see `auv_gym.support.numba_cache`).
register_package(Path(__file__).parent, Path(auv_gym.__file__).parent)

from controllers.algorithms import ALGORITHMS  # noqa: E402
from controllers.backstepping import Backstepping  # noqa: E402
from controllers.base import BatchedController, Policy  # noqa: E402
from controllers.env_settings import env_config, policy_settings  # noqa: E402
from controllers.fbsm import FBSM  # noqa: E402
from controllers.gains import ControllerGains, MembershipSet  # noqa: E402
from controllers.pid import PIDLOS, PIDGains  # noqa: E402
from controllers.registry import CLASSICAL, PRESETS, make_classical  # noqa: E402

__all__ = [
    "AGENT_NAMES",
    "CLASSICAL",
    "FBSM",
    "PIDLOS",
    "PRESETS",
    "RENAMED",
    "Backstepping",
    "BatchedController",
    "ControllerGains",
    "MembershipSet",
    "PIDGains",
    "Policy",
    "import_policy",
    "make",
]

# "agent" loads any saved agent; another algorithm's name loads an agent trained with that
# algorithm (`controllers.algorithms`). "ppo" is not one: it was the former name of "agent".
AGENT_NAMES = ("agent", *(name for name in ALGORITHMS if name != "ppo"))
RENAMED = {"ppo": "controllers.make('agent', path=...)"}  # former name → what to call instead
# What an env fixes of the plant (`policy_settings`): given to an agent, they build its stages
# (the allocation for the fins) or its residual base for that plant.
PLANT_KEYWORDS = ("control_dt", "params", "actuator", "actuator_params")


def make(name: str, env: Any = None, **kwargs: Any) -> Any:
    """A policy by name, configured for ``env`` (default: the default env); keyword arguments
    override.

    ``env`` (an env, a vector env, either wrapped, a `SimConfig` or env keyword arguments)
    supplies what the policy must know of the plant: its control period, vehicle record and
    actuator model (`controllers.env_settings.policy_settings`); for a saved agent they configure
    a residual agent's base controller (``base_kwargs``). Explicit keywords win.

    "fbsm" and "backstepping" (and their `PRESETS`) accept `gains`, `params` (the nominal model),
    `control_dt`, `actuator` and individual gain names. "pid_los" (and its `PRESETS`;
    `controllers.pid.PIDLOS`) accepts `pid` (`controllers.pid.PIDGains`), `gains` (read for
    the guidance only), `params`, `control_dt`, `actuator` and the names of `PIDGains` and
    `controllers.pid.GUIDANCE_GAINS`. All three take ``actuator="realistic"`` with an optional
    `actuator_params` (`auv_gym.vehicle.actuators.ActuatorParams`; docs/model.md §2.7). "agent"
    takes `path` (a saved agent directory of any algorithm of `controllers.algorithms`, plain or
    residual; `controllers.loader.load_policy`) and that function's keywords, and the plant's
    `control_dt`, `params`, `actuator` and `actuator_params` as a classical controller does
    (they build the agent's stages, e.g. the allocation on the fins: ``base_kwargs``; an agent
    trained on the propeller and fins is refused on another actuator); "sac"
    (and "tqc", "crossq") does the same for an agent of that algorithm only. A former name
    (`RENAMED`: "ppo") is a one-line ValueError naming the call that replaces it.
    "residual" (`controllers.residual.ResidualPolicy`, docs/design.md §3.10) takes `agent` (a Policy
    of the residual observation, `controllers.residual.residual_observation_names`, or a saved
    residual agent's directory), `base` (a classical name, default "fbsm_colos"), `bound` (β per X,
    M, N, default (0.25, 0.5, 0.5)), `bound_below` (β⁻, the reach below the base, default β),
    `brake_fin_margin` (the base's fin margin that scales the thrust's β⁻, default none),
    `filter_max` (the learned filter's α_max, default 0: none),
    `envelope_guard` (the guard of the applied action, default none); every other keyword configures
    the base controller. "lowpass"
    (`controllers.lowpass.LowPassPolicy`, docs/design.md §3.11) takes `base` (a classical name,
    default "fbsm_colos") and `alpha` (default 0.5); every other keyword configures the base.
    "guarded" (`controllers.guarded.GuardedPolicy`) takes `base` (default "pid_as_built") and
    `envelope_guard` (its settings; default the guard's, the stern plane's sign of the actuator).
    "onnx" (`controllers.onnx_policy.OnnxPolicy`, docs/design.md §3.18) takes `path` (an
    exported agent's .onnx file, `auv-gym export`) and runs it with onnxruntime alone; with
    ``env`` its observation layout, actuator and control period are checked against the env's.
    """
    if name in RENAMED:
        raise ValueError(f"controller {name!r} was renamed: use {RENAMED[name]}")
    if env is not None:
        kwargs = _with_env_settings(name, policy_settings(env), kwargs)
    if name in CLASSICAL:
        policy = make_classical(name, **kwargs)
        if env is not None:
            _check_width(name, policy, env)
        return policy
    if name in AGENT_NAMES:
        from controllers.loader import load_policy

        if "path" not in kwargs:
            raise ValueError(f"controllers.make({name!r}) needs path=<saved agent directory>")
        algo = None if name == "agent" else name
        return load_policy(kwargs.pop("path"), algo=algo, **_agent_keywords(name, kwargs))
    if name == "onnx":
        from controllers.onnx_policy import OnnxPolicy

        if "path" not in kwargs:
            raise ValueError("controllers.make('onnx') needs path=<exported agent .onnx file>")
        if env is not None:
            kwargs.setdefault("observation_names", env_config(env).observation.names)
        return OnnxPolicy(kwargs.pop("path"), **kwargs)
    if name == "residual":
        from controllers.loader import make_residual

        return make_residual(**kwargs)
    if name == "lowpass":
        from controllers.registry import make_lowpass

        return make_lowpass(**kwargs)
    if name == "guarded":
        from controllers.registry import make_guarded

        return make_guarded(**kwargs)
    valid = [*CLASSICAL, *AGENT_NAMES, "onnx", "residual", "lowpass", "guarded"]
    raise ValueError(
        f"unknown controller {name!r}; valid: {valid} (a saved agent, a reference agent of "
        "benchmarks/agents/ included, loads by its folder: controllers.make('agent', path=...))"
    )


def _check_width(name: str, policy: Any, env: Any) -> None:
    """ValueError if ``env``'s observation is narrower than what ``policy`` reads (a controller
    that takes the current from the DVL needs the agents' velocity over ground)."""
    width = getattr(policy, "observation_width", 0)
    given = len(env_config(env).observation.names)
    if given < width:
        raise ValueError(
            f"{name} reads {width} observation values (the DVL's velocity over ground), the "
            f"env gives {given}: make the env with observation='preview'"
        )


def _agent_keywords(name: str, kwargs: dict[str, Any]) -> dict[str, Any]:
    """``load_policy``'s keywords from those of ``make(name, ...)``: the plant's keywords go into
    ``base_kwargs`` (explicit ones win over the env's); ValueError for any other unknown
    keyword or an unknown actuator."""
    valid = ("device", "num_threads", "base_kwargs", "stages", *PLANT_KEYWORDS)
    unknown = sorted(set(kwargs) - set(valid))
    if unknown:
        raise ValueError(f"controllers.make({name!r}): unknown keywords {unknown}; valid: {valid}")
    plant = {key: kwargs.pop(key) for key in PLANT_KEYWORDS if key in kwargs}
    if plant.get("actuator", "paper") not in ACTUATORS:  # the integrator's actuator models
        raise ValueError(f"unknown actuator {plant['actuator']!r}; valid: {sorted(ACTUATORS)}")
    if plant:
        kwargs["base_kwargs"] = {**(kwargs.get("base_kwargs") or {}), **plant}
    return kwargs


def _with_env_settings(
    name: str, settings: dict[str, Any], kwargs: dict[str, Any]
) -> dict[str, Any]:
    """``kwargs`` with the env's ``settings`` beneath them (an agent: beneath its base's)."""
    if name in AGENT_NAMES:
        return {**kwargs, "base_kwargs": {**settings, **(kwargs.get("base_kwargs") or {})}}
    return {**settings, **kwargs}


def import_policy(spec: str, instantiate: bool = True, **factory_kwargs: Any) -> Any:
    """The policy named ``"module:attribute"``: an object with ``predict`` is returned as is; a
    class or factory is called with ``factory_kwargs``. ValueError names what cannot be imported.
    With ``instantiate=False`` only the import and the kind of object are checked.
    """
    module, sep, attribute = spec.partition(":")
    if not (sep and module and attribute):
        raise ValueError(f"policy {spec!r} must have the form 'module:attribute'")
    try:
        obj = getattr(importlib.import_module(module), attribute)
    except (ImportError, AttributeError) as exc:
        raise ValueError(
            f"policy {spec!r}: cannot import {attribute!r} from {module!r}: {exc}"
        ) from exc
    has_predict = hasattr(obj, "predict") and not isinstance(obj, type)
    if not (has_predict or callable(obj)):
        raise ValueError(f"policy {spec!r} is neither a Policy nor a factory of one")
    if has_predict or not instantiate:
        return obj
    return obj(**factory_kwargs)
