r"""Control allocation for the realistic actuators (docs/model.md §2.7): τ_d → (n, δ_s, δ_r).

The classical controllers compute a desired τ_d = (X, M, N) for the fin-limited plant; on the
realistic actuators (``actuator="realistic"``) `allocate` turns it into the normalised commands
of the propeller shaft speed and the fin angles, at the observed velocity (u, v, w):

    δ_s = M_d / (x_s k_s),    k_s = ½ρ A_s C_Ls (u² + w²)
    δ_r = −N_d / (x_r k_r),   k_r = ½ρ A_r C_Lr (u² + v²)

(the inverse of M = −x_s Z_s, N = x_r Y_r), clipped to ±δ_max; with no flow over a fin
(k = 0) it is deflected fully towards the demanded moment. The propeller then supplies the
surge force left after the fins' induced drag, X_prop = (X_d − X_r − X_s)/(1 − t), by the
inverse of the thrust curve at the current advance speed V_a:

    ahead (X_prop ≥ 0):  n = (−b + √(b² + 4K_T0 T)) / (2K_T0),  b = (K_Tmax − K_T0)/J_max · V_a/D
    astern (X_prop < 0): n = −√(−T / K_T0),                     T = X_prop / (ρD⁴)  [rps²]

(the larger root ahead: the branch on which thrust grows with n), clipped to ±n_max. Where
τ_d is reachable (|δ| ≤ δ_max, |n| ≤ n_max) the actuator model at the commanded state gives
back τ_d up to rounding (tests/test_actuators.py: relative 1e-9). The actuators' lag and rate
limits are not inverted: the controllers' robustness absorbs them.
"""

from __future__ import annotations

import numpy as np

from auv_gym.vehicle.actuators import ActuatorParams

__all__ = ["ALLOCATION_FIELDS", "allocate", "fin_angle", "fin_authority", "fin_gain"]

# The `ActuatorParams` fields `allocate` and `fin_gain` read: an allocation built for one set is
# the allocation of every set equal in these (the torque curve, the motor's and servos' lags and
# the servo rate limit are not inverted). tests/test_onnx_trust.py holds the list to the code.
ALLOCATION_FIELDS = (
    "water_density",
    "prop_diameter",
    "thrust_deduction",
    "advance_speed_ratio",
    "kt_0",
    "kt_max",
    "advance_max",
    "rpm_max",
    "fin_area_stern",
    "fin_area_rudder",
    "lift_coeff_stern",
    "lift_coeff_rudder",
    "x_stern",
    "x_rudder",
    "delta_max_stern",
    "delta_max_rudder",
    "fin_induced_drag",
)


def fin_gain(params: ActuatorParams) -> float:
    """K·δ_max [kg]: the fin moment at full deflection per u², the weaker of the two fin pairs
    (the authority the fin-limited controllers assume, `controllers.base.actuator_vector`)."""
    stern, rudder = params.fin_moment_coeff()
    return min(stern * params.delta_max_stern, rudder * params.delta_max_rudder)


def fin_authority(gain: float, u: np.ndarray) -> np.ndarray:
    """The fin-limited moment bound K·δ_max·max(u|u|, 0) [N·m] at surge speeds ``u`` [m/s] for
    the fin gain ``gain`` = K·δ_max [kg] (vectorised `controllers.fbsm.moment_limits`)."""
    u = np.asarray(u, dtype=np.float64)
    return gain * np.maximum(u * np.abs(u), 0.0)


def fin_angle(moment: np.ndarray, gain: np.ndarray, direction: float, limit: float) -> np.ndarray:
    """moment / gain clipped to ±limit; where gain = 0 (no flow), full deflection towards the
    moment with the sign ``direction`` the gain has under flow."""
    safe = np.where(gain != 0.0, gain, 1.0)
    angle = np.where(gain != 0.0, moment / safe, direction * np.sign(moment) * limit)
    return np.clip(angle, -limit, limit)


def allocate(tau: np.ndarray, nu: np.ndarray, params: ActuatorParams) -> np.ndarray:
    """Normalised commands (n/n_max, δ_s/δ_s,max, δ_r/δ_r,max), shape (n, 3), for the desired
    τ_d = (X [N], M [N·m], N [N·m]) rows ``tau`` at body velocities ``nu`` = (u, v, w) [m/s]."""
    tau = np.asarray(tau, dtype=np.float64).reshape(-1, 3)
    nu = np.asarray(nu, dtype=np.float64).reshape(-1, 3)
    u, v, w = nu[:, 0], nu[:, 1], nu[:, 2]
    p = params
    half_rho = 0.5 * p.water_density
    k_s = half_rho * (u * u + w * w) * p.fin_area_stern * p.lift_coeff_stern
    k_r = half_rho * (u * u + v * v) * p.fin_area_rudder * p.lift_coeff_rudder
    stern_gain = p.x_stern * k_s  # M = x_s k_s δ_s
    rudder_gain = -p.x_rudder * k_r  # N = −x_r k_r δ_r
    delta_s = fin_angle(tau[:, 1], stern_gain, np.sign(p.x_stern), p.delta_max_stern)
    delta_r = fin_angle(tau[:, 2], rudder_gain, -np.sign(p.x_rudder), p.delta_max_rudder)
    # the fins' induced drag −κ·k·δ² (docs/model.md §2.6); κ = 1 multiplies exactly
    kappa = p.fin_induced_drag
    fin_drag = -kappa * k_r * delta_r * delta_r - kappa * k_s * delta_s * delta_s
    thrust = (tau[:, 0] - fin_drag) / (1.0 - p.thrust_deduction)
    d = p.prop_diameter
    t_coeff = thrust / (p.water_density * d**4)  # [rps²]
    v_a = p.advance_speed_ratio * np.sqrt(u * u + v * v + w * w)
    b = (p.kt_max - p.kt_0) / p.advance_max * (v_a / d)
    ahead = (-b + np.sqrt(np.maximum(b * b + 4.0 * p.kt_0 * t_coeff, 0.0))) / (2.0 * p.kt_0)
    astern = -np.sqrt(np.maximum(-t_coeff, 0.0) / p.kt_0)
    rpm = 60.0 * np.where(t_coeff >= 0.0, ahead, astern)
    commands = np.stack(
        [rpm / p.rpm_max, delta_s / p.delta_max_stern, delta_r / p.delta_max_rudder], axis=1
    )
    return np.clip(commands, -1.0, 1.0)
