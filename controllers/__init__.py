"""Policies for `AUVPath3D-v0`: the paper's FBSM, backstepping, a PID + LOS autopilot, PPO
agents and residual policies.

Every controller implements stable-baselines3's `predict` (`controllers.base.Policy`), so the
evaluation code treats FBSM, backstepping, a PPO agent and a user's object alike.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

import auv_gym
from auv_gym.numba_cache import register_package

# Before the first kernel is defined: the controllers' kernels inline auv_gym's dynamics and
# guidance, so an edit there must also recompile them (see `auv_gym.numba_cache`).
register_package(Path(__file__).parent, Path(auv_gym.__file__).parent)

from controllers.backstepping import Backstepping  # noqa: E402
from controllers.base import BatchedController, Policy  # noqa: E402
from controllers.fbsm import FBSM  # noqa: E402
from controllers.gains import ControllerGains, MembershipSet  # noqa: E402
from controllers.pid import PIDLOS, PIDGains  # noqa: E402

__all__ = [
    "CLASSICAL",
    "FBSM",
    "PIDLOS",
    "PRESETS",
    "REGISTRY",
    "Backstepping",
    "BatchedController",
    "ControllerGains",
    "MembershipSet",
    "PIDGains",
    "Policy",
    "import_policy",
    "make",
]

# Named variants of the classical controllers (not in the paper), against ocean currents; see
# `ControllerGains` and README "Results". Integral LOS in the horizontal plane, σ_y = 3. Current-
# observer LOS (`controllers.alos`, docs/model.md §3.7): observer ω_o = 3 rad/s, crab angles over
# ground, speed over ground; backstepping adds the gated ALOS trims (γ = 0.01 rad/(m·s)) that
# remove the bias its fixed nominal model leaves (the FBSM adapts that bias away itself).
_COLOS = {"current_observer": 3.0, "speed_over_ground": True}
PRESETS: dict[str, tuple[str, dict[str, Any]]] = {
    "fbsm_ilos": ("fbsm", {"ilos_y": 3.0}),
    "backstepping_ilos": ("backstepping", {"ilos_y": 3.0}),
    "fbsm_colos": ("fbsm", _COLOS),
    "backstepping_colos": ("backstepping", {**_COLOS, "alos_y": 0.01, "alos_z": 0.01}),
    # The current-robust FBSM through a first-order low-pass (`controllers.lowpass`, α = 0.5):
    # the classical answer to chattering, which a residual agent must beat (docs/design.md §3.11).
    "fbsm_colos_lowpass": ("lowpass", {"base": "fbsm_colos"}),
    # The textbook baseline (`controllers.pid`, docs/model.md §4.9) with the same guidance options.
    "pid_ilos": ("pid_los", {"ilos_y": 3.0}),
    "pid_colos": ("pid_los", _COLOS),
}
CLASSICAL = ("fbsm", "backstepping", "pid_los", *PRESETS)
REGISTRY = (*CLASSICAL, "ppo")  # policy names of the benchmark CLIs (a residual agent: ppo:PATH)


def make(name: str, **kwargs: Any) -> Any:
    """A policy by name, configured for the default env; keyword arguments override.

    "fbsm" and "backstepping" (and their `PRESETS`) accept `gains`, `params` (the nominal model),
    `control_dt`, `actuator` and individual gain names. "pid_los" (and its `PRESETS`;
    `controllers.pid.PIDLOS`) accepts `pid` (`controllers.pid.PIDGains`), `gains` (read for
    the guidance only), `params`, `control_dt`, `actuator` and the names of `PIDGains` and
    `controllers.pid.GUIDANCE_GAINS`. All three take ``actuator="realistic"`` with an optional
    `actuator_params` (`auv_gym.actuators.ActuatorParams`; docs/model.md §2.7). "ppo" takes
    `path` (a saved agent directory).
    "residual" (`controllers.residual.ResidualPolicy`, docs/design.md §3.10) takes `agent` (a
    Policy of the 21-value residual observation, or a saved residual agent's
    directory), `base` (a classical name, default "fbsm_colos"), `bound` (β per X, M, N,
    default (0.25, 0.5, 0.5)), `filter_max` (the learned filter's α_max, default 0: none); every
    other keyword configures the base controller. "lowpass"
    (`controllers.lowpass.LowPassPolicy`, docs/design.md §3.11) takes `base` (a classical name,
    default "fbsm_colos") and `alpha` (default 0.5); every other keyword configures the base.
    """
    if name in PRESETS:
        base, preset = PRESETS[name]
        return make(base, **{**preset, **kwargs})
    if name == "fbsm":
        return FBSM(**kwargs)
    if name == "backstepping":
        return Backstepping(**kwargs)
    if name == "pid_los":
        return PIDLOS(**kwargs)
    if name == "ppo":
        from controllers.ppo import load_policy

        if "path" not in kwargs:
            raise ValueError("controllers.make('ppo') needs path=<saved agent directory>")
        return load_policy(kwargs.pop("path"), **kwargs)
    if name == "residual":
        from controllers.residual import make_residual

        return make_residual(**kwargs)
    if name == "lowpass":
        from controllers.lowpass import make_lowpass

        return make_lowpass(**kwargs)
    raise ValueError(f"unknown controller {name!r}; valid: {[*REGISTRY, 'residual', 'lowpass']}")


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
