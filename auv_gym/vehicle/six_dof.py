r"""The compiled 6-DOF plant (``plant="6dof"``, docs/model.md §15): the equations of
`auv_gym.vehicle.remus6dof` for the kernels, on tuples in registers.

The simulator's 6-DOF state is `SIX_DOF_STATE`: η = (x, y, z, φ, θ, ψ) [m, rad], the velocity
through the water ν_r = (u, v, w, p, q, r) [m/s, rad/s] and the virtual point's s. As in the
5-DOF model (docs/model.md §2.5) the current enters the kinematics, so the kinetics are written
in ν_r (Fossen 2021 §10.3; for a uniform current they are the reference's ν̇ − ν̇_c exactly):

    M ν̇_r = τ + τ_liftdrag(ν_r) + τ_crossflow(ν_r) − (C_RB(ν_r) + C_A(ν_r) + D(ν_r)) ν_r − g(η)
    ṗ_n = R(φ, θ, ψ) (u, v, w) + v_c,     (φ̇, θ̇, ψ̇) = T(φ, θ) (p, q, r)

The hull's numbers are one float64 row per vehicle (`SixDofVehicle.kernel_vector`, layout
`SIX_DOF_FIELDS`): M = M_RB + M_A, M_A and M⁻¹ as full 6×6 blocks (a user's vehicle may put
its centre of gravity anywhere), then the scalars. `six_dof_nu_dot` is checked against numbers
recorded from the reference implementation (tests/test_six_dof_plant.py, ≤ 1e-9 relative).
"""

from __future__ import annotations

import math

from numba import njit

from auv_gym.paths.guidance import body_errors_trig, virtual_point_speed
from auv_gym.paths.shapes import path_eval
from auv_gym.support.records import field_indices
from auv_gym.vehicle.actuators import fin_forces, propeller_thrust, propeller_torque

__all__ = [
    "SIX_DOF",
    "SIX_DOF_FIELDS",
    "SIX_DOF_STATE",
    "SIX_DOF_STATE_DIM",
    "SIX_DOF_STATE_NAMES",
    "six_dof_actuation",
    "six_dof_derivative",
    "six_dof_hull_forces",
    "six_dof_nu_dot",
    "six_dof_rk4",
]

SIX_DOF_STATE_NAMES = ("x", "y", "z", "phi", "theta", "psi", "u", "v", "w", "p", "q", "r", "s")
SIX_DOF_STATE_DIM = len(SIX_DOF_STATE_NAMES)
SIX_DOF_STATE = field_indices("SixDofStateIndex", SIX_DOF_STATE_NAMES, __name__)

# M = M_RB + M_A, M_A, M⁻¹: 36 entries each, row-major
_MATRICES = ("mass", "added", "inverse_mass")
SIX_DOF_FIELDS = (
    *(f"{name}_{i}{j}" for name in _MATRICES for i in range(6) for j in range(6)),
    *(f"damping_{axis}" for axis in ("u", "v", "w", "p", "q", "r")),  # [N·s/m, N·m·s] at U = 0
    "speed_decay",  # [s/m] surge and sway linear damping × exp(−speed_decay·U_r)
    "weight",  # [N] W = B
    "buoyancy",  # [N]
    "x_g",
    "y_g",
    "z_g",  # [m] centre of gravity
    "x_b",
    "y_b",
    "z_b",  # [m] centre of buoyancy
    "water_density",  # [kg/m³]
    "length",  # [m]
    "diameter",  # [m]
    "wing_area",  # [m²] S of the hull's lift and drag
    "lift_slope",  # [1/rad] C_L per α
    "zero_lift_drag",  # [-] C_D0
    "induced_drag",  # [-] 1/(π e A): C_D = C_D0 + induced_drag·C_L²
    "crossflow_coeff",  # [-] Hoerner's 2-D C_D
    "strips",  # cross-flow strips (strips + 1 stations)
    "propeller_torque_scale",  # [-] share of the shaft torque felt in roll
)
SIX_DOF = field_indices("SixDofIndex", SIX_DOF_FIELDS, __name__)
_MASS, _ADDED, _INVERSE = SIX_DOF.mass_00, SIX_DOF.added_00, SIX_DOF.inverse_mass_00


