r"""PID + LOS autopilot: the textbook baseline (not in the paper), docs/model.md §4.9.

Guidance is the one FBSM and backstepping use (`controllers.los.loop_errors`): the LOS laws of
docs/model.md §3.4 give θ_d and ψ_d (command-filtered corrections), and the surge reference is
u_ref = u_D, or with ``speed_over_ground`` the speed through the water that makes u_D over
ground (`controllers.alos`, docs/model.md §3.7); integral LOS (§3.6) and the current observer
are the same gains of `ControllerGains`. Three decoupled loops (Fossen 2021, ch. 15–16), each
with its integrator I Euler-integrated at the control period Δt_c:

Surge PI, with the nominal drag and the reference rate fed forward:

    ũ = u − u_ref,    X = −X_u|u| u_ref|u_ref| + m11 u̇_ref − K_p,u ũ − K_i,u I_u,    İ_u = ũ

Pitch PID (depth through θ_d = sat(θ_F + arctan(k_z z_e) + α)), q as the derivative term:

    θ̃ = θ − θ_d,      M = −K_p,θ θ̃ − K_d,θ q − K_i,θ I_θ,    İ_θ = θ̃

Heading PID, r as the derivative term:

    ψ̃ = wrap(ψ − ψ_d) ∈ (−π, π],     N = −K_p,ψ ψ̃ − K_d,ψ r − K_i,ψ I_ψ,    İ_ψ = ψ̃

Tuning (Fossen 2021, §15.3, PID pole placement): each loop linearised about straight, level
flight at the design speed u0 is a mass–damper–spring m ẍ + d ẋ + k x = τ with, from the
nominal model (docs/model.md §2.1),

    surge:  m = m11,  d = −2 X_u|u| u0,  k = 0           (only the P part is placed)
    pitch:  m = I55,  d = −M_uq u0,      k = z_g W − z_b B  (the righting moment)
    yaw:    m = I66,  d = −N_ur u0,      k = 0

and, for ω_n and ζ chosen (`PIDGains`),

    K_p = m ω_n² − k,    K_d = 2ζ ω_n m − d,    K_i = (ω_n/10) K_p,

which places the PD closed loop at s² + 2ζω_n s + ω_n² and the integrator's zero a decade
below ω_n. The surge P gain K_p,u = m11 ω_u − d places the first-order pole at −ω_u.

Anti-windup (the actuators saturate, docs/model.md §2.3): conditional integration (clamping).
An integrator is frozen while its loop's command τ is at the limit τ_max and integrating would
push it further (ẽ τ < 0, since the integral term is −K_i I), and |K_i I| ≤ τ_max always, so the
integral term alone never demands more than the actuator gives. With the "fins" actuator τ_max
is the fin authority at the observed u (zero at rest).

Climb speed (``climb_speed`` > 0, "fins" and "realistic" actuators only; off by default): the
fins' authority grows as u|u| (docs/model.md §2.3), so a pitch moment the stern plane cannot
make at u_D it can make faster. The surge reference rises towards the speed at which the
demanded (unsaturated) M is the fraction ``climb_authority`` of the authority,

    u_M = √(|M| / (climb_authority · K δ_max)),
    u_c ← u_c + (Δt_c/T_c)(clip(u_M, u_ref, u_max) − u_c),

with u_max = ``climb_speed``, T_c = ``climb_time``, and the loop tracks max(u_ref, u_c) (its rate
fed forward). On a level leg |M| is small, u_M < u_D and the reference is u_D; on a climb the
restoring moment z_g W sin θ needs the speed, which the drag then costs (docs/model.md §4.9).

Notes: the loops neglect what the FBSM adapts to and the backstepping comparator inverts — the
Munk moment M_uw u w, the quadratic damping, the sway and heave coupling, ψ̇ = r/cos θ and the
noise — and leave them to the integrators. With r and q as the derivative terms there is no
derivative kick; the ramp of ψ_d on a helix (ψ̇_F ≈ 0.048 rad/s) is followed because the loop
has two integrators (ψ and I_ψ). Stability is by linear analysis about the design point only:
the outer LOS loops (bandwidth ≈ k_y u0 = 0.1 rad/s and k_z u0 = 0.5 rad/s) must be slower than
the inner ones, which the default ω_n satisfy by a factor of 6 (pitch) and 25 (yaw).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numba import njit, prange

from auv_gym.sim.observation import OBS_INDEX
from auv_gym.support.validation import flag, real
from auv_gym.vehicle import AUVParams
from controllers.alos import guidance_diagnostics
from controllers.base import BatchedController, unknown_keywords
from controllers.fbsm import moment_limits
from controllers.gains import DT, FIN_GAIN, X_MAX, ControllerGains, pack_gains
from controllers.los import FILTER_DIM, LOOP_DIM, loop_errors

__all__ = ["GUIDANCE_GAINS", "PIDLOS", "PID_GUIDANCE", "PIDGains", "PIDTuning", "pid_tuning"]

_U, _Q, _R = (OBS_INDEX[k] for k in ("u", "q", "r"))
# The `ControllerGains` fields that the LOS guidance reads; the FBSM's h, λ, k, c, α and fuzzy
# sets have no meaning for the PID autopilot, so they are refused by name.
GUIDANCE_GAINS = (
    "k_y",
    "k_z",
    "theta_max",
    "filter_wn",
    "filter_zeta",
    "u_guard",
    "sideslip_3d",
    "printed_pitch_los",
    "ilos_y",
    "ilos_z",
    "current_observer",
    "alos_y",
    "alos_z",
    "alos_radius",
    "alos_max",
    "speed_over_ground",
    "dvl_current",
)
# The guidance defaults: the paper's LOS, with a faster command filter. The PID needs no θ̇_d, ψ̇_d,
# so the filter only smooths, and at the paper's ω_n = 2 rad/s its 2ζ/ω_n = 1 s lag inside the
# depth loop (lookahead 1/k_z = 2 m) makes it hunt: RMS z_e 0.13 m instead of 0.0001 m over
# t ≥ 100 s (seed 0, no noise, 300 s, measured).
PID_GUIDANCE = ControllerGains(filter_wn=10.0)
# Per-vehicle diagnostics row: θ_d, ψ_d − ψ_F [rad], then the unsaturated X [N], M, N [N·m].
DIAG_DIM = 5


@dataclass(frozen=True)
class PIDGains:
    """Design parameters of the PID autopilots (module docstring); the gains follow by pole
    placement on the nominal model (`pid_tuning`, Fossen 2021 §15.3).

    Defaults (docs/model.md §4.9): critically damped inner loops 6 (pitch) and 25 (yaw) times
    faster than the LOS loops around them (k_z u0 = 0.5 rad/s, k_y u0 = 0.1 rad/s); K_p,θ
    about three times the destabilising Munk stiffness M_uw u0² = 24 N·m/rad; the yaw value
    chosen on the paper scenario's noise (measured); the surge loop about as fast as the
    paper's (h1 + λ1 = 1.1 1/s), which keeps the start from rest within the 50 N thrust.
    """

    surge_wn: float = 1.0  # [rad/s] ω_u: K_p,u = m11 ω_u − d_u (pole of the P loop at −ω_u)
    pitch_wn: float = 3.0  # [rad/s] ω_n of the pitch loop; must exceed √(k/I55) = 0.84 rad/s
    pitch_zeta: float = 1.0  # [-] ζ of the pitch loop
    yaw_wn: float = 2.5  # [rad/s] ω_n of the heading loop
    yaw_zeta: float = 1.0  # [-] ζ of the heading loop
    integral_ratio: float = 0.1  # [-] K_i = ratio·ω_n·K_p (Fossen's ω_n/10); 0: P(D) only
    design_speed: float = 1.0  # [m/s] u0 of the linearisation (the paper's u_D)
    anti_windup: bool = True  # conditional integration and |K_i I| ≤ τ_max (module docstring)
    climb_speed: float = 0.0  # [m/s] u_max of the climb-speed law (module docstring); 0: off
    climb_authority: float = 0.8  # [-] the share of the fins' pitch authority it aims for
    climb_time: float = 2.0  # [s] T_c, the time constant of the raised surge reference

    def __post_init__(self) -> None:
        positive = {
            "surge_wn": "rad/s",
            "pitch_wn": "rad/s",
            "pitch_zeta": "",
            "yaw_wn": "rad/s",
            "yaw_zeta": "",
            "design_speed": "m/s",
        }
        for name, unit in positive.items():
            real(f"PIDGains.{name}", getattr(self, name), 0.0, low_open=True, unit=unit)
        real("PIDGains.integral_ratio", self.integral_ratio, 0.0)
        flag("PIDGains.anti_windup", self.anti_windup)
        real("PIDGains.climb_speed", self.climb_speed, 0.0, unit="m/s")
        real("PIDGains.climb_authority", self.climb_authority, 0.0, 1.0, low_open=True)
        real("PIDGains.climb_time", self.climb_time, 0.0, low_open=True, unit="s")


@dataclass(frozen=True)
class PIDTuning:
    """The PID gains the kernels use, from `pid_tuning`. Units: K_p,u [N·s/m], K_i,u [N/m],
    K_p,θ, K_p,ψ [N·m/rad], K_d [N·m·s/rad], K_i [N·m/(rad·s)]; drag = −X_u|u| [kg/m] and
    m11 [kg] of the surge feed-forward."""

    kp_u: float
    ki_u: float
    kp_theta: float
    kd_theta: float
    ki_theta: float
    kp_psi: float
    kd_psi: float
    ki_psi: float
    drag: float
    m11: float

    def vector(self, pid: PIDGains) -> np.ndarray:
        """The float64 vector of the kernels: the fields in order, then the anti-windup flag and
        the climb-speed law's u_max [m/s], share [-] and T_c [s] (`PIDGains`)."""
        return np.array(
            [
                *(float(getattr(self, f.name)) for f in fields(self)),
                1.0 if pid.anti_windup else 0.0,
                pid.climb_speed,
                pid.climb_authority,
                pid.climb_time,
            ]
        )


