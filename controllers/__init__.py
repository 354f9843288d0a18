"""Policies for `AUVPath3D-v0`: the paper's FBSM, backstepping and PPO agents.

Every controller implements stable-baselines3's `predict` (`controllers.base.Policy`), so the
evaluation code treats FBSM, backstepping, a PPO agent and a user's object alike.
"""

from __future__ import annotations

from typing import Any

from controllers.backstepping import Backstepping
from controllers.base import BatchedController, Policy
from controllers.fbsm import FBSM
from controllers.gains import ControllerGains, MembershipSet

__all__ = [
    "FBSM",
    "REGISTRY",
    "Backstepping",
    "BatchedController",
    "ControllerGains",
    "MembershipSet",
    "Policy",
    "make",
]

REGISTRY = ("fbsm", "backstepping", "ppo")


def make(name: str, **kwargs: Any) -> Any:
    """A policy by name, configured for the default env; keyword arguments override.

    "fbsm" and "backstepping" accept `gains`, `params` (the nominal model), `control_dt`,
    `actuator` and individual gain names; "ppo" takes `path` (a saved agent directory).
    """
    if name == "fbsm":
        return FBSM(**kwargs)
    if name == "backstepping":
        return Backstepping(**kwargs)
    if name == "ppo":
        from controllers.ppo import load_policy

        if "path" not in kwargs:
            raise ValueError("controllers.make('ppo') needs path=<saved agent directory>")
        return load_policy(kwargs.pop("path"), **kwargs)
    raise ValueError(f"unknown controller {name!r}; valid: {list(REGISTRY)}")