@njit(cache=True, inline="always")
def _matvec3(h, offset, x):
    """The first three rows of the 6×6 row-major block at ``offset`` of ``h`` times the
    6-tuple x (`_matvec`)."""
    return (
        h[offset + 0] * x[0]
        + h[offset + 1] * x[1]
        + h[offset + 2] * x[2]
        + h[offset + 3] * x[3]
        + h[offset + 4] * x[4]
        + h[offset + 5] * x[5],
        h[offset + 6] * x[0]
        + h[offset + 7] * x[1]
        + h[offset + 8] * x[2]
        + h[offset + 9] * x[3]
        + h[offset + 10] * x[4]
        + h[offset + 11] * x[5],
        h[offset + 12] * x[0]
        + h[offset + 13] * x[1]
        + h[offset + 14] * x[2]
        + h[offset + 15] * x[3]
        + h[offset + 16] * x[4]
        + h[offset + 17] * x[5],
    )


@njit(cache=True, inline="always")
def _matvec(h, offset, x):
    """The 6×6 row-major block at ``offset`` of ``h`` times the 6-tuple x."""
    return _matvec3(h, offset, x) + _matvec3(h, offset + 18, x)


@njit(cache=True, inline="always")
def _cross(a0, a1, a2, b0, b1, b2):
    """a × b."""
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@njit(cache=True, inline="always")
def _coriolis_product(mv, nu):
    """C(ν) ν of a symmetric inertia M, given M ν (Fossen 2021 eq. 3.63): with ν = (ν₁, ν₂) and
    M ν = (p₁, p₂), C(ν) ν = (ν₂ × p₁, ν₁ × p₁ + ν₂ × p₂)."""
    top = _cross(nu[3], nu[4], nu[5], mv[0], mv[1], mv[2])
    a = _cross(nu[0], nu[1], nu[2], mv[0], mv[1], mv[2])
    b = _cross(nu[3], nu[4], nu[5], mv[3], mv[4], mv[5])
    return top[0], top[1], top[2], a[0] + b[0], a[1] + b[1], a[2] + b[2]


@njit(cache=True, inline="always")
def _power_sums(first, last):
    """(Σk⁰, Σk¹, Σk², Σk³) over the whole numbers k = first … last (none if last < first)."""
    if last < first:
        return 0.0, 0.0, 0.0, 0.0
    lo, hi = first - 1.0, float(last)
    s1 = 0.5 * (hi * (hi + 1.0) - lo * (lo + 1.0))
    s2 = (hi * (hi + 1.0) * (2.0 * hi + 1.0) - lo * (lo + 1.0) * (2.0 * lo + 1.0)) / 6.0
    s3 = 0.25 * ((hi * (hi + 1.0)) ** 2 - (lo * (lo + 1.0)) ** 2)
    return hi - lo, s1, s2, s3


@njit(cache=True, inline="always")
def _signed_sums(a, b, x0, dx, first, last):
    """Σ (a + b k)² dx and Σ (a + b k)² (x0 + dx k) dx over k = first … last."""
    n0, n1, n2, n3 = _power_sums(first, last)
    quad0 = a * a * n0 + 2.0 * a * b * n1 + b * b * n2  # Σ (a + bk)²
    quad1 = a * a * n1 + 2.0 * a * b * n2 + b * b * n3  # Σ k (a + bk)²
    return quad0 * dx, (x0 * quad0 + dx * quad1) * dx


