"""LOS guidance with command-filtered corrections and the backstepping error variables.

Shared by FBSM, backstepping and the PID (docs/model.md §3.4, §4.3, §4.4, §10.4). All
functions are numba kernels on one vehicle; ``o`` is one observation row (layout
`auv_gym.OBS_NAMES`), ``g`` the packed gains (`controllers.gains.GAIN_LAYOUT`), ``filt`` the
`FILTER_DIM`-entry memory (x_z, ẋ_z, x_y, ẋ_y, previous ψ̇_F, previous θ̇_F, integral-LOS
states y_int, z_int [m], then the current-guidance memory of `controllers.alos`: ε̂ [m], ĉ
[m/s], last g [m/s], β̂, α̂ [rad], previous u_ref [m/s]).
"""

from __future__ import annotations

import math

from numba import njit

from auv_gym.paths.guidance import wrap_angle
from auv_gym.sim.observation import EXTRA_HEAD, OBS_DIM, OBS_INDEX
from controllers.alos import (
    ALPHA_HAT,
    BETA_HAT,
    C_HAT,
    U_REF,
    adapt_trims,
    crab_angles,
    measure_current,
    observe_current,
    path_tangent,
    speed_reference,
)
from controllers.gains import (
    ALOS_MAX,
    ALOS_RADIUS,
    ALOS_Y,
    ALOS_Z,
    BETA_3D,
    C1,
    C2,
    DT,
    DVL_CURRENT,
    ILOS_Y,
    ILOS_Z,
    K1,
    K2,
    KY,
    KZ,
    OBSERVER_WN,
    PRINTED_PITCH,
    SPEED_OVER_GROUND,
    THETA_MAX,
    U_GUARD,
    WN,
    ZETA,
    ControllerGains,
)

__all__ = ["FILTER_DIM", "LOOP_DIM", "loop_errors", "observation_width"]

_XE, _YE, _ZE = OBS_INDEX["x_e"], OBS_INDEX["y_e"], OBS_INDEX["z_e"]
_PSIE, _TH, _THF = OBS_INDEX["psi_error"], OBS_INDEX["theta"], OBS_INDEX["theta_F"]
_U, _V, _W, _Q, _R = (OBS_INDEX[k] for k in ("u", "v", "w", "q", "r"))
_UD, _UP = OBS_INDEX["u_D"], OBS_INDEX["u_p"]
_DPSIF, _DTHF = OBS_INDEX["psi_F_dot"], OBS_INDEX["theta_F_dot"]
# The velocity over ground in the agents' observation (``observation="preview"``), which
# ``dvl_current`` reads: the entries after the paper's 15.
_UG, _VG, _WG = (OBS_DIM + EXTRA_HEAD.index(k) for k in ("u_ground", "v_ground", "w_ground"))
FILTER_DIM = U_REF + 1
# loop_errors output: z1, z2, S2, ż1, α̇1, z3, z4, S3, ż3, α̇2, θ_d, ψ_d − ψ_F, u_ref, u̇_ref
LOOP_DIM = 14


def observation_width(gains: ControllerGains) -> int:
    """How many observation entries the guidance reads: the paper's 15, or with ``dvl_current``
    up to the velocity over ground of the agents' observation (``observation="preview"``)."""
    return _WG + 1 if gains.dvl_current > 0.0 else OBS_DIM


