"""The one definition of the observation vector: names, units, bounds and the builder.

| index | name          | unit  | meaning                                                      |
|-------|---------------|-------|--------------------------------------------------------------|
| 0     | x_e           | m     | along-track error, body frame (vehicle − virtual point)      |
| 1     | y_e           | m     | cross-track error, body frame                                |
| 2     | z_e           | m     | vertical-track error, body frame                             |
| 3     | psi_error     | rad   | ψ − ψ_F wrapped to (−π, π]                                   |
| 4     | theta         | rad   | pitch θ (nose up positive)                                   |
| 5     | theta_F       | rad   | path pitch θ_F at the virtual point                          |
| 6–8   | u, v, w       | m/s   | body velocity through the water                              |
| 9–10  | q, r          | rad/s | pitch and yaw rates                                          |
| 11    | u_D           | m/s   | desired surge speed                                          |
| 12    | u_p           | m/s   | virtual-point speed u_D(1 + tanh(x_e/σ))                     |
| 13    | psi_F_dot     | rad/s | ψ̇_F = ψ_F'(s)·ṡ                                              |
| 14    | theta_F_dot   | rad/s | θ̇_F = θ_F'(s)·ṡ                                              |
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from auv_gym.guidance import wrap_angle

__all__ = ["OBS_HIGH", "OBS_INDEX", "OBS_LOW", "OBS_NAMES", "OBS_UNITS", "build_observation"]

ERROR_BOUND = 500.0  # [m] far beyond any corridor; a vehicle outside it is terminated
SPEED_BOUND = 10.0  # [m/s] 4× REMUS's maximum speed
RATE_BOUND = 2.0 * math.pi  # [rad/s]
PATH_RATE_BOUND = 10.0  # [rad/s]

_TABLE = (
    # name, unit, low, high
    ("x_e", "m", -ERROR_BOUND, ERROR_BOUND),
    ("y_e", "m", -ERROR_BOUND, ERROR_BOUND),
    ("z_e", "m", -ERROR_BOUND, ERROR_BOUND),
    ("psi_error", "rad", -math.pi, math.pi),
    ("theta", "rad", -math.pi / 2, math.pi / 2),
    ("theta_F", "rad", -math.pi / 2, math.pi / 2),
    ("u", "m/s", -SPEED_BOUND, SPEED_BOUND),
    ("v", "m/s", -SPEED_BOUND, SPEED_BOUND),
    ("w", "m/s", -SPEED_BOUND, SPEED_BOUND),
    ("q", "rad/s", -RATE_BOUND, RATE_BOUND),
    ("r", "rad/s", -RATE_BOUND, RATE_BOUND),
    ("u_D", "m/s", 0.0, SPEED_BOUND),
    ("u_p", "m/s", 0.0, 2.0 * SPEED_BOUND),
    ("psi_F_dot", "rad/s", -PATH_RATE_BOUND, PATH_RATE_BOUND),
    ("theta_F_dot", "rad/s", -PATH_RATE_BOUND, PATH_RATE_BOUND),
)

OBS_NAMES: tuple[str, ...] = tuple(row[0] for row in _TABLE)
OBS_UNITS: dict[str, str] = {row[0]: row[1] for row in _TABLE}
OBS_INDEX: dict[str, int] = {name: i for i, name in enumerate(OBS_NAMES)}
OBS_LOW = np.array([row[2] for row in _TABLE], dtype=np.float32)
OBS_HIGH = np.array([row[3] for row in _TABLE], dtype=np.float32)
OBS_DIM = len(OBS_NAMES)

# Guidance quantities computed by the simulator kernel, one row per vehicle.
GUIDANCE_FIELDS = (
    "x_e", "y_e", "z_e", "distance", "psi_F", "theta_F", "psi_F_dot", "theta_F_dot", "u_p", "s_dot",
)  # fmt: skip
G = {name: i for i, name in enumerate(GUIDANCE_FIELDS)}
_GX, _GY, _GZ, _GPSI, _GTH, _GDPSI, _GDTH, _GUP = (
    G[k] for k in ("x_e", "y_e", "z_e", "psi_F", "theta_F", "psi_F_dot", "theta_F_dot", "u_p")
)


@njit(cache=True, inline="always")
def build_observation(state, guid, u_d, out):
    """Write one observation (layout `OBS_NAMES`) from the simulator state and guidance row."""
    out[0] = guid[_GX]
    out[1] = guid[_GY]
    out[2] = guid[_GZ]
    out[3] = wrap_angle(state[4] - guid[_GPSI])
    out[4] = state[3]
    out[5] = guid[_GTH]
    out[6] = state[5]
    out[7] = state[6]
    out[8] = state[7]
    out[9] = state[8]
    out[10] = state[9]
    out[11] = u_d
    out[12] = guid[_GUP]
    out[13] = guid[_GDPSI]
    out[14] = guid[_GDTH]
