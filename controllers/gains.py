"""Gains of the paper's controllers (docs/model.md §3.4, §4.6), packed for the kernels."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from auv_gym.support.validation import flag, real

__all__ = ["GAIN_LAYOUT", "ControllerGains", "MembershipSet"]


@dataclass(frozen=True)
class MembershipSet:
    """Five Gaussian MFs per input: centres c_j = −p + (j − 1)·q_mf, widths σ (f̂), σ_b (b̂).

    d̂(S) uses three Gaussians of width σ_d centred at −σ_d, 0, +σ_d (docs/model.md §4.5).
    Units follow the fuzzy inputs (u, v, w [m/s], q, r [rad/s]) and S of the loop.
    """

    p: float
    q_mf: float
    sigma: float
    sigma_b: float
    sigma_d: float

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"MembershipSet.{f.name} must be positive, got {value}")


NON_NEGATIVE = ("sigma_leak", "ilos_y", "ilos_z")  # gains where 0 switches a feature off
OBSERVER_STEP_LIMIT = 2.0 * math.sqrt(2.0) - 2.0
# The current guidance (`controllers.alos`), checked with `auv_gym.support.validation.real`:
# name -> (low, high, low_open, high_open, unit); 0 switches the observer and the trims off.
GUIDANCE_RANGES = {
    "current_observer": (0.0, math.inf, False, False, "rad/s"),
    "dvl_current": (0.0, math.inf, False, False, "rad/s"),
    "alos_y": (0.0, math.inf, False, False, "rad/(m·s)"),
    "alos_z": (0.0, math.inf, False, False, "rad/(m·s)"),
    "alos_radius": (0.0, math.inf, True, False, "m"),
    "alos_max": (0.0, math.pi / 2, True, True, "rad"),
}


@dataclass(frozen=True)
class ControllerGains:
    """Gains and widths; the defaults are the paper's Section 6 as read in docs/model.md §4.6.

    Surge: Ṡ1 = −(h1 + λ1)S1. Pitch: z1 = θ − θ_d, α1 = −k1 z1 + θ̇_d, S2 = c1 z1 + z2.
    Yaw: z3 = ψ − ψ_d, α2 = cosθ(−k2 z3 + ψ̇_d), S3 = c2 z3 + z4. LOS (docs/model.md §3.4):
    ψ_d = ψ_F − arctan(k_y y_e) − β, θ_d = sat(θ_F + arctan(k_z z_e) + α, ±θ_max), with the
    corrections command-filtered (2nd order, ω_n, ζ; docs/model.md §10.4).

    ``ilos_y``, ``ilos_z`` > 0 switch on integral LOS (Børhaug, Pavlov & Pettersen 2008;
    Caharija et al. 2016), not in the paper: y_e is replaced by y_e + σ_y y_int with
    ẏ_int = k_y y_e / (1 + k_y²(y_e + σ_y y_int)²) (likewise z), which removes the steady
    cross-track offset a constant ocean current leaves on a straight path. 0 = the paper's LOS.

    ``current_observer`` > 0 (ω_o [rad/s]) switches on the current observer and the crab angles
    from the estimated velocity over ground; ``alos_y``, ``alos_z`` > 0 (γ_h, γ_v [rad/(m·s)])
    the adaptive LOS trims β̂, α̂, gated to within ``alos_radius`` of the virtual point and
    projected to ±``alos_max``; ``speed_over_ground`` makes the surge reference the speed
    through the water that gives u_D over ground along the path (needs a current estimate).
    ``dvl_current`` > 0 (ω_c [rad/s]) takes that estimate from the DVL instead of the observer:
    the difference of its velocities over ground and through the water, low-passed at ω_c; it
    needs the observation's velocity over ground (``observation="preview"``). All of it is
    `controllers.alos`; none of it is in the paper (0 / False = the paper's guidance).
    """

    h1: float = 1.0
    lam1: float = 0.1
    h2: float = 0.3
    lam2: float = 0.1
    h3: float = 0.2
    lam3: float = 0.1
    k1: float = 5.0  # [1/s] pitch
    c1: float = 3.0  # [1/s]
    k2: float = 0.3  # [1/s] yaw
    c2: float = 2.0  # [1/s]
    k_y: float = 0.1  # [1/m] calm-function gains
    k_z: float = 0.5  # [1/m]
    theta_max: float = math.radians(40.0)  # [rad] θ_d saturation
    filter_wn: float = 2.0  # [rad/s]
    filter_zeta: float = 1.0
    u_guard: float = 0.1  # [m/s] α = β = 0 below this surge speed
    sideslip_3d: bool = False  # divide β by cos θ_F (docs/model.md §10.5); paper: False
    printed_pitch_los: bool = False  # the paper's misprinted θ_d = θ_F − arctan(k_z z_e) − α
    alpha_f: float = 1.0  # adaptation gains (docs/model.md §4.6, chosen)
    alpha_b: float = 0.1
    alpha_d: float = 0.1
    sigma_leak: float = 0.0  # σ-modification leakage (docs/model.md §4.8); 0 = paper-faithful
    ilos_y: float = 0.0  # integral-LOS gain σ_y (horizontal); 0 = paper's LOS
    ilos_z: float = 0.0  # integral-LOS gain σ_z (vertical); 0 = paper's LOS
    current_observer: float = 0.0  # [rad/s] observer bandwidth ω_o; 0 = off (controllers.alos)
    alos_y: float = 0.0  # [rad/(m·s)] ALOS adaptation gain γ_h; 0 = off
    alos_z: float = 0.0  # [rad/(m·s)] ALOS adaptation gain γ_v; 0 = off
    alos_radius: float = 1.0  # [m] capture radius R of the ALOS gate
    alos_max: float = 0.5  # [rad] projection bound M of β̂, α̂
    speed_over_ground: bool = False  # surge reference for u_D over ground (needs a current source)
    dvl_current: float = 0.0  # [rad/s] bandwidth ω_c of the current read from the DVL; 0 = off
    separate_b_basis: bool = False  # False: b̂ shares f̂'s basis (σ_b = σ), as the prototype
    surge_mf: MembershipSet = MembershipSet(1.0, 0.5, 1.0, 0.1, 1.0)
    pitch_mf: MembershipSet = MembershipSet(
        math.pi / 3, math.pi / 6, math.pi / 6, math.pi / 24, math.pi / 12
    )
    yaw_mf: MembershipSet = MembershipSet(math.pi / 3, math.pi / 6, 1 / 3, math.pi / 12, 1 / 6)

    def __post_init__(self) -> None:
        for name, (low, high, low_open, high_open, unit) in GUIDANCE_RANGES.items():
            real(
                f"ControllerGains.{name}",
                getattr(self, name),
                low,
                high,
                low_open=low_open,
                high_open=high_open,
                unit=unit,
            )
        flag("ControllerGains.speed_over_ground", self.speed_over_ground)
        if self.speed_over_ground and self.current_observer == 0.0 and self.dvl_current == 0.0:
            raise ValueError(
                "ControllerGains.speed_over_ground=True needs current_observer > 0 or "
                "dvl_current > 0 (the speed over ground comes from the current estimate)"
            )
        if self.current_observer > 0.0 and self.dvl_current > 0.0:
            raise ValueError(
                "ControllerGains.current_observer and dvl_current are two sources of the same "
                f"current estimate; switch one off (got {self.current_observer} and "
                f"{self.dvl_current} rad/s)"
            )
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, (bool, MembershipSet)) or f.name in GUIDANCE_RANGES:
                continue
            if not math.isfinite(value):
                raise ValueError(f"ControllerGains.{f.name} must be finite, got {value}")
            if f.name in NON_NEGATIVE:
                if value < 0:
                    raise ValueError(f"ControllerGains.{f.name} must be >= 0, got {value}")
            elif value <= 0:
                raise ValueError(f"ControllerGains.{f.name} must be positive, got {value}")
        if self.theta_max >= math.pi / 2:
            raise ValueError("ControllerGains.theta_max must be below π/2")


# Packed layout read by the numba kernels; extra entries are filled by the controller.
GAIN_LAYOUT = (
    "h1",
    "lam1",
    "h2",
    "lam2",
    "h3",
    "lam3",
    "k1",
    "c1",
    "k2",
    "c2",
    "k_y",
    "k_z",
    "theta_max",
    "filter_wn",
    "filter_zeta",
    "u_guard",
    "sideslip_3d",
    "printed_pitch_los",
    "alpha_f",
    "alpha_b",
    "alpha_d",
    "sigma_leak",
    "separate_b_basis",
    "ilos_y",
    "ilos_z",
    "current_observer",
    "alos_y",
    "alos_z",
    "alos_radius",
    "alos_max",
    "speed_over_ground",
    "dvl_current",
    "mf1_c0",
    "mf1_dc",
    "mf1_s",
    "mf1_sb",
    "mf1_sd",
    "mf2_c0",
    "mf2_dc",
    "mf2_s",
    "mf2_sb",
    "mf2_sd",
    "mf3_c0",
    "mf3_dc",
    "mf3_s",
    "mf3_sb",
    "mf3_sd",
    "dt",
    "b1",
    "b5",
    "b6",
    "fins",
    "fin_gain",
    "X_max",
    "M_max",
    "N_max",
)
(
    H1,
    LAM1,
    H2,
    LAM2,
    H3,
    LAM3,
    K1,
    C1,
    K2,
    C2,
    KY,
    KZ,
    THETA_MAX,
    WN,
    ZETA,
    U_GUARD,
    BETA_3D,
    PRINTED_PITCH,
    ALPHA_F,
    ALPHA_B,
    ALPHA_D,
    SIGMA_LEAK,
    SEPARATE_B,
    ILOS_Y,
    ILOS_Z,
    OBSERVER_WN,
    ALOS_Y,
    ALOS_Z,
    ALOS_RADIUS,
    ALOS_MAX,
    SPEED_OVER_GROUND,
    DVL_CURRENT,
    MF1,
    _m1b,
    _m1c,
    _m1d,
    _m1e,
    MF2,
    _m2b,
    _m2c,
    _m2d,
    _m2e,
    MF3,
    _m3b,
    _m3c,
    _m3d,
    _m3e,
    DT,
    B1,
    B5,
    B6,
    FINS,
    FIN_GAIN,
    X_MAX,
    M_MAX,
    N_MAX,
) = range(len(GAIN_LAYOUT))


def pack_gains(
    gains: ControllerGains,
    dt: float,
    b: tuple[float, float, float],
    actuator: tuple[float, float, float, float, float],
) -> np.ndarray:
    """The float64 vector of `GAIN_LAYOUT` for the kernels (dt [s]: the control period)."""
    # the discretised current observer is stable for ω_o Δt < 2√2 − 2 (controllers.alos, 1)
    if gains.current_observer * dt >= OBSERVER_STEP_LIMIT:
        raise ValueError(
            f"ControllerGains.current_observer × control_dt must be below "
            f"{OBSERVER_STEP_LIMIT:.3f}, got {gains.current_observer} rad/s × "
            f"{dt} s"
        )
    values = {
        f.name: float(getattr(gains, f.name))
        for f in fields(gains)
        if not isinstance(getattr(gains, f.name), MembershipSet)
    }
    for k, mf in enumerate((gains.surge_mf, gains.pitch_mf, gains.yaw_mf), start=1):
        values.update(
            {
                f"mf{k}_c0": -mf.p,
                f"mf{k}_dc": mf.q_mf,
                f"mf{k}_s": mf.sigma,
                f"mf{k}_sb": mf.sigma_b,
                f"mf{k}_sd": mf.sigma_d,
            }
        )
    values.update(dt=dt, b1=b[0], b5=b[1], b6=b[2])
    values.update(zip(("fins", "fin_gain", "X_max", "M_max", "N_max"), actuator, strict=True))
    return np.array([values[name] for name in GAIN_LAYOUT])