@njit(cache=True, inline="always")
def _crossflow(v, r, h):
    """Cross-flow sway force [N] and yaw moment [N·m] by strip theory (docs/model.md §15):
    the reference's sum over its strips + 1 stations x_k = −L/2 + k·dx of
    −½ρ d C_D,2D |v + x_k r|(v + x_k r) dx (and × x_k), in closed form: the flow a + b·k is
    linear in k, so each side of its sign change is a sum of k⁰ … k³."""
    stations = int(h[SIX_DOF.strips])
    length = h[SIX_DOF.length]
    dx = length / stations
    x0 = -0.5 * length
    gain = -0.5 * h[SIX_DOF.water_density] * h[SIX_DOF.diameter] * h[SIX_DOF.crossflow_coeff]
    a, b = v + x0 * r, dx * r  # the flow at station k: a + b·k [m/s]
    if b > 0.0:  # negative flow below the crossing, positive from it on
        split = min(max(math.ceil(-a / b), 0), stations + 1)
        neg = _signed_sums(a, b, x0, dx, 0, split - 1)
        pos = _signed_sums(a, b, x0, dx, split, stations)
    elif b < 0.0:
        split = min(max(math.floor(-a / b) + 1, 0), stations + 1)
        pos = _signed_sums(a, b, x0, dx, 0, split - 1)
        neg = _signed_sums(a, b, x0, dx, split, stations)
    elif a >= 0.0:
        pos, neg = _signed_sums(a, b, x0, dx, 0, stations), (0.0, 0.0)
    else:
        pos, neg = (0.0, 0.0), _signed_sums(a, b, x0, dx, 0, stations)
    return gain * (pos[0] - neg[0]), gain * (pos[1] - neg[1])


@njit(cache=True, inline="always")
def six_dof_hull_forces(nu_r, sin_phi, cos_phi, sin_theta, cos_theta, h):
    """The hull's generalized forces [N, N·m] at ν_r, given sin and cos of roll φ and pitch θ:
    lift and drag, cross-flow drag, −(C_RB + C_A + D) ν_r and −g(η) (module doc; docs/model.md
    §15)."""
    u, v, w, p, q, r = nu_r
    # Rigid-body and added-mass Coriolis; C_A without the Munk moments in pitch and yaw: the
    # entries (5,1), (5,3), (6,1), (6,2) of C_A and their transposes (1-based) are removed.
    # C(M) ν is linear in M, so C_RB + C_A is C of M_RB + M_A: one product.
    c = _coriolis_product(_matvec(h, _MASS, nu_r), nu_r)
    ax, ay, az = _matvec3(h, _ADDED, nu_r)  # the linear part of M_A ν
    coriolis = (
        c[0] - (az * q - ay * r),
        c[1] - ax * r,
        c[2] + ax * q,
        c[3],
        c[4] - (ax * w - az * u),
        c[5] - (ay * u - ax * v),
    )
    speed = math.sqrt(u * u + v * v + w * w)  # U_r [m/s]
    fade = math.exp(-h[SIX_DOF.speed_decay] * speed)
    damping = (
        h[SIX_DOF.damping_u] * fade * u,
        h[SIX_DOF.damping_v] * fade * v,
        h[SIX_DOF.damping_w] * w,
        h[SIX_DOF.damping_p] * p,
        h[SIX_DOF.damping_q] * q,
        h[SIX_DOF.damping_r] * r,
    )
    # The hull as a low-aspect wing at α = atan2(w_r, u_r) (Beard and McLain 2012).
    alpha = math.atan2(w, u)
    lift_coeff = h[SIX_DOF.lift_slope] * alpha
    drag_coeff = h[SIX_DOF.zero_lift_drag] + h[SIX_DOF.induced_drag] * lift_coeff * lift_coeff
    pressure = 0.5 * h[SIX_DOF.water_density] * speed * speed * h[SIX_DOF.wing_area]
    drag, lift = pressure * drag_coeff, pressure * lift_coeff
    axial = math.sqrt(u * u + w * w)  # cos α, sin α without the trigonometry
    ca, sa = (u / axial, w / axial) if axial > 0.0 else (1.0, 0.0)
    sway_cf, yaw_cf = _crossflow(v, r, h)
    # Restoring forces and moments g(η) of W at r_g and B at r_b.
    sth, cth, sphi, cphi = sin_theta, cos_theta, sin_phi, cos_phi
    weight, buoyancy = h[SIX_DOF.weight], h[SIX_DOF.buoyancy]
    net = weight - buoyancy
    gx = h[SIX_DOF.x_g] * weight - h[SIX_DOF.x_b] * buoyancy
    gy = h[SIX_DOF.y_g] * weight - h[SIX_DOF.y_b] * buoyancy
    gz = h[SIX_DOF.z_g] * weight - h[SIX_DOF.z_b] * buoyancy
    restoring = (
        net * sth,
        -net * cth * sphi,
        -net * cth * cphi,
        -gy * cth * cphi + gz * cth * sphi,
        gz * sth + gx * cth * cphi,
        -gx * cth * sphi - gy * sth,
    )
    return (
        -ca * drag + sa * lift - coriolis[0] - damping[0] - restoring[0],
        sway_cf - coriolis[1] - damping[1] - restoring[1],
        -sa * drag - ca * lift - coriolis[2] - damping[2] - restoring[2],
        -coriolis[3] - damping[3] - restoring[3],
        -coriolis[4] - damping[4] - restoring[4],
        yaw_cf - coriolis[5] - damping[5] - restoring[5],
    )


