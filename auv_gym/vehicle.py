"""5-DOF underactuated AUV model (MODEL.md §2): parameters and equations of motion.

State ν = (u, v, w, q, r) is the velocity relative to the water [m/s, rad/s]; pose
η = (x, y, z, θ, ψ) is earth-fixed NED (z down, θ nose-up positive) [m, rad]. Inputs
τ = (X, M, N) [N, N·m]; disturbances f = (f_u, f_v, f_w, f_q, f_r) [N, N·m].

The numeric kernels here are `numba.njit` functions of a packed parameter vector (see
`AUVParams.to_vector`), so that one copy of the equations serves the single env, the vector env,
the controllers' nominal models and the tests.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, fields

import numpy as np
from numba import njit

from auv_gym.validation import flag, real

__all__ = [
    "HYDRODYNAMIC_FIELDS",
    "N_PARAMS",
    "PARAM_INDEX",
    "AUVParams",
    "eta_dot",
    "eta_dot_trig",
    "nu_dot",
    "nu_dot_sin",
    "remus100",
]


@dataclass(frozen=True)
class AUVParams:
    """REMUS 100 (Prestero 2001) mapped onto the paper's 5-DOF form (MODEL.md §2.2).

    All values SI. Coefficient names follow Fossen/Prestero: ``X_uu`` is X_u|u| (the
    quadratic drag in u|u|), ``Y_vv`` is Y_v|v|, and so on. Signs are the NED signs of
    MODEL.md §2.1, where every coefficient enters with a ``+``.
    """

    m: float = 30.48  # [kg] W/g, W = 299 N
    W: float = 299.0  # [N] weight
    B: float = 299.0  # [N] buoyancy; neutral as in the paper (MODEL.md §2.1 f)
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
    X_vr: float = 35.5  # [kg/rad] used as (X_vr + m) v r, MODEL.md §2.1 c
    X_wq: float = -35.5  # [kg/rad] used as (X_wq − m) w q
    Y_ur: float = 5.22  # [kg/rad] added mass + fin lift (−0.93 + 6.15)
    Y_uv: float = -28.6  # [kg/m]
    Y_vv: float = -131.0  # [kg/m] Y_v|v|; table's −1310 read as a ×10 typo (MODEL.md §2.2 note 1)
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
    N_rr: float = -94.0  # [kg m²/rad²] N_r|r|, lost in the paper's OCR (MODEL.md §2.1 d)
    fin_moment_coeff: float = 6.15  # [kg/rad] |M_uuδs| = |N_uuδr|, fin moment per u² per rad
    fin_max: float = math.pi / 6.0  # [rad] fin deflection limit ±30°
    surge_coriolis: bool = True  # include (X_vr + m) v r + (X_wq − m) w q (MODEL.md §2.1 c)

    def __post_init__(self) -> None:
        for f in fields(self):
            check = flag if f.name == "surge_coriolis" else real  # True is no mass
            check(f"AUVParams.{f.name}", getattr(self, f.name))
        for name in ("m", "W", "B", "I_y", "I_z", "fin_max"):
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
        inertia are not uncertain (MODEL.md §10 item 7).
        """
        if not (math.isfinite(epsilon) and 0.0 <= epsilon < 1.0):
            raise ValueError(f"parameter uncertainty epsilon must be in [0, 1), got {epsilon}")
        delta = rng.uniform(-epsilon, epsilon, size=len(HYDRODYNAMIC_FIELDS))
        return self.scaled(dict(zip(HYDRODYNAMIC_FIELDS, 1.0 + delta, strict=True)))

    def to_vector(self) -> np.ndarray:
        """Pack into the float64 vector the numba kernels read (layout: `PARAM_INDEX`)."""
        vec = np.empty(N_PARAMS)
        for name, i in PARAM_INDEX.items():
            vec[i] = float(getattr(self, name))
        return vec


HYDRODYNAMIC_FIELDS: tuple[str, ...] = (
    "z_g", "X_udot", "Y_vdot", "Z_wdot", "M_qdot", "N_rdot", "X_uu", "X_vv", "X_ww", "X_qq",
    "X_rr", "X_vr", "X_wq", "Y_ur", "Y_uv", "Y_vv", "Z_uq", "Z_uw", "Z_ww", "M_qq", "M_uq",
    "M_uw", "M_ww", "N_uv", "N_vv", "N_ur", "N_rr",
)  # fmt: skip

