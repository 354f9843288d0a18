"""A vehicle as one record, read from a TOML file (docs/vehicles.md).

A `Vehicle` holds everything the simulator needs to know about one AUV: its limits, the paper's
5-DOF model (`AUVParams`, docs/model.md §2.2), its propeller and fins (`ActuatorParams`, §2.6),
the 6-DOF hull of Fossen's form (`SixDofVehicle`, §15) and the navigation suite it carries
(`SensorConfig`, §14). `load_vehicle` builds one from a shipped vehicle's name (the files of
`auv_gym/vehicle/data/`), a path to a ``.toml`` file, a mapping of the same layout or a
`Vehicle`; every field is checked when it is read, and a problem is one line naming the file and
the field (`VehicleFileError`, a ValueError).

The fins are listed one by one (area, lift slope, position, the roll angle of the fin's axis,
angle limit, servo time constant and rate). The simulator's fin model drives them as two coupled
pairs, the stern planes (axes horizontal: roll 0 or π) for pitch and the rudders (axes vertical:
roll ±π/2) for yaw, so a layout is accepted when it reduces exactly to those two pairs;
`fin_pairs` does that reduction and names the fin that breaks it.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym.support.files import parse_toml
from auv_gym.support.validation import ArgumentTypeError, keys_within, real
from auv_gym.vehicle.actuators import ActuatorParams
from auv_gym.vehicle.fins import FinLayout
from auv_gym.vehicle.params import AUVParams
from auv_gym.vehicle.remus6dof import COEFFICIENTS as HULL_6DOF_FIELDS
from auv_gym.vehicle.remus6dof import SixDofVehicle
from auv_gym.vehicle.sensors import SENSOR_PRESETS, SensorConfig

__all__ = [
    "CRUISE_SPEED",
    "DEFAULT_VEHICLE",
    "FORMAT_VERSION",
    "VEHICLE_DIRECTORY",
    "DerivedAUVParams",
    "FinSpec",
    "Propeller",
    "Vehicle",
    "VehicleFileError",
    "actuators_from",
    "check_mass_matrix",
    "derived_5dof",
    "fin_pairs",
    "hull_from",
    "load_vehicle",
    "shipped_vehicles",
    "vehicle_file",
    "vehicle_from_bytes",
    "vehicle_from_mapping",
]

FORMAT_VERSION = 1
DEFAULT_VEHICLE = "remus100"
VEHICLE_DIRECTORY = Path(__file__).parent / "data"

# `AUVParams` fields the file keeps in [limits] (every vehicle has them); the rest are
# [model_5dof] (the "paper" actuator's limits X_max, M_max, N_max with them), but for `fin_max`,
# which is the fins' own angle limit (the smallest of theirs).
LIMIT_FIELDS = ("max_surge",)
MODEL_5DOF_FIELDS = tuple(
    f.name for f in fields(AUVParams) if f.name not in (*LIMIT_FIELDS, "fin_max", "surge_coriolis")
)
# `ActuatorParams` fields of [actuators]: the propeller, its motor and the water; the fins'
# fields (area, lift slope, position, limit, servo) are assembled from [[actuators.fins]].
PROPULSION_FIELDS = (
    "water_density",
    "prop_diameter",
    "thrust_deduction",
    "advance_speed_ratio",
    "kt_0",
    "kq_0",
    "kt_max",
    "kq_max",
    "advance_max",
    "rpm_max",
    "motor_time_constant",
)
FIN_FIELDS = (
    "name",
    "area",
    "lift_slope",
    "x",
    "axis_roll",
    "radius",
    "induced_drag",
    "angle_max",
    "servo_time_constant",
    "rate_max",
)
TOP_LEVEL = ("format", "name", "description", "sources", "surge_coriolis")
SECTIONS = ("limits", "model_5dof", "actuators", "model_6dof", "sensors")
# A fin's axis counts as horizontal or vertical when its roll angle is within this of one
# [rad]: 1e-9 rad moves a 1-m fin's lift line by a nanometre.
AXIS_TOLERANCE = 1e-9


CRUISE_SPEED = 1.0  # [m/s] where a 6-DOF hull's linear damping is read as u-proportional terms


@dataclass(frozen=True)
class DerivedAUVParams(AUVParams):
    """A 5-DOF record derived from a vehicle's 6-DOF hull (`derived_5dof`), for what needs a
    vehicle's inertias, damping and limits without flying the 5-DOF model: the PID gains'
    placement, the observation's bounds, the actuator limits. Not a model of the vehicle: the
    paper's model-based controllers refuse it (`controllers.registry`)."""


