r"""The 6-DOF REMUS 100 of Fossen's *Handbook of Marine Craft Hydrodynamics and Motion Control*
(2nd ed., Wiley 2021), as his PythonVehicleSimulator's ``remus100`` writes it: the reference
form of the second plant (docs/model.md §15), in numpy, one state at a time.

With ν = (u, v, w, p, q, r) [m/s, rad/s], ν_r = ν − ν_c the velocity through the water (a
current of speed V_c toward β_c in the horizontal plane, ν_c = V_c(cos(β_c − ψ), sin(β_c − ψ),
0, 0, 0, 0)), η = (x, y, z, φ, θ, ψ):

    M ν̇ = τ_act + τ_liftdrag + τ_crossflow − (C_RB(ν_r) + C_A(ν_r) + D) ν_r − g(η) + M ν̇_c

- M = M_RB + M_A: a prolate spheroid of length L and diameter d, neutrally buoyant; M_RB the
  rigid body at the centre of gravity r_bg = (0, 0, 0.02) m moved to the origin,
  M_RB = H(r_bg)ᵀ diag(m, m, m, I_x, I_y, I_z) H(r_bg); M_A Lamb's k-factors of the spheroid
  (roll added inertia 0.3·I_x). C_RB and C_A from M (Fossen 2021 eq. 3.63, ``m2c``), C_A without
  the Munk moments in pitch and yaw (entries (5,1), (5,3), (6,1), (6,2) and their transposes
  zeroed, which keeps it skew-symmetric).
- D: linear damping from time constants (surge, sway, heave 20 s, yaw 1 s) and damping ratios
  in roll (0.3) and pitch (0.8) of the restoring frequencies; surge and sway fade with speed,
  e^{−3U_r}, where the quadratic terms take over.
- τ_liftdrag: the hull as a low-aspect wing at the angle of attack α = atan2(w_r, u_r) (Beard and
  McLain 2012; C_D0 from the cylinder's 0.42 of Allen et al. 2000).
- τ_crossflow: cross-flow drag by strip theory, 21 strips with Hoerner's 2-D coefficient.
- g(η): restoring forces and moments of weight W = buoyancy B at r_bg and r_bb = 0.
- τ_act: propeller thrust and the fins (`auv_gym.vehicle.actuators`, the same formulas) and the
  propeller torque in roll, K_prop/10 (the reference scales it down to match experiments).

`accelerations` is cross-checked against numbers recorded from the reference on a grid of
states and commands (tests/test_remus6dof.py, ≤ 1e-9 relative); unforced and undamped, the
kinetic energy ½ νᵀMν is conserved (C skew-symmetric).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from auv_gym.support.validation import ArgumentTypeError, integer, keys_within, real, vector
from auv_gym.vehicle.actuators import ActuatorParams, propeller_thrust, propeller_torque
from auv_gym.vehicle.six_dof import SIX_DOF_FIELDS

__all__ = [
    "COEFFICIENTS",
    "REMUS6DOF",
    "UNCERTAIN_COEFFICIENTS",
    "SixDofVehicle",
    "accelerations",
    "actuation",
    "coriolis",
    "coriolis_matrix",
    "hull_accelerations",
    "restoring_forces",
    "rigid_body_matrix",
]

# Hoerner's 2-D cross-flow drag coefficient against B/(2T) (Fossen's ``Hoerner``).
_HOERNER_X = np.array(
    [
        *(0.0109, 0.1766, 0.3530, 0.4519, 0.4728, 0.4929, 0.4933, 0.5585, 0.6464, 0.8336),
        *(0.9880, 1.3081, 1.6392, 1.8600, 2.3129, 2.6000, 3.0088, 3.4508, 3.7379, 4.0031),
    ]
)
_HOERNER_Y = np.array(
    [
        *(1.9661, 1.9657, 1.8976, 1.7872, 1.5837, 1.2786, 1.2108, 1.0836, 0.9986, 0.8796),
        *(0.8284, 0.7599, 0.6914, 0.6571, 0.6307, 0.5962, 0.5868, 0.5859, 0.5599, 0.5593),
    ]
)


_OSWALD = 0.7  # [-] Oswald efficiency e of the hull's induced drag
# Documented ranges of the geometry (docs/model.md §15.1): a prolate spheroid from 1 cm to 1 km
# no more slender than 1000:1 (at d/L = 1e-10 its eccentricity rounds to 1 and Lamb's k-factors
# divide by zero), in water and gravity of finite, physical size.
LENGTH_RANGE = (0.01, 1000.0)  # [m]
MAX_SLENDERNESS = 1000.0  # [-] length / diameter
WATER_DENSITY_RANGE = (1.0, 1e4)  # [kg/m³]
MAX_GRAVITY = 100.0  # [m/s²]
# RK4 is stable for λ·dt inside its stability region, which crosses the negative real axis at
# −2.785 and the imaginary axis at ±2√2. A hull is accepted at a physics step dt when every mode
# of its linearisation at rest (damping, restoring and mass, `SixDofVehicle.stiffest_rate`)
# has |λ|·dt <= RK4_STEP_LIMIT: the half-disc of that radius lies inside the region, with room
# for the speed-dependent terms it leaves out. Measured (docs/model.md §15.1): beyond it the
# first step blows up ("non_finite"), within it every episode stays finite.
RK4_STEP_LIMIT = 2.5
# The damping coefficient of each axis (u, v, w, p, q, r) of the linearisation's modes.
_AXIS_COEFFICIENTS = (
    "surge_time_constant",
    "sway_time_constant",
    "heave_time_constant",
    "roll_damping_ratio",
    "pitch_damping_ratio",
    "yaw_time_constant",
)
_AXIS_NAMES = ("surge", "sway", "heave", "roll", "pitch", "yaw")


def _skew(a: np.ndarray) -> np.ndarray:
    """S(a): a × b = S(a) b."""
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def _transform(r: np.ndarray) -> np.ndarray:
    """H(r) = [[I, S(r)ᵀ], [0, I]]: moves a model from the point r to the origin."""
    h = np.identity(6)
    h[0:3, 3:6] = _skew(r).T
    return h


def rigid_body_matrix(
    mass_kg: float, roll_inertia: float, pitch_inertia: float, r_bg: Sequence[float]
) -> np.ndarray:
    """M_RB (6×6) at the origin of a body of revolution of mass ``mass_kg`` [kg] and principal
    inertias ``roll_inertia`` (I_x), ``pitch_inertia`` (I_y = I_z) [kg m²] about its centre of
    gravity ``r_bg`` [m]: H(r_bg)ᵀ diag(m, m, m, I_x, I_y, I_y) H(r_bg), as Fossen's code moves
    it."""
    h = _transform(np.asarray(r_bg, float))
    m = mass_kg
    return h.T @ np.diag([m, m, m, roll_inertia, pitch_inertia, pitch_inertia]) @ h


@dataclass(frozen=True)
class SixDofVehicle:
    """The hull of the 6-DOF REMUS 100 (module doc); SI units. Derived matrices are computed
    once (`mass`, `added_mass`, `inverse_mass`, `damping_base`)."""

    length: float = 1.6  # [m] L
    diameter: float = 0.19  # [m] d
    water_density: float = 1026.0  # [kg/m³] ρ
    gravity: float = 9.81  # [m/s²]
    r_bg: tuple[float, float, float] = (0.0, 0.0, 0.02)  # [m] centre of gravity from the origin
    r_bb: tuple[float, float, float] = (0.0, 0.0, 0.0)  # [m] centre of buoyancy
    hull_drag_coeff: float = 0.42  # [-] C_d of the cylinder (Allen et al. 2000)
    roll_added_inertia: float = 0.3  # [-] M_A,44 / I_x
    surge_time_constant: float = 20.0  # [s]
    sway_time_constant: float = 20.0  # [s]
    heave_time_constant: float = 20.0  # [s]
    yaw_time_constant: float = 1.0  # [s]
    roll_damping_ratio: float = 0.3  # [-]
    pitch_damping_ratio: float = 0.8  # [-]
    propeller_torque_scale: float = 0.1  # [-] K_prop/10 in roll (the reference's scaling)
    strips: int = 20  # cross-flow strips (21 stations)
    actuators: ActuatorParams = field(default_factory=ActuatorParams.pvs_remus100)

    def __post_init__(self) -> None:
        self._validate()
        a, b = self.length / 2.0, self.diameter / 2.0
        rho = self.water_density
        m = 4.0 / 3.0 * math.pi * rho * a * b * b  # [kg] the spheroid's displaced mass
        ix = 2.0 / 5.0 * m * b * b
        iy = 1.0 / 5.0 * m * (a * a + b * b)
        rigid = rigid_body_matrix(m, ix, iy, self.r_bg)
        e = math.sqrt(1.0 - (b / a) ** 2)
        log = math.log((1.0 + e) / (1.0 - e))
        alpha_0 = 2.0 * (1.0 - e * e) / e**3 * (0.5 * log - e)
        beta_0 = 1.0 / e**2 - (1.0 - e * e) / (2.0 * e**3) * log
        k1, k2 = alpha_0 / (2.0 - alpha_0), beta_0 / (2.0 - beta_0)
        k_prime = (
            e**4
            * (beta_0 - alpha_0)
            / ((2.0 - e * e) * (2.0 * e * e - (2.0 - e * e) * (beta_0 - alpha_0)))
        )
        added = np.diag(
            [m * k1, m * k2, m * k2, self.roll_added_inertia * ix, k_prime * iy, k_prime * iy]
        )
        mass = rigid + added
        weight = m * self.gravity
        arm = self.r_bg[2] - self.r_bb[2]
        w_roll = math.sqrt(weight * arm / mass[3, 3])
        w_pitch = math.sqrt(weight * arm / mass[4, 4])
        damping = np.diag(
            [
                mass[0, 0] / self.surge_time_constant,
                mass[1, 1] / self.sway_time_constant,
                mass[2, 2] / self.heave_time_constant,
                mass[3, 3] * 2.0 * self.roll_damping_ratio * w_roll,
                mass[4, 4] * 2.0 * self.pitch_damping_ratio * w_pitch,
                mass[5, 5] / self.yaw_time_constant,
            ]
        )
        area = 0.7 * self.length * self.diameter  # [m²] S: 70 % of the rectangle
        derived = {
            "mass_kg": m,
            "roll_inertia": ix,  # [kg m²] I_x about the centre of gravity
            "pitch_inertia": iy,  # [kg m²] I_y = I_z
            "weight": weight,
            "rigid_body": rigid,
            "added_mass": added,
            "mass": mass,
            "inverse_mass": np.linalg.inv(mass),
            "damping_base": damping,
            "wing_area": area,
            "zero_lift_drag": self.hull_drag_coeff * math.pi * b * b / area,
            "crossflow_coeff": float(np.interp(0.5, _HOERNER_X, _HOERNER_Y)),  # B/(2T), B = T
        }
        for name, value in derived.items():
            object.__setattr__(self, name, value)

    def _validate(self) -> None:
        """Each coefficient in its physical range, else a one-line error naming it."""
        put = object.__setattr__
        for name in COEFFICIENTS:
            value = getattr(self, name)
            where = f"SixDofVehicle.{name}"
            if name in ("r_bg", "r_bb"):
                put(self, name, vector(where, value, 3, -10.0, 10.0, "m"))
            elif name == "strips":
                put(self, name, integer(where, value, 1, 1000))
            elif name.endswith("damping_ratio") or name in (
                "hull_drag_coeff",
                "propeller_torque_scale",
                "roll_added_inertia",
            ):
                put(self, name, real(where, value, 0.0, 100.0))
            elif name == "length":
                put(self, name, real(where, value, *LENGTH_RANGE, unit="m"))
            elif name == "water_density":
                put(self, name, real(where, value, *WATER_DENSITY_RANGE, unit="kg/m³"))
            elif name == "gravity":
                put(self, name, real(where, value, 0.0, MAX_GRAVITY, low_open=True, unit="m/s²"))
            else:
                put(self, name, real(where, value, 0.0, math.inf, low_open=True))
        if not self.diameter < self.length:
            raise ValueError(
                f"SixDofVehicle.diameter = {self.diameter} m must be below its length "
                f"{self.length} m (a prolate spheroid)"
            )
        if self.diameter * MAX_SLENDERNESS < self.length:
            raise ValueError(
                f"SixDofVehicle.diameter = {self.diameter:.4g} m must be at least length/"
                f"{MAX_SLENDERNESS:g} = {self.length / MAX_SLENDERNESS:.4g} m (a spheroid more "
                f"slender than {MAX_SLENDERNESS:g}:1 has no finite added mass in float64)"
            )
        if not self.r_bg[2] > self.r_bb[2]:
            raise ValueError(
                f"SixDofVehicle.r_bg = {self.r_bg} m must lie below r_bb = {self.r_bb} m "
                "(z_g > z_b): the roll and pitch damping are set from the restoring frequencies"
            )
        if not isinstance(self.actuators, ActuatorParams):
            raise ArgumentTypeError(
                f"SixDofVehicle.actuators must be an ActuatorParams, got {self.actuators!r:.80}"
            )

    def _rest_modes(self, damping: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Eigenvalues and eigenvectors of the hull linearised at rest, state (φ, θ, ν), with
        the linear damping diagonal ``damping`` (6,): ν̇ = −M⁻¹(D ν + G (φ, θ)), φ̇ = p, θ̇ = q;
        G the restoring moments' slopes (W = B). Coriolis, lift and cross-flow terms are
        quadratic in ν and vanish there."""
        w = self.weight
        (xg, yg, zg), (xb, yb, zb) = self.r_bg, self.r_bb
        slopes = np.zeros((6, 2))
        slopes[3, 0] = slopes[4, 1] = w * (zg - zb)
        slopes[5, 0], slopes[5, 1] = -w * (xg - xb), -w * (yg - yb)
        a = np.zeros((8, 8))
        a[0, 5] = a[1, 6] = 1.0
        a[2:, 2:] = -self.inverse_mass * damping  # M⁻¹ diag(d): column j times d_j
        a[2:, :2] = -self.inverse_mass @ slopes
        return np.linalg.eig(a)

    def stiffest_rate(self) -> tuple[float, str]:
        """(|λ| [1/s] of the fastest mode of the hull at rest (`_rest_modes`), the axis whose
        motion dominates it: "surge" … "yaw"). RK4 at a physics step dt steps it when
        |λ|·dt <= `RK4_STEP_LIMIT`."""
        values, vectors = self._rest_modes(np.diag(self.damping_base))
        k = int(np.argmax(np.abs(values)))
        motion = np.abs(vectors[2:, k])  # ν part: φ, θ move with p, q
        motion[3] += abs(vectors[0, k])
        motion[4] += abs(vectors[1, k])
        return float(abs(values[k])), _AXIS_NAMES[int(np.argmax(motion))]

    def _rate_with(self, name: str, value: float) -> float:
        """The fastest rate at rest with one damping coefficient ``name`` set to ``value``."""
        return dataclasses.replace(self, **{name: value}).stiffest_rate()[0]

    def check_step(self, physics_dt: float, uncertainty: float = 0.0) -> None:
        """ValueError (one line, naming the coefficient and its bound) unless RK4 at
        ``physics_dt`` [s] can step every mode of this hull (`RK4_STEP_LIMIT`), also when
        parameter uncertainty ε = ``uncertainty`` scales the damping time constants by 1 − ε
        and the damping ratios and the roll added inertia by 1 ± ε (their stiff ends)."""
        most = RK4_STEP_LIMIT / physics_dt  # [1/s] the fastest rate RK4 can step
        scale = {n: 1.0 - uncertainty for n in _AXIS_COEFFICIENTS if n.endswith("constant")}
        scale.update({n: 1.0 + uncertainty for n in _AXIS_COEFFICIENTS if n.endswith("ratio")})
        hull = self
        if uncertainty > 0.0:
            changes = {n: getattr(self, n) * f for n, f in scale.items()}
            changes["roll_added_inertia"] = self.roll_added_inertia * (1.0 - uncertainty)
            hull = dataclasses.replace(self, **changes)
        rate, axis = hull.stiffest_rate()
        if rate <= most:
            return
        shortest = RK4_STEP_LIMIT / rate  # [s] the physics step that would step it
        where = (
            f" (at its stiff end under param_uncertainty {uncertainty:g})" if uncertainty else ""
        )
        # The coefficient to blame: the one whose softest value (no damping) helps most.
        soft = {n: 0.0 if n.endswith("ratio") else 1e300 for n in _AXIS_COEFFICIENTS}
        relaxed = {n: hull._rate_with(n, soft[n]) for n in _AXIS_COEFFICIENTS}
        name = min(relaxed, key=relaxed.__getitem__)
        if relaxed[name] > most:  # no single coefficient can help
            undamped = dataclasses.replace(hull, **soft).stiffest_rate()[0]
            if undamped > most:
                cause = (
                    f"the {axis} mode of this hull (length, diameter, r_bg, r_bb, "
                    f"roll_added_inertia) moves at {undamped:.4g} rad/s undamped"
                )
            else:
                stiff = [n for n in _AXIS_COEFFICIENTS if relaxed[n] < rate]
                cause = (
                    f"its damping ({', '.join(stiff)}) moves its {axis} mode at {rate:.4g} rad/s"
                )
            raise ValueError(
                f"plant_params: {cause}{where}, faster than the {most:.4g} rad/s that RK4 at "
                f"physics_dt = {physics_dt:g} s can step (|λ|·dt <= {RK4_STEP_LIMIT:g}): use "
                f"physics_dt <= {shortest:.3g} s or another hull"
            )
        axis = _AXIS_NAMES[_AXIS_COEFFICIENTS.index(name)]
        if name.endswith("ratio"):
            low, high = 0.0, getattr(hull, name)
        else:  # a time constant: the rate falls as it grows
            low = high = getattr(hull, name)
            while hull._rate_with(name, high) > most:
                high *= 2.0
        for _ in range(60):
            middle = 0.5 * (low + high)
            fast = hull._rate_with(name, middle) > most
            if name.endswith("ratio"):
                low, high = (low, middle) if fast else (middle, high)
            else:
                low, high = (middle, high) if fast else (low, middle)
        if name.endswith("ratio"):
            bound = _round(low / scale[name], down=True)
            side = "at most"
        else:
            bound = _round(high / scale[name], down=False)
            side = "at least"
        raise ValueError(
            f"plant_params {name} = {getattr(self, name):g} must be {side} {bound:.3g}"
            f"{' s' if name.endswith('constant') else ''}: its {axis} mode moves at "
            f"{rate:.4g} rad/s{where}, faster than the {most:.4g} rad/s that RK4 at physics_dt "
            f"= {physics_dt:g} s can step (|λ|·dt <= {RK4_STEP_LIMIT:g}); or use physics_dt <= "
            f"{shortest:.3g} s"
        )

    @classmethod
    def from_record(cls, record: Mapping[str, Any]) -> SixDofVehicle:
        """A vehicle from a complete record of `COEFFICIENTS` (a user's vehicle, e.g. read from
        TOML; `record` gives the REMUS 100's to start from); a missing or unknown key is a
        one-line error naming it and the coefficients that exist."""
        if isinstance(record, SixDofVehicle):
            return record
        if not isinstance(record, Mapping):
            raise ArgumentTypeError(
                f"plant_params must be a SixDofVehicle or a mapping of {list(COEFFICIENTS)}, "
                f"got {record!r:.80}"
            )
        given = keys_within("plant_params", record, COEFFICIENTS)
        missing = [name for name in COEFFICIENTS if name not in given]
        if missing:
            raise ValueError(
                f"plant_params is missing the coefficient(s) {missing}; a 6-DOF vehicle record "
                f"gives all of {list(COEFFICIENTS)} (SixDofVehicle().record() is the REMUS 100's)"
            )
        return cls(**given)

    def record(self) -> dict[str, Any]:
        """The coefficients as a plain dict (`from_record` reads it back)."""
        return {name: getattr(self, name) for name in COEFFICIENTS}

    def perturbed(self, rng: np.random.Generator, fraction: float) -> SixDofVehicle:
        """A copy whose hydrodynamic coefficients (`UNCERTAIN_COEFFICIENTS`: hull drag, roll
        added inertia, the damping time constants and ratios) are each scaled by
        1 + U[−fraction, fraction], drawn from rng in that order; the geometry and mass stay."""
        scales = 1.0 + rng.uniform(-fraction, fraction, len(UNCERTAIN_COEFFICIENTS))
        changes = {
            name: getattr(self, name) * float(scale)
            for name, scale in zip(UNCERTAIN_COEFFICIENTS, scales, strict=True)
        }
        return dataclasses.replace(self, **changes)

    def kernel_vector(self) -> np.ndarray:
        """The float64 row the compiled plant reads (`six_dof.SIX_DOF_FIELDS`)."""
        span, area = self.diameter, self.wing_area
        aspect = span * span / area
        values = {
            "speed_decay": 3.0,
            "weight": self.weight,
            "buoyancy": self.weight,  # neutrally buoyant, as the reference
            "water_density": self.water_density,
            "length": self.length,
            "diameter": self.diameter,
            "wing_area": area,
            "lift_slope": math.pi * aspect / (1.0 + math.sqrt(1.0 + (aspect / 2.0) ** 2)),
            "zero_lift_drag": self.zero_lift_drag,
            "induced_drag": 1.0 / (math.pi * _OSWALD * aspect),
            "crossflow_coeff": self.crossflow_coeff,
            "strips": float(self.strips),
            "propeller_torque_scale": self.propeller_torque_scale,
        }
        for axis, value in zip("xyz", self.r_bg, strict=True):
            values[f"{axis}_g"] = value
        for axis, value in zip("xyz", self.r_bb, strict=True):
            values[f"{axis}_b"] = value
        for axis, value in zip("uvwpqr", np.diag(self.damping_base), strict=True):
            values[f"damping_{axis}"] = value
        for name, matrix in (
            ("mass", self.rigid_body + self.added_mass),
            ("added", self.added_mass),
            ("inverse_mass", self.inverse_mass),
        ):
            for i in range(6):
                for j in range(6):
                    values[f"{name}_{i}{j}"] = matrix[i, j]
        return np.array([float(values[name]) for name in SIX_DOF_FIELDS])