(KP_U, KI_U, KP_TH, KD_TH, KI_TH, KP_PSI, KD_PSI, KI_PSI, DRAG, M11, ANTI_WINDUP) = range(11)
CLIMB_SPEED, CLIMB_AUTHORITY, CLIMB_TIME = range(11, 14)


def _placed(
    loop: str, wn_name: str, m: float, d: float, k: float, wn: float, zeta: float, ratio: float
) -> tuple[float, float, float]:
    """(K_p, K_d, K_i) of Fossen's pole placement; ValueError when ω_n is too low to place."""
    kp = m * wn * wn - k
    kd = 2.0 * zeta * wn * m - d
    if kp <= 0.0:
        raise ValueError(
            f"PIDGains.{wn_name} = {wn} rad/s gives the {loop} loop K_p = "
            f"m ω_n² − k = {kp:.3g} ≤ 0; it must exceed √(k/m) = "
            f"{math.sqrt(max(k, 0.0) / m):.3g} rad/s"
        )
    if kd < 0.0:
        raise ValueError(
            f"PIDGains.{wn_name} = {wn} rad/s gives the {loop} loop K_d = "
            f"2ζω_n m − d = {kd:.3g} < 0; raise ω_n or ζ above the open-loop "
            "damping"
        )
    return kp, kd, ratio * wn * kp