class VehicleFileError(ValueError):
    """A vehicle file or mapping that cannot describe a vehicle; one line naming the field."""


@dataclass(frozen=True)
class FinSpec:
    """One control fin (SI): its area A [m²], lift slope C_L [1/rad], position x [m] along the
    body (aft negative), the roll angle of its axis [rad] (0: a horizontal stern plane, π/2: a
    vertical rudder), the radius [m] of its centre of pressure from the body's x axis, its
    induced-drag factor [-] (`auv_gym.vehicle.fins`), angle limit [rad], servo time constant [s]
    and rate limit [rad/s]."""

    name: str
    area: float
    lift_slope: float
    x: float
    axis_roll: float
    radius: float
    induced_drag: float
    angle_max: float
    servo_time_constant: float
    rate_max: float

    @property
    def pitch_share(self) -> float:
        """|cos(axis roll)|: the share of the fin's lift that turns the vehicle in pitch."""
        return abs(math.cos(self.axis_roll))

    @property
    def yaw_share(self) -> float:
        """|sin(axis roll)|: the share of the fin's lift that turns the vehicle in yaw."""
        return abs(math.sin(self.axis_roll))


@dataclass(frozen=True)
class Propeller:
    """The propeller, its motor and the water of [actuators] (the propeller fields of
    `ActuatorParams`, docs/model.md §2.6; SI)."""

    water_density: float
    prop_diameter: float
    thrust_deduction: float
    advance_speed_ratio: float
    kt_0: float
    kq_0: float
    kt_max: float
    kq_max: float
    advance_max: float
    rpm_max: float
    motor_time_constant: float


@dataclass(frozen=True)
class Vehicle:
    """One vehicle: name, limits and models (module doc). ``source`` is the file it was read
    from ("" for a mapping)."""

    name: str
    description: str
    limits: dict[str, float]
    hull_5dof: AUVParams | None  # None: the vehicle has no model in the paper's 5-DOF form
    actuators: ActuatorParams | None  # the fins as the simulator's two pairs; None: they are not
    fins: tuple[FinSpec, ...]
    hull_6dof: SixDofVehicle
    sensors: SensorConfig
    propeller: Propeller
    sources: tuple[str, ...] = ()
    source: str = ""
    pairs_problem: str = ""  # why the fins are not two coupled pairs (when actuators is None)

    @property
    def max_surge(self) -> float:
        """Top speed [m/s]."""
        return self.limits["max_surge"]

    @property
    def fin_layout(self) -> FinLayout:
        """The fins as the arrays of the general fin model (`auv_gym.vehicle.fins`)."""
        return FinLayout.from_fins(self.fins, self.propeller.water_density)

    def simulated_5dof(self) -> AUVParams:
        """The 5-DOF record the env carries: the vehicle's own, or one derived from its 6-DOF
        hull (`derived_5dof`) for a vehicle without a [model_5dof]."""
        return self.hull_5dof if self.hull_5dof is not None else derived_5dof(self)

    def check_simulated(self) -> None:
        """Raise `VehicleFileError`, in one line naming the fin and the file, unless the
        simulator can fly the fins: as the two coupled pairs of the fin model."""
        if self.actuators is None:
            raise VehicleFileError(self.pairs_problem)


def shipped_vehicles() -> tuple[str, ...]:
    """The names of the vehicle files shipped with the package."""
    return tuple(sorted(p.stem for p in VEHICLE_DIRECTORY.glob("*.toml")))


def load_vehicle(spec: str | Path | Mapping[str, Any] | Vehicle | None = None) -> Vehicle:
    """The vehicle of the env's ``vehicle`` argument: None (REMUS 100), a shipped vehicle's name,
    a path to a ``.toml`` vehicle file, a mapping of the file's layout, or a `Vehicle`.

    Raises `VehicleFileError` naming the file and the field for a missing, unknown, non-finite
    or physically impossible value, and ValueError listing the shipped names for an unknown one.
    """
    if isinstance(spec, Vehicle):
        return spec
    if isinstance(spec, Mapping):
        return vehicle_from_mapping(spec, "vehicle mapping")
    file = vehicle_file(spec)
    if file is not None:
        return _read_file(file)
    if isinstance(spec, str):
        raise ValueError(
            f"vehicle {spec!r:.80} is not a shipped vehicle {list(shipped_vehicles())} "
            "nor a path to a .toml vehicle file"
        )
    raise TypeError(
        "vehicle must be a shipped vehicle's name, a path to a .toml file, a mapping or a "
        f"Vehicle, got {spec!r:.80}"
    )


