"""Realistic actuators (auv_gym.vehicle.actuators, docs/model.md §2.6): the reference cross-check,
the ideal limit, rate and angle limits, state handling in the simulator, and bad input."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import controllers
from auv_gym import AUVPath3DEnv
from auv_gym.paths.guidance import wrap_angle
from auv_gym.rollout import rollouts
from auv_gym.sim.integrator import rk4_step
from auv_gym.vehicle import remus100
from auv_gym.vehicle.actuators import (
    ACTUATOR_STATE,
    ActuatorParams,
    actuator_forces,
    actuator_record,
    actuator_step,
    propeller_thrust,
    propeller_torque,
)
from auv_gym.vehicle.dynamics import STATE, STATE_DIM

REFERENCE = Path(__file__).parent / "data" / "pvs_remus100_actuators.json"
IDEAL = {"motor_time_constant": 0.0, "fin_time_constant": 0.0, "fin_rate_max": math.inf}


def test_forces_equal_the_reference_implementation_on_its_grid() -> None:
    """Numbers recorded from PythonVehicleSimulator's remus100.dynamics (360 points of
    (u, v, w, rpm, δ_s, δ_r)) are reproduced to float precision by the reference's parameters."""
    data = json.loads(REFERENCE.read_text())
    assert data["columns"][:6] == ["u", "v", "w", "rpm", "delta_s", "delta_r"]
    rows = np.array(data["rows"])
    assert rows.shape == (360, 13)
    a = actuator_record(ActuatorParams.pvs_remus100())
    got = np.array(
        [
            [
                *actuator_forces(r[3], r[4], r[5], r[0], r[1], r[2], a),
                propeller_thrust(r[3], math.sqrt(r[0] ** 2 + r[1] ** 2 + r[2] ** 2), a),
                propeller_torque(r[3], math.sqrt(r[0] ** 2 + r[1] ** 2 + r[2] ** 2), a),
            ]
            for r in rows
        ]
    )
    np.testing.assert_allclose(got, rows[:, 6:], rtol=1e-13, atol=1e-13)
    assert np.abs(rows[:, 6:11]).max() > 100.0  # the grid spans the full thrust range


def test_default_fins_give_the_paper_vehicles_fin_moment() -> None:
    """|x_fin|·½ρAC_L = `AUVParams.fin_moment_coeff` and δ_max = `AUVParams.fin_max`: at zero
    incidence the fin moment is the "fins" mode's a·K·δ_max·u|u| with δ = −a·δ_max (stern)."""
    p, vehicle = ActuatorParams(), remus100()
    np.testing.assert_allclose(p.fin_moment_coeff(), (6.15, 6.15), rtol=1e-14)
    assert p.delta_max_stern == p.delta_max_rudder == vehicle.fin_max
    a = actuator_record(p)
    for u, act in ((0.5, 0.3), (1.0, -1.0), (1.7, 0.8)):
        _, _, _, m, n = actuator_forces(
            0.0, -act * p.delta_max_stern, act * p.delta_max_rudder, u, 0.0, 0.0, a
        )
        fins = act * vehicle.fin_moment_coeff * vehicle.fin_max * u * abs(u)
        assert m == pytest.approx(fins, rel=1e-13) and n == pytest.approx(fins, rel=1e-13)


def _ideal_reference(seed: int, commands: np.ndarray) -> np.ndarray:
    """The states of an instantaneous actuator: τ of the commanded (n, δ_s, δ_r), held over
    each RK4 step, integrated with the public `rk4_step` (no noise, no current)."""
    env = AUVPath3DEnv(actuator="realistic", disturbance="none", actuator_params=IDEAL)
    env.reset(seed=seed)
    p = ActuatorParams(**IDEAL)
    a, params = actuator_record(p), env.config.params.to_vector()
    path = env.config.path
    x, nxt, out = env.sim.state[0].copy(), np.empty(STATE_DIM), []
    limits = np.array([p.rpm_max, p.delta_max_stern, p.delta_max_rudder])
    dt = env.config.physics_dt
    for c in commands:
        n_rpm, d_s, d_r = c * limits
        for _ in range(env.config.substeps):
            X, Y, Z, M, N = actuator_forces(n_rpm, d_s, d_r, x[STATE.u], x[STATE.v], x[STATE.w], a)
            rk4_step(
                x,
                (X, M, N),
                (0.0, Y, Z, 0.0, 0.0),
                (0.0, 0.0, 0.0),
                params,
                path.kind,
                path.data,
                1.0,
                env.config.kernel_sigma,
                dt,
                nxt,
            )
            x = nxt.copy()
            x[STATE.psi] = wrap_angle(x[STATE.psi])
        out.append(x.copy())
    return np.array(out)


