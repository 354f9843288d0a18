r"""Fuzzy backstepping sliding-mode controller (FBSM) of Liang et al. (2018), docs/model.md §4.

Surge (31)–(34), first order, S1 = u − u_D:

    X = (1/b̂1) [ −f̂1(v) − d̂1(S1) + u̇_D − (h1 + λ1) S1 ]      (u̇_D = 0: u_D is constant)

Pitch (35)–(39), with z1 = θ − θ_d, α1 = −k1 z1 + θ̇_d, z2 = q − α1, S2 = c1 z1 + z2:

    M = (1/b̂5) [ −f̂5(v) − c1 ż1 + α̇1 − d̂5(S2) − (h2 + λ2) S2 ]

Yaw (40)–(43), with the 1/cosθ correction of docs/model.md §4.4, z3 = ψ − ψ_d,
α2 = cosθ(−k2 z3 + ψ̇_d), z4 = r − α2, S3 = c2 z3 + z4:

    N = (1/b̂6) [ −f̂6(v) − c2 ż3 + α̇2 − d̂6(S3) − (h3 + λ3) S3 ]

f̂, b̂ are 3125-rule adaptive fuzzy systems of v = (u, v, w, q, r) and d̂ a 3-rule one of S
(`controllers.fuzzy`); θ_d and ψ_d come from the LOS laws of docs/model.md §3.4 (`controllers.los`).

Notes (Lyapunov argument, paper (44)–(53)): with V = ½S² + Σ(1/2α)|θ − θ*|², the adaptive laws
(30) cancel the parameter-error terms, leaving V̇ ≤ −(h + λ − η)S² + ε|S| for the approximation
error ε ≤ η|S|; on S = 0 the pitch error obeys ż1 = −(k1 + c1) z1 and the yaw error
ż3 = −(k2 + c2/cosθ) z3.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from auv_gym.sim.observation import OBS_INDEX
from auv_gym.vehicle import AUVParams
from controllers.alos import guidance_diagnostics
from controllers.base import BatchedController
from controllers.fuzzy import N_RULES, WORK_DIM, adaptive_loop
from controllers.gains import (
    B1,
    B5,
    B6,
    C1,
    C2,
    FIN_GAIN,
    FINS,
    H1,
    H2,
    H3,
    LAM1,
    LAM2,
    LAM3,
    M_MAX,
    N_MAX,
    SPEED_OVER_GROUND,
    X_MAX,
    ControllerGains,
    pack_gains,
)
from controllers.los import FILTER_DIM, LOOP_DIM, loop_errors

__all__ = ["FBSM", "moment_limits"]

_U, _V, _W, _Q, _R = (OBS_INDEX[k] for k in ("u", "v", "w", "q", "r"))
LOOPS = ("surge", "pitch", "yaw")
# Per-vehicle diagnostics row: (f̂, b̂, d̂) per loop, then θ_d and ψ_d − ψ_F [rad].
DIAG_DIM = 11


@njit(cache=True, inline="always")
def moment_limits(u, g):
    """(M_max, N_max) [N·m] at surge speed u: constant, or fin authority K·δ_max·u|u|."""
    if g[FINS] > 0.0:
        authority = max(g[FIN_GAIN] * u * abs(u), 0.0)
        return authority, authority
    return g[M_MAX], g[N_MAX]


@njit(cache=True)
def _fbsm_row(o, g, theta_f, theta_b, theta_d, filt, started, action, diag, errors, work, v_in):
    loop_errors(o, g, filt, started, errors)
    S2, dz1, da1, S3, dz3, da2 = errors[2], errors[3], errors[4], errors[7], errors[8], errors[9]
    u = o[_U]
    v_in[0], v_in[1], v_in[2], v_in[3], v_in[4] = u, o[_V], o[_W], o[_Q], o[_R]
    m_max, n_max = moment_limits(u, g)
    S1 = u - errors[12]  # u_D, or the speed-over-ground reference (controllers.alos)
    h1, h2, h3 = g[H1] + g[LAM1], g[H2] + g[LAM2], g[H3] + g[LAM3]
    rest1 = -h1 * S1
    if g[SPEED_OVER_GROUND] > 0.0:
        rest1 += errors[13]
    action[0] = adaptive_loop(
        0, v_in, S1, rest1, g[X_MAX], g[B1], theta_f[0], theta_b[0], theta_d[0], g, work, diag[0:3]
    )
    action[1] = adaptive_loop(
        1,
        v_in,
        S2,
        -g[C1] * dz1 + da1 - h2 * S2,
        m_max,
        g[B5],
        theta_f[1],
        theta_b[1],
        theta_d[1],
        g,
        work,
        diag[3:6],
    )
    action[2] = adaptive_loop(
        2,
        v_in,
        S3,
        -g[C2] * dz3 + da2 - h3 * S3,
        n_max,
        g[B6],
        theta_f[2],
        theta_b[2],
        theta_d[2],
        g,
        work,
        diag[6:9],
    )
    diag[9], diag[10] = errors[10], errors[11]


def _fbsm_rows(obs, g, theta_f, theta_b, theta_d, filt, started, actions, diag):
    for i in prange(obs.shape[0]):
        errors = np.empty(LOOP_DIM)
        work = np.empty(WORK_DIM)
        v_in = np.empty(5)
        _fbsm_row(
            obs[i],
            g,
            theta_f[i],
            theta_b[i],
            theta_d[i],
            filt[i],
            started[i],
            actions[i],
            diag[i],
            errors,
            work,
            v_in,
        )
        started[i] = True


_fbsm_serial = njit(cache=True)(_fbsm_rows)
_fbsm_parallel = njit(cache=True, parallel=True)(_fbsm_rows)


class FBSM(BatchedController):
    """The paper's FBSM controller (module docstring), batched over vehicles.

    Args:
        gains: `ControllerGains` (defaults: the paper's Section 6, docs/model.md §4.6).
        params: nominal `AUVParams`; the FBSM uses only b_n = (1/m11, 1/I55, 1/I66) to
            initialise and bound b̂ (docs/model.md §4.6), never the true perturbed vehicle.
        control_dt: control period [s], the Euler step of the adaptive laws and filter.
        actuator: "paper" or "fins" — how τ is normalised into actions; "realistic": the
            "fins" law, its τ allocated to shaft speed and fin angles (`controllers.allocation`,
            numbers from the keyword ``actuator_params``, an `ActuatorParams` or dict).
        threads: "auto" runs batches of ≥ 64 vehicles on numba's threads, "serial" never.

    State (dict of arrays, leading vehicle axis): theta_f, theta_b (n, 3, 3125), theta_d
    (n, 3, 3), filter (n, FILTER_DIM), started (n,), diag (n, 11).
    """

    name = "fbsm"

    def __init__(
        self,
        gains: ControllerGains | None = None,
        params: AUVParams | None = None,
        control_dt: float = 0.05,
        actuator: str = "paper",
        threads: str = "auto",
        **gain_overrides: float,
    ) -> None:
        super().__init__(gains, params, control_dt, actuator, gain_overrides, threads)
        p = self.params
        self.b_nominal = (1.0 / p.m11, 1.0 / p.I55, 1.0 / p.I66)
        self._g = pack_gains(self.gains, self.control_dt, self.b_nominal, self._actuator)

    def init_state(self, n: int) -> dict[str, np.ndarray]:
        theta_b = np.empty((n, 3, N_RULES))
        theta_b[:] = np.asarray(self.b_nominal)[None, :, None]  # b̂(0) = b_n (docs/model.md §4.6)
        return {
            "theta_f": np.zeros((n, 3, N_RULES)),
            "theta_b": theta_b,
            "theta_d": np.zeros((n, 3, 3)),
            "filter": np.zeros((n, FILTER_DIM)),
            "started": np.zeros(n, dtype=bool),
            "diag": np.zeros((n, DIAG_DIM)),
        }

    def _control(self, obs: np.ndarray, state: dict[str, np.ndarray], actions: np.ndarray) -> None:
        kernel = _fbsm_parallel if (self.threads == "auto" and obs.shape[0] >= 64) else _fbsm_serial
        kernel(
            obs,
            self._g,
            state["theta_f"],
            state["theta_b"],
            state["theta_d"],
            state["filter"],
            state["started"],
            actions,
            state["diag"],
        )

    def diagnostics(self, state: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Desired angles, adaptive-parameter norms and the current-guidance states
        (`controllers.alos.guidance_diagnostics`) for `auv_gym.rollout` (extras)."""
        out = {"theta_d": state["diag"][:, 9].copy(), "psi_d_rel": state["diag"][:, 10].copy()}
        for k, loop in enumerate(LOOPS):
            out[f"norm_theta_f_{loop}"] = np.linalg.norm(state["theta_f"][:, k], axis=1)
            out[f"norm_theta_d_{loop}"] = np.linalg.norm(state["theta_d"][:, k], axis=1)
            out[f"b_hat_{loop}"] = state["diag"][:, 3 * k + 1].copy()
        return {**out, **guidance_diagnostics(self.gains, state["filter"])}
