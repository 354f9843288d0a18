r"""Traditional backstepping comparator (docs/model.md §4.7): nominal-model inverse, same guidance.

With the nominal model ν̇ = f_n(ν, θ) + b_n τ (f_n from `auv_gym.vehicle.dynamics.nu_dot` with τ = 0,
including the surge Coriolis terms when the model has them, docs/model.md §10.3):

    X = m11 (−f1 + u̇_D − k_u S1),                  k_u = h1 + λ1
    M = I55 (−f5 + α̇1 − z1 − k_q z2),              k_q = c1 + h2 + λ2
    N = I66 (−f6 + α̇2 − z3/cosθ − k_r z4),         k_r = c2 + h3 + λ3

(u̇_D = 0: the env's u_D is constant over an episode.)

Notes: with an exact model the closed loop is ż1 = z2 − k1 z1, ż2 = −z1 − k_q z2,
ż3 = z4/cosθ − k2 z3, ż4 = −z3/cosθ − k_r z4, so V = ½(S1² + z1² + z2² + z3² + z4²) has
V̇ = −k_u S1² − k1 z1² − k_q z2² − k2 z3² − k_r z4² (the cross terms cancel).
A mis-specified model (e.g. coefficients × 1.3) leaves the f_n error uncompensated: a steady
offset, which is what docs/model.md §8 check 7 measures.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from auv_gym.sim.observation import OBS_INDEX
from auv_gym.vehicle.dynamics import nu_dot
from auv_gym.vehicle.params import AUVParams, params_record
from controllers.alos import guidance_diagnostics
from controllers.base import BatchedController
from controllers.fbsm import moment_limits
from controllers.gains import (
    B1,
    B5,
    B6,
    C1,
    C2,
    H1,
    H2,
    H3,
    LAM1,
    LAM2,
    LAM3,
    SPEED_OVER_GROUND,
    X_MAX,
    ControllerGains,
    pack_gains,
)
from controllers.los import FILTER_DIM, LOOP_DIM, loop_errors

__all__ = ["Backstepping", "nominal_law"]

_U, _V, _W, _Q, _R, _TH, _UD = (OBS_INDEX[k] for k in ("u", "v", "w", "q", "r", "theta", "u_D"))


@njit(cache=True, inline="always")
def _saturated(tau, limit):
    if limit <= 0.0:
        return 0.0 if tau == 0.0 else math.copysign(1.0, tau)
    return min(max(tau / limit, -1.0), 1.0)


@njit(cache=True, inline="always")
def nominal_law(o, g, p, errors):
    """(X [N], f5, f6, k_q, k_r): the surge command of the module docstring and the nominal
    model's pitch and yaw accelerations at τ = 0 [rad/s²] with the moment loops' gains [1/s],
    shared with `controllers.command_filtered`; ``errors`` from `loop_errors`."""
    u, theta = o[_U], o[_TH]
    nu = (u, o[_V], o[_W], o[_Q], o[_R])
    f1, _, _, f5, f6 = nu_dot(
        nu, theta, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0, 0.0), params_record(p)
    )
    k_u = g[H1] + g[LAM1]
    k_q = g[C1] + g[H2] + g[LAM2]
    k_r = g[C2] + g[H3] + g[LAM3]
    if g[SPEED_OVER_GROUND] > 0.0:  # u_ref and u̇_ref from controllers.alos
        X = (-f1 + errors[13] - k_u * (u - errors[12])) / g[B1]
    else:
        X = (-f1 - k_u * (u - o[_UD])) / g[B1]
    return X, f5, f6, k_q, k_r


@njit(cache=True)
def _backstepping_row(o, g, p, filt, started, action, diag, errors):
    loop_errors(o, g, filt, started, errors)
    z1, z2, _, _, da1, z3, z4, _, _, da2 = errors[:10]
    u, theta = o[_U], o[_TH]
    X, f5, f6, k_q, k_r = nominal_law(o, g, p, errors)
    M = (-f5 + da1 - z1 - k_q * z2) / g[B5]
    N = (-f6 + da2 - z3 / math.cos(theta) - k_r * z4) / g[B6]
    m_max, n_max = moment_limits(u, g)
    action[0] = _saturated(X, g[X_MAX])
    action[1] = _saturated(M, m_max)
    action[2] = _saturated(N, n_max)
    diag[0], diag[1], diag[2], diag[3], diag[4] = X, M, N, errors[10], errors[11]


def _backstepping_rows(obs, g, p, filt, started, actions, diag):
    for i in prange(obs.shape[0]):
        errors = np.empty(LOOP_DIM)
        _backstepping_row(obs[i], g, p, filt[i], started[i], actions[i], diag[i], errors)
        started[i] = True


_bs_serial = njit(cache=True)(_backstepping_rows)
_bs_parallel = njit(cache=True, parallel=True)(_backstepping_rows)


class Backstepping(BatchedController):
    """Nominal-model backstepping (module docstring), batched over vehicles.

    Args:
        gains: `ControllerGains` (shared with FBSM: h, λ, k, c and the LOS gains).
        params: the *nominal* model the controller inverts; pass e.g.
            ``remus100().scaled({k: 1.3 for k in HYDRODYNAMIC_FIELDS})`` for a +30 % error.
        control_dt, actuator, threads: as for `controllers.fbsm.FBSM`.
    """

    name = "backstepping"

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
        self._p = p.to_vector()
        b = (1.0 / p.m11, 1.0 / p.I55, 1.0 / p.I66)
        self._g = pack_gains(self.gains, self.control_dt, b, self._actuator)

    def init_state(self, n: int) -> dict[str, np.ndarray]:
        return {
            "filter": np.zeros((n, FILTER_DIM)),
            "started": np.zeros(n, dtype=bool),
            "diag": np.zeros((n, 5)),
        }

    def _control(self, obs: np.ndarray, state: dict[str, np.ndarray], actions: np.ndarray) -> None:
        kernel = _bs_parallel if (self.threads == "auto" and obs.shape[0] >= 64) else _bs_serial
        kernel(obs, self._g, self._p, state["filter"], state["started"], actions, state["diag"])

    def diagnostics(self, state: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Desired angles and the current-guidance states (`controllers.alos`) (extras)."""
        out = {"theta_d": state["diag"][:, 3].copy(), "psi_d_rel": state["diag"][:, 4].copy()}
        return {**out, **guidance_diagnostics(self.gains, state["filter"])}
