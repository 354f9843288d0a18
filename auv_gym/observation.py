"""The one definition of the observation (names, units, bounds, builder) and the guidance row.

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

from auv_gym.dynamics import STATE
from auv_gym.guidance import body_errors, path_angles, virtual_point_speed, wrap_angle
from auv_gym.paths import path_eval
from auv_gym.records import field_indices

__all__ = [
    "GUIDANCE_DIM",
    "GUIDANCE_FIELDS",
    "GUIDE",
    "OBS",
    "OBS_HIGH",
    "OBS_INDEX",
    "OBS_LOW",
    "OBS_NAMES",
    "OBS_UNITS",
    "build_observation",
    "guidance_row",
]

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

# Guidance quantities computed by the simulator kernel, one row per vehicle [m, rad, rad/s, m/s].
GUIDANCE_FIELDS = (
    "x_e", "y_e", "z_e", "distance", "psi_F", "theta_F", "psi_F_dot", "theta_F_dot", "u_p", "s_dot",
)  # fmt: skip
GUIDANCE_DIM = len(GUIDANCE_FIELDS)
GUIDE = field_indices("GuidanceIndex", GUIDANCE_FIELDS, __name__)
OBS = field_indices("ObservationIndex", OBS_NAMES, __name__)


@njit(cache=True)
def guidance_row(st, kind, pdata, u_d, sigma, out):
    """Fill one guidance row ``out`` (layout `GUIDE`) from the simulator state ``st`` (layout
    `dynamics.STATE`): errors, distance, path angles and their rates, u_p and ṡ
    (docs/model.md §3)."""
    px, py, pz, dpx, dpy, dpz, ddx, ddy, ddz = path_eval(kind, pdata, st[STATE.s])
    x_e, y_e, z_e = body_errors(st[STATE.x], st[STATE.y], st[STATE.z], st[STATE.theta],
                                st[STATE.psi], px, py, pz)  # fmt: skip
    psi_f, theta_f, dpsi_ds, dtheta_ds, speed = path_angles(dpx, dpy, dpz, ddx, ddy, ddz)
    u_p = virtual_point_speed(x_e, u_d, sigma)
    s_dot = u_p / speed
    out[GUIDE.x_e], out[GUIDE.y_e], out[GUIDE.z_e] = x_e, y_e, z_e
    out[GUIDE.distance] = math.sqrt(x_e * x_e + y_e * y_e + z_e * z_e)
    out[GUIDE.psi_F], out[GUIDE.theta_F] = psi_f, theta_f
    out[GUIDE.psi_F_dot], out[GUIDE.theta_F_dot] = dpsi_ds * s_dot, dtheta_ds * s_dot
    out[GUIDE.u_p], out[GUIDE.s_dot] = u_p, s_dot


@njit(cache=True, inline="always")
def build_observation(st, guid, u_d, out):
    """Write one observation ``out`` (layout `OBS`) from the simulator state ``st`` and its
    guidance row ``guid``."""
    out[OBS.x_e] = guid[GUIDE.x_e]
    out[OBS.y_e] = guid[GUIDE.y_e]
    out[OBS.z_e] = guid[GUIDE.z_e]
    out[OBS.psi_error] = wrap_angle(st[STATE.psi] - guid[GUIDE.psi_F])
    out[OBS.theta] = st[STATE.theta]
    out[OBS.theta_F] = guid[GUIDE.theta_F]
    out[OBS.u] = st[STATE.u]
    out[OBS.v] = st[STATE.v]
    out[OBS.w] = st[STATE.w]
    out[OBS.q] = st[STATE.q]
    out[OBS.r] = st[STATE.r]
    out[OBS.u_D] = u_d
    out[OBS.u_p] = guid[GUIDE.u_p]
    out[OBS.psi_F_dot] = guid[GUIDE.psi_F_dot]
    out[OBS.theta_F_dot] = guid[GUIDE.theta_F_dot]
