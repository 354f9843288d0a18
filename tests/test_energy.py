"""Propulsive energy: the shaft power the rollout records and the metrics it gives, against a
hand-computed constant-thrust run."""

from __future__ import annotations

import math

import numpy as np
import pytest

from auv_gym.metrics import SHAFT_POWER, compute_metrics
from auv_gym.paths.shapes import StraightLine
from auv_gym.rollout import rollouts
from auv_gym.vehicle.actuators import ActuatorParams


class ConstantCommand:
    """Half shaft speed, fins centred, every step."""

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        n = np.atleast_2d(obs).shape[0]
        return np.tile(np.array([0.5, 0.0, 0.0], np.float32), (n, 1)), state


def test_a_constant_thrust_run_uses_the_hand_computed_power_and_energy():
    (run,) = rollouts(
        ConstantCommand(),
        [0],
        path=StraightLine(start=(0.0, 0.0, 0.0), direction=(1.0, 0.0, 0.0)),
        actuator="realistic",
        disturbance="none",
        max_time=200.0,
        start_position=(0.0, 0.0, 0.0),
        start_heading=0.0,
    )
    assert run.termination_reason == "time_limit"
    metrics = compute_metrics(run, transient=150.0)
    # By 150 s the motor (1 s lag) and the surge (a few tens of s) are steady: P = 2π n Q(n, U)
    # with K_Q linear in the advance number, and energy per metre P/U (W per m/s = kJ/km).
    a = ActuatorParams()
    n = 0.5 * a.rpm_max / 60.0  # [rps]
    speed = float(run["u"][-1])
    assert 1.0 < speed < 2.5 and abs(run["v"][-1]) < 1e-12 and abs(run["w"][-1]) < 1e-12
    advance = a.advance_speed_ratio * speed / a.prop_diameter
    torque = (
        a.water_density
        * a.prop_diameter**5
        * (a.kq_0 * n * n + (a.kq_max - a.kq_0) / a.advance_max * advance * n)
    )
    power = 2.0 * math.pi * n * torque  # [W]
    assert metrics["mean_shaft_power"] == pytest.approx(power, rel=1e-9)
    assert metrics["energy_per_km"] == pytest.approx(power / speed, rel=1e-9)
    early = run.extras[SHAFT_POWER][:10]
    assert early[0] < early[-1] < power  # the motor spins up from rest


def test_only_the_propeller_has_propulsion_metrics():
    (paper,) = rollouts(ConstantCommand(), [0], max_time=20.0, disturbance="none")
    assert SHAFT_POWER not in paper.extras
    assert "energy_per_km" not in compute_metrics(paper)
