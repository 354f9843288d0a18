"""The simulator core: path-following state derivative, RK4, and the batched control-step kernel.

Simulator state per vehicle (`STATE_NAMES`): η = (x, y, z, θ, ψ) [m, rad], ν = (u, v, w, q, r)
relative to the water [m/s, rad/s], and the virtual-point parameter s. The virtual point moves
with ṡ = u_p/|p'(s)| (MODEL.md §3.3) and is integrated by the same RK4 as the vehicle, so the
guidance is exact to the integrator's order. Everything that simulates calls `advance_vehicle`: the
single env with one row, the vector env with thousands.
"""

from __future__ import annotations

import math

from numba import njit, types
from numba.core.errors import TypingError
from numba.extending import overload
from numba.np.unsafe.ndarray import to_fixed_tuple

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
from auv_gym.vehicle import FIN_COEFF_INDEX, FIN_MAX_INDEX, N_PARAMS, eta_dot_trig, nu_dot_sin

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


def fixed_tuple(array, length):
    """``array[:length]`` as a tuple; compiled, a register copy (numba's `to_fixed_tuple`).

    The plain-Python body keeps the kernels runnable with ``NUMBA_DISABLE_JIT=1`` (debugging).
    """
    return tuple(array[:length])


@overload(fixed_tuple, prefer_literal=True)
def _fixed_tuple_compiled(array, length):
    if not isinstance(length, types.IntegerLiteral):
        raise TypingError("fixed_tuple needs a compile-time constant length")
    n = length.literal_value

    def impl(array, length):
        return to_fixed_tuple(array, n)

    return impl


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


@njit(cache=True, inline="always")
def _stage(st, h, k):
    """st + h·k for 11-tuples (stays in registers: no array per RK4 stage)."""
    return (
        st[0] + h * k[0], st[1] + h * k[1], st[2] + h * k[2], st[3] + h * k[3],
        st[4] + h * k[4], st[5] + h * k[5], st[6] + h * k[6], st[7] + h * k[7],
        st[8] + h * k[8], st[9] + h * k[9], st[10] + h * k[10],
    )  # fmt: skip


@njit(cache=True, inline="always")
def _rk4_combine(st, h, k1, k2, k3, k4):
    """st + h·(k1 + 2 k2 + 2 k3 + k4) for 11-tuples, with h = dt/6."""
    return _stage(st, h, (
        k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0], k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1],
        k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2], k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3],
        k1[4] + 2.0 * k2[4] + 2.0 * k3[4] + k4[4], k1[5] + 2.0 * k2[5] + 2.0 * k3[5] + k4[5],
        k1[6] + 2.0 * k2[6] + 2.0 * k3[6] + k4[6], k1[7] + 2.0 * k2[7] + 2.0 * k3[7] + k4[7],
        k1[8] + 2.0 * k2[8] + 2.0 * k3[8] + k4[8], k1[9] + 2.0 * k2[9] + 2.0 * k3[9] + k4[9],
        k1[10] + 2.0 * k2[10] + 2.0 * k3[10] + k4[10],
    ))  # fmt: skip


@njit(cache=True, inline="always")
def rk4_tuple(st, X, M, N, f, cx, cy, cz, p, kind, pdata, u_d, sigma, dt):
    """One classical RK4 step of `state_derivative` on an 11-tuple, τ, f and current held."""
    k1 = state_derivative(st, X, M, N, f, cx, cy, cz, p, kind, pdata, u_d, sigma)
    k2 = state_derivative(_stage(st, 0.5 * dt, k1), X, M, N, f, cx, cy, cz, p, kind, pdata,
                          u_d, sigma)  # fmt: skip
    k3 = state_derivative(_stage(st, 0.5 * dt, k2), X, M, N, f, cx, cy, cz, p, kind, pdata,
                          u_d, sigma)  # fmt: skip
    k4 = state_derivative(_stage(st, dt, k3), X, M, N, f, cx, cy, cz, p, kind, pdata, u_d, sigma)
    return _rk4_combine(st, dt / 6.0, k1, k2, k3, k4)


@njit(cache=True)
def rk4_step(st, X, M, N, f, cx, cy, cz, p, kind, pdata, u_d, sigma, dt, out):
    """One classical RK4 step of `state_derivative` with τ, f and current held over dt [s].

    Array form of `rk4_tuple`: reads the 11-state ``st``, writes the new state into ``out``.
    """
    nxt = rk4_tuple(fixed_tuple(st, STATE_DIM), X, M, N, f, cx, cy, cz, p, kind, pdata,
                    u_d, sigma, dt)  # fmt: skip
    for i in range(STATE_DIM):
        out[i] = nxt[i]


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