@njit(cache=True, inline="always")
def six_dof_nu_dot(nu_r, phi, theta, tau, h):
    """ν̇_r = M⁻¹ (τ + hull forces) [m/s², rad/s²] for generalized forces τ (6,) [N, N·m]."""
    return _nu_dot(nu_r, math.sin(phi), math.cos(phi), math.sin(theta), math.cos(theta), tau, h)


@njit(cache=True, inline="always")
def _nu_dot(nu_r, sin_phi, cos_phi, sin_theta, cos_theta, tau, h):
    """`six_dof_nu_dot` given the sines and cosines of φ and θ (the derivative shares them)."""
    hull = six_dof_hull_forces(nu_r, sin_phi, cos_phi, sin_theta, cos_theta, h)
    total = (
        tau[0] + hull[0],
        tau[1] + hull[1],
        tau[2] + hull[2],
        tau[3] + hull[3],
        tau[4] + hull[4],
        tau[5] + hull[5],
    )
    return _matvec(h, _INVERSE, total)


@njit(cache=True, inline="always")
def six_dof_actuation(n_rpm, delta_s, delta_r, nu_r, propeller_speed, torque_scale, a):
    """τ (6,) [N, N·m] of the propeller and fins (`auv_gym.vehicle.actuators`, the same formulas)
    at the velocity through the water ν_r, with the propeller's torque in roll scaled by
    ``torque_scale``; the propeller's advance speed is ``propeller_speed`` [m/s] (the env passes
    |ν_r|, the speed through the water; the reference's check passes the speed over ground)."""
    drag, y_r, z_s, m_s, n_r = fin_forces(delta_s, delta_r, nu_r[0], nu_r[1], nu_r[2], a)
    thrust = (1.0 - a.thrust_deduction) * propeller_thrust(n_rpm, propeller_speed, a)
    roll = torque_scale * propeller_torque(n_rpm, propeller_speed, a)
    return thrust + drag, y_r, z_s, roll, m_s, n_r