def vehicle_file(spec: Any) -> Path | None:
    """The file `load_vehicle` reads for ``spec`` (None: the default vehicle's; a shipped
    vehicle's name: its file; a path to a ``.toml`` file), or None (a mapping, a `Vehicle`, or a
    name that is no shipped vehicle, which `load_vehicle` refuses)."""
    if spec is None:
        spec = DEFAULT_VEHICLE
    if isinstance(spec, Path) or (isinstance(spec, str) and spec.endswith(".toml")):
        return Path(spec)
    if isinstance(spec, str) and spec in shipped_vehicles():
        return VEHICLE_DIRECTORY / f"{spec}.toml"
    return None


def vehicle_from_bytes(text: bytes, where: str) -> Vehicle:
    """A `Vehicle` from a vehicle file's bytes; ``where`` names the file in errors."""
    try:
        data = parse_toml(text, f"vehicle file {where}")
    except ValueError as error:
        raise VehicleFileError(str(error)) from None
    return vehicle_from_mapping(data, where)


def _read_file(path: Path) -> Vehicle:
    try:
        text = path.read_bytes()
    except OSError as exc:
        raise VehicleFileError(f"vehicle file {path}: cannot be read ({exc.strerror})") from None
    return vehicle_from_bytes(text, str(path))


def vehicle_from_mapping(data: Mapping[str, Any], where: str) -> Vehicle:
    """A `Vehicle` from the parsed layout of a vehicle file; ``where`` names the file in errors."""

    def fail(field: str, problem: str) -> VehicleFileError:
        return VehicleFileError(f"{where}: {field}: {problem}")

    def section(name: str, allowed: tuple[str, ...], required: bool = True) -> dict[str, Any]:
        value = data.get(name, {})
        if not isinstance(value, Mapping):
            raise fail(f"[{name}]", f"must be a table, got {value!r:.60}")
        unknown = sorted(set(value) - set(allowed))
        if unknown:
            raise fail(f"[{name}] {unknown[0]}", f"unknown field; known: {', '.join(allowed)}")
        if required:
            missing = [key for key in allowed if key not in value]
            if missing:
                raise fail(f"[{name}] {missing[0]}", "missing")
        return dict(value)

    def number(field: str, value: Any) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise fail(field, f"must be a number, got {value!r:.60}")
        if not math.isfinite(value):
            raise fail(field, f"must be finite, got {value!r}")
        return float(value)

    if not isinstance(data, Mapping):
        raise VehicleFileError(f"{where}: must be a table of the vehicle-file layout")
    unknown = sorted(set(data) - set(TOP_LEVEL) - set(SECTIONS))
    if unknown:
        raise fail(unknown[0], f"unknown field; known: {', '.join((*TOP_LEVEL, *SECTIONS))}")
    for key in ("format", "name"):
        if key not in data:
            raise fail(key, "missing")
    if data["format"] != FORMAT_VERSION:
        raise fail("format", f"must be {FORMAT_VERSION}, got {data['format']!r:.40}")
    name = data["name"]
    if not (isinstance(name, str) and name.strip()):
        raise fail("name", f"must be a non-empty string, got {name!r:.60}")
    description = data.get("description", "")
    if not isinstance(description, str):
        raise fail("description", "must be a string")
    sources = data.get("sources", [])
    if not (isinstance(sources, list) and all(isinstance(s, str) for s in sources)):
        raise fail("sources", "must be a list of strings")
    surge_coriolis = data.get("surge_coriolis", True)
    if not isinstance(surge_coriolis, bool):
        raise fail("surge_coriolis", f"must be true or false, got {surge_coriolis!r:.40}")
    if "surge_coriolis" in data and "model_5dof" not in data:
        raise fail(
            "surge_coriolis",
            "sets a term of [model_5dof], which this file has none of (its 5-DOF record is "
            "derived from [model_6dof], without it): drop it or add the section",
        )

    actuator_values = section("actuators", (*PROPULSION_FIELDS, "fins"))
    fins, actuators, pairs_problem = _actuators(actuator_values, number, fail)
    propeller = Propeller(
        **{key: number(f"[actuators] {key}", actuator_values[key]) for key in PROPULSION_FIELDS}
    )
    limits = {
        key: number(f"[limits] {key}", v) for key, v in section("limits", LIMIT_FIELDS).items()
    }
    for key, value in limits.items():
        if not value > 0.0:
            raise fail(f"[limits] {key}", f"must be positive, got {value:g}")
    hull_5dof = None
    if "model_5dof" in data:
        model = section("model_5dof", MODEL_5DOF_FIELDS)
        values = {key: number(f"[model_5dof] {key}", v) for key, v in model.items()}
        values["fin_max"] = min(fin.angle_max for fin in fins)
        hull_5dof = _built(
            AUVParams, {**limits, **values, "surge_coriolis": surge_coriolis}, fail, "model_5dof"
        )
        check_added_mass(hull_5dof, fail)

    hull = section("model_6dof", HULL_6DOF_FIELDS)
    hull_values = {}
    for key, value in hull.items():
        if key in ("r_bg", "r_bb"):
            if not (isinstance(value, list) and len(value) == 3):
                raise fail(f"[model_6dof] {key}", f"must be a list of 3 numbers, got {value!r:.60}")
            hull_values[key] = tuple(number(f"[model_6dof] {key}", v) for v in value)
        elif key == "strips":
            if isinstance(value, bool) or not isinstance(value, int):
                raise fail("[model_6dof] strips", f"must be an integer, got {value!r:.40}")
            hull_values[key] = value
        else:
            hull_values[key] = number(f"[model_6dof] {key}", value)
    hull_6dof = _built(SixDofVehicle, hull_values, fail, "model_6dof")
    check_mass_matrix(hull_6dof.mass, fail)
    for fin in fins:
        if abs(fin.x) > 0.5 * hull_6dof.length * (1.0 + 1e-9):
            raise fail(
                f"[[actuators.fins]] {fin.name!r} x",
                f"{fin.x:g} m lies off the {hull_6dof.length:g}-m hull of [model_6dof] (a fin "
                f"is on the hull: |x| ≤ length/2 = {0.5 * hull_6dof.length:g} m)",
            )
    if not math.isclose(propeller.water_density, hull_6dof.water_density, rel_tol=1e-9):
        raise fail(
            "[model_6dof] water_density",
            f"{hull_6dof.water_density:g} kg/m³ differs from [actuators] water_density = "
            f"{propeller.water_density:g} kg/m³: the hull, its propeller and its fins are in "
            "one sea",
        )
    if hull_5dof is not None:
        check_rigid_body(hull_5dof, hull_6dof, fail)
        if actuators is not None:
            check_fin_authority(hull_5dof, actuators, fail)

    return Vehicle(
        name=name,
        description=description,
        limits=limits,
        hull_5dof=hull_5dof,
        actuators=actuators,
        pairs_problem=pairs_problem,
        fins=fins,
        hull_6dof=hull_6dof,
        sensors=_sensors(data.get("sensors", {"preset": "ideal"}), fail),
        propeller=propeller,
        sources=tuple(sources),
        source="" if where == "vehicle mapping" else where,
    )