PARAM_INDEX: dict[str, int] = {f.name: i for i, f in enumerate(fields(AUVParams))}
N_PARAMS = len(PARAM_INDEX)
# Kernel-side indices (numba needs plain integer globals).
_m, _W, _B, _Iy, _Iz, _zg, _zb = (
    PARAM_INDEX[k] for k in ("m", "W", "B", "I_y", "I_z", "z_g", "z_b")
)
_Xud, _Yvd, _Zwd, _Mqd, _Nrd = (
    PARAM_INDEX[k] for k in ("X_udot", "Y_vdot", "Z_wdot", "M_qdot", "N_rdot")
)
_Xuu, _Xvv, _Xww, _Xqq, _Xrr, _Xvr, _Xwq = (
    PARAM_INDEX[k] for k in ("X_uu", "X_vv", "X_ww", "X_qq", "X_rr", "X_vr", "X_wq")
)
_Yur, _Yuv, _Yvv = (PARAM_INDEX[k] for k in ("Y_ur", "Y_uv", "Y_vv"))
_Zuq, _Zuw, _Zww = (PARAM_INDEX[k] for k in ("Z_uq", "Z_uw", "Z_ww"))
_Mqq, _Muq, _Muw, _Mww = (PARAM_INDEX[k] for k in ("M_qq", "M_uq", "M_uw", "M_ww"))
_Nuv, _Nvv, _Nur, _Nrr = (PARAM_INDEX[k] for k in ("N_uv", "N_vv", "N_ur", "N_rr"))
_COR = PARAM_INDEX["surge_coriolis"]
FIN_COEFF_INDEX = PARAM_INDEX["fin_moment_coeff"]
FIN_MAX_INDEX = PARAM_INDEX["fin_max"]


def remus100(**overrides: float) -> AUVParams:
    """The default vehicle: REMUS 100 as in MODEL.md §2.2, with optional field overrides."""
    return AUVParams(**overrides)


@njit(cache=True, inline="always")
def nu_dot_sin(u, v, w, q, r, sin_theta, X, M, N, fu, fv, fw, fq, fr, p):
    """`nu_dot` given sin θ instead of θ (the simulator computes the trigonometry once)."""
    m = p[_m]
    zgW = p[_zg] * p[_W] - p[_zb] * p[_B]
    surge = X + fu + p[_Xuu] * u * abs(u) + p[_Xvv] * v * v + p[_Xww] * w * w
    surge += p[_Xqq] * q * q + p[_Xrr] * r * r
    surge += p[_COR] * ((p[_Xvr] + m) * v * r + (p[_Xwq] - m) * w * q)
    sway = fv - (m - p[_Yur]) * u * r + p[_Yuv] * u * v + p[_Yvv] * v * abs(v)
    heave = fw + (m + p[_Zuq]) * u * q + p[_Zuw] * u * w + p[_Zww] * w * abs(w)
    heave += m * p[_zg] * q * q
    pitch = M + fq + p[_Mqq] * q * abs(q) + p[_Muq] * u * q + p[_Muw] * u * w
    pitch += p[_Mww] * w * abs(w) - zgW * sin_theta - m * p[_zg] * (w * q - v * r)
    yaw = N + fr + p[_Nuv] * u * v + p[_Nvv] * v * abs(v) + p[_Nur] * u * r + p[_Nrr] * r * abs(r)
    return (
        surge / (m - p[_Xud]),
        sway / (m - p[_Yvd]),
        heave / (m - p[_Zwd]),
        pitch / (p[_Iy] - p[_Mqd]),
        yaw / (p[_Iz] - p[_Nrd]),
    )


@njit(cache=True, inline="always")
def nu_dot(u, v, w, q, r, theta, X, M, N, fu, fv, fw, fq, fr, p):
    """Accelerations (u̇, v̇, ẇ, q̇, ṙ) of MODEL.md §2.1 (paper (1), corrected) [m/s², rad/s²]."""
    return nu_dot_sin(u, v, w, q, r, math.sin(theta), X, M, N, fu, fv, fw, fq, fr, p)


@njit(cache=True, inline="always")
def eta_dot_trig(u, v, w, q, r, cth, sth, cps, sps):
    """`eta_dot` given cos θ, sin θ, cos ψ, sin ψ."""
    return (
        u * cps * cth - v * sps + w * cps * sth,
        u * sps * cth + v * cps + w * sps * sth,
        -u * sth + w * cth,
        q,
        r / cth,
    )


@njit(cache=True, inline="always")
def eta_dot(u, v, w, q, r, theta, psi):
    """Kinematics of MODEL.md §2.1 (paper (2)): (ẋ, ẏ, ż, θ̇, ψ̇) for body velocity (u, v, w)."""
    return eta_dot_trig(
        u, v, w, q, r, math.cos(theta), math.sin(theta), math.cos(psi), math.sin(psi)
    )