# Called, not inlined: the RK4 inlined four copies of this body, and compiling them took 134 s
# of the set-up's kernel compile on 2 cores against 13.5 s for one called copy; the call costs
# 11 % of an RK4 step (1.43 against 1.59 µs, one run each; docs/performance.md).
@njit(cache=True)
def six_dof_derivative(st, tau, f, current, h, kind, pdata, u_d, sigma):
    """d/dt of the 6-DOF state (layout `SIX_DOF_STATE`) under τ (6,) and the disturbance f
    (f_u, f_v, f_w, f_q, f_r) [N, N·m] (no roll channel), in the earth-fixed current (v_c,x,
    v_c,y, v_c,z) [m/s]; ``kind``, ``pdata``, ``u_d``, ``sigma`` the virtual point's path and
    law, as `dynamics.state_derivative`."""
    phi, theta, psi = st[3], st[4], st[5]
    nu = (st[6], st[7], st[8], st[9], st[10], st[11])
    forces = (
        tau[0] + f[0],
        tau[1] + f[1],
        tau[2] + f[2],
        tau[3],
        tau[4] + f[3],
        tau[5] + f[4],
    )
    cphi, sphi = math.cos(phi), math.sin(phi)
    cth, sth = math.cos(theta), math.sin(theta)
    du, dv, dw, dp, dq, dr = _nu_dot(nu, sphi, cphi, sth, cth, forces, h)
    cpsi, spsi = math.cos(psi), math.sin(psi)
    u, v, w, p, q, r = nu
    # ṗ_n = R(φ, θ, ψ) (u, v, w), Fossen's zyx convention; (φ̇, θ̇, ψ̇) = T(φ, θ)(p, q, r).
    dx = (
        cpsi * cth * u
        + (-spsi * cphi + cpsi * sth * sphi) * v
        + (spsi * sphi + cpsi * cphi * sth) * w
    )
    dy = (
        spsi * cth * u
        + (cpsi * cphi + sphi * sth * spsi) * v
        + (-cpsi * sphi + sth * spsi * cphi) * w
    )
    dz = -sth * u + cth * sphi * v + cth * cphi * w
    turn = q * sphi + r * cphi
    dphi = p + turn * sth / cth
    dtheta = q * cphi - r * sphi
    dpsi = turn / cth
    # The virtual point's law reads the along-track error x_e, which the body x-axis alone
    # fixes: roll does not enter it (docs/model.md §15).
    px, py, pz, dpx, dpy, dpz, _, _, _ = path_eval(kind, pdata, st[12])
    x_e, _, _ = body_errors_trig(st[0] - px, st[1] - py, st[2] - pz, cth, sth, cpsi, spsi)
    s_dot = virtual_point_speed(x_e, u_d, sigma) / math.sqrt(dpx * dpx + dpy * dpy + dpz * dpz)
    return (
        dx + current[0],
        dy + current[1],
        dz + current[2],
        dphi,
        dtheta,
        dpsi,
        du,
        dv,
        dw,
        dp,
        dq,
        dr,
        s_dot,
    )


@njit(cache=True, inline="always")
def _stage(st, h, k):
    """st + h·k on 13-tuples."""
    return (
        st[0] + h * k[0],
        st[1] + h * k[1],
        st[2] + h * k[2],
        st[3] + h * k[3],
        st[4] + h * k[4],
        st[5] + h * k[5],
        st[6] + h * k[6],
        st[7] + h * k[7],
        st[8] + h * k[8],
        st[9] + h * k[9],
        st[10] + h * k[10],
        st[11] + h * k[11],
        st[12] + h * k[12],
    )


@njit(cache=True, inline="always")
def _weighted(k1, k2, k3, k4):
    """k1 + 2 k2 + 2 k3 + k4 on 13-tuples."""
    return (
        k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0],
        k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1],
        k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2],
        k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3],
        k1[4] + 2.0 * k2[4] + 2.0 * k3[4] + k4[4],
        k1[5] + 2.0 * k2[5] + 2.0 * k3[5] + k4[5],
        k1[6] + 2.0 * k2[6] + 2.0 * k3[6] + k4[6],
        k1[7] + 2.0 * k2[7] + 2.0 * k3[7] + k4[7],
        k1[8] + 2.0 * k2[8] + 2.0 * k3[8] + k4[8],
        k1[9] + 2.0 * k2[9] + 2.0 * k3[9] + k4[9],
        k1[10] + 2.0 * k2[10] + 2.0 * k3[10] + k4[10],
        k1[11] + 2.0 * k2[11] + 2.0 * k3[11] + k4[11],
        k1[12] + 2.0 * k2[12] + 2.0 * k3[12] + k4[12],
    )


@njit(cache=True, inline="always")
def six_dof_rk4(st, tau, f, current, h, kind, pdata, u_d, sigma, dt):
    """One classical RK4 step of `six_dof_derivative` over dt [s], τ, f and the current held."""
    k1 = six_dof_derivative(st, tau, f, current, h, kind, pdata, u_d, sigma)
    k2 = six_dof_derivative(_stage(st, 0.5 * dt, k1), tau, f, current, h, kind, pdata, u_d, sigma)
    k3 = six_dof_derivative(_stage(st, 0.5 * dt, k2), tau, f, current, h, kind, pdata, u_d, sigma)
    k4 = six_dof_derivative(_stage(st, dt, k3), tau, f, current, h, kind, pdata, u_d, sigma)
    return _stage(st, dt / 6.0, _weighted(k1, k2, k3, k4))