def check_mass_matrix(mass: np.ndarray, fail) -> None:
    """Refuse a 6-DOF mass matrix M_RB + M_A [kg, kg m, kg m²] that is not symmetric positive
    definite: ν̇ = M⁻¹(τ − …) would be unbounded or run backwards."""
    smallest = float(np.linalg.eigvalsh(0.5 * (mass + mass.T)).min())
    if not (smallest > 0.0 and np.allclose(mass, mass.T, rtol=1e-12, atol=0.0)):
        raise fail(
            "[model_6dof]",
            f"mass matrix M_RB + M_A is not positive definite (smallest eigenvalue {smallest:.3g})",
        )


ADDED_MASS_FIELDS = ("X_udot", "Y_vdot", "Z_wdot", "M_qdot", "N_rdot")


def check_added_mass(model: AUVParams, fail) -> None:
    """Refuse a [model_5dof] added-mass derivative X_u̇ … N_ṙ [kg, kg m²/rad] above 0: a
    submerged hull carries water along, so each is ≤ 0 in this sign convention (docs/model.md
    §2.1); a positive one lowers the vehicle's inertia instead (M_q̇ = 3.449 against I_y = 3.45
    left 0.001 kg m², and the first step went non-finite)."""
    for name in ADDED_MASS_FIELDS:
        value = getattr(model, name)
        if value > 0.0:
            raise fail(
                f"[model_5dof] {name}",
                f"{value:g} must be ≤ 0: a submerged hull's added mass adds to its inertia "
                "(docs/model.md §2.1; a sign lost in a copy?)",
            )


# W = m·g within local gravity's spread (9.78-9.83 m/s²) and the file's rounding.
WEIGHT_TOLERANCE = 0.01
# The 6-DOF hull is the spheroid of the vehicle's length and diameter; a real hull lies between
# that spheroid and the cylinder around it, 3/2 of its volume, so a neutral vehicle's mass does.
MASS_RATIO_RANGE = (2.0 / 3.0, 3.0 / 2.0)


