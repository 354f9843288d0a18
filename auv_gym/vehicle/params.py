"""REMUS 100 parameters (docs/model.md §2.2) and their packed form for the numba kernels.

`AUVParams` holds the coefficients of the equations of motion in `auv_gym.vehicle.dynamics`.
`AUVParams.to_vector` packs them into the float64 row the kernels read (layout `PARAM_NAMES`: the
fields, then the inertias m11 … I66 it derives), and `params_record` lets a kernel read that row
by name, ``p.X_uu``, from registers.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numba import njit

from auv_gym.support.records import fixed_tuple, record_type
from auv_gym.support.validation import ArgumentTypeError, flag, keys_within, real

__all__ = [
    "DERIVED_INERTIAS",
    "HYDRODYNAMIC_FIELDS",
    "N_PARAMS",
    "PARAM_INDEX",
    "PARAM_NAMES",
    "AUVParams",
    "ParamsRecord",
    "params_from_spec",
    "params_record",
    "remus100",
]


# The quadratic drag of each axis on its own velocity (X_u|u|, Y_v|v|, Z_w|w|, M_q|q|, N_r|r|).
DISSIPATIVE_DRAG = ("X_uu", "Y_vv", "Z_ww", "M_qq", "N_rr")


@dataclass(frozen=True)
class AUVParams:
    """REMUS 100 (Prestero 2001) mapped onto the paper's 5-DOF form (docs/model.md §2.2).

    All values SI. Coefficient names follow Fossen/Prestero: ``X_uu`` is X_u|u| (the
    quadratic drag in u|u|), ``Y_vv`` is Y_v|v|, and so on. Signs are the NED signs of
    docs/model.md §2.1, where every coefficient enters with a ``+``.
    """

    m: float = 30.48  # [kg] W/g, W = 299 N
    W: float = 299.0  # [N] weight
    B: float = 299.0  # [N] buoyancy; neutral as in the paper (docs/model.md §2.1 f)
    I_y: float = 3.45  # [kg m²]
    I_z: float = 3.45  # [kg m²]
    z_g: float = 0.0196  # [m] CG below CB
    z_b: float = 0.0  # [m]
    X_udot: float = -0.93  # [kg] added mass
    Y_vdot: float = -35.5  # [kg]
    Z_wdot: float = -35.5  # [kg]
    M_qdot: float = -4.88  # [kg m²/rad]
    N_rdot: float = -4.88  # [kg m²/rad]
    X_uu: float = -1.62  # [kg/m] axial drag X_u|u|
    X_vv: float = 0.0  # [kg/m] not in Prestero
    X_ww: float = 0.0  # [kg/m] not in Prestero
    X_qq: float = -1.93  # [kg m/rad]
    X_rr: float = -1.93  # [kg m/rad]
    X_vr: float = 35.5  # [kg/rad] used as (X_vr + m) v r, docs/model.md §2.1 c
    X_wq: float = -35.5  # [kg/rad] used as (X_wq − m) w q
    Y_ur: float = 5.22  # [kg/rad] added mass + fin lift (−0.93 + 6.15)
    Y_uv: float = -28.6  # [kg/m]
    Y_vv: float = -131.0  # [kg/m] Y_v|v|; table's −1310 is a ×10 typo (docs/model.md §2.2)
    Z_uq: float = -5.22  # [kg/rad]
    Z_uw: float = -28.6  # [kg/m]
    Z_ww: float = -131.0  # [kg/m] Z_w|w|
    M_qq: float = -188.0  # [kg m²/rad²] M_q|q|
    M_uq: float = -2.0  # [kg m/rad]
    M_uw: float = 24.0  # [kg] Munk − body − fin lift (destabilising)
    M_ww: float = 0.0  # [kg] M_w|w|; Prestero +3.18, absent from the paper's form
    N_uv: float = -24.0  # [kg]
    N_vv: float = -3.18  # [kg] N_v|v|
    N_ur: float = -2.0  # [kg m/rad]
    N_rr: float = -94.0  # [kg m²/rad²] N_r|r|, lost in the paper's OCR (docs/model.md §2.1 d)
    fin_moment_coeff: float = 6.15  # [kg/rad] |M_uuδs| = |N_uuδr|, fin moment per u² per rad
    fin_max: float = math.pi / 6.0  # [rad] fin deflection limit ±30°
    # Actuator limits (docs/model.md §2.3): |X| <= X_max; |M| <= M_max, |N| <= N_max for the
    # "paper" model ("fins" bounds M, N by the fin authority instead). Plant and controllers
    # read them from here (`actuator_limits`, `controllers.base.actuator_vector`).
    X_max: float = 50.0  # [N]
    M_max: float = 10.0  # [N·m]
    N_max: float = 10.0  # [N·m]
    # Top speed u_max [m/s]: the default surge limit of the speed-limited env ids
    # (`surge_limit="vehicle"`, `auv_gym.sim.task`) and the observation's speed scale
    # (`observation.vehicle_speed_bound`); below REMUS 100's ~2.3-2.5 m/s at full thrust.
    max_surge: float = 2.0  # [m/s]
    surge_coriolis: bool = True  # include (X_vr + m) v r + (X_wq − m) w q (docs/model.md §2.1 c)

    def __post_init__(self) -> None:
        for f in fields(self):
            check = flag if f.name == "surge_coriolis" else real  # True is no mass
            check(f"AUVParams.{f.name}", getattr(self, f.name))
        for name in (
            "m",
            "W",
            "B",
            "I_y",
            "I_z",
            "fin_max",
            "X_max",
            "M_max",
            "N_max",
            "max_surge",
        ):
            if getattr(self, name) <= 0.0:
                raise ValueError(f"AUVParams.{name} must be positive, got {getattr(self, name)}")
        for name, value in (
            ("m11 = m − X_udot", self.m11),
            ("m22 = m − Y_vdot", self.m22),
            ("m33 = m − Z_wdot", self.m33),
            ("I55 = I_y − M_qdot", self.I55),
            ("I66 = I_z − N_rdot", self.I66),
        ):
            if value <= 0.0:
                raise ValueError(f"AUVParams: {name} must be positive, got {value}")
        if self.fin_max > math.pi / 2:
            raise ValueError(f"AUVParams.fin_max must be in (0, π/2] rad, got {self.fin_max}")
        if self.fin_moment_coeff < 0.0:
            raise ValueError("AUVParams.fin_moment_coeff must be non-negative")
        # Each axis's own quadratic drag enters with a + (docs/model.md §2.1) and must oppose
        # its motion: a positive one feeds energy in (a sign lost in a copy, or a scale of −1).
        for name in DISSIPATIVE_DRAG:
            if getattr(self, name) > 0.0:
                raise ValueError(
                    f"AUVParams.{name} must be ≤ 0 (a drag that opposes the motion), got "
                    f"{getattr(self, name)}"
                )

    @property
    def m11(self) -> float:
        """Surge inertia m − X_u̇ [kg]."""
        return self.m - self.X_udot

    @property
    def m22(self) -> float:
        """Sway inertia m − Y_v̇ [kg]."""
        return self.m - self.Y_vdot

    @property
    def m33(self) -> float:
        """Heave inertia m − Z_ẇ [kg]."""
        return self.m - self.Z_wdot

    @property
    def I55(self) -> float:
        """Pitch inertia I_y − M_q̇ [kg m²]."""
        return self.I_y - self.M_qdot

    @property
    def I66(self) -> float:
        """Yaw inertia I_z − N_ṙ [kg m²]."""
        return self.I_z - self.N_rdot

    @property
    def actuator_limits(self) -> tuple[float, float, float]:
        """(X_max [N], M_max [N·m], N_max [N·m])."""
        return self.X_max, self.M_max, self.N_max

    def replace(self, **changes: float) -> AUVParams:
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def scaled(self, factors: dict[str, float]) -> AUVParams:
        """A copy with the named coefficients multiplied by the given factors."""
        unknown = set(factors) - {f.name for f in fields(self)}
        if unknown:
            raise ValueError(f"unknown AUVParams fields: {sorted(unknown)}")
        return self.replace(**{k: getattr(self, k) * v for k, v in factors.items()})

    def perturbed(self, rng: np.random.Generator, epsilon: float) -> AUVParams:
        """A copy with each hydrodynamic coefficient scaled by 1 + δ, δ ~ U[−ε, ε].

        The perturbed set is `HYDRODYNAMIC_FIELDS` (added mass, damping, lift, Munk and
        cross-flow terms, and z_g for the restoring moment z_g W); rigid-body mass and
        inertia are not uncertain (docs/model.md §2.5).
        """
        if not (math.isfinite(epsilon) and 0.0 <= epsilon < 1.0):
            raise ValueError(f"parameter uncertainty epsilon must be in [0, 1), got {epsilon}")
        delta = rng.uniform(-epsilon, epsilon, size=len(HYDRODYNAMIC_FIELDS))
        return self.scaled(dict(zip(HYDRODYNAMIC_FIELDS, 1.0 + delta, strict=True)))

    def check_perturbation(self, epsilon: float) -> None:
        """Raise ValueError, naming the coefficient, if some draw of `perturbed` with this ε
        could be an invalid vehicle; every draw is valid otherwise.

        A draw scales each coefficient by a factor f = 1 + δ ≤ 1 + ε (floating-point rounding
        is monotonic, so the bound holds for the computed products too). The checks of
        `AUVParams` that a scaled coefficient enters are the inertias m − X_u̇ … I_z − N_ṙ > 0,
        smallest at f = 1 + ε for a positive added mass, and finiteness, worst at f = 1 + ε.
        """
        if not (math.isfinite(epsilon) and 0.0 <= epsilon < 1.0):
            raise ValueError(f"parameter uncertainty epsilon must be in [0, 1), got {epsilon}")
        most = 1.0 + epsilon
        for name in HYDRODYNAMIC_FIELDS:
            if not math.isfinite(getattr(self, name) * most):
                raise ValueError(
                    f"param_uncertainty = {epsilon:g} can scale AUVParams.{name} = "
                    f"{getattr(self, name):g} beyond the float range"
                )
        for inertia, rigid, added in (
            ("m11", "m", "X_udot"),
            ("m22", "m", "Y_vdot"),
            ("m33", "m", "Z_wdot"),
            ("I55", "I_y", "M_qdot"),
            ("I66", "I_z", "N_rdot"),
        ):
            body, coefficient = getattr(self, rigid), getattr(self, added)
            worst = body - coefficient * most
            if coefficient > 0.0 and not worst > 0.0:
                raise ValueError(
                    f"param_uncertainty = {epsilon:g} can draw an invalid vehicle: {inertia} = "
                    f"{rigid} - {added}·(1 + δ) falls to {worst:.4g} at δ = +{epsilon:g} "
                    f"({rigid} = {body:g}, {added} = {coefficient:g}); use param_uncertainty < "
                    f"{body / coefficient - 1.0:.4g} or a smaller {added}"
                )

    def to_vector(self) -> np.ndarray:
        """Pack into the float64 row the numba kernels read (layout `PARAM_NAMES`)."""
        return np.array([float(getattr(self, name)) for name in PARAM_NAMES])


HYDRODYNAMIC_FIELDS: tuple[str, ...] = (
    "z_g",
    "X_udot",
    "Y_vdot",
    "Z_wdot",
    "M_qdot",
    "N_rdot",
    "X_uu",
    "X_vv",
    "X_ww",
    "X_qq",
    "X_rr",
    "X_vr",
    "X_wq",
    "Y_ur",
    "Y_uv",
    "Y_vv",
    "Z_uq",
    "Z_uw",
    "Z_ww",
    "M_qq",
    "M_uq",
    "M_uw",
    "M_ww",
    "N_uv",
    "N_vv",
    "N_ur",
    "N_rr",
)

# The diagonal of M = M_RB + M_A, packed after the fields so that the kernels divide by the
# values `AUVParams` derives instead of recomputing them.
DERIVED_INERTIAS = ("m11", "m22", "m33", "I55", "I66")
PARAM_NAMES: tuple[str, ...] = (*(f.name for f in fields(AUVParams)), *DERIVED_INERTIAS)
PARAM_INDEX: dict[str, int] = {name: i for i, name in enumerate(PARAM_NAMES)}
N_PARAMS = len(PARAM_NAMES)
ParamsRecord = record_type("ParamsRecord", PARAM_NAMES, __name__)


def params_from_spec(spec: AUVParams | Mapping[str, Any] | None) -> AUVParams:
    """The vehicle of the env's ``params`` argument: None (REMUS 100), an `AUVParams`, or a dict
    of field values [SI] with an optional ``scale`` dict of factors on REMUS 100's fields, e.g.
    ``{"m": 32.0, "scale": {"X_uu": 1.2}}`` (values first, then the factors). An unknown name
    raises ValueError naming it."""
    if spec is None:
        return remus100()
    if isinstance(spec, AUVParams):
        return spec
    names = [f.name for f in fields(AUVParams)]
    if not isinstance(spec, Mapping):
        raise ArgumentTypeError(
            f"params must be None, an AUVParams or a dict of its fields "
            f"(and 'scale'), got {spec!r:.80}"
        )
    values = keys_within("params", spec, [*names, "scale"])
    scale = values.pop("scale", {})
    scale = keys_within("params scale", scale, names)
    for name, factor in scale.items():
        real(f"params scale {name}", factor)
    try:
        params = AUVParams(**values)
    except TypeError as exc:  # a wrong kind of value, named by AUVParams' own checks
        raise ArgumentTypeError(str(exc)) from None
    return params.scaled(scale) if scale else params


def remus100(**overrides: float) -> AUVParams:
    """The default vehicle: REMUS 100 as in docs/model.md §2.2, with optional field overrides."""
    return AUVParams(**overrides)


@njit(cache=True, inline="always")
def params_record(p):
    """The packed row ``p`` (`AUVParams.to_vector`) as a `ParamsRecord` held in registers."""
    return ParamsRecord(*fixed_tuple(p, N_PARAMS))
