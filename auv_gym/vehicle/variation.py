"""Per-episode variation of the hull within stated ranges: mass, centre of gravity, added mass
and damping (docs/model.md §15.3).

`param_uncertainty` scales the hydrodynamic coefficients of either plant (the paper's "model
perturbation"); a hull as built differs in more than that: its mass and inertia are known to a
few per cent, its centre of gravity to millimetres, and its added mass and damping per axis.
`HullVariation` draws all of them per episode, from the episode's own random stream
(`auv_gym.sim.simulator`), so that every other draw of a seed is the same with or without it,
and both plants read the same draw:

- **mass** ε_m: the rigid-body mass and inertias × f_m, f_m = 1 + U[−ε_m, ε_m], and the weight
  with them; the buoyancy stays. The 6-DOF plant then has a net buoyancy (B − W) of −(f_m − 1)·W
  (a ballast error); the 5-DOF model has no (W − B) force (docs/model.md §2.1 f) and sees the
  mass in its inertias and in the restoring moment z_g·W;
- **cg_offset** d [m]: the centre of gravity moved by U[−d, d] along x and along z (the 5-DOF
  model has no x_g and takes the z part only); ``d`` must stay below z_g − z_b, so that the
  vehicle stays upright in pitch and roll;
- **added_mass** ε_a: the added mass of each axis (surge, sway, heave, roll, pitch, yaw) ×
  1 + U[−ε_a, ε_a], one factor per axis;
- **damping** ε_d: every damping and drag term of each axis's equation × 1 + U[−ε_d, ε_d], one
  factor per axis (5-DOF: X_u|u|, X_qq, X_rr in surge; Y_v|v|, Y_uv in sway; ...; 6-DOF: the
  linear damping of the axis, and the axial drag C_D0 with surge), and one more for the 6-DOF
  cross-flow drag coefficient, which acts on sway, heave, pitch and yaw together.

The draw takes 16 uniforms in a fixed order whatever the plant (`HullDraw`); a range of 0 gives
factors of exactly 1 and offsets of exactly 0.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from auv_gym.support.validation import ArgumentTypeError, keys_within, real
from auv_gym.vehicle.params import AUVParams
from auv_gym.vehicle.remus6dof import RK4_STEP_LIMIT, SixDofVehicle, rigid_body_matrix
from auv_gym.vehicle.six_dof import SIX_DOF

__all__ = [
    "ADDED_MASS_FIELDS",
    "DAMPING_FIELDS",
    "MAX_COEFFICIENT_VARIATION",
    "MAX_MASS_VARIATION",
    "HullDraw",
    "HullVariation",
    "varied_hull_row",
    "varied_params",
]

MAX_MASS_VARIATION = 0.5  # ε_m: the mass between half and one and a half times its record
MAX_COEFFICIENT_VARIATION = 0.9  # ε_a, ε_d: a coefficient between 0.1 and 1.9 times its record
AXES = ("surge", "sway", "heave", "roll", "pitch", "yaw")
# The 5-DOF record's added mass per axis (no roll: the paper's model has none).
ADDED_MASS_FIELDS = {
    "surge": ("X_udot",),
    "sway": ("Y_vdot",),
    "heave": ("Z_wdot",),
    "pitch": ("M_qdot",),
    "yaw": ("N_rdot",),
}
# The 5-DOF record's damping and drag terms per axis: each equation's terms in |·|·, u·, qq, rr
# (docs/model.md §2.1); the Munk moments and the Coriolis-like terms are added mass, not damping.
DAMPING_FIELDS = {
    "surge": ("X_uu", "X_qq", "X_rr"),
    "sway": ("Y_vv", "Y_uv"),
    "heave": ("Z_ww", "Z_uw"),
    "pitch": ("M_qq", "M_uq", "M_ww"),
    "yaw": ("N_rr", "N_vv", "N_ur"),
}
_DRAWS = 16  # mass; cg x, z; added mass × 6; damping × 6; cross-flow


@dataclass(frozen=True)
class HullDraw:
    """One episode's variation: factors (dimensionless) and the centre of gravity's offset [m]."""

    mass: float  # f_m on the rigid-body mass, inertias and weight
    cg_offset: tuple[float, float]  # [m] (Δx_g, Δz_g)
    added_mass: tuple[float, ...]  # per axis, `AXES` order
    damping: tuple[float, ...]  # per axis, `AXES` order
    crossflow: float  # the 6-DOF cross-flow drag coefficient's factor


@dataclass(frozen=True)
class HullVariation:
    """The ranges of the per-episode hull draws (module doc); all 0 (the default): no variation."""

    mass: float = 0.0  # ε_m in [0, MAX_MASS_VARIATION]
    cg_offset: float = 0.0  # [m] d >= 0, below the vehicle's z_g − z_b
    added_mass: float = 0.0  # ε_a in [0, MAX_COEFFICIENT_VARIATION]
    damping: float = 0.0  # ε_d in [0, MAX_COEFFICIENT_VARIATION]

    def __post_init__(self) -> None:
        put = object.__setattr__
        put(self, "mass", real("hull_variation.mass", self.mass, 0.0, MAX_MASS_VARIATION))
        put(self, "cg_offset", real("hull_variation.cg_offset", self.cg_offset, 0.0, 1.0, unit="m"))
        for name in ("added_mass", "damping"):
            value = getattr(self, name)
            put(self, name, real(f"hull_variation.{name}", value, 0.0, MAX_COEFFICIENT_VARIATION))

    @classmethod
    def from_spec(cls, spec: HullVariation | Mapping[str, Any] | None) -> HullVariation:
        """From the env argument: None (no variation), a `HullVariation`, or a mapping of its
        fields ({"mass": 0.05, "cg_offset": 0.005, ...}; the others 0)."""
        if spec is None:
            return cls()
        if isinstance(spec, cls):
            return spec
        if not isinstance(spec, Mapping):
            raise ArgumentTypeError(
                "hull_variation must be None, a HullVariation or a mapping of mass, cg_offset, "
                f"added_mass and damping, got {spec!r:.80}"
            )
        keys_within("hull_variation", spec, [f.name for f in dataclasses.fields(cls)])
        return cls(**spec)

    @property
    def active(self) -> bool:
        """True when some range is above 0."""
        return any((self.mass, self.cg_offset, self.added_mass, self.damping))

    def draw(self, rng: np.random.Generator) -> HullDraw:
        """One episode's draw: 16 uniforms of ``rng`` in a fixed order (module doc)."""
        u = rng.uniform(-1.0, 1.0, _DRAWS)
        return HullDraw(
            mass=1.0 + self.mass * float(u[0]),
            cg_offset=(self.cg_offset * float(u[1]), self.cg_offset * float(u[2])),
            added_mass=tuple(1.0 + self.added_mass * u[3:9]),
            damping=tuple(1.0 + self.damping * u[9:15]),
            crossflow=1.0 + self.damping * float(u[15]),
        )

    def check(
        self, params: AUVParams, hull: SixDofVehicle | None, physics_dt: float, uncertainty: float
    ) -> None:
        """ValueError (one line, naming the range) unless every draw, on top of parameter
        uncertainty ``uncertainty``, is a valid vehicle: upright (the centre of gravity below
        the centre of buoyancy), positive inertias, and on the 6-DOF ``hull`` (None: the 5-DOF
        plant) modes RK4 can step at ``physics_dt`` [s]."""
        if not self.active:
            return
        plant, arm = "5-DOF", params.z_g - params.z_b
        if hull is not None:
            plant, arm = "6-DOF", hull.r_bg[2] - hull.r_bb[2]
        if not self.cg_offset < arm:
            raise ValueError(
                f"hull_variation.cg_offset = {self.cg_offset:g} m can lift the centre of "
                f"gravity above the centre of buoyancy (z_g − z_b = {arm:g} m on the {plant} "
                "plant): use a smaller offset"
            )
        low = 1.0 - self.mass
        if hull is None:
            high = (1.0 + self.added_mass) * (1.0 + uncertainty)
            for axis, added in ADDED_MASS_FIELDS.items():
                rigid = {"yaw": params.I_z, "pitch": params.I_y}.get(axis, params.m)
                coefficient = getattr(params, added[0])
                if coefficient > 0.0 and not rigid * low - coefficient * high > 0.0:
                    raise ValueError(
                        f"hull_variation (mass {self.mass:g}, added_mass {self.added_mass:g}) "
                        f"can draw a non-positive {axis} inertia from {added[0]} = "
                        f"{coefficient:g}: use smaller ranges"
                    )
            return
        # A bound on the fastest mode: a damped one moves at damping over inertia, a restoring
        # one (roll, pitch) at sqrt(weight × arm / inertia); each at its draws' extreme.
        least_inertia = min(low, 1.0 - self.added_mass)
        damped = (1.0 + self.damping) / least_inertia
        restoring = math.sqrt((1.0 + self.mass) * (arm + self.cg_offset) / (arm * least_inertia))
        stiff = (1.0 + uncertainty) / (1.0 - uncertainty)  # parameter uncertainty's own end
        rate = hull.stiffest_rate()[0] * stiff * max(damped, restoring)
        if rate * physics_dt > RK4_STEP_LIMIT:
            raise ValueError(
                f"hull_variation (mass {self.mass:g}, added_mass {self.added_mass:g}, damping "
                f"{self.damping:g}) can draw a hull mode at {rate:.4g} rad/s, faster than RK4 at "
                f"physics_dt = {physics_dt:g} s can step (|λ|·dt <= {RK4_STEP_LIMIT:g}): use "
                f"physics_dt <= {RK4_STEP_LIMIT / rate:.3g} s or smaller ranges"
            )