def check_rigid_body(model: AUVParams, hull: SixDofVehicle, fail) -> None:
    """Refuse a [model_5dof] whose weight, buoyancy and mass are not one neutrally buoyant
    vehicle with the [model_6dof] hull: B = W (the 5-DOF form has no (W − B) force, docs/model.md
    §2.1 f, so a difference would fly as neutral in heave), W = m·g [N] with the hull's gravity,
    and m [kg] within `MASS_RATIO_RANGE` of the hull's displaced mass (a unit slip, 10³ or 10³⁰
    kg, otherwise loads and flies)."""
    if not model.z_g > model.z_b:
        raise fail(
            "[model_5dof] z_g",
            f"{model.z_g:g} m must lie below z_b = {model.z_b:g} m (z_g > z_b, z down): the "
            "restoring moment −(z_g W − z_b B) sin θ would capsize the vehicle in pitch",
        )
    if not math.isclose(model.B, model.W, rel_tol=1e-9):
        raise fail(
            "[model_5dof] B",
            f"{model.B:g} N must equal W = {model.W:g} N: the 5-DOF form has no (W − B) force "
            "(docs/model.md §2.1 f), so a buoyant vehicle would fly as a neutral one",
        )
    weight = model.m * hull.gravity
    if abs(model.W / weight - 1.0) > WEIGHT_TOLERANCE:
        raise fail(
            "[model_5dof] W",
            f"{model.W:g} N is not m·g = {model.m:g} kg × {hull.gravity:g} m/s² "
            f"([model_6dof] gravity) = {weight:.4g} N (within {WEIGHT_TOLERANCE:.0%}): a mass "
            "changes W and B with it",
        )
    low, high = MASS_RATIO_RANGE
    ratio = model.m / hull.mass_kg
    if not low <= ratio <= high:
        raise fail(
            "[model_5dof] m",
            f"{model.m:g} kg is {ratio:.3g}× the {hull.mass_kg:.4g} kg of water the [model_6dof] "
            f"hull displaces ({hull.length:g} m × {hull.diameter:g} m spheroid); a neutrally "
            f"buoyant vehicle's mass is within {low:.2g}-{high:g}× of it",
        )


# The paper's form has one fin coefficient for pitch and yaw; the fins' own, to the file's rounding.
FIN_AUTHORITY_TOLERANCE = 0.01


def check_fin_authority(model: AUVParams, actuators: ActuatorParams, fail) -> None:
    """Refuse a [model_5dof] ``fin_moment_coeff`` [kg/rad] that is not the fins' moment per u²
    per radian, |x|·½ρAC_L of the stern planes and of the rudders (`ActuatorParams.
    fin_moment_coeff`, docs/model.md §2.6): actuator="fins" flies the coefficient and
    actuator="realistic" the fins, and they would be two different vehicles."""
    stern, rudder = actuators.fin_moment_coeff()
    for pair, value in (("stern planes", stern), ("rudders", rudder)):
        if abs(model.fin_moment_coeff / value - 1.0) > FIN_AUTHORITY_TOLERANCE:
            raise fail(
                "[model_5dof] fin_moment_coeff",
                f"{model.fin_moment_coeff:g} kg/rad is not the {pair}' |x|·½ρAC_L = {value:.4g} "
                f"kg/rad (stern planes {stern:.4g}, rudders {rudder:.4g}; within "
                f"{FIN_AUTHORITY_TOLERANCE:.0%}): the paper's 5-DOF form has one fin coefficient, "
                "so a [model_5dof] needs stern planes and rudders of equal authority and this "
                f"coefficient their value (fin_moment_coeff = {value:.4g})",
            )


def _built(kind: type, values: dict[str, Any], fail, section_name: str):
    """``kind(**values)``, its own range checks reported against the file."""
    try:
        return kind(**values)
    except (TypeError, ValueError) as exc:
        raise fail(f"[{section_name}]", str(exc)) from None


