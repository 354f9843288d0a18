"""The agent observation's extra entries (``observation="preview"``), computed after each step.

`extend_rows` fills, per vehicle, the entries that follow the paper's 15 (table in
`auv_gym.sim.observation`; docs/design.md §3.12): the velocity over ground in the body frame, the
previous saturated action and K points of the path ahead of the virtual point with the path's
curvature and torsion there. Everything is a function of the state, the current and the path,
so the single env and the vector env (both a `simulator.Simulator`) agree bit for bit.

Preview points are Δs of *arc length* apart: the path parameter advances by a midpoint step
s ← s + Δs/‖p′(s + ½Δs/‖p′(s)‖)‖, exact for the helix and the line (‖p′‖ constant) and within
O(Δs³) of the arc length on a spline. Beyond the end of a finite path the path continues along
its last tangent, p(s_end) + (s − s_end)·p′(s_end), so a preview is never NaN.
"""

from __future__ import annotations

import math

from numba import njit

from auv_gym.paths.guidance import body_errors_trig
from auv_gym.paths.shapes import path_eval, path_third_derivative
from auv_gym.sim.integrator import config_record
from auv_gym.sim.observation import CURVATURE_BOUND, EXTRA_HEAD, PREVIEW_FEATURES, PREVIEW_MARGIN
from auv_gym.vehicle.dynamics import STATE

__all__ = ["curvature_torsion", "extend_rows", "extended_path"]

_HEAD = len(EXTRA_HEAD)
_PER_POINT = len(PREVIEW_FEATURES)


@njit(cache=True, inline="always")
def extended_path(kind, data, s, s_end):
    """(p, p′, p″, p‴) at s as 12 numbers; past s_end, the tangent line at s_end."""
    if s <= s_end:
        px, py, pz, dx, dy, dz, ddx, ddy, ddz = path_eval(kind, data, s)
        tx, ty, tz = path_third_derivative(kind, data, s)
        return px, py, pz, dx, dy, dz, ddx, ddy, ddz, tx, ty, tz
    px, py, pz, dx, dy, dz, _, _, _ = path_eval(kind, data, s_end)
    h = s - s_end
    return px + h * dx, py + h * dy, pz + h * dz, dx, dy, dz, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0


@njit(cache=True, inline="always")
def curvature_torsion(dx, dy, dz, ddx, ddy, ddz, tx, ty, tz):
    """(κ, τ) [1/m] from p′, p″, p‴, each saturated at ±`CURVATURE_BOUND`; τ = 0 where κ = 0."""
    cx, cy, cz = dy * ddz - dz * ddy, dz * ddx - dx * ddz, dx * ddy - dy * ddx
    cross2 = cx * cx + cy * cy + cz * cz
    speed = math.sqrt(dx * dx + dy * dy + dz * dz)
    kappa = math.sqrt(cross2) / (speed * speed * speed)
    tau = 0.0
    if kappa > 1e-12:
        tau = (cx * tx + cy * ty + cz * tz) / cross2
    kappa = min(kappa, CURVATURE_BOUND)
    tau = min(max(tau, -CURVATURE_BOUND), CURVATURE_BOUND)
    return kappa, tau


@njit(cache=True, inline="always")
def _tangent_norm(kind, data, s, s_end):
    p = extended_path(kind, data, s, s_end)
    return math.sqrt(p[3] * p[3] + p[4] * p[4] + p[5] * p[5])


@njit(cache=True)
def extend_rows(
    rows,
    state,
    current,
    last_action,
    row,
    kinds,
    pdata,
    cfgs,
    tasks,
    s_end_column,
    points,
    spacing,
    out,
):
    """Write the extra entries of vehicles ``rows`` into ``out`` (n, 6 + 5K).

    ``state`` (layout `dynamics.STATE`), ``current`` the Gauss–Markov deviation (x, y, z) [m/s]
    added to the config's mean, ``last_action`` the previous saturated action; the path, config
    and task of vehicle i are row ``row[i]`` of ``kinds``, ``pdata``, ``cfgs``, ``tasks`` (the
    path's end s_end in column ``s_end_column``).
    """
    for i in rows:
        r = row[i]
        cfg = config_record(cfgs[r])
        st = state[i]
        cth, sth = math.cos(st[STATE.theta]), math.sin(st[STATE.theta])
        cps, sps = math.cos(st[STATE.psi]), math.sin(st[STATE.psi])
        c_x, c_y = cfg.current_x + current[i, 0], cfg.current_y + current[i, 1]
        c_z = cfg.current_z + current[i, 2]
        cu, cv, cw = body_errors_trig(c_x, c_y, c_z, cth, sth, cps, sps)  # R_Bᵀ v_c
        o = out[i]
        o[0], o[1], o[2] = st[STATE.u] + cu, st[STATE.v] + cv, st[STATE.w] + cw
        o[3], o[4], o[5] = last_action[i, 0], last_action[i, 1], last_action[i, 2]
        kind, data, end = kinds[r], pdata[r], tasks[r, s_end_column]
        s = st[STATE.s]
        prev = extended_path(kind, data, s, end)
        for k in range(points):
            half = 0.5 * spacing / _tangent_norm(kind, data, s, end)
            step = spacing / _tangent_norm(kind, data, s + half, end)
            p = extended_path(kind, data, s + step, end)
            # Where ‖p′‖ changes fast within a step (a spline's near-reversal) the midpoint
            # rule can jump far along the path: halve the step until its chord is at most
            # the margin the observation bound allows, so every point stays in its bound.
            for _ in range(64):
                dx, dy, dz = p[0] - prev[0], p[1] - prev[1], p[2] - prev[2]
                if dx * dx + dy * dy + dz * dz <= (PREVIEW_MARGIN * spacing) ** 2:
                    break
                step *= 0.5
                p = extended_path(kind, data, s + step, end)
            s = s + step
            prev = p
            ex, ey, ez = body_errors_trig(
                p[0] - st[STATE.x], p[1] - st[STATE.y], p[2] - st[STATE.z], cth, sth, cps, sps
            )
            kappa, tau = curvature_torsion(p[3], p[4], p[5], p[6], p[7], p[8], p[9], p[10], p[11])
            j = _HEAD + _PER_POINT * k
            o[j], o[j + 1], o[j + 2], o[j + 3], o[j + 4] = ex, ey, ez, kappa, tau
