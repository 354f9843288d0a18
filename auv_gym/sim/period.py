"""The control-period loop: one vehicle of the fleet through one control period, on any plant.

Per physics step (docs/model.md §11.1): draw the white noise and the current (with the waves
and the profiled current of `auv_gym.ocean`, when configured), move the realistic actuators'
state or apply the commanded forces, take one RK4 step of the plant and advance the
Gauss–Markov current. At the end of the period: the mean τ and f, the guidance row and the
observation. The plant (`plants`) and the options (`fleet`) are chosen by the types of the
fleet's arrays when a kernel compiles, so this one loop is the 5-DOF and the 6-DOF loop, each
without the code of the options its configuration leaves off.
"""

from __future__ import annotations

import math

from numba import njit

from auv_gym.ocean.disturbances import KEY, gauss_markov_step
from auv_gym.ocean.forcing import NO_WAVE
from auv_gym.sim.fleet import (
    actuator_state,
    ocean_active,
    realistic_actuators,
    store_actuator_state,
    virtual_point_law,
)
from auv_gym.sim.integrator import (
    CONFIG_DIM,
    actuation,
    add_noise,
    config_record,
    finish_period,
    physics_step_forcing,
)
from auv_gym.sim.plants import (
    commanded_forces,
    load_state,
    plant_rk4,
    pose,
    propulsion_forces,
    store_state,
    surge,
    wrap_state,
)
from auv_gym.vehicle.actuators import DEFAULT_ACTUATOR_CONFIG, actuator_config, actuator_step
from auv_gym.vehicle.params import params_record

__all__ = ["advance_period", "period_body"]


# Two entry points to one body: the serial step kernel inlines it (`period_body`: the call and its
# records passed by value cost the paper configuration several % of its speed), the threaded one
# calls it (`advance_period`: its compilation grows steeply with the size of its loop body, and
# inlined writes into the records' arrays were lost in a prange loop).
@njit(cache=True, inline="always")
def period_body(fleet, i, a_X, a_M, a_N, kind, pdata, cfg_array, out):
    """Advance vehicle i of the `fleet.Fleet` by one control period, in place; returns False on a
    non-finite state.

    (a_X, a_M, a_N) is the saturated action in [−1, 1] (realistic actuators: the normalised
    commands of n, δ_s, δ_r); ``kind`` and ``pdata`` are the vehicle's path, ``cfg_array`` its
    packed config (`SimConfig.packed`, layout `integrator.CONFIG_FIELDS`). The state, the
    current deviation and the actuator state are updated; vehicle i's rows of ``out``
    (`fleet.StepOutputs`: guidance row, observation, period record) are rewritten only while
    the state is finite, so the caller keeps the last valid observation. The physics steps are
    keyed by the vehicle's step index (`disturbances.white_noise`, `gauss_markov_step`), which
    the caller advances.
    """
    cfg = config_record(cfg_array)
    p = params_record(fleet.params[i])
    hull, act, ocean = fleet.hull, fleet.actuators, fleet.ocean  # hull: None on the 5-DOF
    n_sub, hold_steps = int(cfg.n_sub), int(cfg.hold_steps)
    noise_amplitude = (cfg.noise_f_u, cfg.noise_f_v, cfg.noise_f_w, cfg.noise_f_q, cfg.noise_f_r)
    noise_key, current_key = fleet.keys[i, KEY.noise], fleet.keys[i, KEY.current]
    step_index = fleet.step_index[i]
    gm_b = (cfg.gm_b_x, cfg.gm_b_y, cfg.gm_b_z)
    fin_gain = p.fin_moment_coeff * p.fin_max
    x = load_state(hull, fleet, i)
    dc = (fleet.current[i, 0], fleet.current[i, 1], fleet.current[i, 2])
    sum_X = sum_M = sum_N = 0.0
    sum_f = (0.0, 0.0, 0.0, 0.0, 0.0)
    finite = True
    ocean_on = ocean_active(ocean, i)
    wave = NO_WAVE
    # Realistic actuators (docs/model.md §2.6): their state moves first in each physics step,
    # then its τ is held over the RK4 step.
    realistic = realistic_actuators(cfg.actuator)
    a = actuator_config(cfg_array, CONFIG_DIM) if realistic else DEFAULT_ACTUATOR_CONFIG
    shaft, d_s, d_r = actuator_state(act, i)
    rate_limited = 0
    added = (0.0, 0.0, 0.0)
    # the virtual point's law: the plant's at the true x_e, or a guidance computer's held u_p
    u_law, sigma_law = virtual_point_law(fleet.guidance, i, cfg.u_d, cfg.sigma)
    dt = cfg.physics_dt
    for k in range(n_sub):
        n = step_index + k
        f, current, wave, added = physics_step_forcing(
            cfg,
            p,
            noise_amplitude,
            noise_key,
            hold_steps,
            dc,
            ocean_on,
            ocean,
            i,
            pose(hull, x),
            n,
            k,
            wave,
            added,
        )
        if realistic:
            shaft, d_s, d_r, limited = actuator_step(shaft, d_s, d_r, a_X, a_M, a_N, a)
            rate_limited += limited
            tau, f_in, X, M, N = propulsion_forces(hull, i, x, f, shaft, d_s, d_r, a)
        else:
            X, M, N = actuation(a_X, a_M, a_N, cfg, fin_gain, surge(hull, x))
            tau, f_in = commanded_forces(hull, X, M, N, f)
        nxt = plant_rk4(hull, i, x, tau, f_in, current, p, kind, pdata, u_law, sigma_law, dt)
        dc = gauss_markov_step(dc, cfg.gm_a, gm_b, current_key, n)
        sum_X += X
        sum_M += M
        sum_N += N
        sum_f = add_noise(sum_f, f)
        for j in range(len(nxt)):
            if not math.isfinite(nxt[j]):
                finite = False
        if not finite:
            x = nxt
            break
        x = wrap_state(hull, nxt)
    store_state(hull, fleet, i, x)
    fleet.current[i, 0], fleet.current[i, 1], fleet.current[i, 2] = dc
    if realistic:
        store_actuator_state(act, i, shaft, d_s, d_r, rate_limited / n_sub)
    if not finite:
        return False
    finish_period(
        fleet.state[i],
        kind,
        pdata,
        cfg,
        out.guid[i],
        out.obs[i],
        out.record[i],
        sum_X,
        sum_M,
        sum_N,
        sum_f,
        ocean_on,
        added,
    )
    return True


@njit(cache=True)
def advance_period(fleet, i, a_X, a_M, a_N, kind, pdata, cfg_array, out):
    """`period_body` as a called function (the threaded step kernel's)."""
    return period_body(fleet, i, a_X, a_M, a_N, kind, pdata, cfg_array, out)