def _actuators(
    values: dict[str, Any], number, fail
) -> tuple[tuple[FinSpec, ...], ActuatorParams | None, str]:
    """The fins of [[actuators.fins]], the propeller of [actuators] and the fins as the
    simulator's pairs, in one `ActuatorParams` (None, and why, when the fins are not pairs)."""
    propulsion = {key: number(f"[actuators] {key}", values[key]) for key in PROPULSION_FIELDS}
    try:  # the propeller's ranges, whatever the fins
        ActuatorParams(**propulsion)
    except (TypeError, ValueError) as exc:
        raise fail("[actuators]", str(exc)) from None
    listed = values["fins"]
    if not isinstance(listed, list) or not listed:
        raise fail("[[actuators.fins]]", "must list at least one fin")
    fins = []
    for i, entry in enumerate(listed):
        where = f"[[actuators.fins]] #{i + 1}"
        if not isinstance(entry, Mapping):
            raise fail(where, "must be a table")
        unknown = sorted(set(entry) - set(FIN_FIELDS))
        if unknown:
            raise fail(f"{where} {unknown[0]}", f"unknown field; known: {', '.join(FIN_FIELDS)}")
        missing = [key for key in FIN_FIELDS if key not in entry]
        if missing:
            raise fail(f"{where} {missing[0]}", "missing")
        if not (isinstance(entry["name"], str) and entry["name"]):
            raise fail(f"{where} name", "must be a non-empty string")
        where = f"[[actuators.fins]] {entry['name']!r}"
        fin = FinSpec(
            name=entry["name"],
            **{
                key: math.inf
                if key == "rate_max" and entry[key] == math.inf  # no rate limit
                else number(f"{where} {key}", entry[key])
                for key in FIN_FIELDS[1:]
            },
        )
        for key in ("area", "lift_slope", "angle_max"):
            if not getattr(fin, key) > 0.0:
                raise fail(f"{where} {key}", f"must be positive, got {getattr(fin, key):g}")
        if fin.angle_max > math.pi / 2:
            raise fail(f"{where} angle_max", f"must be at most π/2 rad, got {fin.angle_max:g}")
        for key in ("radius", "induced_drag"):
            if getattr(fin, key) < 0.0:
                raise fail(f"{where} {key}", f"must be non-negative, got {getattr(fin, key):g}")
        if fin.servo_time_constant < 0.0:
            raise fail(f"{where} servo_time_constant", "must be non-negative")
        if not fin.rate_max > 0.0:
            raise fail(f"{where} rate_max", f"must be positive, got {fin.rate_max:g}")
        fins.append(fin)
    names = [fin.name for fin in fins]
    if len(set(names)) != len(names):
        raise fail("[[actuators.fins]] name", f"fin names repeat: {names}")
    check_steerable(tuple(fins), fail)
    try:
        stern, rudder = fin_pairs(tuple(fins), fail)
    except VehicleFileError as exc:
        return tuple(fins), None, str(exc)
    try:
        actuators = ActuatorParams(
            **propulsion,
            fin_area_stern=stern[0],
            lift_coeff_stern=stern[1],
            x_stern=stern[2],
            delta_max_stern=stern[3],
            fin_area_rudder=rudder[0],
            lift_coeff_rudder=rudder[1],
            x_rudder=rudder[2],
            delta_max_rudder=rudder[3],
            fin_time_constant=fins[0].servo_time_constant,
            fin_rate_max=fins[0].rate_max,
            fin_induced_drag=fins[0].induced_drag,
        )
    except (TypeError, ValueError) as exc:
        raise fail("[actuators]", str(exc)) from None
    return tuple(fins), actuators, ""


def check_steerable(fins: tuple[FinSpec, ...], fail) -> None:
    """Refuse a layout whose fins cannot turn the vehicle in pitch or in yaw: no fin with a
    horizontal share of its lift (|cos φ| > 0) away from x = 0, or none with a vertical one."""
    for moment, share, kind in (
        ("pitch", "pitch_share", "stern plane"),
        ("yaw", "yaw_share", "rudder"),
    ):
        if not any(getattr(fin, share) > AXIS_TOLERANCE and fin.x != 0.0 for fin in fins):
            raise fail(
                "[[actuators.fins]]",
                f"no fin can produce a {moment} moment (no {kind} away from x = 0): "
                "the vehicle could not be steered",
            )


