"""The `info` of both envs, built once from the simulator's rows through their named layouts.

`info_columns` gives every vehicle's value of each key, in the info's order; the vector env
reports them as arrays with masks, the single env takes row 0 (`single_info`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from auv_gym.sim.integrator import RECORD
from auv_gym.sim.observation import GUIDE
from auv_gym.sim.plants import ROLL
from auv_gym.sim.task import REWARD_TERMS, TERMINATION_REASONS
from auv_gym.vehicle.dynamics import STATE

if TYPE_CHECKING:
    from auv_gym.sim.simulator import Simulator

__all__ = ["REASONS", "STEP_KEYS", "add_vector_infos", "info_columns", "single_info", "track_point"]

REWARD_KEYS = tuple(f"reward_{name}" for name in REWARD_TERMS)
STEP_KEYS = frozenset((*REWARD_KEYS, "cost"))  # reported only by vehicles that stepped
REASONS = np.array([None, *TERMINATION_REASONS[1:]], dtype=object)  # code 0: no reason
_POSITION = slice(STATE.x, STATE.z + 1)  # x, y, z [m]
_ERRORS = slice(GUIDE.x_e, GUIDE.z_e + 1)  # x_e, y_e, z_e [m]
_TAU = slice(RECORD.X, RECORD.N + 1)  # applied X, M, N [N, N·m]
_DISTURBANCE = slice(RECORD.f_u, RECORD.f_r + 1)  # white noise f_u … f_r [N, N·m]


def info_columns(sim: Simulator, physics_dt: float, stepped: bool) -> dict[str, np.ndarray]:
    """Each info key's values over vehicles, in the info's order (views of the simulator's
    rows, except ``t``); with ``stepped`` also the reward terms and the safety cost; on the
    6-DOF plant also the roll angle ``phi`` [rad] and rate ``roll_rate`` [rad/s]."""
    g, record = sim.guid, sim.record
    columns: dict[str, np.ndarray] = {
        "x_e": g[:, GUIDE.x_e],
        "y_e": g[:, GUIDE.y_e],
        "z_e": g[:, GUIDE.z_e],
        "distance": g[:, GUIDE.distance],
        "s": sim.state[:, STATE.s],
        "u_p": g[:, GUIDE.u_p],
        "t": sim.step_index * physics_dt,
        "tau": record[:, _TAU],
        "disturbance": record[:, _DISTURBANCE],
    }
    if sim.six_dof:  # the 6-DOF plant
        columns["phi"] = sim.roll[:, ROLL.phi]
        columns["roll_rate"] = sim.roll[:, ROLL.p]
    if stepped:
        columns.update(zip(REWARD_KEYS, sim.terms.T, strict=True))
        columns["cost"] = sim.cost
    return columns


def single_info(sim: Simulator, physics_dt: float, code: int, reset: bool) -> dict[str, Any]:
    """Vehicle 0's info: Python floats, copies of its ``tau`` (3,) and ``disturbance`` (5,), and
    ``termination_reason`` if ``code`` ends the episode; no reward terms after a reset."""
    info: dict[str, Any] = {
        key: values[0].copy() if values.ndim > 1 else float(values[0])
        for key, values in info_columns(sim, physics_dt, not reset).items()
    }
    if code:
        info["termination_reason"] = TERMINATION_REASONS[code]
    return info


def track_point(sim: Simulator, v: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Vehicle ``v``'s position [m], path errors (x_e, y_e, z_e) [m] and s: what the renderer
    draws."""
    return sim.state[v, _POSITION], sim.guid[v, _ERRORS], sim.state[v, STATE.s]


def add_vector_infos(
    infos: dict[str, Any],
    sim: Simulator,
    physics_dt: float,
    base: np.ndarray,
    stepped: np.ndarray,
    fill: bool = False,
) -> None:
    """Add the single env's info keys to the vector env's ``infos`` as arrays with ``_key``
    masks (SyncVectorEnv layout).

    ``base`` marks vehicles reporting the keys every info has, ``stepped`` those that also
    report the reward terms and, if terminated, the reason. With ``fill`` the values of
    unmarked vehicles are zeroed as SyncVectorEnv leaves them.
    """
    columns = info_columns(sim, physics_dt, bool(stepped.any()))
    for key, values in columns.items():
        mask = stepped if key in STEP_KEYS else base
        if fill and not mask.all():
            values = np.where(mask.reshape(-1, *([1] * (values.ndim - 1))), values, 0.0)
        infos[key] = np.array(values, dtype=np.float64)
        infos[f"_{key}"] = mask.copy()
    reason_mask = stepped & (sim.code != 0)
    if reason_mask.any():
        infos["termination_reason"] = np.where(reason_mask, REASONS[sim.code], None)
        infos["_termination_reason"] = reason_mask
