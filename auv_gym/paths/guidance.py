"""Serret-Frenet guidance: path angles, body-frame errors, virtual-point speed (docs/model.md §3).

Conventions: ε = (x_e, y_e, z_e) = R_Bᵀ(η_pos − p(s)), vehicle minus virtual point, expressed in
the body frame with R_B = Rz(ψ)·Ry(θ) (paper (5)–(8), computed geometrically as docs/model.md §3.2
prescribes). x_e > 0 means the vehicle is ahead of the virtual point P.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = [
    "body_errors",
    "body_errors_trig",
    "error_rates",
    "path_angles",
    "virtual_point_speed",
    "wrap_angle",
]


@njit(cache=True, inline="always")
def wrap_angle(angle):
    """Wrap an angle to (−π, π] [rad]."""
    return angle - 2.0 * math.pi * math.ceil((angle - math.pi) / (2.0 * math.pi))


@njit(cache=True, inline="always")
def path_angles(dx, dy, dz, ddx, ddy, ddz):
    """(ψ_F, θ_F, dψ_F/ds, dθ_F/ds, |p'|) from p' and p'' (docs/model.md §3.1, paper (4)).

    ψ_F = atan2(y', x'), θ_F = −atan2(z', h) with h = sqrt(x'² + y'²) [rad, rad per unit s].
    """
    h2 = dx * dx + dy * dy
    h = math.sqrt(h2)
    speed = math.sqrt(h2 + dz * dz)
    psi_f = math.atan2(dy, dx)
    theta_f = -math.atan2(dz, h)
    if h2 > 1e-12:
        dpsi_f = (dx * ddy - dy * ddx) / h2
        dh = (dx * ddx + dy * ddy) / h
        dtheta_f = -(ddz * h - dz * dh) / (h2 + dz * dz)
    else:  # vertical tangent: heading undefined, hold it
        dpsi_f = 0.0
        dtheta_f = 0.0
    return psi_f, theta_f, dpsi_f, dtheta_f, speed


@njit(cache=True, inline="always")
def body_errors_trig(dx, dy, dz, cth, sth, cps, sps):
    """R_Bᵀ(dx, dy, dz) given cos θ, sin θ, cos ψ, sin ψ [m]."""
    a = cps * dx + sps * dy
    return cth * a - sth * dz, -sps * dx + cps * dy, sth * a + cth * dz


@njit(cache=True, inline="always")
def body_errors(x, y, z, theta, psi, px, py, pz):
    """ε = R_Bᵀ(η_pos − p) with R_B = Rz(ψ)Ry(θ) [m] (docs/model.md §3.2)."""
    return body_errors_trig(
        x - px, y - py, z - pz, math.cos(theta), math.sin(theta), math.cos(psi), math.sin(psi)
    )


@njit(cache=True, inline="always")
def virtual_point_speed(x_e, u_d, sigma):
    """u_p = u_D(1 + tanh(x_e/σ)) [m/s] (docs/model.md §3.3; the paper's 1 − tanh is unstable)."""
    return u_d * (1.0 + math.tanh(x_e / sigma))


def error_rates(
    eps: np.ndarray,
    nu: np.ndarray,
    theta: float,
    psi: float,
    psi_f: float,
    theta_f: float,
    u_p: float,
) -> np.ndarray:
    """Exact ε̇ = −ω_b × ε + (u, v, w) − (R_Bᵀ R_F e1) u_p (docs/model.md §3.2) [m/s].

    ``nu`` is (u, v, w, q, r); ω_b = (−r tanθ, q, r) since roll is held at zero.
    """
    u, v, w, q, r = nu
    omega_b = np.array([-r * math.tan(theta), q, r])
    tangent = np.array(
        [
            math.cos(psi_f) * math.cos(theta_f),
            math.sin(psi_f) * math.cos(theta_f),
            -math.sin(theta_f),
        ]
    )
    cps, sps, cth, sth = math.cos(psi), math.sin(psi), math.cos(theta), math.sin(theta)
    r_b = np.array([[cps * cth, -sps, cps * sth], [sps * cth, cps, sps * sth], [-sth, 0.0, cth]])
    return -np.cross(omega_b, eps) + np.array([u, v, w]) - (r_b.T @ tangent) * u_p
