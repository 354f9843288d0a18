"""auv-gym: 3D path following of an underactuated AUV, for control and RL research.

Importing the package registers these ids with Gymnasium (idempotently); each is
`AUVPath3DEnv` with the keyword arguments of `VARIANTS` as its defaults:

| id                       | what it is                                                       |
|--------------------------|------------------------------------------------------------------|
| `AUVPath3D-v0`           | the paper's scenario: helix, ±35 white noise, 15-entry observation |
| `AUVPath3DNominal-v0`    | v0 without disturbances                                          |
| `AUVPath3DFins-v0`       | v0 with fin actuators (moment authority ∝ u²)                    |
| `AUVPath3DSpeedLimit-v0` | v0 limited to the vehicle's top speed (REMUS 100: 2.0 m/s)        |
| `AUVPath3DPreview-v0`    | the RL task: the surge limit and the agent observation (path     |
|                          | preview, velocity over ground, previous action; `observation`)  |

Integral action is an option of the RL task: ``gym.make("AUVPath3DPreview-v0",
observation="preview_integral")``.

The ids are separate names, not versions of one name, so that `gym.make("AUVPath3D-v0")` prints
no "out of date" warning.

The modules live in rooms, imported one way (docs/architecture.md): `support` → `paths` →
`vehicle`, `ocean` → `sim` (the simulation core) → `envs` (the env API) → this top level, which
also holds the evaluation API (`auv_gym.rollout`, `auv_gym.metrics`).
"""

from __future__ import annotations

# First: the kernel cache locator must be in place before any kernel is defined.
import auv_gym.support.numba_cache  # noqa: F401

# isort: split
from gymnasium.envs.registration import register, registry

from auv_gym.envs.env import AUVPath3DEnv
from auv_gym.paths.shapes import (
    FittedCurve,
    Helix,
    Path,
    Spline,
    StraightLine,
    fit_curve,
    make_path,
)
from auv_gym.sim.observation import (
    OBS_HIGH,
    OBS_INDEX,
    OBS_LOW,
    OBS_NAMES,
    OBS_UNITS,
    ObservationConfig,
)
from auv_gym.sim.path_generator import PathDistribution
from auv_gym.sim.task import VEHICLE_TOP_SPEED
from auv_gym.vehicle.params import AUVParams, remus100
from auv_gym.vehicle.sensors import SensorConfig

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
    "ObservationConfig",
    "Path",
    "PathDistribution",
    "SensorConfig",
    "Spline",
    "StraightLine",
    "fit_curve",
    "make_path",
    "remus100",
    "resolve_env_id",
]

__version__ = "0.1.0"

ENV_ID = "AUVPath3D-v0"


SPEED_LIMIT_ENV_ID = "AUVPath3DSpeedLimit-v0"
PREVIEW_ENV_ID = "AUVPath3DPreview-v0"

# Variants are separate ids with fixed keyword arguments (docs/design.md §3, Registration).
VARIANTS: dict[str, dict] = {
    ENV_ID: {},
    "AUVPath3DNominal-v0": {"disturbance": "none"},
    "AUVPath3DFins-v0": {"actuator": "fins"},
    # the default reward changed: overspeed term and termination above 2.0 m/s (env docstring)
    SPEED_LIMIT_ENV_ID: {"surge_limit": VEHICLE_TOP_SPEED},
    PREVIEW_ENV_ID: {"surge_limit": VEHICLE_TOP_SPEED, "observation": "preview"},
}


def resolve_env_id(env_id: str) -> str:
    """``env_id`` checked: a `VARIANTS` key; ValueError naming the id and the ids that exist
    otherwise."""
    if env_id not in VARIANTS:
        raise ValueError(f"unknown env id {env_id!r}; valid: {list(VARIANTS)}")
    return env_id


def _register() -> None:
    for env_id, kwargs in VARIANTS.items():
        if env_id in registry:
            continue
        register(
            id=env_id,
            entry_point="auv_gym.envs.env:AUVPath3DEnv",
            vector_entry_point="auv_gym.envs.vector_env:AUVPath3DVectorEnv",
            # The envs truncate at max_time themselves, for any control_dt; a registered
            # TimeLimit would cut every other control_dt at the wrong step (env.spec reports the
            # episode length of the arguments).
            max_episode_steps=None,
            kwargs=kwargs,
            # Gymnasium's passive env checker (1.4) marks its first reset as checked before
            # calling it: after a refused first reset (seed -1, unknown options) the next
            # step unpacks None and raises a TypeError (CartPole-v1 does the same). The env
            # checks its own arguments, observations and actions (docs/design.md §3).
            disable_env_checker=True,
        )


_register()