@njit(cache=True)
def loop_errors(o, g, filt, started, out):
    """Desired angles (LOS) and the pitch/yaw backstepping errors; advances the filter by dt.

    θ_d = θ_F + x_z, ψ_d = ψ_F + x_y, where x_z, x_y are the corrections
    c_z = sat(θ_F + arctan(k_z z_e) + α, ±θ_max) − θ_F and c_y = −arctan(k_y y_e) − β
    (with integral LOS, y_e + σ_y y_int and z_e + σ_z z_int in place of y_e and z_e)
    through ẍ = ω_n²(c − x) − 2ζω_n ẋ (initialised at c with zero rate). θ̇_d, θ̈_d add the
    analytic θ̇_F and its finite difference over one control step (likewise for ψ).
    With `controllers.alos` switched on, α and β are the crab angles over ground (α_c, β_c)
    from the current observer (or, with ``dvl_current``, the DVL's current: ``o`` then has the
    agents' layout up to w_ground), the ALOS trims α̂, β̂ are added, and the surge reference u_ref
    (out[12], u_D unless ``speed_over_ground``) and its rate (out[13]) account for the current.
    Pitch (35)–(36): z1 = θ − θ_d, α1 = −k1 z1 + θ̇_d, z2 = q − α1, S2 = c1 z1 + z2,
    ż1 = q − θ̇_d, α̇1 = −k1 ż1 + θ̈_d. Yaw (40) with the 1/cosθ correction (docs/model.md §4.4):
    z3 = wrap(ψ − ψ_d), α2 = cosθ(−k2 z3 + ψ̇_d), z4 = r − α2, S3 = c2 z3 + z4,
    ż3 = r/cosθ − ψ̇_d, α̇2 = −q sinθ(−k2 z3 + ψ̇_d) + cosθ(−k2 ż3 + ψ̈_d).
    """
    if filt.shape[0] != FILTER_DIM or out.shape[0] != LOOP_DIM:
        raise ValueError("loop_errors: filter memory must have FILTER_DIM, out LOOP_DIM entries")
    dt = g[DT]
    u, v, w, q, r, theta = o[_U], o[_V], o[_W], o[_Q], o[_R], o[_TH]
    theta_f = o[_THF]
    if u >= g[U_GUARD]:  # attack and sideslip angles (35), undefined at rest
        alpha = math.atan(w / u)
        beta = math.atan(v / math.sqrt(u * u + w * w))
    else:
        alpha = 0.0
        beta = 0.0
    if g[BETA_3D] > 0.0:
        beta /= math.cos(theta_f)
    k_y, k_z, x_e, y_e, z_e = g[KY], g[KZ], o[_XE], o[_YE], o[_ZE]
    observer = g[OBSERVER_WN] > 0.0 or g[DVL_CURRENT] > 0.0  # a current estimate ĉ
    trims = g[ALOS_Y] > 0.0 or g[ALOS_Z] > 0.0
    if not started:  # β̂(0) = α̂(0) = 0, u_ref = u_D (the observer initialises itself)
        filt[BETA_HAT], filt[ALPHA_HAT], filt[U_REF] = 0.0, 0.0, o[_UD]
    t0, t1, t2 = 0.0, 0.0, 0.0
    dc_y = dc_z = 0.0  # rates of the corrections fed forward through the filter (alos only)
    if observer:
        t0, t1, t2 = path_tangent(o[_PSIE], theta, theta_f)
        cx, cy, cz = filt[C_HAT], filt[C_HAT + 1], filt[C_HAT + 2]
        if g[DVL_CURRENT] > 0.0:
            measure_current(
                u, v, w, o[_UG], o[_VG], o[_WG], q, r, theta, g[DVL_CURRENT], dt, started, filt
            )
        else:
            observe_current(
                x_e,
                y_e,
                z_e,
                u,
                v,
                w,
                q,
                r,
                theta,
                t0,
                t1,
                t2,
                o[_UP],
                g[OBSERVER_WN],
                dt,
                started,
                filt,
            )
        if u >= g[U_GUARD]:
            beta, alpha = crab_angles(
                u + filt[C_HAT], v + filt[C_HAT + 1], w + filt[C_HAT + 2], theta
            )
            if started:  # the part of their rate that the turning estimate ĉ causes (ν, θ held)
                # (at the first step ĉ is initialised, not turned: the observer's ĉ(0) = 0
                # gives no rate either way, the DVL's ĉ(0) = m would be a jump read as a rate)
                beta0, alpha0 = crab_angles(u + cx, v + cy, w + cz, theta)
                dc_y, dc_z = -(beta - beta0) / dt, (alpha - alpha0) / dt
    y_int, z_int = (filt[6], filt[7]) if started else (0.0, 0.0)
    y_los = y_e + g[ILOS_Y] * y_int  # = y_e unless integral LOS is on
    z_los = z_e + g[ILOS_Z] * z_int
    c_y = -math.atan(k_y * y_los) - beta
    if g[PRINTED_PITCH] > 0.0:  # the paper's print: both signs flipped (fails, docs/model.md §8.9)
        theta_d_raw = theta_f - math.atan(k_z * z_los) - alpha
    else:
        theta_d_raw = theta_f + math.atan(k_z * z_los) + alpha
    if trims:
        beta_hat, alpha_hat = filt[BETA_HAT], filt[ALPHA_HAT]
        c_y -= beta_hat
        theta_d_raw += alpha_hat
        adapt_trims(
            x_e, y_e, z_e, k_y, k_z, g[ALOS_Y], g[ALOS_Z], g[ALOS_RADIUS], g[ALOS_MAX], dt, filt
        )
        dc_y -= (filt[BETA_HAT] - beta_hat) / dt
        dc_z += (filt[ALPHA_HAT] - alpha_hat) / dt
    c_z = min(max(theta_d_raw, -g[THETA_MAX]), g[THETA_MAX]) - theta_f
    if g[SPEED_OVER_GROUND] > 0.0:
        u_ref = speed_reference(o[_UD], t0, t1, t2, filt[C_HAT], filt[C_HAT + 1], filt[C_HAT + 2])
        out[12], out[13] = u_ref, (u_ref - filt[U_REF]) / dt if started else 0.0
        filt[U_REF] = u_ref
    else:
        out[12], out[13] = o[_UD], 0.0
    if not started:
        filt[0], filt[1], filt[2], filt[3] = c_z, 0.0, c_y, 0.0
        filt[4], filt[5] = o[_DPSIF], o[_DTHF]
    # ẏ_int = k_y y_e / (1 + (k_y y_los)²): slows down far from the path; 0 with ILOS off
    filt[6] = y_int + dt * k_y * y_e / (1.0 + (k_y * y_los) ** 2) if g[ILOS_Y] > 0.0 else 0.0
    filt[7] = z_int + dt * k_z * z_e / (1.0 + (k_z * z_los) ** 2) if g[ILOS_Z] > 0.0 else 0.0
    wn, zeta = g[WN], g[ZETA]
    x_z, v_z, x_y, v_y = filt[0], filt[1], filt[2], filt[3]
    if observer or trims:  # ẍ = ω_n²(c − x) + 2ζω_n(ċ − ẋ): no lag behind a ramp in c
        a_z = wn * wn * (c_z - x_z) + 2.0 * zeta * wn * (dc_z - v_z)
        a_y = wn * wn * (c_y - x_y) + 2.0 * zeta * wn * (dc_y - v_y)
    else:
        a_z = wn * wn * (c_z - x_z) - 2.0 * zeta * wn * v_z
        a_y = wn * wn * (c_y - x_y) - 2.0 * zeta * wn * v_y
    theta_d = theta_f + x_z
    dtheta_d = o[_DTHF] + v_z
    ddtheta_d = (o[_DTHF] - filt[5]) / dt + a_z
    z3 = wrap_angle(o[_PSIE] - x_y)
    dpsi_d = o[_DPSIF] + v_y
    ddpsi_d = (o[_DPSIF] - filt[4]) / dt + a_y
    filt[0], filt[1] = x_z + dt * v_z, v_z + dt * a_z
    filt[2], filt[3] = x_y + dt * v_y, v_y + dt * a_y
    filt[4], filt[5] = o[_DPSIF], o[_DTHF]

    k1, c1, k2, c2 = g[K1], g[C1], g[K2], g[C2]
    z1 = theta - theta_d
    z2 = q + k1 * z1 - dtheta_d
    dz1 = q - dtheta_d
    cth, sth = math.cos(theta), math.sin(theta)
    base = -k2 * z3 + dpsi_d
    z4 = r - cth * base
    dz3 = r / cth - dpsi_d
    out[0], out[1], out[2], out[3] = z1, z2, c1 * z1 + z2, dz1
    out[4] = -k1 * dz1 + ddtheta_d
    out[5], out[6], out[7], out[8] = z3, z4, c2 * z3 + z4, dz3
    out[9] = -q * sth * base + cth * (-k2 * dz3 + ddpsi_d)
    out[10], out[11] = theta_d, x_y
