"""The plants the period loop flies, behind one interface chosen when a kernel compiles.

Two plants exist (docs/model.md §11.1, §15): the paper's 5-DOF vehicle (eqs. 1–2, `dynamics`,
its numbers the 5-DOF record ``params``) and Fossen's 6-DOF hull (`six_dof`, its numbers one
`SixDofVehicle.kernel_vector` row per vehicle). The plant is named by the type of the fleet's
``hull`` (`fleet.Fleet`), which every hook takes first: None is the 5-DOF, a 2-D array the
6-DOF. Each hook below is plain
Python (it runs with ``NUMBA_DISABLE_JIT=1``) and an overload that numba resolves by that type,
so a kernel holds one plant's code and none of the other's.

The 6-DOF state is split between the fleet's 5-DOF row (x, y, z, θ, ψ, u, v, w, q, r, s: what
the guidance, the observation, the navigation and the task read, so they are one code for both
plants) and its roll row (`ROLL`: φ [rad], p [rad/s]).

How the 5-DOF actuator modes act on the 6-DOF hull (docs/model.md §15.1): "paper" applies
τ = (X, 0, 0, 0, M, N); "fins" the same with the fin authority of the 5-DOF record; "realistic"
the propeller and fins with their lift, side and heave forces and the propeller's torque in
roll, at the velocity through the water.
"""

from __future__ import annotations

import math

from numba import types
from numba.extending import overload

from auv_gym.paths.guidance import wrap_angle
from auv_gym.sim.integrator import rk4
from auv_gym.support.records import field_indices, fixed_tuple
from auv_gym.vehicle.actuators import actuator_forces
from auv_gym.vehicle.dynamics import STATE, STATE_DIM
from auv_gym.vehicle.six_dof import SIX_DOF, six_dof_actuation, six_dof_rk4

__all__ = [
    "ROLL",
    "ROLL_DIM",
    "ROLL_NAMES",
    "commanded_forces",
    "load_state",
    "plant_rk4",
    "pose",
    "propulsion_forces",
    "store_state",
    "surge",
    "wrap_state",
]

ROLL_NAMES = ("phi", "p")  # [rad], [rad/s]
ROLL_DIM = len(ROLL_NAMES)
ROLL = field_indices("RollIndex", ROLL_NAMES, __name__)


def _five_dof(hull_type) -> bool:
    """Whether a hook is being compiled for the 5-DOF plant (its hull is None)."""
    return isinstance(hull_type, types.NoneType)


# load_state / store_state: the plant's state tuple from and into the fleet's rows.
def _five_dof_load(hull, fleet, i):
    return fixed_tuple(fleet.state[i], STATE_DIM)


def _six_dof_load(hull, fleet, i):
    st, roll = fleet.state, fleet.roll
    return (
        st[i, STATE.x],
        st[i, STATE.y],
        st[i, STATE.z],
        roll[i, ROLL.phi],
        st[i, STATE.theta],
        st[i, STATE.psi],
        st[i, STATE.u],
        st[i, STATE.v],
        st[i, STATE.w],
        roll[i, ROLL.p],
        st[i, STATE.q],
        st[i, STATE.r],
        st[i, STATE.s],
    )


def load_state(hull, fleet, i):
    """Vehicle i's state as a tuple: the 5-DOF state (`dynamics.STATE`) when ``hull`` is None,
    else the 6-DOF one (`six_dof.SIX_DOF_STATE`)."""
    return (_five_dof_load if hull is None else _six_dof_load)(hull, fleet, i)


@overload(load_state, inline="always")
def _load_state(hull, fleet, i):
    return _five_dof_load if _five_dof(hull) else _six_dof_load


def _five_dof_store(hull, fleet, i, x):
    for j in range(STATE_DIM):
        fleet.state[i, j] = x[j]


def _six_dof_store(hull, fleet, i, x):
    st, roll = fleet.state, fleet.roll
    st[i, STATE.x], st[i, STATE.y], st[i, STATE.z] = x[0], x[1], x[2]
    st[i, STATE.theta], st[i, STATE.psi] = x[4], x[5]
    st[i, STATE.u], st[i, STATE.v], st[i, STATE.w] = x[6], x[7], x[8]
    st[i, STATE.q], st[i, STATE.r], st[i, STATE.s] = x[10], x[11], x[12]
    roll[i, ROLL.phi], roll[i, ROLL.p] = x[3], x[9]


def store_state(hull, fleet, i, x):
    """Write the state tuple x back into vehicle i's rows of the fleet."""
    (_five_dof_store if hull is None else _six_dof_store)(hull, fleet, i, x)


@overload(store_state, inline="always")
def _store_state(hull, fleet, i, x):
    return _five_dof_store if _five_dof(hull) else _six_dof_store


# pose / surge: what the ocean and the fin authority read from the state tuple.
def _five_dof_pose(hull, x):
    return x[0], x[1], x[2], x[3], x[4]


def _six_dof_pose(hull, x):
    return x[0], x[1], x[2], x[4], x[5]


def pose(hull, x):
    """(x, y, z [m], θ, ψ [rad]) of the state tuple x."""
    return (_five_dof_pose if hull is None else _six_dof_pose)(hull, x)