# The coefficients of a vehicle record (`SixDofVehicle.from_record`); the actuators are the env's.
COEFFICIENTS = tuple(f.name for f in fields(SixDofVehicle) if f.name != "actuators")
# What parameter uncertainty scales (`SixDofVehicle.perturbed`).
UNCERTAIN_COEFFICIENTS = (
    "hull_drag_coeff",
    "roll_added_inertia",
    "surge_time_constant",
    "sway_time_constant",
    "heave_time_constant",
    "yaw_time_constant",
    "roll_damping_ratio",
    "pitch_damping_ratio",
)
REMUS6DOF = SixDofVehicle()


def _round(value: float, down: bool) -> float:
    """``value`` to three significant digits, rounded down or up (a bound that still holds)."""
    if value <= 0.0:
        return 0.0
    unit = 10.0 ** (math.floor(math.log10(value)) - 2)
    steps = value / unit
    return (math.floor(steps) if down else math.ceil(steps)) * unit


def coriolis(mass: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """C(ν) of a symmetric 6×6 inertia matrix (Fossen 2021 eq. 3.63), skew-symmetric."""
    m = 0.5 * (mass + mass.T)
    p1 = m[0:3, 0:3] @ nu[0:3] + m[0:3, 3:6] @ nu[3:6]
    p2 = m[3:6, 0:3] @ nu[0:3] + m[3:6, 3:6] @ nu[3:6]
    c = np.zeros((6, 6))
    c[0:3, 3:6] = -_skew(p1)
    c[3:6, 0:3] = -_skew(p1)
    c[3:6, 3:6] = -_skew(p2)
    return c


def restoring_forces(vehicle: SixDofVehicle, phi: float, theta: float) -> np.ndarray:
    """g(η) [N, N·m] of weight and buoyancy (W = B) at r_bg and r_bb, roll φ and pitch θ [rad]."""
    w = b = vehicle.weight
    xg, yg, zg = vehicle.r_bg
    xb, yb, zb = vehicle.r_bb
    sth, cth, sphi, cphi = math.sin(theta), math.cos(theta), math.sin(phi), math.cos(phi)
    return np.array(
        [
            (w - b) * sth,
            -(w - b) * cth * sphi,
            -(w - b) * cth * cphi,
            -(yg * w - yb * b) * cth * cphi + (zg * w - zb * b) * cth * sphi,
            (zg * w - zb * b) * sth + (xg * w - xb * b) * cth * cphi,
            -(xg * w - xb * b) * cth * sphi - (yg * w - yb * b) * sth,
        ]
    )


def _lift_drag(vehicle: SixDofVehicle, alpha: float, u_r: float) -> np.ndarray:
    """The hull's lift and drag at angle of attack α [rad] and relative speed U_r [m/s]."""
    span, area = vehicle.diameter, vehicle.wing_area
    aspect = span * span / area
    cl = math.pi * aspect / (1.0 + math.sqrt(1.0 + (aspect / 2.0) ** 2)) * alpha
    cd = vehicle.zero_lift_drag + cl * cl / (math.pi * _OSWALD * aspect)
    pressure = 0.5 * vehicle.water_density * u_r * u_r * area
    drag, lift = pressure * cd, pressure * cl
    ca, sa = math.cos(alpha), math.sin(alpha)
    return np.array([-ca * drag + sa * lift, 0.0, -sa * drag - ca * lift, 0.0, 0.0, 0.0])


def _crossflow(vehicle: SixDofVehicle, v_r: float, r: float) -> np.ndarray:
    """Cross-flow drag in sway and yaw by strip theory."""
    n, length, depth = vehicle.strips, vehicle.length, vehicle.diameter
    dx = length / n
    x = -length / 2.0 + dx * np.arange(n + 1)
    flow = v_r + x * r
    strip = -0.5 * vehicle.water_density * depth * vehicle.crossflow_coeff * np.abs(flow) * flow
    return np.array([0.0, float(np.sum(strip * dx)), 0.0, 0.0, 0.0, float(np.sum(strip * x * dx))])


def accelerations(
    vehicle: SixDofVehicle,
    eta: np.ndarray,
    nu: np.ndarray,
    actuator_state: np.ndarray,
    current_speed: float = 0.0,
    current_direction: float = 0.0,
) -> np.ndarray:
    """ν̇ [m/s², rad/s²] at pose η (x, y, z [m], φ, θ, ψ [rad]), velocity ν (u, v, w [m/s],
    p, q, r [rad/s]) and actuator state (δ_r, δ_s [rad], n [rpm]; saturated at their limits),
    in a current V_c [m/s] toward β_c [rad] (module doc)."""
    nu_c = _current(nu, eta[5], current_speed, current_direction)[0]
    tau = actuation(vehicle, nu, np.asarray(nu, float) - nu_c, actuator_state)
    return hull_accelerations(vehicle, eta, nu, tau, current_speed, current_direction)


def _current(
    nu: np.ndarray, psi: float, speed: float, direction: float
) -> tuple[np.ndarray, np.ndarray]:
    """(ν_c, ν̇_c) of a horizontal current of ``speed`` [m/s] toward ``direction`` [rad]."""
    u_c, v_c = speed * math.cos(direction - psi), speed * math.sin(direction - psi)
    nu_c = np.array([u_c, v_c, 0.0, 0.0, 0.0, 0.0])
    return nu_c, np.array([nu[5] * v_c, -nu[5] * u_c, 0.0, 0.0, 0.0, 0.0])


def actuation(
    vehicle: SixDofVehicle, nu: np.ndarray, nu_r: np.ndarray, actuator_state: np.ndarray
) -> np.ndarray:
    """τ_act [N, N·m] of the propeller and fins (δ_r, δ_s [rad], n [rpm], saturated) at
    velocity ν and velocity through the water ν_r: thrust, fin forces and moments, and the
    propeller torque in roll (module doc)."""
    a = vehicle.actuators
    speed = math.sqrt(nu[0] ** 2 + nu[1] ** 2 + nu[2] ** 2)
    delta_r = float(np.clip(actuator_state[0], -a.delta_max_rudder, a.delta_max_rudder))
    delta_s = float(np.clip(actuator_state[1], -a.delta_max_stern, a.delta_max_stern))
    n_rpm = float(np.clip(actuator_state[2], -a.rpm_max, a.rpm_max))
    x_prop, k_prop = _propeller(n_rpm, speed, a)
    half_rho = 0.5 * a.water_density
    k_r = half_rho * (nu_r[0] ** 2 + nu_r[1] ** 2) * a.fin_area_rudder * a.lift_coeff_rudder
    k_s = half_rho * (nu_r[0] ** 2 + nu_r[2] ** 2) * a.fin_area_stern * a.lift_coeff_stern
    y_r, z_s = -k_r * delta_r, -k_s * delta_s
    return np.array(
        [
            (1.0 - a.thrust_deduction) * x_prop
            + a.fin_induced_drag * (-k_r * delta_r**2 - k_s * delta_s**2),
            y_r,
            z_s,
            vehicle.propeller_torque_scale * k_prop,
            -a.x_stern * z_s,
            a.x_rudder * y_r,
        ]
    )


def hull_accelerations(
    vehicle: SixDofVehicle,
    eta: np.ndarray,
    nu: np.ndarray,
    tau: np.ndarray,
    current_speed: float = 0.0,
    current_direction: float = 0.0,
) -> np.ndarray:
    """ν̇ [m/s², rad/s²] of the hull under generalized forces ``tau`` (6,) [N, N·m] (module doc):
    what `accelerations` gives for the actuators' τ, and the way to apply any other τ (the
    5-DOF model's X, M, N, say)."""
    nu_c, dnu_c = _current(nu, eta[5], current_speed, current_direction)
    nu_r = np.asarray(nu, float) - nu_c
    alpha = math.atan2(nu_r[2], nu_r[0])
    u_r = math.sqrt(nu_r[0] ** 2 + nu_r[1] ** 2 + nu_r[2] ** 2)
    d = vehicle.damping_base.copy()
    d[0, 0] *= math.exp(-3.0 * u_r)
    d[1, 1] *= math.exp(-3.0 * u_r)
    total = (
        np.asarray(tau, float)
        + _lift_drag(vehicle, alpha, u_r)
        + _crossflow(vehicle, nu_r[1], nu_r[5])
        - (coriolis_matrix(vehicle, nu_r) + d) @ nu_r
        - restoring_forces(vehicle, eta[3], eta[4])
    )
    return dnu_c + vehicle.inverse_mass @ total


def coriolis_matrix(vehicle: SixDofVehicle, nu_r: np.ndarray) -> np.ndarray:
    """C_RB(ν_r) + C_A(ν_r) without the Munk moments in pitch and yaw (module doc)."""
    added = coriolis(vehicle.added_mass, nu_r)
    for i, j in ((4, 0), (4, 2), (5, 0), (5, 1)):
        added[i, j] = added[j, i] = 0.0
    return coriolis(vehicle.rigid_body, nu_r) + added


def _propeller(n_rpm: float, speed: float, a: ActuatorParams) -> tuple[float, float]:
    """(thrust X_prop [N], shaft torque K_prop [N·m]) at n [rpm] and vehicle speed U [m/s]."""
    # the kernels' own formulas, run as Python on the parameter record
    return propeller_thrust.py_func(n_rpm, speed, a), propeller_torque.py_func(n_rpm, speed, a)
