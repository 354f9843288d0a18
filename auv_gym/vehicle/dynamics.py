r"""Equations of motion of the simulated system: the AUV (paper Eq. (1)–(2)) and its virtual point.

Vehicle (docs/model.md §2.1, the paper's (1) with its OCR corrected; NED, z down, θ nose-up
positive, roll held at zero). ν = (u, v, w, q, r) is the velocity through the water [m/s, rad/s],
η = (x, y, z, θ, ψ) the earth-fixed pose [m, rad], τ = (X, M, N) the actuation [N, N·m] and
f = (f_u, f_v, f_w, f_q, f_r) the disturbance [N, N·m]. In groups, M ν̇ = τ + f + c + d + g with

    inertia          M = M_RB + M_A = diag(m − X_u̇, m − Y_v̇, m − Z_ẇ, I_y − M_q̇, I_z − N_ṙ)
                       = diag(m11, m22, m33, I55, I66)             (diagonal: §2.1 e)
    actuation        τ + f = (X + f_u, f_v, f_w, M + f_q, N + f_r)
    Coriolis and     c: surge  X_qq q² + X_rr r² + [(X_vr + m) v r + (X_wq − m) w q]
      centripetal       sway   −(m − Y_ur) u r
                        heave  (m + Z_uq) u q + m z_g q²
                        pitch  M_uq u q + M_uw u w − m z_g (w q − v r)
                        yaw    N_uv u v + N_ur u r
    damping          d: surge  X_u|u| u|u| + X_vv v² + X_ww w²
      (drag, lift)      sway   Y_uv u v + Y_v|v| v|v|
                        heave  Z_uw u w + Z_w|w| w|w|
                        pitch  M_q|q| q|q| + M_w|w| w|w|
                        yaw    N_v|v| v|v| + N_r|r| r|r|
    restoring        g: pitch  −(z_g W − z_b B) sin θ   (no (W − B) force: B = W, §2.1 f)

Every coefficient enters with its own (NED, Prestero) sign. The bracketed surge terms are switched
by ``surge_coriolis`` (§2.1 c). Prestero's u-proportional coefficients Y_ur, Z_uq, M_uq, M_uw,
N_uv and N_ur lump fin lift with added mass (and the Munk moment) and so sit under Coriolis;
Y_uv and Z_uw are pure body and fin lift. Kinematics (paper (2)):

    ẋ = u cosψ cosθ − v sinψ + w cosψ sinθ + v_c,x      θ̇ = q
    ẏ = u sinψ cosθ + v cosψ + w sinψ sinθ + v_c,y      ψ̇ = r / cosθ
    ż = −u sinθ + w cosθ + v_c,z

with the earth-fixed ocean current v_c (docs/model.md §2.5). The virtual point moves along the
path with ṡ = u_p/|p'(s)| (docs/model.md §3.3), so the simulator state is (η, ν, s):
`STATE_NAMES`, read by name through `STATE`.

The kernels read the parameters as a `vehicle.ParamsRecord` (``p.X_uu``) and are inlined into
the integrator, so none of this costs a call. `generalized_forces` writes each row as
docs/model.md §2.1 does, labelling the groups: the terms are added left to right in that order,
the order of the committed results (regrouping them would change the last bits of every
trajectory).
"""

from __future__ import annotations

import math

from numba import njit

from auv_gym.paths.guidance import body_errors_trig, virtual_point_speed
from auv_gym.paths.shapes import path_eval
from auv_gym.support.records import field_indices

__all__ = [
    "STATE",
    "STATE_DIM",
    "STATE_NAMES",
    "eta_dot",
    "generalized_forces",
    "nu_dot",
    "nu_dot_sin",
    "state_derivative",
]

STATE_NAMES = ("x", "y", "z", "theta", "psi", "u", "v", "w", "q", "r", "s")
STATE_DIM = len(STATE_NAMES)
STATE = field_indices("StateIndex", STATE_NAMES, __name__)