@njit(cache=True, inline="always")
def _noise(amplitude, key, counter):
    """Bounded white noise A·(2U − 1), U = uniform01(key, counter) [N or N·m]."""
    return amplitude * (2.0 * uniform01(key, counter) - 1.0)


@njit(cache=True, inline="always")
def _gauss_markov(deviation, a, b, key, counter):
    """One exact step of the Gauss–Markov current deviation [m/s]: a·δ + b·N(0, 1)."""
    if b == 0.0:  # no random current: skip the ~25 ns normal draw
        return a * deviation
    return a * deviation + b * standard_normal(key, counter)


@njit(cache=True, inline="always")
def advance_vehicle(st, cur, action, p_array, noise_key, current_key, step_index, kind, pdata,
                    cfg_array, guid, obs, record):  # fmt: skip
    """Advance one vehicle by one control period, in place; returns False on a non-finite state.

    ``st`` (11) and ``cur`` (3, Gauss–Markov current deviation [m/s]) are updated; ``guid``,
    ``obs`` and ``record`` (mean τ over the period, then mean f) are rewritten only while the
    state is finite, so the caller keeps the last valid observation. ``cfg`` is `SimConfig`'s
    packed vector (layout `CFG`). White noise channel c at physics step n is A_c·(2U − 1) with
    U = uniform01(noise_key, 5·(n // hold_steps) + c): a function of the seed and time only.
    Actuator "paper" gives τ = a ⊙ limits; "fins" keeps X = a_0·X_max and gives
    M, N = a·K·δ_max·u|u| from the fin-lift coefficient (MODEL.md §2.3), updated every step.
    """
    # State, parameters, config and sums live in registers for the whole control period: no
    # heap arrays, and no array references (each costs two atomic reference-count updates).
    cfg = fixed_tuple(cfg_array, CFG_DIM)
    p = fixed_tuple(p_array, N_PARAMS)
    n_sub, dt, hold_steps = int(cfg[0]), cfg[1], int(cfg[2])
    u_d, sigma, actuator = cfg[3], cfg[4], int(cfg[5])
    gm_a = cfg[6]
    fin_gain = p[FIN_COEFF_INDEX] * p[FIN_MAX_INDEX]
    x = fixed_tuple(st, STATE_DIM)
    a_X, a_M, a_N = action[0], action[1], action[2]
    dc = (cur[0], cur[1], cur[2])
    sum_X = sum_M = sum_N = 0.0
    sum_f = (0.0, 0.0, 0.0, 0.0, 0.0)
    finite = True
    for k in range(n_sub):
        n = step_index + k
        block = (n // hold_steps) * 5
        f = (
            _noise(cfg[7], noise_key, block), _noise(cfg[8], noise_key, block + 1),
            _noise(cfg[9], noise_key, block + 2), _noise(cfg[10], noise_key, block + 3),
            _noise(cfg[11], noise_key, block + 4),
        )  # fmt: skip
        X = a_X * cfg[12]
        if actuator == 0:
            M = a_M * cfg[13]
            N = a_N * cfg[14]
        else:
            authority = fin_gain * x[5] * abs(x[5])
            M = a_M * authority
            N = a_N * authority
        nxt = rk4_tuple(x, X, M, N, f, cfg[15] + dc[0], cfg[16] + dc[1], cfg[17] + dc[2], p,
                        kind, pdata, u_d, sigma, dt)  # fmt: skip
        dc = (
            _gauss_markov(dc[0], gm_a, cfg[18], current_key, 3 * n),
            _gauss_markov(dc[1], gm_a, cfg[19], current_key, 3 * n + 1),
            _gauss_markov(dc[2], gm_a, cfg[20], current_key, 3 * n + 2),
        )
        sum_X += X
        sum_M += M
        sum_N += N
        sum_f = (sum_f[0] + f[0], sum_f[1] + f[1], sum_f[2] + f[2], sum_f[3] + f[3],
                 sum_f[4] + f[4])  # fmt: skip
        for j in range(STATE_DIM):
            if not math.isfinite(nxt[j]):
                finite = False
        if not finite:
            x = nxt
            break
        x = (
            nxt[0], nxt[1], nxt[2], nxt[3], wrap_angle(nxt[4]), nxt[5], nxt[6], nxt[7], nxt[8],
            nxt[9], nxt[10],
        )  # fmt: skip
    for j in range(STATE_DIM):
        st[j] = x[j]
    for c in range(3):
        cur[c] = dc[c]
    if not finite:
        return False
    record[0], record[1], record[2] = sum_X / n_sub, sum_M / n_sub, sum_N / n_sub
    for c in range(5):
        record[3 + c] = sum_f[c] / n_sub
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
CFG_DIM = len(CFG)
