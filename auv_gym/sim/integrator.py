"""The pieces of a physics step every plant shares: the packed config, the 5-DOF RK4, the
commanded actuation, the forcing of one physics step and the period's records.

The period loop that puts them together, for either plant, is `period.advance_period`; the
plant-specific steps are in `plants`. Speed (docs/performance.md): the state, the RK4 stages,
the parameters, the packed config and the sums stay in registers as tuples for the whole period;
no heap array is made and no array reference is taken inside the loop (each costs two atomic
reference-count updates).
"""

from __future__ import annotations

from numba import njit

from auv_gym.ocean.disturbances import N_CHANNELS, white_noise
from auv_gym.ocean.forcing import ocean_forcing, refresh_waves
from auv_gym.sim.observation import build_observation, guidance_row
from auv_gym.support.records import field_indices, fixed_tuple, record_type
from auv_gym.vehicle.actuators import ACTUATOR_CONFIG_FIELDS
from auv_gym.vehicle.dynamics import STATE_DIM, state_derivative
from auv_gym.vehicle.params import params_record

__all__ = [
    "ACTUATORS",
    "CONFIG_DIM",
    "CONFIG_FIELDS",
    "REALISTIC_ACTUATOR",
    "RECORD",
    "RECORD_DIM",
    "RECORD_FIELDS",
    "actuation",
    "add_noise",
    "config_record",
    "finish_period",
    "physics_step_forcing",
    "rk4",
    "rk4_step",
]

PAPER_ACTUATOR, FIN_ACTUATOR, REALISTIC_ACTUATOR = 0, 1, 2
ACTUATORS = {"paper": PAPER_ACTUATOR, "fins": FIN_ACTUATOR, "realistic": REALISTIC_ACTUATOR}

# Layout of the packed simulation config (`config.SimConfig.packed`): the fields every mode
# reads as a record, then the realistic actuators' parameters, read only in that mode (a wider
# record costs the default kernel a third of its speed).
_RECORD_FIELDS = (
    "n_sub",
    "physics_dt",
    "hold_steps",
    "u_d",
    "sigma",
    "actuator",
    "gm_a",
    "noise_f_u",
    "noise_f_v",
    "noise_f_w",
    "noise_f_q",
    "noise_f_r",
    "limit_X",
    "limit_M",
    "limit_N",
    "current_x",
    "current_y",
    "current_z",
    "gm_b_x",
    "gm_b_y",
    "gm_b_z",
)
CONFIG_FIELDS = (*_RECORD_FIELDS, *ACTUATOR_CONFIG_FIELDS)
CONFIG_DIM = len(_RECORD_FIELDS)  # entries of `ConfigRecord`; the actuators' follow
ConfigRecord = record_type("ConfigRecord", _RECORD_FIELDS, __name__)

# Per-vehicle record of a control period: mean applied τ [N, N·m] and mean disturbance f.
# The control period's mean τ and white noise, and the earth-frame velocity the ocean row
# (waves, profiled current) added to the current in its last physics step [m/s]: what a
# bottom-tracking DVL sees beside the uniform current (`auv_gym.sim.navigation`).
RECORD_FIELDS = ("X", "M", "N", "f_u", "f_v", "f_w", "f_q", "f_r", "ocean_x", "ocean_y", "ocean_z")
RECORD_DIM = len(RECORD_FIELDS)
RECORD = field_indices("RecordIndex", RECORD_FIELDS, __name__)


@njit(cache=True, inline="always")
def config_record(cfg):
    """The packed config row ``cfg`` as a `ConfigRecord` held in registers."""
    return ConfigRecord(*fixed_tuple(cfg, CONFIG_DIM))


# RK4 arithmetic on whole 11-tuples, element by element (a tuple cannot be built in a loop).
@njit(cache=True, inline="always")
def _stage(st, h, k):
    """st + h·k."""
    return (
        st[0] + h * k[0],
        st[1] + h * k[1],
        st[2] + h * k[2],
        st[3] + h * k[3],
        st[4] + h * k[4],
        st[5] + h * k[5],
        st[6] + h * k[6],
        st[7] + h * k[7],
        st[8] + h * k[8],
        st[9] + h * k[9],
        st[10] + h * k[10],
    )


@njit(cache=True, inline="always")
def _rk4_combine(st, h, k1, k2, k3, k4):
    """st + h·(k1 + 2 k2 + 2 k3 + k4), with h = dt/6."""
    return _stage(
        st,
        h,
        (
            k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0],
            k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1],
            k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2],
            k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3],
            k1[4] + 2.0 * k2[4] + 2.0 * k3[4] + k4[4],
            k1[5] + 2.0 * k2[5] + 2.0 * k3[5] + k4[5],
            k1[6] + 2.0 * k2[6] + 2.0 * k3[6] + k4[6],
            k1[7] + 2.0 * k2[7] + 2.0 * k3[7] + k4[7],
            k1[8] + 2.0 * k2[8] + 2.0 * k3[8] + k4[8],
            k1[9] + 2.0 * k2[9] + 2.0 * k3[9] + k4[9],
            k1[10] + 2.0 * k2[10] + 2.0 * k3[10] + k4[10],
        ),
    )


