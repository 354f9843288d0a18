"""The records the step kernels read and write: the fleet, the episode table and the outputs.

A `Simulator` keeps n vehicles as arrays, one row each. The kernels take them grouped in three
named tuples (numba passes a named tuple of arrays as one argument) instead of two dozen
positional arrays:

- `Fleet`: what each vehicle is and carries from step to step (state, parameters, keys, the
  plant's and the options' rows);
- `EpisodeTable`: what each vehicle's episode reads (its row of the path, config and task
  tables) and the observation bounds;
- `StepOutputs`: what a step writes (guidance row, observation, period record, reward terms,
  reward, end code, safety cost).

A record member that is None is compiled out: a kernel is compiled for the types it is given,
so it holds no code for it. That is how the plant is chosen (the 6-DOF plant's ``roll`` and
``hull``, None on the 5-DOF: `plants`), how a safety cost with zero weights is skipped
(``cost``) and how the virtual point moves (``guidance``: None, the plant's law at the true
along-track error; an array, the speeds a guidance computer holds, `virtual_point_law`). The
realistic actuators' state and the ocean rows are always passed; their per-row flags decide at
run time (compiling them out bought little speed for a minute of compiling per combination,
docs/performance.md).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, types
from numba.extending import overload

from auv_gym.ocean.forcing import OCEAN, ocean_velocity
from auv_gym.sim.integrator import REALISTIC_ACTUATOR, RECORD
from auv_gym.vehicle.actuators import ACTUATOR_STATE
from auv_gym.vehicle.dynamics import STATE

__all__ = [
    "EpisodeTable",
    "Fleet",
    "StepOutputs",
    "actuator_state",
    "ocean_active",
    "ocean_over_ground",
    "realistic_actuators",
    "store_actuator_state",
    "virtual_point_law",
]


class Fleet(NamedTuple):
    """Per-vehicle arrays (n rows) carried from step to step; None where an option is off."""

    state: np.ndarray  # 5-DOF state rows (`dynamics.STATE`)
    current: np.ndarray  # Gauss–Markov current deviation (x, y, z) [m/s]
    params: np.ndarray  # 5-DOF parameter rows (`AUVParams.to_vector`)
    keys: np.ndarray  # uint64 noise and current keys (`disturbances.KEY`)
    step_index: np.ndarray  # int64 physics steps since the reset
    roll: np.ndarray | None  # 6-DOF plant: (φ [rad], p [rad/s]) (`plants.ROLL`)
    hull: np.ndarray | None  # 6-DOF plant: hull rows (`SixDofVehicle.kernel_vector`)
    actuators: np.ndarray  # realistic actuators: `actuators.ACTUATOR_STATE` rows (else zero)
    ocean: np.ndarray  # waves or profiled current: `ocean.ocean_row` rows (else inactive)
    # the virtual-point speed u_p [m/s] a guidance computer holds over the control period
    # (sensors virtual_point="estimate", `navigation`); None: the plant's law at the true x_e
    guidance: np.ndarray | None


class EpisodeTable(NamedTuple):
    """What each vehicle's episode reads: row ``row[i]`` of the path, config and task tables."""

    row: np.ndarray  # int64 (n,): each vehicle's table row
    kinds: np.ndarray  # int64 path kinds
    pdata: np.ndarray  # path vectors, padded to the longest
    cfgs: np.ndarray  # packed configs (`SimConfig.packed`, layout `integrator.CONFIG_FIELDS`)
    tasks: np.ndarray  # task rows (`task.TASK_FIELDS`)
    obs_low: np.ndarray  # the paper observation's bounds, for the termination check
    obs_high: np.ndarray


class StepOutputs(NamedTuple):
    """What a step writes per vehicle; ``cost`` is None when the safety cost is off (it stays
    0 then)."""

    guid: np.ndarray  # guidance rows (`observation.GUIDANCE_DIM`)
    obs: np.ndarray  # paper observations (`observation.OBS_DIM`)
    record: np.ndarray  # period records (`integrator.RECORD`)
    terms: np.ndarray  # reward terms (`task.REWARD_TERMS`)
    reward: np.ndarray
    code: np.ndarray  # int64 end codes (`task.TERMINATION_REASONS`)
    cost: np.ndarray | None  # safety cost c ≥ 0 (`safety_cost`)


@njit(cache=True, inline="always")
def ocean_active(ocean, i):
    """Whether vehicle i's ocean row (`ocean.ocean_row`) adds waves or a profiled current."""
    return ocean[i, OCEAN.active] != 0.0


@njit(cache=True, inline="always")
def ocean_over_ground(ocean, i, reset, st, t, record):
    """(active, v_x, v_y, v_z): whether vehicle i's ocean row adds to the current, and the
    earth-frame velocity [m/s] it adds at the state ``st`` at time t [s] (at a reset) or in the
    period's last physics step (its ``record`` row, `integrator.RECORD`)."""
    if ocean[i, OCEAN.active] == 0.0:
        return False, 0.0, 0.0, 0.0
    if reset:
        ox, oy, oz = ocean_velocity(ocean[i], st[STATE.x], st[STATE.y], st[STATE.z], t)
        return True, ox, oy, oz
    return True, record[i, RECORD.ocean_x], record[i, RECORD.ocean_y], record[i, RECORD.ocean_z]


@njit(cache=True, inline="always")
def realistic_actuators(actuator):
    """Whether a vehicle flies the realistic actuators this episode (its config's code)."""
    return int(actuator) == REALISTIC_ACTUATOR


@njit(cache=True, inline="always")
def actuator_state(actuators, i):
    """(shaft speed [rpm], δ_s, δ_r [rad]) of vehicle i's actuators (`ACTUATOR_STATE`)."""
    state = ACTUATOR_STATE
    return actuators[i, state.n_rpm], actuators[i, state.delta_s], actuators[i, state.delta_r]


@njit(cache=True, inline="always")
def store_actuator_state(actuators, i, shaft, d_s, d_r, rate_limited):
    """Write vehicle i's actuator state and the period's rate-limited fraction."""
    actuators[i, ACTUATOR_STATE.n_rpm] = shaft
    actuators[i, ACTUATOR_STATE.delta_s] = d_s
    actuators[i, ACTUATOR_STATE.delta_r] = d_r
    actuators[i, ACTUATOR_STATE.rate_limited] = rate_limited


# virtual_point_law: the (u_D [m/s], σ [m]) of u_p = u_D(1 + tanh(x_e/σ)) (docs/model.md §3.3)
# the RK4 stages of vehicle i's physics step use. A held speed enters the same law as u_D = the
# speed and σ = ∞: tanh(x_e/∞) = tanh(±0) = ±0 exactly, so u_p is the held speed whatever x_e,
# and the plants' state equations need no second form.
def _plant_law(guidance, i, u_d, sigma):
    return u_d, sigma


def _held_law(guidance, i, u_d, sigma):
    return guidance[i], math.inf


def virtual_point_law(guidance, i, u_d, sigma):
    """(u_D, σ) for vehicle i: the configured law (``guidance`` None) or its held speed."""
    return (_plant_law if guidance is None else _held_law)(guidance, i, u_d, sigma)


@overload(virtual_point_law, inline="always")
def _virtual_point_law(guidance, i, u_d, sigma):
    return _plant_law if isinstance(guidance, types.NoneType) else _held_law