def test_zero_lag_and_infinite_rate_reproduce_an_instantaneous_actuator() -> None:
    commands = np.random.default_rng(4).uniform(-1, 1, size=(40, 3))
    commands[:, 0] = np.abs(commands[:, 0])
    env = AUVPath3DEnv(actuator="realistic", disturbance="none", actuator_params=IDEAL)
    env.reset(seed=2)
    p = ActuatorParams(**IDEAL)
    states = []
    for c in commands:
        env.step(c)
        act = env.sim.actuator_state[0]
        # the state is the command, exactly
        assert act[ACTUATOR_STATE.n_rpm] == c[0] * p.rpm_max
        assert act[ACTUATOR_STATE.delta_s] == c[1] * p.delta_max_stern
        assert act[ACTUATOR_STATE.delta_r] == c[2] * p.delta_max_rudder
        assert act[ACTUATOR_STATE.rate_limited] == 0.0
        states.append(env.sim.state[0].copy())
    np.testing.assert_allclose(
        np.array(states), _ideal_reference(2, commands), rtol=1e-12, atol=1e-12
    )


@settings(max_examples=60, deadline=None)
@given(
    commands=st.lists(st.tuples(*[st.floats(-1.0, 1.0)] * 3), min_size=1, max_size=40),
    rate=st.floats(0.01, 20.0),
    time_constant=st.floats(0.0, 2.0),
    dt=st.sampled_from([0.001, 0.01, 0.05]),
    start=st.tuples(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(-1.0, 1.0)),
)
@example(  # a fresh CI machine's draw: the move over rate·dt by 0.6 ulp of the angle
    commands=[(0.0, 0.0, 0.0)], rate=0.015625, time_constant=0.0, dt=0.001, start=(0.0, 0.0, 0.5)
)
def test_rate_and_angle_limits_hold_for_any_command_sequence(
    commands, rate, time_constant, dt, start
) -> None:
    p = ActuatorParams(
        fin_rate_max=rate, fin_time_constant=time_constant, motor_time_constant=time_constant
    )
    a = actuator_record(p, dt)
    n, d_s, d_r = start[0] * p.rpm_max, start[1] * p.delta_max_stern, start[2] * p.delta_max_rudder
    for c in commands:
        for _ in range(3):
            n1, s1, r1, _ = actuator_step(n, d_s, d_r, c[0], c[1], c[2], a)
            for before, after, limit in (
                (d_s, s1, p.delta_max_stern),
                (d_r, r1, p.delta_max_rudder),
            ):
                # the capped angle delta ± rate·dt is rounded to the angle's own precision:
                # half an ulp of it may add to the move (rate 0.015625 rad/s, dt 1 ms at
                # 0.26 rad: 1.5625000000019e-5 rad, over rate·dt by 3.5e-17 = 0.6 ulp)
                assert abs(after - before) <= rate * dt * (1 + 1e-12) + np.spacing(abs(before))
                assert abs(after) <= limit
            assert abs(n1) <= p.rpm_max
            # the lag never overshoots its command
            assert min(n, c[0] * p.rpm_max) - 1e-9 <= n1 <= max(n, c[0] * p.rpm_max) + 1e-9
            n, d_s, d_r = n1, s1, r1


def test_fin_rate_limit_and_lag_in_the_simulator() -> None:
    """A full stern-plane step at 60°/s takes π/6 ÷ (π/3 rad/s) = 0.5 s, rate-limited meanwhile;
    the motor reaches 1 − e^(−1) of a step in one time constant (1 s)."""
    env = AUVPath3DEnv(actuator="realistic", disturbance="none")
    env.reset(seed=0)
    act = env.sim.actuator_state[0]
    p = ActuatorParams()
    for k in range(20):  # 20 × 0.05 s = 1 s
        env.step(np.array([1.0, 1.0, 0.0]))
        if k < 7:  # 0.35 s: still at the rate limit (the lag is slower beyond 0.41 rad)
            assert act[ACTUATOR_STATE.delta_s] == pytest.approx((k + 1) * 0.05 * p.fin_rate_max)
            assert act[ACTUATOR_STATE.rate_limited] == 1.0
    assert act[ACTUATOR_STATE.delta_s] == pytest.approx(p.delta_max_stern, abs=1e-3)
    assert act[ACTUATOR_STATE.rate_limited] == 0.0
    assert act[ACTUATOR_STATE.n_rpm] == pytest.approx(p.rpm_max * (1 - math.exp(-1.0)), rel=1e-12)
    env.reset(seed=1)
    assert not env.sim.actuator_state.any()  # reset: propeller stopped, fins centred


