"""The navigation estimate the observation is computed from when sensors are modelled.

Per control step t and vehicle (docs/model.md §14): sample the DVL, AHRS and depth sensor with
the errors of a `sensors.SensorConfig`, update the horizontal position (a fix, or dead reckoning
on the DVL's velocity over ground rotated by the AHRS attitude), store the measurements in a
ring of k + 1 slots and build the observation from those of step t − k: the guidance row is
recomputed from the estimated pose (x_e, y_e, z_e, ψ_e), velocities and rates come from the
DVL and AHRS. The path parameter s stays the plant's. The reward, termination and metrics read
the true state and the true guidance row (`Simulator.guid`), which this module writes only with
a guidance computer (``virtual_point="estimate"``, docs/model.md §14.9): then it keeps the
virtual-point speed u_p of the estimated x_e for the next control period (`SensorArrays`
``held_speed``, which the physics reads through `fleet.Fleet`) and gives the true row that
speed.

Randomness is counter-based like the disturbances (`disturbances.uniform01`): sample errors
from the episode's sensor key at counter ``STRIDE·t + channel``, per-episode biases from its
bias key (`sensors.sensor_key`), so every policy meets the same sensor errors.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numba import njit

from auv_gym.ocean.disturbances import KEY, standard_normal, uniform01
from auv_gym.paths.guidance import body_errors_trig, wrap_angle
from auv_gym.sim.fleet import ocean_over_ground
from auv_gym.sim.integrator import config_record
from auv_gym.sim.observation import (
    GUIDANCE_DIM,
    GUIDE,
    OBS_DIM,
    build_observation,
    guidance_row,
)
from auv_gym.sim.task import ENVELOPE, NON_FINITE
from auv_gym.support.records import field_indices, fixed_tuple, record_type
from auv_gym.vehicle.dynamics import STATE, STATE_DIM, eta_dot
from auv_gym.vehicle.sensors import SENSOR_FIELDS, SensorConfig, sensor_key

if TYPE_CHECKING:
    from auv_gym.sim.simulator import Simulator

__all__ = ["MEAS", "MEAS_FIELDS", "NAV", "NAV_FIELDS", "STRIDE", "Navigation"]

# Per-vehicle navigation state: per-episode biases and scale factors, the dead-reckoned
# position [m] and its rate [m/s], the last valid DVL sample through the water and over ground,
# and the navigation filter's bias estimates, its covariance P (row-major 4×4 over x, y, k, β)
# and the scratch of its update (gain K, 4×2, and H P, 2×4; docs/model.md §14.8).
NAV_FIELDS = (
    "b_u",
    "b_v",
    "b_w",
    "k_u",
    "k_v",
    "k_w",
    "b_theta",
    "b_psi",
    "b_q",
    "b_r",
    "b_z",
    "x_hat",
    "y_hat",
    "x_dot_hat",
    "y_dot_hat",
    "dvl_u",
    "dvl_v",
    "dvl_w",
    "dvl_ground_u",
    "dvl_ground_v",
    "dvl_ground_w",
    "scale_error",
    "heading_error",
    *(f"p{i}{j}" for i in range(4) for j in range(4)),
    *(f"k{i}" for i in range(8)),
    *(f"hp{i}" for i in range(8)),
)
NAV = field_indices("NavIndex", NAV_FIELDS, __name__)
NAV_DIM = len(NAV_FIELDS)
# One measurement: the entries of the state the observation reads, estimated.
MEAS_FIELDS = ("x", "y", "z", "theta", "psi", "u", "v", "w", "q", "r")
MEAS_DIM = len(MEAS_FIELDS)
MEAS = field_indices("MeasIndex", MEAS_FIELDS, __name__)
_MEAS_STATE = tuple(getattr(STATE, name) for name in MEAS_FIELDS)
# Counter layout of the sample key: normal draws per control step t at STRIDE·t + channel
# (DVL u, v, w; pitch, heading, q, r; depth; fix x, y), the dropout's uniform draw at DROP.
STRIDE = 16
CH_DVL, CH_PITCH, CH_HEADING, CH_Q, CH_R, CH_DEPTH, CH_FIX, CH_DROP = 0, 4, 5, 6, 7, 8, 9, 15
SensorRecord = record_type("SensorRecord", SENSOR_FIELDS, __name__)
_SENSOR_DIM = len(SENSOR_FIELDS)


@njit(cache=True, inline="always")
def _normal(sigma, key, counter):
    """σ·N(0, 1) at ``counter`` of ``key``; exactly 0 (and no draw) for σ = 0."""
    if sigma == 0.0:
        return 0.0
    return sigma * standard_normal(key, counter)


@njit(cache=True, inline="always")
def _add(x, error):
    """x + error, or x itself for a zero error: exact sensors reproduce the state bit for bit
    (−0.0 + 0.0 would be +0.0)."""
    return x if error == 0.0 else x + error


@njit(cache=True, inline="always")
def _draw_biases(s, bias_key, nv):
    """The per-episode constants (`NAV` b_*, k_*) from the bias key, one channel each."""
    for j in range(3):
        nv[NAV.b_u + j] = _normal(s.dvl_bias, bias_key, j)
        nv[NAV.k_u + j] = _normal(s.dvl_scale, bias_key, 3 + j)
    nv[NAV.b_theta] = _normal(s.pitch_bias, bias_key, 6)
    nv[NAV.b_psi] = _normal(s.heading_bias, bias_key, 7)
    nv[NAV.b_q] = _normal(s.rate_bias, bias_key, 8)
    nv[NAV.b_r] = _normal(s.rate_bias, bias_key, 9)
    nv[NAV.b_z] = _normal(s.depth_bias, bias_key, 10)


@njit(cache=True, inline="always")
def _sample_dvl(s, st, c_x, c_y, c_z, key, block, nv):
    """One DVL sample ν̂ = (1 + k)ν + b + σn (docs/model.md §14.1) through the water and over
    ground (ν + R_Bᵀ v_c, bottom lock), with the same ping noise n, into ``nv``."""
    cth, sth = math.cos(st[STATE.theta]), math.sin(st[STATE.theta])
    cps, sps = math.cos(st[STATE.psi]), math.sin(st[STATE.psi])
    cu, cv, cw = body_errors_trig(c_x, c_y, c_z, cth, sth, cps, sps)  # R_Bᵀ v_c
    water = (st[STATE.u], st[STATE.v], st[STATE.w])
    ground = (water[0] + cu, water[1] + cv, water[2] + cw)
    for j in range(3):
        noise = _normal(s.dvl_noise, key, block + CH_DVL + j)
        k, b = nv[NAV.k_u + j], nv[NAV.b_u + j]
        nv[NAV.dvl_u + j] = _add(water[j], k * water[j] + b + noise)
        nv[NAV.dvl_ground_u + j] = _add(ground[j], k * ground[j] + b + noise)


@njit(cache=True, inline="always")
def _p(nv, i, j):
    return nv[NAV.p00 + 4 * i + j]


@njit(cache=True, inline="always")
def _filter_position(s, st, key, block, reset, fix, dx, dy, nv):
    """One step of the navigation filter (docs/model.md §14.8), state (x, y, k, β): the
    horizontal position [m], the scale-factor error k [-] and the heading error β [rad] of the
    dead-reckoned velocity v̂ = (1 + k) R(β) v.

    Predict with the trapezoidal mean v̄ of the measured rate: p ← p + Δt (v̄ − k v̄ − β J v̄),
    J v̄ = (−v̄_y, v̄_x); P ← F P Fᵀ + Q, F = I + G with G's only entries
    ∂p/∂(k, β) = Δt [[−v̄_x, v̄_y], [−v̄_y, −v̄_x]], Q = diag(q_p, q_p, q_b, q_b). On a fix
    z = p + σ_fix n: S = P_pp + σ_fix² I, K = P Hᵀ S⁻¹, P ← P − K H P. A reset starts at the
    first fix, k = β = 0, P = diag(σ_fix², σ_fix², σ_k0², σ_β0²).
    """
    noise_x = _normal(s.fix_noise, key, block + CH_FIX)
    noise_y = _normal(s.fix_noise, key, block + CH_FIX + 1)
    r = s.fix_noise * s.fix_noise
    if reset:
        nv[NAV.x_hat] = st[STATE.x] + noise_x
        nv[NAV.y_hat] = st[STATE.y] + noise_y
        nv[NAV.scale_error], nv[NAV.heading_error] = 0.0, 0.0
        for j in range(16):
            nv[NAV.p00 + j] = 0.0
        nv[NAV.p00], nv[NAV.p11] = r, r
        nv[NAV.p22], nv[NAV.p33] = s.p0_scale, s.p0_heading
        return
    dt = s.control_dt
    vx = 0.5 * (nv[NAV.x_dot_hat] + dx)
    vy = 0.5 * (nv[NAV.y_dot_hat] + dy)
    k, beta = nv[NAV.scale_error], nv[NAV.heading_error]
    nv[NAV.x_hat] += dt * (vx - k * vx + beta * vy)
    nv[NAV.y_hat] += dt * (vy - k * vy - beta * vx)
    g02, g03, g12, g13 = -dt * vx, dt * vy, -dt * vy, -dt * vx
    for j in range(4):  # F P: rows 0, 1 gain G's rows times rows 2, 3
        nv[NAV.p00 + j] += g02 * _p(nv, 2, j) + g03 * _p(nv, 3, j)
        nv[NAV.p10 + j] += g12 * _p(nv, 2, j) + g13 * _p(nv, 3, j)
    for i in range(4):  # (F P) Fᵀ: columns 0, 1 alike
        nv[NAV.p00 + 4 * i] += g02 * _p(nv, i, 2) + g03 * _p(nv, i, 3)
        nv[NAV.p00 + 4 * i + 1] += g12 * _p(nv, i, 2) + g13 * _p(nv, i, 3)
    nv[NAV.p00] += s.q_position
    nv[NAV.p11] += s.q_position
    nv[NAV.p22] += s.q_bias
    nv[NAV.p33] += s.q_bias
    if not fix:
        return
    s00, s01, s11 = nv[NAV.p00] + r, nv[NAV.p01], nv[NAV.p11] + r
    det = s00 * s11 - s01 * s01
    i00, i01, i11 = s11 / det, -s01 / det, s00 / det  # S⁻¹
    for i in range(4):  # K = P Hᵀ S⁻¹ and H P, kept in the scratch columns
        nv[NAV.k0 + 2 * i] = _p(nv, i, 0) * i00 + _p(nv, i, 1) * i01
        nv[NAV.k0 + 2 * i + 1] = _p(nv, i, 0) * i01 + _p(nv, i, 1) * i11
        nv[NAV.hp0 + i] = _p(nv, 0, i)
        nv[NAV.hp0 + 4 + i] = _p(nv, 1, i)
    innovation_x = st[STATE.x] + noise_x - nv[NAV.x_hat]
    innovation_y = st[STATE.y] + noise_y - nv[NAV.y_hat]
    for i, name in enumerate((NAV.x_hat, NAV.y_hat, NAV.scale_error, NAV.heading_error)):
        nv[name] += nv[NAV.k0 + 2 * i] * innovation_x + nv[NAV.k0 + 2 * i + 1] * innovation_y
    for i in range(4):
        for j in range(4):
            nv[NAV.p00 + 4 * i + j] -= (
                nv[NAV.k0 + 2 * i] * nv[NAV.hp0 + j] + nv[NAV.k0 + 2 * i + 1] * nv[NAV.hp0 + 4 + j]
            )


@njit(cache=True, inline="always")
def _sense_row(i, reset, fleet, episodes, outputs, s, sensors):
    """Measure vehicle i, update its navigation state and write its observation (module
    docstring); ``reset`` starts an episode (biases, a start fix, a full delay ring)."""
    if outputs.code[i] == NON_FINITE:  # the state is not finite: the last observation stays
        return
    r = episodes.row[i]
    cfg = config_record(episodes.cfgs[r])
    st, nv, ring = fleet.state[i], sensors.nav[i], sensors.buffer[i]
    step_index = fleet.step_index[i]
    t = step_index // int(cfg.n_sub)
    key, block = sensors.keys[i, 0], STRIDE * t
    if reset:
        _draw_biases(s, sensors.keys[i, 1], nv)
    dropped = not reset and uniform01(key, 2 * (block + CH_DROP)) < s.dvl_dropout
    if not dropped:  # a lost ping leaves the last valid sample in `nv`
        c_x = cfg.current_x + fleet.current[i, 0]
        c_y = cfg.current_y + fleet.current[i, 1]
        c_z = cfg.current_z + fleet.current[i, 2]
        t_s = step_index * cfg.physics_dt
        flowing, ox, oy, oz = ocean_over_ground(fleet.ocean, i, reset, st, t_s, outputs.record)
        if flowing:  # over ground: the waves and profile too
            c_x, c_y, c_z = c_x + ox, c_y + oy, c_z + oz
        _sample_dvl(s, st, c_x, c_y, c_z, key, block, nv)
    theta = _add(st[STATE.theta], nv[NAV.b_theta] + _normal(s.pitch_noise, key, block + CH_PITCH))
    psi_error = nv[NAV.b_psi] + _normal(s.heading_noise, key, block + CH_HEADING)
    psi = st[STATE.psi] if psi_error == 0.0 else wrap_angle(st[STATE.psi] + psi_error)
    q = _add(st[STATE.q], nv[NAV.b_q] + _normal(s.rate_noise, key, block + CH_Q))
    r_rate = _add(st[STATE.r], nv[NAV.b_r] + _normal(s.rate_noise, key, block + CH_R))
    z = _add(st[STATE.z], nv[NAV.b_z] + _normal(s.depth_noise, key, block + CH_DEPTH))
    # Dead reckoning: paper (2) on the measured velocity over ground and attitude, integrated
    # by the trapezoidal rule over the control period (docs/model.md §14.2).
    ground = (nv[NAV.dvl_ground_u], nv[NAV.dvl_ground_v], nv[NAV.dvl_ground_w], q, r_rate)
    dx, dy, _, _, _ = eta_dot(
        ground, math.cos(theta), math.sin(theta), math.cos(psi), math.sin(psi)
    )
    fix_steps = int(s.fix_steps)
    fix = reset or (fix_steps > 0 and t % fix_steps == 0)
    if s.kalman != 0.0:
        _filter_position(s, st, key, block, reset, fix, dx, dy, nv)
    elif fix:  # a fix: p̂ = p + σ_fix n
        nv[NAV.x_hat] = _add(st[STATE.x], _normal(s.fix_noise, key, block + CH_FIX))
        nv[NAV.y_hat] = _add(st[STATE.y], _normal(s.fix_noise, key, block + CH_FIX + 1))
    else:
        nv[NAV.x_hat] += 0.5 * s.control_dt * (nv[NAV.x_dot_hat] + dx)
        nv[NAV.y_hat] += 0.5 * s.control_dt * (nv[NAV.y_dot_hat] + dy)
    nv[NAV.x_dot_hat], nv[NAV.y_dot_hat] = dx, dy
    size = ring.shape[0]  # k + 1: the slot of step t − k is the one after step t's
    slot = t % size
    for first in range(size if reset else 1):  # a reset fills the ring with its measurement
        m = ring[(slot + first) % size]
        m[MEAS.x], m[MEAS.y], m[MEAS.z] = nv[NAV.x_hat], nv[NAV.y_hat], z
        m[MEAS.theta], m[MEAS.psi] = theta, psi
        m[MEAS.u], m[MEAS.v], m[MEAS.w] = nv[NAV.dvl_u], nv[NAV.dvl_v], nv[NAV.dvl_w]
        m[MEAS.q], m[MEAS.r] = q, r_rate
    delayed = ring[(t + 1) % size]
    est = sensors.estimate[i]
    for j in range(STATE_DIM):
        est[j] = st[j]
    for j in range(MEAS_DIM):
        est[_MEAS_STATE[j]] = delayed[j]
    nav_guid = sensors.guid[i]
    kind, pdata = episodes.kinds[r], episodes.pdata[r]
    guidance_row(est, kind, pdata, cfg.u_d, cfg.sigma, nav_guid)
    if s.guidance_estimate != 0.0:  # the guidance computer's u_p, held until the next step
        held = nav_guid[GUIDE.u_p]
        sensors.held_speed[i] = held
        # the true row at the speed the point now moves at (u_D = held, σ = ∞: u_p = held)
        guidance_row(st, kind, pdata, held, math.inf, outputs.guid[i])
    o = outputs.obs[i]
    build_observation(est, nav_guid, cfg.u_d, o)
    # The readings saturate at the observation bounds, except where the true observation left
    # them (an "envelope" end): there exact sensors return what "ideal" returns.
    if outputs.code[i] != ENVELOPE:
        for j in range(OBS_DIM):
            o[j] = min(max(o[j], episodes.obs_low[j]), episodes.obs_high[j])


# One serial pass, also beside the threaded physics kernel: it costs about 1 µs per vehicle
# (a fifth of a control step's physics), and it allocates nothing, so it runs without numba's
# reference counting (`_nrt=False`, as `simulator._step_one`). A threaded pass was slower: the
# reference counts of its row views are atomic updates the threads contend for.
@njit(cache=True, _nrt=False)
def _sense(rows, reset, fleet, episodes, outputs, scfg, sensors):
    s = SensorRecord(*fixed_tuple(scfg, _SENSOR_DIM))
    for n in range(rows.shape[0]):
        _sense_row(rows[n], reset, fleet, episodes, outputs, s, sensors)


class SensorArrays(NamedTuple):
    """The sensor model's per-vehicle arrays, as the compiled pass takes them."""

    keys: np.ndarray  # uint64 (sample key, bias key)
    nav: np.ndarray  # navigation state (`NAV`)
    buffer: np.ndarray  # delay ring of measurements (`MEAS`)
    estimate: np.ndarray  # the state with the measured entries
    guid: np.ndarray  # guidance row of the estimated pose
    held_speed: np.ndarray  # [m/s] the guidance computer's u_p (virtual_point="estimate")


