"""The control-period loop of the 6-DOF plant (``plant="6dof"``): `advance_six_dof`.

It is `integrator.advance_vehicle` with the hull of `auv_gym.vehicle.six_dof`: the same white
noise, current, ocean and actuator models per physics step (`integrator.physics_step_forcing`,
`actuators.actuator_step`), the same classical RK4 and period records. The 6-DOF state is split
between the simulator's 5-DOF state row (x, y, z, θ, ψ, u, v, w, q, r, s: what the guidance, the
observation, the navigation and the task read, so they are the same code for both plants) and a
roll row (φ [rad], p [rad/s], `ROLL`).

How the 5-DOF actuator modes act on the 6-DOF hull (docs/model.md §15.2): "paper" applies
τ = (X, 0, 0, 0, M, N); "fins" the same with the fin authority of the 5-DOF vehicle record;
"realistic" the propeller and fins with their lift, side and heave forces and the propeller's
torque in roll, at the velocity through the water.
"""

from __future__ import annotations

import math

from numba import njit

from auv_gym.ocean.disturbances import gauss_markov_step
from auv_gym.ocean.forcing import NO_WAVE, OCEAN
from auv_gym.paths.guidance import wrap_angle
from auv_gym.sim.integrator import (
    CONFIG_DIM,
    REALISTIC_ACTUATOR,
    actuation,
    add_noise,
    config_record,
    finish_period,
    physics_step_forcing,
)
from auv_gym.support.records import field_indices
from auv_gym.vehicle.actuators import (
    ACTUATOR_STATE,
    DEFAULT_ACTUATOR_CONFIG,
    actuator_config,
    actuator_step,
)
from auv_gym.vehicle.dynamics import STATE
from auv_gym.vehicle.params import params_record
from auv_gym.vehicle.six_dof import (
    SIX_DOF,
    SIX_DOF_STATE_DIM,
    six_dof_actuation,
    six_dof_rk4,
)

__all__ = ["ROLL", "ROLL_DIM", "ROLL_NAMES", "advance_six_dof"]

ROLL_NAMES = ("phi", "p")  # [rad], [rad/s]
ROLL_DIM = len(ROLL_NAMES)
ROLL = field_indices("RollIndex", ROLL_NAMES, __name__)