def fin_pairs(fins: tuple[FinSpec, ...], fail=None):
    """The fins as the simulator's two coupled pairs: ((area, lift slope, x, angle limit) of the
    stern planes, the same of the rudders) [m², 1/rad, m, rad], areas summed.

    Refuses, naming the fin, an axis that is neither horizontal nor vertical, and fins of one pair
    (or the servos or induced drag of any two fins) that differ, which the coupled pairs cannot
    represent.
    """
    if fail is None:

        def fail(field: str, problem: str) -> VehicleFileError:
            return VehicleFileError(f"{field}: {problem}")

    groups: dict[str, list[FinSpec]] = {"stern planes": [], "rudders": []}
    for fin in fins:
        if fin.yaw_share <= AXIS_TOLERANCE:
            groups["stern planes"].append(fin)
        elif fin.pitch_share <= AXIS_TOLERANCE:
            groups["rudders"].append(fin)
        else:
            raise fail(
                f"[[actuators.fins]] {fin.name!r} axis_roll",
                f"{fin.axis_roll:g} rad is neither horizontal (0, π) nor vertical (±π/2); the "
                "fin model drives stern planes and rudders as coupled pairs",
            )
    for group in groups.values():
        if not group:
            raise fail("[[actuators.fins]]", "the fin model needs both stern planes and rudders")
    first = fins[0]
    for fin in fins[1:]:
        for key in ("servo_time_constant", "rate_max", "induced_drag"):
            if getattr(fin, key) != getattr(first, key):
                raise fail(
                    f"[[actuators.fins]] {fin.name!r} {key}",
                    f"{getattr(fin, key):g} differs from fin {first.name!r}'s "
                    f"{getattr(first, key):g}; the fins share one servo and drag model",
                )
    pairs = []
    for group in ("stern planes", "rudders"):
        lead = groups[group][0]
        for fin in groups[group][1:]:
            for key in ("lift_slope", "x", "radius", "angle_max"):
                if getattr(fin, key) != getattr(lead, key):
                    raise fail(
                        f"[[actuators.fins]] {fin.name!r} {key}",
                        f"{getattr(fin, key):g} differs from {lead.name!r}'s "
                        f"{getattr(lead, key):g}; the {group} are driven as one coupled pair",
                    )
        # Fin i's roll moment is −r_i f_i, its lift f_i ∝ A_i δ_i with δ_i = cos φ_i δ_s (stern
        # planes) or −sin φ_i δ_r (rudders): the pair has none only if Σ A_i r_i cos φ_i (or
        # sin φ_i) vanishes, fins of equal area opposite each other or on the axis (r = 0).
        side = math.cos if group == "stern planes" else math.sin
        arm = sum(fin.area * fin.radius * side(fin.axis_roll) for fin in groups[group])
        scale = sum(fin.area * fin.radius for fin in groups[group])
        if abs(arm) > 1e-9 * scale:
            raise fail(
                f"[[actuators.fins]] {groups[group][-1].name!r}",
                f"the {group}' roll moments do not cancel (Σ A·r·{side.__name__} φ = {arm:.3g} "
                "m³): the coupled pairs have no roll moment; give each fin an opposite one of "
                "equal area, or put them on the axis (radius 0)",
            )
        area = 0.0
        for fin in groups[group]:
            area += fin.area
        pairs.append((area, lead.lift_slope, lead.x, lead.angle_max))
    return pairs[0], pairs[1]


def _sensors(value: Any, fail) -> SensorConfig:
    """[sensors]: ``preset = "<name>"`` (`SENSOR_PRESETS`) or the fields of a `SensorConfig`."""
    if not isinstance(value, Mapping):
        raise fail("[sensors]", "must be a table")
    if set(value) == {"preset"}:
        preset = value["preset"]
        if preset not in SENSOR_PRESETS:
            raise fail("[sensors] preset", f"{preset!r:.40} is not one of {list(SENSOR_PRESETS)}")
        return SENSOR_PRESETS[preset]
    try:
        return SensorConfig.from_spec(dict(value))
    except (TypeError, ValueError) as exc:
        raise fail("[sensors]", str(exc)) from None


def hull_from(vehicle: Vehicle, params: AUVParams | Mapping[str, Any] | None) -> AUVParams:
    """The env's ``params`` on ``vehicle``: None (its 5-DOF model), an `AUVParams`, or a dict of
    field values [SI] replacing the vehicle's, with an optional ``scale`` dict of factors applied
    after them, e.g. ``{"m": 32.0, "scale": {"X_uu": 1.2}}``. An unknown name is a ValueError
    naming it."""
    vehicle.check_simulated()
    if params is not None and vehicle.hull_5dof is None:
        raise ValueError(
            f"params: vehicle {vehicle.name!r} has no [model_5dof] to change (its 5-DOF record "
            "is derived from the 6-DOF hull); edit the vehicle file's [model_6dof] instead"
        )
    if params is None:
        return vehicle.simulated_5dof()
    if isinstance(params, AUVParams):
        return params
    names = [f.name for f in fields(AUVParams)]
    if not isinstance(params, Mapping):
        raise ArgumentTypeError(
            f"params must be None, an AUVParams or a dict of its fields "
            f"(and 'scale'), got {params!r:.80}"
        )
    values = keys_within("params", params, [*names, "scale"])
    scale = keys_within("params scale", values.pop("scale", {}), names)
    for name, factor in scale.items():
        real(f"params scale {name}", factor)
    try:
        hull = vehicle.hull_5dof.replace(**values)
    except TypeError as exc:  # a wrong kind of value, named by AUVParams' own checks
        raise ArgumentTypeError(str(exc)) from None
    return hull.scaled(scale) if scale else hull


