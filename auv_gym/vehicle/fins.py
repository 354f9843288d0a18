r"""Control fins anywhere on the hull: the general fin model and the allocation of the stern-plane
and rudder commands onto any fin layout (docs/vehicles.md §1.4, docs/model.md §2.6).

A fin i at x_i along the body, its axis rolled φ_i from the body's y axis toward z (0: a
starboard stern plane, π/2: a bottom rudder) and its centre of pressure at a radius r_i from the
x axis, deflected δ_i [rad], gives the lift (Fossen's PythonVehicleSimulator, ``fin.tau``)

    f_i = ½ρ A_i C_L,i δ_i U_i²,    U_i² = u_r² + (v_r sin φ_i)² + (w_r cos φ_i)²
    F_i = (−κ_i f_i δ_i, f_i sin φ_i, −f_i cos φ_i),    R_i = (x_i, r_i cos φ_i, r_i sin φ_i)
    τ_i = (F_i, R_i × F_i)

with (u_r, v_r, w_r) the velocity through the water and κ_i the fin's induced-drag factor
(1 in Fossen's ``remus100``, whose drag is −½ρU²AC_Lδ²; 0 in its ``torpedo``). Two fins of a
pair at r = 0 with κ = 1 give `actuators.fin_forces` of the REMUS 100.

The commands (δ_s, δ_r) [rad] of the stern planes and rudders reach fin i as

    δ_i = cos φ_i δ_s − sin φ_i δ_r

so that every fin's lift adds to the pair's heave force −k δ_s and side force −k δ_r (the
REMUS 100's signs); `allocate_fins` clips each to its angle limit. The trigonometry of the
cardinal axes (0, ±π/2, π) is exact, so the REMUS 100's pairs get today's commands bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from auv_gym.vehicle.actuators import propeller_thrust, propeller_torque
from auv_gym.vehicle.remus6dof import SixDofVehicle, hull_accelerations

__all__ = ["FinLayout", "accelerations", "allocate_fins", "axis_trigonometry", "fin_wrench"]

# An axis this close to a cardinal angle [rad] is that angle: cos and sin exactly 0 or ±1.
CARDINAL_TOLERANCE = 1e-9


def axis_trigonometry(axis_roll: float) -> tuple[float, float]:
    """(cos φ, sin φ) of a fin's axis roll φ [rad], exact on the cardinal axes."""
    c, s = math.cos(axis_roll), math.sin(axis_roll)
    if abs(s) <= CARDINAL_TOLERANCE:
        return math.copysign(1.0, c), 0.0
    if abs(c) <= CARDINAL_TOLERANCE:
        return 0.0, math.copysign(1.0, s)
    return c, s


@dataclass(frozen=True)
class FinLayout:
    """The fins of a vehicle as arrays, one entry per fin (SI): area A [m²], lift slope C_L
    [1/rad], position x [m], axis roll φ [rad], radius r [m], induced-drag factor κ [-] and
    angle limit [rad]; ``water_density`` ρ [kg/m³]."""

    area: np.ndarray
    lift_slope: np.ndarray
    x: np.ndarray
    axis_roll: np.ndarray
    radius: np.ndarray
    induced_drag: np.ndarray
    angle_max: np.ndarray
    water_density: float

    @classmethod
    def from_fins(cls, fins: Sequence, water_density: float) -> FinLayout:
        """From `FinSpec` records (`auv_gym.vehicle.record`)."""

        def column(name: str) -> np.ndarray:
            return np.array([float(getattr(fin, name)) for fin in fins])

        return cls(
            *(column(name) for name in ("area", "lift_slope", "x", "axis_roll", "radius")),
            column("induced_drag"),
            column("angle_max"),
            float(water_density),
        )

    @property
    def trigonometry(self) -> tuple[np.ndarray, np.ndarray]:
        """(cos φ_i, sin φ_i) of every fin, exact on the cardinal axes."""
        pairs = np.array([axis_trigonometry(phi) for phi in self.axis_roll]).reshape(-1, 2)
        return pairs[:, 0], pairs[:, 1]


def allocate_fins(layout: FinLayout, delta_s: float, delta_r: float) -> np.ndarray:
    """Each fin's deflection [rad] for stern-plane and rudder commands δ_s, δ_r [rad] (module
    doc), clipped to its angle limit."""
    cos_phi, sin_phi = layout.trigonometry
    return np.clip(cos_phi * delta_s - sin_phi * delta_r, -layout.angle_max, layout.angle_max)


def fin_wrench(layout: FinLayout, nu_r: np.ndarray, deflections: np.ndarray) -> np.ndarray:
    """τ (6,) [N, N·m] of all fins at deflections δ_i [rad] and velocity through the water
    ν_r = (u, v, w [m/s], p, q, r [rad/s]) (module doc)."""
    cos_phi, sin_phi = layout.trigonometry
    u, v, w = float(nu_r[0]), float(nu_r[1]), float(nu_r[2])
    delta = np.asarray(deflections, float)
    speed_sq = u * u + (v * sin_phi) ** 2 + (w * cos_phi) ** 2
    lift = 0.5 * layout.water_density * layout.area * layout.lift_slope * delta * speed_sq
    force = np.stack([-layout.induced_drag * lift * delta, lift * sin_phi, -lift * cos_phi], 1)
    arm = np.stack([layout.x, layout.radius * cos_phi, layout.radius * sin_phi], 1)
    return np.concatenate([force.sum(axis=0), np.cross(arm, force).sum(axis=0)])


def accelerations(
    hull: SixDofVehicle,
    propeller,
    layout: FinLayout,
    eta: np.ndarray,
    nu: np.ndarray,
    deflections: np.ndarray,
    n_rpm: float,
    current_speed: float = 0.0,
    current_direction: float = 0.0,
) -> np.ndarray:
    """ν̇ [m/s², rad/s²] of a 6-DOF hull driven by a propeller at n [rpm] and fins at deflections
    δ_i [rad] (each clipped to its limit), at pose η and velocity ν, in a current V_c [m/s]
    toward β_c [rad]: `remus6dof.hull_accelerations` under the actuators' τ. ``propeller`` holds
    the propeller fields of `ActuatorParams` (`auv_gym.vehicle.record.Vehicle.propeller`)."""
    nu = np.asarray(nu, float)
    psi = float(eta[5])
    nu_r = nu.copy()
    nu_r[0] -= current_speed * math.cos(current_direction - psi)
    nu_r[1] -= current_speed * math.sin(current_direction - psi)
    n_rpm = min(max(float(n_rpm), -propeller.rpm_max), propeller.rpm_max)
    speed = math.sqrt(nu[0] ** 2 + nu[1] ** 2 + nu[2] ** 2)
    thrust = propeller_thrust.py_func(n_rpm, speed, propeller)
    torque = propeller_torque.py_func(n_rpm, speed, propeller)
    tau = np.array(
        [
            (1.0 - propeller.thrust_deduction) * thrust,
            0,
            0,
            hull.propeller_torque_scale * torque,
            0,
            0,
        ]
    )
    clipped = np.clip(np.asarray(deflections, float), -layout.angle_max, layout.angle_max)
    tau += fin_wrench(layout, nu_r, clipped)
    return hull_accelerations(hull, eta, nu, tau, current_speed, current_direction)