@njit(cache=True, inline="always")
def generalized_forces(nu, sin_theta, tau, f, p):
    """Right-hand sides of the five rows above, M ν̇ [N, N, N, N·m, N·m], given sin θ.

    ``nu`` = (u, v, w, q, r), ``tau`` = (X, M, N), ``f`` the 5 disturbance channels, ``p`` a
    `vehicle.ParamsRecord`.
    """
    u, v, w, q, r = nu
    X, M, N = tau
    f_u, f_v, f_w, f_q, f_r = f
    m = p.m
    restoring = (p.z_g * p.W - p.z_b * p.B) * sin_theta  # g_q(θ), docs/model.md §2.1 f
    surge = (
        X
        + f_u
        + p.X_uu * u * abs(u)
        + p.X_vv * v * v
        + p.X_ww * w * w  # damping
        + (p.X_qq * q * q + p.X_rr * r * r)  # centripetal
        + p.surge_coriolis * ((p.X_vr + m) * v * r + (p.X_wq - m) * w * q)
    )  # Coriolis
    sway = (
        f_v
        - (m - p.Y_ur) * u * r  # Coriolis
        + p.Y_uv * u * v
        + p.Y_vv * v * abs(v)
    )  # lift, drag
    heave = (
        f_w
        + (m + p.Z_uq) * u * q  # Coriolis
        + p.Z_uw * u * w
        + p.Z_ww * w * abs(w)  # lift, drag
        + m * p.z_g * q * q
    )  # Coriolis
    # The last bracket of the pitch row is one partial sum (see the module docstring).
    pitch = (
        M
        + f_q
        + p.M_qq * q * abs(q)  # damping
        + p.M_uq * u * q
        + p.M_uw * u * w  # Coriolis
        + (p.M_ww * w * abs(w) - restoring - m * p.z_g * (w * q - v * r))
    )
    yaw = (
        N
        + f_r
        + p.N_uv * u * v  # Coriolis
        + p.N_vv * v * abs(v)  # damping
        + p.N_ur * u * r  # Coriolis
        + p.N_rr * r * abs(r)
    )  # damping
    return surge, sway, heave, pitch, yaw


@njit(cache=True, inline="always")
def nu_dot_sin(nu, sin_theta, tau, f, p):
    """Accelerations ν̇ = M⁻¹ (right-hand sides) [m/s², rad/s²], given sin θ (the simulator
    computes the trigonometry once per stage)."""
    surge, sway, heave, pitch, yaw = generalized_forces(nu, sin_theta, tau, f, p)
    return surge / p.m11, sway / p.m22, heave / p.m33, pitch / p.I55, yaw / p.I66


@njit(cache=True, inline="always")
def nu_dot(nu, theta, tau, f, p):
    """Accelerations (u̇, v̇, ẇ, q̇, ṙ) of paper (1), docs/model.md §2.1 [m/s², rad/s²]."""
    return nu_dot_sin(nu, math.sin(theta), tau, f, p)


@njit(cache=True, inline="always")
def eta_dot(nu, cos_theta, sin_theta, cos_psi, sin_psi):
    """Kinematics of paper (2), docs/model.md §2.1: (ẋ, ẏ, ż, θ̇, ψ̇) through the water, given
    the cosines and sines of θ and ψ [m/s, rad/s]."""
    u, v, w, q, r = nu
    return (
        u * cos_psi * cos_theta - v * sin_psi + w * cos_psi * sin_theta,
        u * sin_psi * cos_theta + v * cos_psi + w * sin_psi * sin_theta,
        -u * sin_theta + w * cos_theta,
        q,
        r / cos_theta,
    )


@njit(cache=True, inline="always")
def state_derivative(st, tau, f, current, p, kind, pdata, u_d, sigma):
    """d/dt of the simulator state (layout `STATE`): ν̇, η̇ plus the current, and ṡ.

    ``current`` is the earth-fixed current (v_c,x, v_c,y, v_c,z) [m/s]; ``kind``, ``pdata``
    the path (`paths.path_eval`); ``u_d`` [m/s] and ``sigma`` [m] the virtual-point law.
    """
    # The trigonometry of θ and ψ is shared by the dynamics, kinematics and guidance.
    cos_theta, sin_theta = math.cos(st[STATE.theta]), math.sin(st[STATE.theta])
    cos_psi, sin_psi = math.cos(st[STATE.psi]), math.sin(st[STATE.psi])
    nu = (st[STATE.u], st[STATE.v], st[STATE.w], st[STATE.q], st[STATE.r])
    du, dv, dw, dq, dr = nu_dot_sin(nu, sin_theta, tau, f, p)
    dx, dy, dz, dtheta, dpsi = eta_dot(nu, cos_theta, sin_theta, cos_psi, sin_psi)
    px, py, pz, dpx, dpy, dpz, _, _, _ = path_eval(kind, pdata, st[STATE.s])
    x_e, _, _ = body_errors_trig(
        st[STATE.x] - px, st[STATE.y] - py, st[STATE.z] - pz, cos_theta, sin_theta, cos_psi, sin_psi
    )
    s_dot = virtual_point_speed(x_e, u_d, sigma) / math.sqrt(dpx * dpx + dpy * dpy + dpz * dpz)
    c_x, c_y, c_z = current
    return (dx + c_x, dy + c_y, dz + c_z, dtheta, dpsi, du, dv, dw, dq, dr, s_dot)