@overload(pose, inline="always")
def _pose(hull, x):
    return _five_dof_pose if _five_dof(hull) else _six_dof_pose


def _five_dof_surge(hull, x):
    return x[STATE.u]


def _six_dof_surge(hull, x):
    return x[6]


def surge(hull, x):
    """The surge speed u [m/s] of the state tuple x."""
    return (_five_dof_surge if hull is None else _six_dof_surge)(hull, x)


@overload(surge, inline="always")
def _surge(hull, x):
    return _five_dof_surge if _five_dof(hull) else _six_dof_surge


# commanded_forces / propulsion_forces: τ in the plant's layout and the disturbance it feels.
def _five_dof_commanded(hull, X, M, N, f):
    return (X, M, N), f


def _six_dof_commanded(hull, X, M, N, f):
    return (X, 0.0, 0.0, 0.0, M, N), f


def commanded_forces(hull, X, M, N, f):
    """(τ, f) for the commanded X [N], M, N [N·m] of the "paper" and "fins" modes."""
    return (_five_dof_commanded if hull is None else _six_dof_commanded)(hull, X, M, N, f)


@overload(commanded_forces, inline="always")
def _commanded_forces(hull, X, M, N, f):
    return _five_dof_commanded if _five_dof(hull) else _six_dof_commanded


def _five_dof_propulsion(hull, i, x, f, shaft, d_s, d_r, a):
    # The fins' side and heave forces Y, Z enter the 5-DOF model where f_v, f_w do.
    X, Y, Z, M, N = actuator_forces(shaft, d_s, d_r, x[STATE.u], x[STATE.v], x[STATE.w], a)
    return (X, M, N), (f[0], f[1] + Y, f[2] + Z, f[3], f[4]), X, M, N


def _six_dof_propulsion(hull, i, x, f, shaft, d_s, d_r, a):
    nu_r = (x[6], x[7], x[8], x[9], x[10], x[11])
    speed = math.sqrt(nu_r[0] * nu_r[0] + nu_r[1] * nu_r[1] + nu_r[2] * nu_r[2])
    tau = six_dof_actuation(
        shaft, d_s, d_r, nu_r, speed, hull[i, SIX_DOF.propeller_torque_scale], a
    )
    return tau, f, tau[0], tau[4], tau[5]


def propulsion_forces(hull, i, x, f, shaft, d_s, d_r, a):
    """(τ, f, X, M, N) of the realistic actuators at shaft speed ``shaft`` [rpm] and fin angles
    ``d_s``, ``d_r`` [rad] (`actuators.ACTUATOR_CONFIG_FIELDS` in ``a``)."""
    return (_five_dof_propulsion if hull is None else _six_dof_propulsion)(
        hull, i, x, f, shaft, d_s, d_r, a
    )


@overload(propulsion_forces, inline="always")
def _propulsion_forces(hull, i, x, f, shaft, d_s, d_r, a):
    return _five_dof_propulsion if _five_dof(hull) else _six_dof_propulsion


# plant_rk4 / wrap_state: one physics step and the angles wrapped to (−π, π].
def _five_dof_rk4(hull, i, x, tau, f, current, p, kind, pdata, u_d, sigma, dt):
    return rk4(x, tau, f, current, p, kind, pdata, u_d, sigma, dt)


def _six_dof_rk4(hull, i, x, tau, f, current, p, kind, pdata, u_d, sigma, dt):
    return six_dof_rk4(x, tau, f, current, hull[i], kind, pdata, u_d, sigma, dt)


def plant_rk4(hull, i, x, tau, f, current, p, kind, pdata, u_d, sigma, dt):
    """One classical RK4 step of vehicle i's plant over dt [s] with τ, f and the current held
    (`integrator.rk4`, `six_dof.six_dof_rk4` with hull row i); ``p`` is the 5-DOF record."""
    step = _five_dof_rk4 if hull is None else _six_dof_rk4
    return step(hull, i, x, tau, f, current, p, kind, pdata, u_d, sigma, dt)


@overload(plant_rk4, inline="always")
def _plant_rk4(hull, i, x, tau, f, current, p, kind, pdata, u_d, sigma, dt):
    return _five_dof_rk4 if _five_dof(hull) else _six_dof_rk4


def _five_dof_wrap(hull, x):
    return (x[0], x[1], x[2], x[3], wrap_angle(x[4]), x[5], x[6], x[7], x[8], x[9], x[10])


def _six_dof_wrap(hull, x):
    return (
        x[0],
        x[1],
        x[2],
        wrap_angle(x[3]),
        x[4],
        wrap_angle(x[5]),
        x[6],
        x[7],
        x[8],
        x[9],
        x[10],
        x[11],
        x[12],
    )


def wrap_state(hull, x):
    """The state tuple x with its heading (and on the 6-DOF its roll) wrapped to (−π, π]."""
    return (_five_dof_wrap if hull is None else _six_dof_wrap)(hull, x)


@overload(wrap_state, inline="always")
def _wrap_state(hull, x):
    return _five_dof_wrap if _five_dof(hull) else _six_dof_wrap
