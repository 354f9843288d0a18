"""auv-gym: 3D path following of an underactuated AUV, for control and RL research.

Importing the package registers `AUVPath3D-v0`, `AUVPath3D-v1` (v0 with the realistic-speed
limit, `auv_gym.task.SURGE_LIMIT`) and the variants below with Gymnasium (idempotently).
"""

from __future__ import annotations

# First: the kernel cache locator must be in place before any kernel is defined.
import auv_gym.numba_cache  # noqa: F401

# isort: split
from gymnasium.envs.registration import register, registry

from auv_gym.env import AUVPath3DEnv
from auv_gym.observation import OBS_HIGH, OBS_INDEX, OBS_LOW, OBS_NAMES, OBS_UNITS
from auv_gym.path_generator import PathDistribution
from auv_gym.paths import FittedCurve, Helix, Path, Spline, StraightLine, fit_curve, make_path
from auv_gym.task import SURGE_LIMIT
from auv_gym.vehicle import AUVParams, remus100

__all__ = [
    "OBS_HIGH",
    "OBS_INDEX",
    "OBS_LOW",
    "OBS_NAMES",
    "OBS_UNITS",
    "AUVParams",
    "AUVPath3DEnv",
    "FittedCurve",
    "Helix",
    "Path",
    "PathDistribution",
    "Spline",
    "StraightLine",
    "fit_curve",
    "make_path",
    "remus100",
]

__version__ = "0.1.0"

ENV_ID = "AUVPath3D-v0"


# Variants are separate ids with fixed keyword arguments (docs/design.md §3, Registration).
VARIANTS: dict[str, dict] = {
    ENV_ID: {},
    "AUVPath3DNominal-v0": {"disturbance": "none"},
    "AUVPath3DFins-v0": {"actuator": "fins"},
    # v1: the default reward changed (overspeed term and termination above 2.0 m/s, env docstring)
    "AUVPath3D-v1": {"surge_limit": SURGE_LIMIT},
}


def _register() -> None:
    for env_id, kwargs in VARIANTS.items():
        if env_id in registry:
            continue
        register(
            id=env_id,
            entry_point="auv_gym.env:AUVPath3DEnv",
            vector_entry_point="auv_gym.vector_env:AUVPath3DVectorEnv",
            # The envs truncate at max_time themselves, for any control_dt; a registered
            # TimeLimit would cut every other control_dt at the wrong step (env.spec reports the
            # episode length of the arguments).
            max_episode_steps=None,
            kwargs=kwargs,
        )


_register()