@njit(cache=True, inline="always")
def rk4(st, tau, f, current, p, kind, pdata, u_d, sigma, dt):
    """One classical RK4 step of `dynamics.state_derivative` over dt [s] on a state tuple, with
    τ, f and the current held; arguments as there."""
    k1 = state_derivative(st, tau, f, current, p, kind, pdata, u_d, sigma)
    k2 = state_derivative(_stage(st, 0.5 * dt, k1), tau, f, current, p, kind, pdata, u_d, sigma)
    k3 = state_derivative(_stage(st, 0.5 * dt, k2), tau, f, current, p, kind, pdata, u_d, sigma)
    k4 = state_derivative(_stage(st, dt, k3), tau, f, current, p, kind, pdata, u_d, sigma)
    return _rk4_combine(st, dt / 6.0, k1, k2, k3, k4)


@njit(cache=True)
def rk4_step(st, tau, f, current, p_array, kind, pdata, u_d, sigma, dt, out):
    """Array form of `rk4`: reads the state row ``st`` and the packed parameters ``p_array``
    (`AUVParams.to_vector`), writes the new state into ``out``."""
    nxt = rk4(
        fixed_tuple(st, STATE_DIM),
        tau,
        f,
        current,
        params_record(p_array),
        kind,
        pdata,
        u_d,
        sigma,
        dt,
    )
    for i in range(STATE_DIM):
        out[i] = nxt[i]


@njit(cache=True, inline="always")
def actuation(a_X, a_M, a_N, cfg, fin_gain, u):
    """τ = (X, M, N) [N, N·m] for the action (a_X, a_M, a_N) in [−1, 1]³ (docs/model.md §2.3):
    "paper" scales by the constant limits; "fins" keeps X = a_X·X_max and gives
    M, N = a·K·δ_max·u|u| (fin-lift coefficient K, deflection limit δ_max), updated every step."""
    X = a_X * cfg.limit_X
    if int(cfg.actuator) == PAPER_ACTUATOR:
        return X, a_M * cfg.limit_M, a_N * cfg.limit_N
    authority = fin_gain * u * abs(u)
    return X, a_M * authority, a_N * authority


@njit(cache=True, inline="always")
def physics_step_forcing(
    cfg, p, noise_amplitude, noise_key, hold_steps, dc, ocean_on, ocean, i, pose, n, k, wave, added
):
    """The white noise f and the earth-fixed current [m/s] of physics step n (the k-th of the
    period) at ``pose`` (x, y, z [m], θ, ψ [rad]), held across its RK4 stages: the uniform
    current plus its Gauss–Markov deviation ``dc``, and with an active ocean row (row i of
    ``ocean``) its waves and profile (t at mid-step). Returns (f, current, wave, added):
    ``added`` [m/s] is the ocean's part of the current, the last one kept when there is no
    ocean."""
    f = white_noise(noise_amplitude, noise_key, n, hold_steps)
    current = (cfg.current_x + dc[0], cfg.current_y + dc[1], cfg.current_z + dc[2])
    if ocean_on:
        row = ocean[i]
        wave = refresh_waves(row, pose, n, k, cfg.physics_dt, wave)
        uniform = current
        current, f = ocean_forcing(row, pose, (n + 0.5) * cfg.physics_dt, wave, current, f, p)
        added = (current[0] - uniform[0], current[1] - uniform[1], current[2] - uniform[2])
    return f, current, wave, added


@njit(cache=True, inline="always")
def add_noise(total, f):
    """The running sum of the five disturbance channels plus f."""
    return (total[0] + f[0], total[1] + f[1], total[2] + f[2], total[3] + f[3], total[4] + f[4])


@njit(cache=True, inline="always")
def finish_period(
    st, kind, pdata, cfg, guid, obs, record, sum_X, sum_M, sum_N, sum_f, ocean_on, added
):
    """Write the period's mean τ and f and, with an ocean row, the ocean's last added velocity
    into ``record`` (layout `RECORD`), then the guidance row and the observation of the state
    ``st``."""
    n_sub = int(cfg.n_sub)
    record[RECORD.X] = sum_X / n_sub
    record[RECORD.M] = sum_M / n_sub
    record[RECORD.N] = sum_N / n_sub
    for c in range(N_CHANNELS):  # f_u … f_r
        record[RECORD.f_u + c] = sum_f[c] / n_sub
    if ocean_on:
        record[RECORD.ocean_x], record[RECORD.ocean_y], record[RECORD.ocean_z] = added
    guidance_row(st, kind, pdata, cfg.u_d, cfg.sigma, guid)
    build_observation(st, guid, cfg.u_d, obs)
