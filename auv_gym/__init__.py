"""auv-gym: 3D path following of an underactuated AUV, for control and RL research.

Importing the package registers these ids with Gymnasium (idempotently); each is
`AUVPath3DEnv` with the keyword arguments of `VARIANTS` as its defaults:

| id                       | what it is                                                       |
|--------------------------|------------------------------------------------------------------|
| `AUVPath3D-v0`           | the paper's scenario: helix, ±35 white noise, 15-entry observation |
| `AUVPath3DNominal-v0`    | v0 without disturbances                                          |
| `AUVPath3DFins-v0`       | v0 with fin actuators (moment authority ∝ u²)                    |
| `AUVPath3DSpeedLimit-v0` | v0 limited to the vehicle's top speed (REMUS 100: 2.0 m/s); was v1 |
| `AUVPath3DPreview-v0`    | the RL task: the surge limit and the agent observation (path     |
|                          | preview, velocity over ground, previous action; `observation`)  |
| `AUVPath3DPreviewIntegral-v0` | the RL task with leaky integrals of y_e, z_e (T = 10 s) added |
|                          | to the agent observation (`ObservationConfig.integral_time`)    |
| `AUVPath3DPreviewAntiWindup-v0` | the RL task with integrals of x_e, y_e, z_e (T = 10 s), each |
|                          | clipped to ±1 m·s (`integral_errors`, `integral_limit`)         |

The ids are separate names, not versions of one name, so that `gym.make("AUVPath3D-v0")` prints
no "out of date" warning. `LEGACY_ENV_IDS` maps ids that agents' metadata may still record
(`AUVPath3D-v1`) to today's (`resolve_env_id`).
"""

from __future__ import annotations

# First: the kernel cache locator must be in place before any kernel is defined.
import auv_gym.numba_cache  # noqa: F401

# isort: split
from gymnasium.envs.registration import register, registry

from auv_gym.env import AUVPath3DEnv
from auv_gym.observation import (
    OBS_HIGH,
    OBS_INDEX,
    OBS_LOW,
    OBS_NAMES,
    OBS_UNITS,
    ObservationConfig,
)
from auv_gym.path_generator import PathDistribution
from auv_gym.paths import FittedCurve, Helix, Path, Spline, StraightLine, fit_curve, make_path
from auv_gym.sensors import SensorConfig
from auv_gym.task import SURGE_LIMIT, VEHICLE_TOP_SPEED  # noqa: F401  (SURGE_LIMIT: former name)
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
PREVIEW_INTEGRAL_ENV_ID = "AUVPath3DPreviewIntegral-v0"
PREVIEW_ANTIWINDUP_ENV_ID = "AUVPath3DPreviewAntiWindup-v0"

# Variants are separate ids with fixed keyword arguments (docs/design.md §3, Registration).
VARIANTS: dict[str, dict] = {
    ENV_ID: {},
    "AUVPath3DNominal-v0": {"disturbance": "none"},
    "AUVPath3DFins-v0": {"actuator": "fins"},
    # the default reward changed: overspeed term and termination above 2.0 m/s (env docstring)
    SPEED_LIMIT_ENV_ID: {"surge_limit": VEHICLE_TOP_SPEED},
    PREVIEW_ENV_ID: {"surge_limit": VEHICLE_TOP_SPEED, "observation": "preview"},
    # integral action for a static policy: what the third-generation generalist observes
    PREVIEW_INTEGRAL_ENV_ID: {
        "surge_limit": VEHICLE_TOP_SPEED,
        "observation": {"kind": "preview", "integral_time": 10.0},
    },
    # the along-track error integrated too, every integral clipped: the fourth generation's
    PREVIEW_ANTIWINDUP_ENV_ID: {
        "surge_limit": VEHICLE_TOP_SPEED,
        "observation": {
            "kind": "preview",
            "integral_time": 10.0,
            "integral_errors": "xyz",
            "integral_limit": 1.0,
        },
    },
}
# Ids of earlier releases → today's: registered as a version of `AUVPath3D`, v1 made Gymnasium
# call v0 "out of date" on every `gym.make("AUVPath3D-v0")`.
LEGACY_ENV_IDS: dict[str, str] = {"AUVPath3D-v1": SPEED_LIMIT_ENV_ID}


def resolve_env_id(env_id: str) -> str:
    """Today's id for ``env_id`` (a `VARIANTS` key or a `LEGACY_ENV_IDS` one); ValueError
    naming the id and the ids that exist otherwise."""
    env_id = LEGACY_ENV_IDS.get(env_id, env_id) if isinstance(env_id, str) else env_id
    if env_id not in VARIANTS:
        raise ValueError(
            f"unknown env id {env_id!r}; valid: {list(VARIANTS)} (and the earlier "
            f"{list(LEGACY_ENV_IDS)})"
        )
    return env_id


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
