r"""The realistic actuators (``actuator="realistic"``, docs/model.md §2.6): propeller and fins.

The vehicle is commanded as the real one is: a propeller shaft speed n [rpm] and the stern-plane
and rudder angles δ_s, δ_r [rad], each normalised to [−1, 1] by its limit. The actuators have
states (n, δ_s, δ_r), advanced inside the physics steps by `actuator_step`: a first-order motor
and fin servos with angle limits, rate limits and a lag. `actuator_forces` turns them into
τ = (X, Y, Z, M, N) with the formulas of Fossen's PythonVehicleSimulator ``remus100.dynamics``
(propeller thrust from K_T linear in the advance number; fin lift and induced drag ∝ U²):

    X = (1 − t) X_prop(n, V_a) + X_r + X_s           X_r = −½ρ U_h² A_r C_Lr δ_r²
    Y = Y_r = −½ρ U_h² A_r C_Lr δ_r                  X_s = −½ρ U_v² A_s C_Ls δ_s²
    Z = Z_s = −½ρ U_v² A_s C_Ls δ_s                  M = −x_s Z_s,   N = x_r Y_r

with U_h² = u² + v², U_v² = u² + w² and V_a = (V_a/U)·√(u² + v² + w²). The propeller torque
acts in roll, which the 5-DOF model does not have: `propeller_torque` is there for the record
and the cross-check only. `ActuatorParams` holds the numbers (SI, validated); they follow the
packed simulation config's record fields (`ACTUATOR_CONFIG_FIELDS`), and the kernel reads them
by name through `actuator_config`, in the realistic mode only.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numba import njit

from auv_gym.support.records import field_indices, fixed_tuple, record_type
from auv_gym.support.validation import ArgumentTypeError, keys_within, real

__all__ = [
    "ACTUATOR_COMMANDS",
    "ACTUATOR_CONFIG_FIELDS",
    "ACTUATOR_STATE",
    "ACTUATOR_STATE_DIM",
    "ActuatorParams",
    "actuator_forces",
    "actuator_params_from_spec",
    "actuator_step",
    "check_commands",
    "fin_forces",
    "propeller_thrust",
    "propeller_torque",
    "shaft_powers",
]

# The paper's vehicle (Prestero 2001): fin moment per u² per radian |M_uuδs| = |N_uuδr| [kg/rad]
# (`AUVParams.fin_moment_coeff`, the "fins" mode) at the fin position x_fin [m]; their ratio is
# the lift per u² per radian, 9.64 kg/(m·rad) = Prestero's Y_uuδr.
_PRESTERO_FIN_MOMENT = 6.15
_PRESTERO_X_FIN = -0.638
_RHO = 1026.0  # [kg/m³] sea water, as the reference
_FIN_PAIR_AREA = 2 * 0.00665  # [m²] two fins of 0.00665 m² (reference and Prestero)
# [1/rad] the lift coefficient that gives the pair of fins at x_fin that moment
_LIFT_COEFF = _PRESTERO_FIN_MOMENT / (-_PRESTERO_X_FIN * 0.5 * _RHO * _FIN_PAIR_AREA)


@dataclass(frozen=True)
class ActuatorParams:
    """Propeller, motor, fins and servos of the realistic mode (docs/model.md §2.6); SI units.

    The propeller and motor are those of Fossen's PythonVehicleSimulator ``remus100``; the fins
    keep its area but take their lift coefficient, position and deflection limit from the
    paper's vehicle, so that the fin moment equals the "fins" mode's (`ActuatorParams.pvs_remus100`
    is the reference's own set). ``fin_rate_max = inf`` removes the rate limit and zero time
    constants make the motor and servos instantaneous.
    """

    water_density: float = _RHO  # [kg/m³] ρ
    prop_diameter: float = 0.14  # [m] D, 5.5 in
    thrust_deduction: float = 0.1  # [-] t: the hull feels (1 − t) of the propeller thrust
    advance_speed_ratio: float = 0.944  # [-] V_a/U = 1 − w (wake fraction w = 0.056)
    kt_0: float = 0.4566  # [-] K_T at J = 0 (Wageningen B3-71.8, via the reference)
    kq_0: float = 0.0700  # [-] K_Q at J = 0
    kt_max: float = 0.1798  # [-] K_T at J = advance_max
    kq_max: float = 0.0312  # [-] K_Q at J = advance_max
    advance_max: float = 0.6632  # [-] J = V_a/(nD) at 2.5 m/s and 1525 rpm
    rpm_max: float = 1525.0  # [rpm] shaft-speed limit (2.5 m/s top speed)
    motor_time_constant: float = 1.0  # [s] T_n of ṅ = (n_c − n)/T_n
    fin_area_stern: float = _FIN_PAIR_AREA  # [m²] A_s, both stern planes
    fin_area_rudder: float = _FIN_PAIR_AREA  # [m²] A_r, both rudders
    lift_coeff_stern: float = _LIFT_COEFF  # [1/rad] C_Ls = 1.4128
    lift_coeff_rudder: float = _LIFT_COEFF  # [1/rad] C_Lr
    x_stern: float = _PRESTERO_X_FIN  # [m] stern-plane position, aft of the origin
    x_rudder: float = _PRESTERO_X_FIN  # [m] rudder position
    delta_max_stern: float = math.pi / 6.0  # [rad] |δ_s| limit, `AUVParams.fin_max`
    delta_max_rudder: float = math.pi / 6.0  # [rad] |δ_r| limit
    fin_rate_max: float = math.radians(60.0)  # [rad/s] |δ̇| limit (assumed; inf: none)
    fin_time_constant: float = 0.1  # [s] T_δ of δ̇ = (δ_c − δ)/T_δ
    # [-] κ of the fins' drag −κ ½ρU²AC_Lδ²: 1 in the reference's remus100, 0 in its torpedo
    fin_induced_drag: float = 1.0

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            name = f"ActuatorParams.{f.name}"
            if f.name == "fin_rate_max" and value == math.inf:
                continue  # no rate limit
            if f.name.endswith("time_constant"):
                object.__setattr__(self, f.name, real(name, value, 0.0, unit="s"))
            elif f.name in ("x_stern", "x_rudder", "kt_max", "kq_max"):
                object.__setattr__(self, f.name, real(name, value))
            elif f.name == "fin_induced_drag":
                object.__setattr__(self, f.name, real(name, value, 0.0, 10.0))
            elif f.name == "thrust_deduction":
                object.__setattr__(self, f.name, real(name, value, 0.0, 1.0, high_open=True))
            elif f.name.startswith("delta_max"):
                object.__setattr__(
                    self, f.name, real(name, value, 0.0, math.pi / 2, low_open=True, unit="rad")
                )
            else:
                object.__setattr__(self, f.name, real(name, value, 0.0, low_open=True))
        # K_T and K_Q fall linearly in the advance ratio J from kt_0, kq_0 at J = 0 to kt_max,
        # kq_max at advance_max, the top speed's J, where the propeller still drives the hull.
        for coefficient in ("kt", "kq"):
            at_rest, at_top = getattr(self, f"{coefficient}_0"), getattr(self, f"{coefficient}_max")
            if not 0.0 < at_top <= at_rest:
                raise ValueError(
                    f"ActuatorParams.{coefficient}_max = {at_top:g} must be in (0, "
                    f"{coefficient}_0 = {at_rest:g}]: the propeller's coefficient at the top "
                    "speed's advance ratio is positive and at most its value at rest"
                )

    @classmethod
    def pvs_remus100(cls) -> ActuatorParams:
        """The reference's own fins: C_Ls = 0.7, C_Lr = 0.5, x = −0.8 m (half its 1.6-m hull),
        ±15°; servo rate unlimited. The cross-check runs on this set."""
        return cls(
            lift_coeff_stern=0.7,
            lift_coeff_rudder=0.5,
            x_stern=-0.8,
            x_rudder=-0.8,
            delta_max_stern=math.radians(15.0),
            delta_max_rudder=math.radians(15.0),
            fin_rate_max=math.inf,
        )

    def replace(self, **changes: float) -> ActuatorParams:
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def fin_moment_coeff(self) -> tuple[float, float]:
        """(|x_s|·½ρA_sC_Ls, |x_r|·½ρA_rC_Lr) [kg/rad]: fin moment per U² per radian."""
        half_rho = 0.5 * self.water_density
        stern = abs(self.x_stern) * half_rho * self.fin_area_stern * self.lift_coeff_stern
        rudder = abs(self.x_rudder) * half_rho * self.fin_area_rudder * self.lift_coeff_rudder
        return stern, rudder

    def packed(self, physics_dt: float) -> dict[str, float]:
        """The values of `ACTUATOR_CONFIG_FIELDS` for a physics step ``physics_dt`` [s]: the
        fields, then the exact per-step lag factors 1 − exp(−Δt/T) (1 for T = 0) and the
        largest fin move per step, fin_rate_max·Δt."""
        values = {f.name: float(getattr(self, f.name)) for f in fields(self)}
        values["motor_alpha"] = _lag_factor(physics_dt, self.motor_time_constant)
        values["fin_alpha"] = _lag_factor(physics_dt, self.fin_time_constant)
        values["fin_rate_step"] = self.fin_rate_max * physics_dt
        return values


def _lag_factor(dt: float, time_constant: float) -> float:
    return 1.0 if time_constant == 0.0 else -math.expm1(-dt / time_constant)


ACTUATOR_CONFIG_FIELDS: tuple[str, ...] = (
    *(f.name for f in fields(ActuatorParams)),
    "motor_alpha",
    "fin_alpha",
    "fin_rate_step",
)
# The record `actuator_forces` reads outside the simulator (tests, allocation): the same names.
ActuatorRecord = record_type("ActuatorRecord", ACTUATOR_CONFIG_FIELDS, __name__)

# Per-vehicle actuator state: shaft speed [rpm], stern-plane and rudder angles [rad], and the
# fraction of the last control period's physics steps in which a fin was rate-limited [-].
ACTUATOR_COMMANDS = ("rpm", "delta_s", "delta_r")  # the action of the realistic mode
ACTUATOR_STATE_NAMES = ("n_rpm", "delta_s", "delta_r", "rate_limited")
ACTUATOR_STATE_DIM = len(ACTUATOR_STATE_NAMES)
ACTUATOR_STATE = field_indices("ActuatorStateIndex", ACTUATOR_STATE_NAMES, __name__)


def actuator_record(params: ActuatorParams, physics_dt: float = 0.01) -> Any:
    """``params`` as the named record the kernels read (`ACTUATOR_CONFIG_FIELDS`)."""
    return ActuatorRecord(**params.packed(physics_dt))


# A placeholder of the record's type for the kernels' other modes, which never read it.
DEFAULT_ACTUATOR_CONFIG = actuator_record(ActuatorParams())
_ACTUATOR_CONFIG_DIM = len(ACTUATOR_CONFIG_FIELDS)


@njit(cache=True, inline="always")
def actuator_config(row, offset):
    """Entries offset … of the packed config row as an `ActuatorRecord` in registers."""
    return ActuatorRecord(*fixed_tuple(row[offset:], _ACTUATOR_CONFIG_DIM))


def actuator_params_from_spec(spec: ActuatorParams | Mapping[str, Any] | None) -> ActuatorParams:
    """The env's ``actuator_params`` argument: None (the defaults), an `ActuatorParams`, or a
    dict of its fields [SI]; an unknown name raises ValueError naming it."""
    if spec is None:
        return ActuatorParams()
    if isinstance(spec, ActuatorParams):
        return spec
    if not isinstance(spec, Mapping):
        raise ArgumentTypeError(
            f"actuator_params must be None, an ActuatorParams or a dict of "
            f"its fields, got {spec!r:.80}"
        )
    values = keys_within("actuator_params", spec, [f.name for f in fields(ActuatorParams)])
    return ActuatorParams(**values)


def check_commands(commands: np.ndarray) -> None:
    """ValueError naming the first row of normalised commands (n, δ_s, δ_r) outside [−1, 1]³:
    the realistic actuators take commands in their range, they do not saturate them silently.
    Non-finite rows pass (the simulator's own check names them)."""
    outside = np.abs(commands) > 1.0
    if outside.any():
        i, j = np.argwhere(outside)[0]
        raise ValueError(
            f"actuator='realistic' takes commands (rpm, delta_s, delta_r) normalised "
            f"to [-1, 1]; got {ACTUATOR_COMMANDS[j]} = {float(commands[i, j])!r} "
            f"(row {i})"
        )


@njit(cache=True, inline="always")
def propeller_thrust(n_rpm, speed, a):
    """Propeller thrust X_prop [N] at shaft speed n [rpm] and vehicle speed U [m/s] (reference
    ``remus100.dynamics``): K_T linear in the advance number J = V_a/(nD) ahead, K_T0 astern."""
    n_rps = n_rpm / 60.0
    d = a.prop_diameter
    v_a = a.advance_speed_ratio * speed
    if n_rps > 0.0:  # ahead: ρD⁴(K_T0 n|n| + (K_Tmax − K_T0)/J_max · (V_a/D)|n|)
        return (
            a.water_density
            * d**4
            * (
                a.kt_0 * abs(n_rps) * n_rps
                + (a.kt_max - a.kt_0) / a.advance_max * (v_a / d) * abs(n_rps)
            )
        )
    return a.water_density * d**4 * a.kt_0 * abs(n_rps) * n_rps  # astern (braking)


@njit(cache=True, inline="always")
def propeller_torque(n_rpm, speed, a):
    """Propeller shaft torque K_prop [N·m], the roll moment the 5-DOF model drops (K_Q as K_T)."""
    n_rps = n_rpm / 60.0
    d = a.prop_diameter
    v_a = a.advance_speed_ratio * speed
    if n_rps > 0.0:
        return (
            a.water_density
            * d**5
            * (
                a.kq_0 * abs(n_rps) * n_rps
                + (a.kq_max - a.kq_0) / a.advance_max * (v_a / d) * abs(n_rps)
            )
        )
    return a.water_density * d**5 * a.kq_0 * abs(n_rps) * n_rps


@njit(cache=True)
def shaft_powers(n_rpm, u, v, w, a):
    """Shaft power P = 2π·n·Q(n, U) [W] the motor delivers to each vehicle's propeller, for shaft
    speeds n [rpm] and body velocities u, v, w [m/s] (arrays of one length; U = √(u² + v² +
    w²), as in the thrust): positive ahead and astern (docs/model.md §2.6)."""
    out = np.empty(n_rpm.shape[0])
    for i in range(n_rpm.shape[0]):
        speed = math.sqrt(u[i] * u[i] + v[i] * v[i] + w[i] * w[i])
        out[i] = 2.0 * math.pi * (n_rpm[i] / 60.0) * propeller_torque(n_rpm[i], speed, a)
    return out


@njit(cache=True, inline="always")
def fin_forces(delta_s, delta_r, u, v, w, a):
    """Fin induced drag X_r + X_s [N], rudder side force Y_r [N], stern-plane heave force Z_s [N]
    and their moments M = −x_s Z_s, N = x_r Y_r [N·m], for angles δ_s, δ_r [rad] and the
    velocity through the water (u, v, w) [m/s] (reference ``remus100.dynamics``)."""
    half_rho = 0.5 * a.water_density
    k_r = half_rho * (u * u + v * v) * a.fin_area_rudder * a.lift_coeff_rudder  # ½ρU_h²A_rC_Lr
    k_s = half_rho * (u * u + w * w) * a.fin_area_stern * a.lift_coeff_stern  # ½ρU_v²A_sC_Ls
    y_r = -k_r * delta_r
    z_s = -k_s * delta_s
    drag = a.fin_induced_drag * (-k_r * delta_r * delta_r - k_s * delta_s * delta_s)  # X_r + X_s
    return drag, y_r, z_s, -a.x_stern * z_s, a.x_rudder * y_r


@njit(cache=True, inline="always")
def actuator_forces(n_rpm, delta_s, delta_r, u, v, w, a):
    """τ = (X, Y, Z, M, N) [N, N, N, N·m, N·m] of the actuator state (docs/model.md §2.6)."""
    drag, y_r, z_s, m_s, n_r = fin_forces(delta_s, delta_r, u, v, w, a)
    speed = math.sqrt(u * u + v * v + w * w)
    x = (1.0 - a.thrust_deduction) * propeller_thrust(n_rpm, speed, a) + drag
    return x, y_r, z_s, m_s, n_r


@njit(cache=True, inline="always")
def _servo(delta, command, alpha, rate_step, limit):
    """One physics step of a fin: exact first-order lag to the held command, its move capped
    at rate_step, the angle clipped to ±limit; and whether the rate cap acted."""
    target = command if alpha == 1.0 else delta + alpha * (command - delta)
    limited = False
    if target - delta > rate_step:
        target, limited = delta + rate_step, True
    elif delta - target > rate_step:
        target, limited = delta - rate_step, True
    return min(max(target, -limit), limit), limited


@njit(cache=True, inline="always")
def actuator_step(n_rpm, delta_s, delta_r, a_n, a_s, a_r, a):
    """Advance (n [rpm], δ_s, δ_r [rad]) one physics step towards the normalised commands
    (a_n, a_s, a_r) ∈ [−1, 1]³; returns the new state and whether a fin was rate-limited."""
    n_c = a_n * a.rpm_max
    n_new = n_c if a.motor_alpha == 1.0 else n_rpm + a.motor_alpha * (n_c - n_rpm)
    n_new = min(max(n_new, -a.rpm_max), a.rpm_max)
    s_new, s_lim = _servo(
        delta_s, a_s * a.delta_max_stern, a.fin_alpha, a.fin_rate_step, a.delta_max_stern
    )
    r_new, r_lim = _servo(
        delta_r, a_r * a.delta_max_rudder, a.fin_alpha, a.fin_rate_step, a.delta_max_rudder
    )
    return n_new, s_new, r_new, s_lim or r_lim