# Not inlined: the kernels call it, so its large body is compiled once and not into each kernel
# (the threaded kernel's compilation grows steeply with the size of its loop body).
@njit(cache=True)
def advance_six_dof(
    st,
    roll,
    cur,
    act,
    action,
    p_array,
    hull,
    noise_key,
    current_key,
    step_index,
    kind,
    pdata,
    cfg_array,
    guid,
    obs,
    record,
    ocean,
):
    """Advance one 6-DOF vehicle by one control period, in place; returns False on a non-finite
    state. Arguments as `integrator.advance_vehicle`, plus ``roll`` (φ, p) and ``hull``, the
    vehicle's `SixDofVehicle.kernel_vector` row; ``p_array`` (the 5-DOF record) gives the
    "fins" mode's authority and the waves' inertia force only."""
    cfg = config_record(cfg_array)
    p = params_record(p_array)
    n_sub, hold_steps = int(cfg.n_sub), int(cfg.hold_steps)
    noise_amplitude = (cfg.noise_f_u, cfg.noise_f_v, cfg.noise_f_w, cfg.noise_f_q, cfg.noise_f_r)
    gm_b = (cfg.gm_b_x, cfg.gm_b_y, cfg.gm_b_z)
    fin_gain = p.fin_moment_coeff * p.fin_max
    torque_scale = hull[SIX_DOF.propeller_torque_scale]
    x = (
        st[STATE.x],
        st[STATE.y],
        st[STATE.z],
        roll[ROLL.phi],
        st[STATE.theta],
        st[STATE.psi],
        st[STATE.u],
        st[STATE.v],
        st[STATE.w],
        roll[ROLL.p],
        st[STATE.q],
        st[STATE.r],
        st[STATE.s],
    )
    a_X, a_M, a_N = action[0], action[1], action[2]
    dc = (cur[0], cur[1], cur[2])
    sum_X = sum_M = sum_N = 0.0
    sum_f = (0.0, 0.0, 0.0, 0.0, 0.0)
    finite = True
    ocean_on = ocean[OCEAN.active] != 0.0
    wave = NO_WAVE
    realistic = int(cfg.actuator) == REALISTIC_ACTUATOR
    a = actuator_config(cfg_array, CONFIG_DIM) if realistic else DEFAULT_ACTUATOR_CONFIG
    shaft, d_s = act[ACTUATOR_STATE.n_rpm], act[ACTUATOR_STATE.delta_s]
    d_r = act[ACTUATOR_STATE.delta_r]
    rate_limited = 0
    added = (0.0, 0.0, 0.0)
    for k in range(n_sub):
        n = step_index + k
        pose = (x[0], x[1], x[2], x[4], x[5])  # x, y, z, θ, ψ: what the ocean reads
        f, current, wave, added = physics_step_forcing(
            cfg,
            p,
            noise_amplitude,
            noise_key,
            hold_steps,
            dc,
            ocean_on,
            ocean,
            pose,
            n,
            k,
            wave,
            added,
        )
        nu_r = (x[6], x[7], x[8], x[9], x[10], x[11])
        if realistic:
            shaft, d_s, d_r, limited = actuator_step(shaft, d_s, d_r, a_X, a_M, a_N, a)
            rate_limited += limited
            speed = math.sqrt(nu_r[0] * nu_r[0] + nu_r[1] * nu_r[1] + nu_r[2] * nu_r[2])
            tau = six_dof_actuation(shaft, d_s, d_r, nu_r, speed, torque_scale, a)
            X, M, N = tau[0], tau[4], tau[5]
        else:
            X, M, N = actuation(a_X, a_M, a_N, cfg, fin_gain, x[6])
            tau = (X, 0.0, 0.0, 0.0, M, N)
        nxt = six_dof_rk4(x, tau, f, current, hull, kind, pdata, cfg.u_d, cfg.sigma, cfg.physics_dt)
        dc = gauss_markov_step(dc, cfg.gm_a, gm_b, current_key, n)
        sum_X += X
        sum_M += M
        sum_N += N
        sum_f = add_noise(sum_f, f)
        for j in range(SIX_DOF_STATE_DIM):
            if not math.isfinite(nxt[j]):
                finite = False
        if not finite:
            x = nxt
            break
        x = (  # φ and ψ wrapped to (−π, π]
            nxt[0],
            nxt[1],
            nxt[2],
            wrap_angle(nxt[3]),
            nxt[4],
            wrap_angle(nxt[5]),
            nxt[6],
            nxt[7],
            nxt[8],
            nxt[9],
            nxt[10],
            nxt[11],
            nxt[12],
        )
    st[STATE.x], st[STATE.y], st[STATE.z] = x[0], x[1], x[2]
    st[STATE.theta], st[STATE.psi] = x[4], x[5]
    st[STATE.u], st[STATE.v], st[STATE.w] = x[6], x[7], x[8]
    st[STATE.q], st[STATE.r], st[STATE.s] = x[10], x[11], x[12]
    roll[ROLL.phi], roll[ROLL.p] = x[3], x[9]
    cur[0], cur[1], cur[2] = dc
    if realistic:
        act[ACTUATOR_STATE.n_rpm], act[ACTUATOR_STATE.delta_s] = shaft, d_s
        act[ACTUATOR_STATE.delta_r] = d_r
        act[ACTUATOR_STATE.rate_limited] = rate_limited / n_sub
    if not finite:
        return False
    finish_period(
        st, kind, pdata, cfg, guid, obs, record, sum_X, sum_M, sum_N, sum_f, ocean_on, added
    )
    return True