def test_batched_equals_single_and_is_deterministic(assert_same_episodes) -> None:
    kw = {
        "actuator": "realistic",
        "disturbance": "paper",
        "max_time": 15.0,
        "param_uncertainty": 0.2,
    }
    policy = controllers.make("pid_los", actuator="realistic")
    batched = rollouts(policy, [0, 1, 2], batch_size=3, **kw)
    single = rollouts(policy, [0, 1, 2], batch_size=1, **kw)
    assert_same_episodes(batched, single)
    assert_same_episodes(batched, rollouts(policy, [0, 1, 2], batch_size=3, **kw))
    for name in ("samples", "intervals"):
        assert np.isfinite(np.concatenate(list(getattr(batched[0], name).values()))).all()
    assert batched[0].extras["fin_rate_limited"].shape == (300,)


def test_snapshot_restore_continues_the_actuator_state(make_sim) -> None:
    sim = make_sim(2, actuator="realistic")
    commands = np.random.default_rng(0).uniform(-1, 1, size=(30, 2, 3))
    for c in commands[:10]:
        sim.step(c)
    snap = sim.snapshot()
    for c in commands[10:]:
        sim.step(c)
    end = sim.state.copy(), sim.actuator_state.copy()
    sim.restore(snap)
    for c in commands[10:]:
        sim.step(c)
    np.testing.assert_array_equal(sim.state, end[0])
    np.testing.assert_array_equal(sim.actuator_state, end[1])


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (
            {"fin_time_constant": -0.1},
            "ActuatorParams.fin_time_constant must be a finite number in [0, ∞) s, got -0.1",
        ),
        (
            {"motor_time_constant": math.inf},
            "ActuatorParams.motor_time_constant must be a finite number in [0, ∞) s, got inf",
        ),
        (
            {"fin_rate_max": math.nan},
            "ActuatorParams.fin_rate_max must be a finite number in (0, ∞), got nan",
        ),
        (
            {"fin_rate_max": -1.0},
            "ActuatorParams.fin_rate_max must be a finite number in (0, ∞), got -1.0",
        ),
        ({"rpm_max": 0.0}, "ActuatorParams.rpm_max must be a finite number in (0, ∞), got 0.0"),
        (
            {"delta_max_stern": 2.0},
            "ActuatorParams.delta_max_stern must be a finite number in (0, 1.5708] rad, got 2.0",
        ),
        (
            {"thrust_deduction": 1.0},
            "ActuatorParams.thrust_deduction must be a finite number in [0, 1), got 1.0",
        ),
    ],
)
def test_bad_actuator_params_raise_naming_the_field(kwargs, message) -> None:
    with pytest.raises(ValueError) as info:
        AUVPath3DEnv(actuator="realistic", actuator_params=kwargs)
    assert str(info.value) == message


def test_bad_commands_raise_named_errors() -> None:
    env = AUVPath3DEnv(actuator="realistic")
    env.reset(seed=0)
    with pytest.raises(ValueError) as info:
        env.step(np.array([0.5, -1.5, 0.0]))
    assert str(info.value) == (
        "actuator='realistic' takes commands (rpm, delta_s, delta_r) "
        "normalised to [-1, 1]; got delta_s = -1.5 (row 0)"
    )
    with pytest.raises(ValueError, match="action must be finite"):
        env.step(np.array([np.nan, 0.0, 0.0]))
    with pytest.raises(ValueError, match=r"actuator_params has unknown key\(s\) \[.rpm.\]"):
        AUVPath3DEnv(actuator="realistic", actuator_params={"rpm": 3.0})
    assert env.sim.actuator_state[0, ACTUATOR_STATE.n_rpm] == 0.0  # nothing moved