def pid_tuning(params: AUVParams, pid: PIDGains) -> PIDTuning:
    """The gains of the three loops by pole placement on the nominal model (module docstring)."""
    u0 = pid.design_speed
    d_u = -2.0 * params.X_uu * u0
    kp_u = params.m11 * pid.surge_wn - d_u
    if kp_u <= 0.0:
        raise ValueError(
            f"PIDGains.surge_wn = {pid.surge_wn} rad/s gives K_p,u = m11 ω_u − d = "
            f"{kp_u:.3g} ≤ 0; it must exceed d/m11 = {d_u / params.m11:.3g} rad/s"
        )
    restoring = params.z_g * params.W - params.z_b * params.B
    kp_th, kd_th, ki_th = _placed(
        "pitch",
        "pitch_wn",
        params.I55,
        -params.M_uq * u0,
        restoring,
        pid.pitch_wn,
        pid.pitch_zeta,
        pid.integral_ratio,
    )
    kp_psi, kd_psi, ki_psi = _placed(
        "yaw",
        "yaw_wn",
        params.I66,
        -params.N_ur * u0,
        0.0,
        pid.yaw_wn,
        pid.yaw_zeta,
        pid.integral_ratio,
    )
    return PIDTuning(
        kp_u=kp_u,
        ki_u=pid.integral_ratio * pid.surge_wn * kp_u,
        kp_theta=kp_th,
        kd_theta=kd_th,
        ki_theta=ki_th,
        kp_psi=kp_psi,
        kd_psi=kd_psi,
        ki_psi=ki_psi,
        drag=-params.X_uu,
        m11=params.m11,
    )


