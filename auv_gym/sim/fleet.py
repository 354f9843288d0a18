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

An option that a configuration does not use is None in its record, and a kernel is compiled for
the types it is given, so it holds no code for it: the 6-DOF plant's ``roll`` and ``hull``
(`plants`), the realistic actuators' ``actuators``, the waves' and profiled current's
``ocean``, the safety cost's ``cost``. The hooks below read and write those optional arrays.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import types
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
    actuators: np.ndarray | None  # realistic actuators: `actuators.ACTUATOR_STATE` rows
    ocean: np.ndarray | None  # waves or profiled current: `ocean.ocean_row` rows


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


def _is_none(array_type) -> bool:
    return isinstance(array_type, types.NoneType)


def _ocean_off(ocean, i):
    return False


def _ocean_flag(ocean, i):
    return ocean[i, OCEAN.active] != 0.0


def ocean_active(ocean, i):
    """Whether vehicle i's ocean row (`ocean.ocean_row`) adds waves or a profiled current; False
    for an ``ocean`` of None, when no vehicle of the configuration has them."""
    return ocean is not None and ocean[i, OCEAN.active] != 0.0


@overload(ocean_active, inline="always")
def _ocean_active(ocean, i):
    return _ocean_off if _is_none(ocean) else _ocean_flag


def _still_water(ocean, i, reset, st, t, record):
    return False, 0.0, 0.0, 0.0


def _ocean_velocity(ocean, i, reset, st, t, record):
    if ocean[i, OCEAN.active] == 0.0:
        return False, 0.0, 0.0, 0.0
    if reset:  # evaluated at the start; later the physics' last step's (`integrator.RECORD`)
        ox, oy, oz = ocean_velocity(ocean[i], st[STATE.x], st[STATE.y], st[STATE.z], t)
        return True, ox, oy, oz
    return True, record[i, RECORD.ocean_x], record[i, RECORD.ocean_y], record[i, RECORD.ocean_z]


def ocean_over_ground(ocean, i, reset, st, t, record):
    """(active, v_x, v_y, v_z): whether vehicle i's ocean row adds to the current, and the
    earth-frame velocity [m/s] it adds at the state ``st`` at time t [s] (at a reset) or in the
    period's last physics step (its ``record`` row); inactive for an ``ocean`` of None."""
    return (_still_water if ocean is None else _ocean_velocity)(ocean, i, reset, st, t, record)


@overload(ocean_over_ground, inline="always")
def _ocean_over_ground(ocean, i, reset, st, t, record):
    return _still_water if _is_none(ocean) else _ocean_velocity


# The hooks take the whole (n, ·) array and the vehicle's index, never a row view: a row view
# returned by an inlined overload from a named tuple's member came back as a copy (numba 0.68),
# and the realistic actuators' state then never moved.
def _never_realistic(actuators, actuator):
    return False


def _realistic_code(actuators, actuator):
    return int(actuator) == REALISTIC_ACTUATOR


def realistic_actuators(actuators, actuator):
    """Whether a vehicle flies the realistic actuators this episode (its config's ``actuator``
    code); False for ``actuators`` None, when no vehicle has them."""
    return actuators is not None and int(actuator) == REALISTIC_ACTUATOR


@overload(realistic_actuators, inline="always")
def _realistic_actuators(actuators, actuator):
    return _never_realistic if _is_none(actuators) else _realistic_code


def _stopped(actuators, i):
    return 0.0, 0.0, 0.0


def _actuator_values(actuators, i):
    state = ACTUATOR_STATE
    return actuators[i, state.n_rpm], actuators[i, state.delta_s], actuators[i, state.delta_r]


def actuator_state(actuators, i):
    """(shaft speed [rpm], δ_s, δ_r [rad]) of vehicle i's actuators; the stopped propeller and
    centred fins for None, when no vehicle has the realistic actuators."""
    return _stopped(actuators, i) if actuators is None else _actuator_values(actuators, i)


@overload(actuator_state, inline="always")
def _actuator_state(actuators, i):
    return _stopped if _is_none(actuators) else _actuator_values


def _keep_nothing(actuators, i, shaft, d_s, d_r, rate_limited):
    return None


def _store_actuators(actuators, i, shaft, d_s, d_r, rate_limited):
    actuators[i, ACTUATOR_STATE.n_rpm] = shaft
    actuators[i, ACTUATOR_STATE.delta_s] = d_s
    actuators[i, ACTUATOR_STATE.delta_r] = d_r
    actuators[i, ACTUATOR_STATE.rate_limited] = rate_limited


def store_actuator_state(actuators, i, shaft, d_s, d_r, rate_limited):
    """Write vehicle i's actuator state and the period's rate-limited fraction, if it has one."""
    store = _keep_nothing if actuators is None else _store_actuators
    store(actuators, i, shaft, d_s, d_r, rate_limited)


@overload(store_actuator_state, inline="always")
def _store_actuator_state(actuators, i, shaft, d_s, d_r, rate_limited):
    return _keep_nothing if _is_none(actuators) else _store_actuators
