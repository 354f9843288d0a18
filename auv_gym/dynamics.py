"""The simulator core: path-following state derivative, RK4, and the batched control-step kernel.

Simulator state per vehicle (`STATE_NAMES`): η = (x, y, z, θ, ψ) [m, rad], ν = (u, v, w, q, r)
relative to the water [m/s, rad/s], and the virtual-point parameter s. The virtual point moves
with ṡ = u_p/|p'(s)| (MODEL.md §3.3) and is integrated by the same RK4 as the vehicle, so the
guidance is exact to the integrator's order. Everything that simulates calls `advance_vehicle`: the
single env with one row, the vector env with thousands.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from auv_gym.disturbances import standard_normal, uniform01
from auv_gym.guidance import (
    body_errors,
    body_errors_trig,
    path_angles,
    virtual_point_speed,
    wrap_angle,
)
from auv_gym.observation import GUIDANCE_FIELDS, build_observation
from auv_gym.paths import path_eval
from auv_gym.vehicle import FIN_COEFF_INDEX, FIN_MAX_INDEX, eta_dot_trig, nu_dot_sin

__all__ = [
    "ACTUATORS",
    "CFG",
    "STATE_NAMES",
    "advance_vehicle",
    "guidance_row",
    "rk4_step",
    "state_derivative",
]

STATE_NAMES = ("x", "y", "z", "theta", "psi", "u", "v", "w", "q", "r", "s")
STATE_DIM = len(STATE_NAMES)
N_GUIDANCE = len(GUIDANCE_FIELDS)
ACTUATORS = {"paper": 0, "fins": 1}
# Per-vehicle record of a control step: mean applied τ (X, M, N) and mean disturbance f (5).
RECORD_DIM = 8


@njit(cache=True, inline="always")
def state_derivative(st, X, M, N, f, cx, cy, cz, p, kind, pdata, u_d, sigma):
    """d/dt of the 11-state: MODEL.md §2.1 dynamics and kinematics plus ṡ of §3.3."""
    # The trigonometry of θ and ψ is shared by the dynamics, kinematics and guidance.
    cth, sth = math.cos(st[3]), math.sin(st[3])
    cps, sps = math.cos(st[4]), math.sin(st[4])
    u, v, w, q, r = st[5], st[6], st[7], st[8], st[9]
    du, dv, dw, dq, dr = nu_dot_sin(u, v, w, q, r, sth, X, M, N, f[0], f[1], f[2], f[3], f[4], p)
    dx, dy, dz, dth, dps = eta_dot_trig(u, v, w, q, r, cth, sth, cps, sps)
    px, py, pz, dpx, dpy, dpz, _, _, _ = path_eval(kind, pdata, st[10])
    x_e, _, _ = body_errors_trig(st[0] - px, st[1] - py, st[2] - pz, cth, sth, cps, sps)
    s_dot = virtual_point_speed(x_e, u_d, sigma) / math.sqrt(dpx * dpx + dpy * dpy + dpz * dpz)
    return (dx + cx, dy + cy, dz + cz, dth, dps, du, dv, dw, dq, dr, s_dot)


@njit(cache=True)
def rk4_step(st, X, M, N, f, cx, cy, cz, p, kind, pdata, u_d, sigma, dt, out):
    """One classical RK4 step of `state_derivative` with τ, f and current held over dt [s]."""
    k1 = state_derivative(st, X, M, N, f, cx, cy, cz, p, kind, pdata, u_d, sigma)
    tmp = np.empty(STATE_DIM)
    for i in range(STATE_DIM):
        tmp[i] = st[i] + 0.5 * dt * k1[i]
    k2 = state_derivative(tmp, X, M, N, f, cx, cy, cz, p, kind, pdata, u_d, sigma)
    for i in range(STATE_DIM):
        tmp[i] = st[i] + 0.5 * dt * k2[i]
    k3 = state_derivative(tmp, X, M, N, f, cx, cy, cz, p, kind, pdata, u_d, sigma)
    for i in range(STATE_DIM):
        tmp[i] = st[i] + dt * k3[i]
    k4 = state_derivative(tmp, X, M, N, f, cx, cy, cz, p, kind, pdata, u_d, sigma)
    for i in range(STATE_DIM):
        out[i] = st[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


@njit(cache=True)
def guidance_row(st, kind, pdata, u_d, sigma, out):
    """Fill one row of `GUIDANCE_FIELDS` (errors, distance, path angles and rates, u_p, ṡ)."""
    px, py, pz, dpx, dpy, dpz, ddx, ddy, ddz = path_eval(kind, pdata, st[10])
    x_e, y_e, z_e = body_errors(st[0], st[1], st[2], st[3], st[4], px, py, pz)
    psi_f, theta_f, dpsi_ds, dtheta_ds, speed = path_angles(dpx, dpy, dpz, ddx, ddy, ddz)
    u_p = virtual_point_speed(x_e, u_d, sigma)
    s_dot = u_p / speed
    out[0], out[1], out[2] = x_e, y_e, z_e
    out[3] = math.sqrt(x_e * x_e + y_e * y_e + z_e * z_e)
    out[4], out[5] = psi_f, theta_f
    out[6], out[7] = dpsi_ds * s_dot, dtheta_ds * s_dot
    out[8], out[9] = u_p, s_dot


@njit(cache=True)
def advance_vehicle(st, cur, action, p, noise_key, current_key, step_index, kind, pdata, cfg,
                    guid, obs, record):  # fmt: skip
    """Advance one vehicle by one control period, in place; returns False on a non-finite state.

    ``st`` (11) and ``cur`` (3, Gauss–Markov current deviation [m/s]) are updated; ``guid``,
    ``obs`` and ``record`` (mean τ over the period, then mean f) are rewritten only while the
    state is finite, so the caller keeps the last valid observation. ``cfg`` is `SimConfig`'s
    packed vector (layout `CFG`). White noise channel c at physics step n is A_c·(2U − 1) with
    U = uniform01(noise_key, 5·(n // hold_steps) + c): a function of the seed and time only.
    Actuator "paper" gives τ = a ⊙ limits; "fins" keeps X = a_0·X_max and gives
    M, N = a·K·δ_max·u|u| from the fin-lift coefficient (MODEL.md §2.3), updated every step.
    """
    n_sub, dt, hold_steps = int(cfg[0]), cfg[1], int(cfg[2])
    u_d, sigma, actuator = cfg[3], cfg[4], int(cfg[5])
    gm_a = cfg[6]
    nxt = np.empty(STATE_DIM)
    f = np.empty(5)
    rec = np.zeros(RECORD_DIM)
    fin_gain = p[FIN_COEFF_INDEX] * p[FIN_MAX_INDEX]
    finite = True
    for k in range(n_sub):
        n = step_index + k
        block = (n // hold_steps) * 5
        for c in range(5):
            f[c] = cfg[7 + c] * (2.0 * uniform01(noise_key, block + c) - 1.0)
        X = action[0] * cfg[12]
        if actuator == 0:
            M = action[1] * cfg[13]
            N = action[2] * cfg[14]
        else:
            authority = fin_gain * st[5] * abs(st[5])
            M = action[1] * authority
            N = action[2] * authority
        rk4_step(st, X, M, N, f, cfg[15] + cur[0], cfg[16] + cur[1], cfg[17] + cur[2], p,
                 kind, pdata, u_d, sigma, dt, nxt)  # fmt: skip
        for c in range(3):  # Gauss–Markov current, exact discretisation
            if cfg[18 + c] != 0.0:  # b = 0 (no random current): skip the ~25 ns normal draw
                cur[c] = gm_a * cur[c] + cfg[18 + c] * standard_normal(current_key, 3 * n + c)
            else:
                cur[c] = gm_a * cur[c]
        rec[0] += X
        rec[1] += M
        rec[2] += N
        for c in range(5):
            rec[3 + c] += f[c]
        for j in range(STATE_DIM):
            if not math.isfinite(nxt[j]):
                finite = False
        st[:] = nxt
        if not finite:
            return False
        st[4] = wrap_angle(st[4])
    for c in range(RECORD_DIM):
        record[c] = rec[c] / n_sub
    guidance_row(st, kind, pdata, u_d, sigma, guid)
    build_observation(st, guid, u_d, obs)
    return True


# Layout of the packed simulation config read by `advance_vehicle`.
CFG = (
    "n_sub", "physics_dt", "hold_steps", "u_d", "sigma", "actuator", "gm_a",
    "noise_f_u", "noise_f_v", "noise_f_w", "noise_f_q", "noise_f_r",
    "limit_X", "limit_M", "limit_N", "current_x", "current_y", "current_z",
    "gm_b_x", "gm_b_y", "gm_b_z",
)  # fmt: skip