@njit(cache=True, inline="always")
def _loop(tau, limit, error, ki, integral, dt, anti_windup):
    """(normalised action, next integral) of one loop whose command is ``tau`` [N or N·m].

    Conditional integration: the integral of ``error`` advances unless the command saturates
    and integrating would drive it further (error·τ < 0), then |K_i I| ≤ limit.
    """
    if limit > 0.0:
        action = min(max(tau / limit, -1.0), 1.0)
    else:  # no authority (fins at rest): the sign only, as the other controllers do
        action = 0.0 if tau == 0.0 else math.copysign(1.0, tau)
    if anti_windup == 0.0:
        return action, integral + dt * error
    if abs(tau) < limit or error * tau > 0.0:
        integral += dt * error
    if ki > 0.0:
        bound = max(limit, 0.0) / ki
        integral = min(max(integral, -bound), bound)
    return action, integral


@njit(cache=True, inline="always")
def _climb_reference(moment, u_ref, du_ref, g, k, climb, started):
    """(surge reference [m/s], its rate [m/s²]) of the climb-speed law (module docstring);
    advances its state ``climb`` = [u_c] by one control period."""
    if not started:
        climb[0] = u_ref
    needed = math.sqrt(abs(moment) / (k[CLIMB_AUTHORITY] * g[FIN_GAIN]))
    target = min(max(needed, u_ref), k[CLIMB_SPEED])
    step = g[DT] / k[CLIMB_TIME] * (target - climb[0])
    climb[0] += step
    if climb[0] > u_ref:
        return climb[0], step / g[DT]
    return u_ref, du_ref


@njit(cache=True)
def _pid_row(o, g, k, filt, integral, started, action, diag, errors, climb):
    loop_errors(o, g, filt, started, errors)
    dt, aw = g[DT], k[ANTI_WINDUP]
    u, q, r = o[_U], o[_Q], o[_R]
    theta_err, psi_err = errors[0], errors[5]  # θ − θ_d; wrap(ψ − ψ_d)
    u_ref, du_ref = errors[12], errors[13]  # u_D (or the speed-over-ground reference), its rate
    M = -k[KP_TH] * theta_err - k[KD_TH] * q - k[KI_TH] * integral[1]
    N = -k[KP_PSI] * psi_err - k[KD_PSI] * r - k[KI_PSI] * integral[2]
    if k[CLIMB_SPEED] > 0.0:
        u_ref, du_ref = _climb_reference(M, u_ref, du_ref, g, k, climb, started)
    speed_err = u - u_ref
    X = k[DRAG] * u_ref * abs(u_ref) + k[M11] * du_ref - k[KP_U] * speed_err - k[KI_U] * integral[0]
    m_max, n_max = moment_limits(u, g)
    action[0], integral[0] = _loop(X, g[X_MAX], speed_err, k[KI_U], integral[0], dt, aw)
    action[1], integral[1] = _loop(M, m_max, theta_err, k[KI_TH], integral[1], dt, aw)
    action[2], integral[2] = _loop(N, n_max, psi_err, k[KI_PSI], integral[2], dt, aw)
    diag[0], diag[1], diag[2], diag[3], diag[4] = errors[10], errors[11], X, M, N


def _pid_rows(obs, g, k, filt, integral, started, actions, diag, climb):
    for i in prange(obs.shape[0]):
        errors = np.empty(LOOP_DIM)
        _pid_row(
            obs[i], g, k, filt[i], integral[i], started[i], actions[i], diag[i], errors, climb[i]
        )
        started[i] = True


_pid_serial = njit(cache=True)(_pid_rows)
_pid_parallel = njit(cache=True, parallel=True)(_pid_rows)