def varied_params(params: AUVParams, draw: HullDraw) -> AUVParams:
    """The 5-DOF record with one episode's draw applied (module doc)."""
    factors = {name: draw.mass for name in ("m", "W", "I_y", "I_z")}
    for k, axis in enumerate(AXES):
        factors.update({name: draw.added_mass[k] for name in ADDED_MASS_FIELDS.get(axis, ())})
        factors.update({name: draw.damping[k] for name in DAMPING_FIELDS.get(axis, ())})
    changes = {name: getattr(params, name) * f for name, f in factors.items()}
    changes["z_g"] = params.z_g + draw.cg_offset[1]
    return params.replace(**changes)


def varied_hull_row(hull: SixDofVehicle, draw: HullDraw) -> np.ndarray:
    """The 6-DOF hull's kernel row (`SixDofVehicle.kernel_vector`) with one episode's draw
    applied: M_RB from the drawn mass about the moved centre of gravity, M_A per axis, their
    inverse, the damping per axis, the weight; the buoyancy stays (module doc)."""
    row = hull.kernel_vector()
    dx, dz = draw.cg_offset
    r_bg = (hull.r_bg[0] + dx, hull.r_bg[1], hull.r_bg[2] + dz)
    f = draw.mass
    rigid = rigid_body_matrix(hull.mass_kg * f, hull.roll_inertia * f, hull.pitch_inertia * f, r_bg)
    added = hull.added_mass * np.asarray(draw.added_mass)  # diagonal: column j × f_j
    mass = rigid + added
    for name, matrix in (("mass", mass), ("added", added), ("inverse_mass", np.linalg.inv(mass))):
        start = getattr(SIX_DOF, f"{name}_00")
        row[start : start + 36] = matrix.reshape(-1)
    for k, axis in enumerate("uvwpqr"):
        row[getattr(SIX_DOF, f"damping_{axis}")] *= draw.damping[k]
    row[SIX_DOF.zero_lift_drag] *= draw.damping[0]
    row[SIX_DOF.crossflow_coeff] *= draw.crossflow
    row[SIX_DOF.weight] = hull.weight * draw.mass
    row[SIX_DOF.x_g], row[SIX_DOF.z_g] = r_bg[0], r_bg[2]
    return row