class Navigation:
    """The sensor model of n vehicles: its per-vehicle arrays (`ARRAYS`, saved by
    `Simulator.snapshot`) and the compiled pass that turns the simulator's true state into
    the estimated observation, run after every physics step and reset."""

    ARRAYS = ("keys", "nav", "buffer", "estimate", "guid")
    GUIDANCE_ARRAYS = ("held_speed",)  # saved too with virtual_point="estimate"

    def __init__(self, config: SensorConfig, control_dt: float, n: int, speed: float = 1.0) -> None:
        self.config = config
        self._packed = config.packed(control_dt, speed)
        self.keys = np.zeros((n, 2), dtype=np.uint64)  # sample key, bias key
        self.nav = np.zeros((n, NAV_DIM))
        self.buffer = np.zeros((n, config.delay + 1, MEAS_DIM))
        self.estimate = np.zeros((n, STATE_DIM))  # the state with the measured entries
        self.guid = np.zeros((n, GUIDANCE_DIM))  # guidance row of the estimated pose
        # [m/s] the virtual-point speed a guidance computer holds over the next control period
        # (virtual_point="estimate"; the physics reads it through `Fleet.guidance`)
        self.held_speed = np.zeros(n)

    @property
    def arrays(self) -> tuple[str, ...]:
        """The names of the per-vehicle arrays a snapshot saves."""
        extra = self.GUIDANCE_ARRAYS if self.config.guidance_from_estimate else ()
        return (*self.ARRAYS, *extra)

    @property
    def guidance(self) -> np.ndarray | None:
        """The held virtual-point speeds the physics reads (`fleet.Fleet.guidance`), or None
        when the plant's law moves the virtual point."""
        return self.held_speed if self.config.guidance_from_estimate else None

    def ground_velocity(self, rows: np.ndarray) -> np.ndarray:
        """The last valid DVL sample over ground (u, v, w) of ``rows``, body frame [m/s]: what
        the agent observation's velocity over ground reads when sensors are modelled."""
        return self.nav[rows, NAV.dvl_ground_u : NAV.dvl_ground_w + 1]

    def sense(self, sim: Simulator, rows: np.ndarray, reset: bool) -> None:
        """Measure ``rows`` of the `Simulator` ``sim`` and overwrite their observations;
        ``reset``: new episodes, whose keys derive from their white-noise keys."""
        if reset:
            noise_keys = sim.keys[rows, KEY.noise]
            self.keys[rows, 0] = sensor_key(noise_keys, 0)
            self.keys[rows, 1] = sensor_key(noise_keys, 1)
        sensors = SensorArrays(
            self.keys, self.nav, self.buffer, self.estimate, self.guid, self.held_speed
        )
        _sense(rows, reset, sim.fleet, sim.episodes, sim.outputs, self._packed, sensors)