class PIDLOS(BatchedController):
    """PID autopilots behind the paper's LOS guidance (module docstring), batched over vehicles.

    Args:
        pid: `PIDGains` (ω_n, ζ per loop; default `PIDGains()`).
        gains: `ControllerGains` for the guidance; only its `GUIDANCE_GAINS` are read
            (default `PID_GUIDANCE`: the paper's LOS with a 10-rad/s command filter).
        params: the nominal `AUVParams` the gains are placed on (default REMUS 100).
        control_dt, actuator, threads: as for `controllers.fbsm.FBSM`.
        **overrides: any field of `PIDGains` or a name of `GUIDANCE_GAINS`; other names are a
            ValueError.

    State (dict of arrays, leading vehicle axis): filter (n, FILTER_DIM), the guidance memory;
    integral (n, 3), the integrators I_u [m], I_θ, I_ψ [rad·s]; started (n,); diag (n, 5).
    """

    name = "pid_los"

    def __init__(
        self,
        pid: PIDGains | None = None,
        gains: ControllerGains | None = None,
        params: AUVParams | None = None,
        control_dt: float = 0.05,
        actuator: str = "paper",
        threads: str = "auto",
        **overrides: Any,
    ) -> None:
        pid = pid if pid is not None else PIDGains()
        if not isinstance(pid, PIDGains):
            raise ValueError(f"pid must be a PIDGains, got {type(pid).__name__}")
        pid_names = {f.name for f in fields(PIDGains)}
        unknown = sorted(set(overrides) - pid_names - {*GUIDANCE_GAINS, "actuator_params"})
        if unknown:
            raise ValueError(
                unknown_keywords(self.name, unknown, [*pid_names, *GUIDANCE_GAINS], ("pid",))
            )
        pid_overrides = {n: v for n, v in overrides.items() if n in pid_names}
        guidance = {n: v for n, v in overrides.items() if n not in pid_names}
        gains = gains if gains is not None else PID_GUIDANCE
        super().__init__(gains, params, control_dt, actuator, guidance, threads)
        # the Euler-discretised command filter has the double pole 1 − ω_n Δt_c (ζ = 1)
        if self.gains.filter_wn * self.control_dt >= 1.0:
            raise ValueError(
                f"pid_los: filter_wn × control_dt must be below 1, got "
                f"{self.gains.filter_wn} rad/s × {self.control_dt} s"
            )
        self.pid = dataclasses.replace(pid, **pid_overrides) if pid_overrides else pid
        p = self.params
        self.tuning = pid_tuning(p, self.pid)
        self._g = pack_gains(
            self.gains, self.control_dt, (1.0 / p.m11, 1.0 / p.I55, 1.0 / p.I66), self._actuator
        )
        if self.pid.climb_speed > 0.0:
            self._check_climb_law(actuator)
        self._k = self.tuning.vector(self.pid)

    def _check_climb_law(self, actuator: str) -> None:
        """ValueError unless the climb-speed law has the fins' authority to raise and a time
        constant its Euler step keeps stable (T_c ≥ Δt_c)."""
        if self._actuator[0] <= 0.0:
            raise ValueError(
                "pid_los: climb_speed needs the fins' authority (actuator 'fins' or "
                f"'realistic'), got actuator {actuator!r}"
            )
        if self.pid.climb_time < self.control_dt:
            raise ValueError(
                f"pid_los: climb_time = {self.pid.climb_time} s must be at least control_dt = "
                f"{self.control_dt} s"
            )

    def init_state(self, n: int) -> dict[str, np.ndarray]:
        return {
            "filter": np.zeros((n, FILTER_DIM)),
            "integral": np.zeros((n, 3)),
            "started": np.zeros(n, dtype=bool),
            "diag": np.zeros((n, DIAG_DIM)),
            "climb": np.zeros((n, 1)),
        }

    def _control(self, obs: np.ndarray, state: dict[str, np.ndarray], actions: np.ndarray) -> None:
        kernel = _pid_parallel if (self.threads == "auto" and obs.shape[0] >= 64) else _pid_serial
        kernel(
            obs,
            self._g,
            self._k,
            state["filter"],
            state["integral"],
            state["started"],
            actions,
            state["diag"],
            state["climb"],
        )

    def diagnostics(self, state: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Desired angles, the integrators (``integral``, (n, 3): I_u [m], I_θ, I_ψ [rad·s]),
        with the climb-speed law its raised reference u_c (``climb_reference`` [m/s]; the loop
        tracks max(u_ref, u_c)), and the current-guidance states
        (`controllers.alos.guidance_diagnostics`) (extras)."""
        out = {
            "theta_d": state["diag"][:, 0].copy(),
            "psi_d_rel": state["diag"][:, 1].copy(),
            "integral": state["integral"].copy(),
        }
        if self.pid.climb_speed > 0.0:
            out["climb_reference"] = state["climb"][:, 0].copy()
        return {**out, **guidance_diagnostics(self.gains, state["filter"])}
