r"""Command-filtered backstepping for the fin-limited vehicle (docs/model.md §4.10).

The backstepping law of `controllers.backstepping` asks for moments the fins may not give: a
magnitude beyond their authority K·δ_max·u|u| and, on the vehicle as built, a rate beyond what
the fin servos' 60°/s allow. Saturating the command then breaks the cancellation the design
rests on, and the virtual controls wind up. Command-filtered backstepping (Farrell, Polycarpou,
Sharma & Dong, "Command filtered backstepping", IEEE TAC 54(6):1391-1395, 2009) passes each
moment command through a second-order filter with magnitude and rate limits and removes the
filter's effect from the tracking errors it feeds back:

    filter      ẋ₁ = x₂,  ẋ₂ = 2ζω_n (S_R(ω_n/(2ζ) (S_M(M_c) − x₁)) − x₂),  M = x₁
    compensate  ξ̇₂ = −k_q ξ₂ + (M − M_c)/I₅₅,   ξ̇₁ = −k₁ ξ₁ + ξ₂
    law         M_c = I₅₅ (−f₅ + α̇₁ − z̄₁ − k_q z₂),   z̄₁ = z₁ − ξ₁

with S_M, S_R the saturations at the fins' moment authority and moment rate
K·δ_max·u|u|·(δ̇_max/δ_max) = K·u|u|·δ̇_max (K [kg/rad] the fin moment per u² per radian,
docs/model.md §4.10), and the same in yaw (ξ̇₄ = −k_r ξ₄ + (N − N_c)/I₆₆,
ξ̇₃ = −k₂ ξ₃ + ξ₄/cosθ, N_c = I₆₆ (−f₆ + α̇₂ − z̄₃/cosθ − k_r z₄)). With the nominal model the
compensated errors z̄ᵢ = zᵢ − ξᵢ obey the unconstrained closed loop of backstepping
(V = ½ Σ z̄ᵢ², V̇ = −k₁z̄₁² − k_q z̄₂² − k₂z̄₃² − k_r z̄₄²) whatever the limits do; ξ is
bounded while the limits act and decays once they release (Farrell et al., Theorem 1). The
surge law is backstepping's. Gains, guidance and current options are the backstepping's
(`controllers.gains.ControllerGains`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from auv_gym.sim.observation import OBS_INDEX
from auv_gym.vehicle.actuators import ActuatorParams
from auv_gym.vehicle.params import AUVParams
from controllers.backstepping import Backstepping, _saturated, nominal_law
from controllers.fbsm import moment_limits
from controllers.gains import B5, B6, DT, FINS, K1, K2, X_MAX, ControllerGains
from controllers.los import LOOP_DIM, loop_errors

__all__ = ["FILTER_SUBSTEPS", "CommandFilteredBackstepping"]

_U, _TH = OBS_INDEX["u"], OBS_INDEX["theta"]
# Command-filter state per vehicle: (M, Ṁ, N, Ṅ) of the filters, ξ₁ … ξ₄ of the compensation.
_M, _M_RATE, _N, _N_RATE, _XI1, _XI2, _XI3, _XI4 = range(8)
COMMAND_DIM = 8
FILTER_SUBSTEPS = 10  # Euler substeps per control step: ω_n·Δt/10 ≤ 0.1 for ω_n ≤ 20 rad/s
# Layout of the filter settings row: ω_n [rad/s], ζ, moment rate per unit authority [1/s].
_WN, _ZETA, _RATE_PER_AUTHORITY = range(3)


@njit(cache=True, inline="always")
def _clip(x, limit):
    return min(max(x, -limit), limit)


@njit(cache=True, inline="always")
def _command_filter(x, rate, command, limit, rate_limit, wn, zeta, dt):
    """(x, ẋ) after Δt of the magnitude- and rate-limited second-order filter (module doc)."""
    h = dt / FILTER_SUBSTEPS
    target = _clip(command, limit)
    for _ in range(FILTER_SUBSTEPS):
        wanted_rate = _clip(wn / (2.0 * zeta) * (target - x), rate_limit)
        accel = 2.0 * zeta * wn * (wanted_rate - rate)
        x += h * rate
        rate += h * accel
    return _clip(x, limit), rate


@njit(cache=True)
def _cfb_row(o, g, p, cf, settings, filt, started, action, diag, errors):
    if not started:
        for j in range(COMMAND_DIM):
            cf[j] = 0.0
    loop_errors(o, g, filt, started, errors)
    z1, z2, _, _, da1, z3, z4, _, _, da2 = errors[:10]
    u, cos_theta = o[_U], math.cos(o[_TH])
    X, f5, f6, k_q, k_r = nominal_law(o, g, p, errors)
    z1_bar = z1 - cf[_XI1]
    z3_bar = z3 - cf[_XI3]
    m_command = (-f5 + da1 - z1_bar - k_q * z2) / g[B5]
    n_command = (-f6 + da2 - z3_bar / cos_theta - k_r * z4) / g[B6]
    m_max, n_max = moment_limits(u, g)
    dt, wn, zeta = g[DT], settings[_WN], settings[_ZETA]
    m_rate = settings[_RATE_PER_AUTHORITY] * m_max
    n_rate = settings[_RATE_PER_AUTHORITY] * n_max
    cf[_M], cf[_M_RATE] = _command_filter(
        cf[_M], cf[_M_RATE], m_command, m_max, m_rate, wn, zeta, dt
    )
    cf[_N], cf[_N_RATE] = _command_filter(
        cf[_N], cf[_N_RATE], n_command, n_max, n_rate, wn, zeta, dt
    )
    # The compensation, one Euler step of Δt (k·Δt ≤ 0.2 for the default gains).
    xi2 = cf[_XI2] + dt * (-k_q * cf[_XI2] + (cf[_M] - m_command) * g[B5])
    xi1 = cf[_XI1] + dt * (-g[K1] * cf[_XI1] + cf[_XI2])
    xi4 = cf[_XI4] + dt * (-k_r * cf[_XI4] + (cf[_N] - n_command) * g[B6])
    xi3 = cf[_XI3] + dt * (-g[K2] * cf[_XI3] + cf[_XI4] / cos_theta)
    cf[_XI1], cf[_XI2], cf[_XI3], cf[_XI4] = xi1, xi2, xi3, xi4
    action[0] = _saturated(X, g[X_MAX])
    action[1] = _saturated(cf[_M], m_max)
    action[2] = _saturated(cf[_N], n_max)
    diag[0], diag[1], diag[2], diag[3], diag[4] = X, cf[_M], cf[_N], errors[10], errors[11]


def _cfb_rows(obs, g, p, cf, settings, filt, started, actions, diag):
    for i in prange(obs.shape[0]):
        errors = np.empty(LOOP_DIM)
        _cfb_row(obs[i], g, p, cf[i], settings, filt[i], started[i], actions[i], diag[i], errors)
        started[i] = True


_cfb_serial = njit(cache=True)(_cfb_rows)
_cfb_parallel = njit(cache=True, parallel=True)(_cfb_rows)


class CommandFilteredBackstepping(Backstepping):
    """Command-filtered backstepping (module docstring), batched over vehicles.

    Args:
        gains, params, control_dt, actuator, threads: as for `controllers.backstepping`.
        filter_wn: [rad/s] natural frequency ω_n of the command filters (10: a tenth of a
            second, the fin servos' own lag, docs/model.md §2.6).
        filter_zeta: damping ζ of the command filters.
        fin_rate_max: [rad/s] the fin rate the filters respect; None: the actuator's
            (`ActuatorParams.fin_rate_max`, 60°/s), whose moment rate is
            (δ̇_max/δ_max)·K·δ_max·u|u| [N·m/s].
    """

    name = "command_filtered"

    def __init__(
        self,
        gains: ControllerGains | None = None,
        params: AUVParams | None = None,
        control_dt: float = 0.05,
        actuator: str = "fins",
        threads: str = "auto",
        filter_wn: float = 10.0,
        filter_zeta: float = 0.9,
        fin_rate_max: float | None = None,
        **gain_overrides: float,
    ) -> None:
        super().__init__(gains, params, control_dt, actuator, threads, **gain_overrides)
        for name, value, high in (
            ("filter_wn", filter_wn, 20.0),
            ("filter_zeta", filter_zeta, 10.0),
        ):
            if not (isinstance(value, int | float) and 0.0 < value <= high):
                raise ValueError(f"command_filtered {name} must be in (0, {high}], got {value!r}")
        actuators = self.actuator_params or ActuatorParams()
        rate = actuators.fin_rate_max if fin_rate_max is None else fin_rate_max
        if not (isinstance(rate, int | float) and rate > 0.0):
            raise ValueError(f"command_filtered fin_rate_max must be > 0 rad/s, got {rate!r}")
        delta_max = min(actuators.delta_max_stern, actuators.delta_max_rudder)
        per_authority = rate / delta_max if math.isfinite(rate) else 1e9
        self._settings = np.array([float(filter_wn), float(filter_zeta), per_authority])
        if self._g[FINS] == 0.0:
            raise ValueError(
                "command_filtered limits moments to the fins' authority: give actuator='fins' "
                f"or 'realistic', got {actuator!r}"
            )

    def init_state(self, n: int) -> dict[str, np.ndarray]:
        return {**super().init_state(n), "command": np.zeros((n, COMMAND_DIM))}

    def _control(self, obs: np.ndarray, state: dict[str, np.ndarray], actions: np.ndarray) -> None:
        kernel = _cfb_parallel if (self.threads == "auto" and obs.shape[0] >= 64) else _cfb_serial
        kernel(
            obs,
            self._g,
            self._p,
            state["command"],
            self._settings,
            state["filter"],
            state["started"],
            actions,
            state["diag"],
        )

    def diagnostics(self, state: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Backstepping's (desired angles, current guidance) and the compensation ξ₁ … ξ₄."""
        command = state["command"]
        xi = {f"xi_{j + 1}": command[:, _XI1 + j].copy() for j in range(4)}
        return {**super().diagnostics(state), **xi}