def actuators_from(
    vehicle: Vehicle, actuator_params: ActuatorParams | Mapping[str, Any] | None
) -> ActuatorParams:
    """The env's ``actuator_params`` on ``vehicle``: None (its propeller and fins), an
    `ActuatorParams`, or a dict of fields [SI] replacing the vehicle's; an unknown name is a
    ValueError naming it."""
    if actuator_params is None:
        return vehicle.actuators
    if isinstance(actuator_params, ActuatorParams):
        return actuator_params
    if not isinstance(actuator_params, Mapping):
        raise ArgumentTypeError(
            f"actuator_params must be None, an ActuatorParams or a dict of "
            f"its fields, got {actuator_params!r:.80}"
        )
    values = keys_within(
        "actuator_params", actuator_params, [f.name for f in fields(ActuatorParams)]
    )
    return dataclasses.replace(vehicle.actuators, **values)


def derived_5dof(vehicle: Vehicle) -> DerivedAUVParams:
    """The 5-DOF record of a vehicle without one, from its 6-DOF hull and actuators [SI].

    Derived: the rigid body (the spheroid's mass, weight = buoyancy, I_y and I_z about the
    origin, z_g, z_b), the added mass (the hull's Lamb factors), the axial drag
    X_u|u| = −½ρ S C_D0, the heave, pitch and yaw damping of the hull at `CRUISE_SPEED` u0 as
    u-proportional terms (Z_uw = −(d_33 + ½ρ S C_Lα u0)/u0 with the hull's lift slope, M_uq =
    −d_55/u0, N_ur = −d_66/u0, Y_uv as Z_uw), the fin authority |x_s| ½ρ A_s C_Ls, and the
    limits: full thrust at rest, the fins' moments at top speed and full deflection. The
    remaining coefficients (quadratic cross-flow, Munk and coupling terms) are 0: nothing that
    flies such a vehicle reads them (the 6-DOF plant has its own, docs/vehicles.md §1.3).
    """
    hull, actuators = vehicle.hull_6dof, vehicle.actuators
    if actuators is None:
        vehicle.check_simulated()
    rho, u0 = hull.water_density, CRUISE_SPEED
    aspect = hull.diameter**2 / hull.wing_area
    lift_slope = math.pi * aspect / (1.0 + math.sqrt(1.0 + (aspect / 2.0) ** 2))
    damping = np.diag(hull.damping_base)
    heave = -(damping[2] + 0.5 * rho * hull.wing_area * lift_slope * u0) / u0
    stern, rudder = actuators.fin_moment_coeff()
    n_rps = actuators.rpm_max / 60.0
    thrust = rho * actuators.prop_diameter**4 * actuators.kt_0 * n_rps * n_rps
    top = vehicle.max_surge
    return DerivedAUVParams(
        m=hull.mass_kg,
        W=hull.weight,
        B=hull.weight,
        I_y=float(hull.rigid_body[4, 4]),
        I_z=float(hull.rigid_body[5, 5]),
        z_g=float(hull.r_bg[2]),
        z_b=float(hull.r_bb[2]),
        X_udot=-float(hull.added_mass[0, 0]),
        Y_vdot=-float(hull.added_mass[1, 1]),
        Z_wdot=-float(hull.added_mass[2, 2]),
        M_qdot=-float(hull.added_mass[4, 4]),
        N_rdot=-float(hull.added_mass[5, 5]),
        X_uu=-0.5 * rho * hull.wing_area * hull.zero_lift_drag,
        X_vv=0.0,
        X_ww=0.0,
        X_qq=0.0,
        X_rr=0.0,
        X_vr=0.0,
        X_wq=0.0,
        Y_ur=0.0,
        Y_uv=heave,
        Y_vv=0.0,
        Z_uq=0.0,
        Z_uw=heave,
        Z_ww=0.0,
        M_qq=0.0,
        M_uq=float(-damping[4] / u0),
        M_uw=0.0,
        M_ww=0.0,
        N_uv=0.0,
        N_vv=0.0,
        N_ur=float(-damping[5] / u0),
        N_rr=0.0,
        fin_moment_coeff=stern,
        fin_max=min(actuators.delta_max_stern, actuators.delta_max_rudder),
        X_max=(1.0 - actuators.thrust_deduction) * thrust,
        M_max=stern * actuators.delta_max_stern * top * top,
        N_max=rudder * actuators.delta_max_rudder * top * top,
        max_surge=top,
        surge_coriolis=False,
    )
