"""The guidance computer (sensors virtual_point="estimate", docs/model.md §14.9): the virtual
point advanced from the estimated along-track error, its speed held over each control period."""

from __future__ import annotations

import math

import numpy as np
import pytest

import controllers
from auv_gym import AUVPath3DEnv
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.rollout import rollouts
from auv_gym.sim.config import SimConfig
from auv_gym.sim.observation import GUIDE
from auv_gym.sim.simulator import Simulator
from auv_gym.vehicle.dynamics import STATE
from auv_gym.vehicle.sensors import SensorConfig
from benchmarks.analysis.navigation_floor import _SeenErrors
from tests.test_sensors import CRUISE, flown_through_a_snapshot

TYPICAL = {"preset": "typical_kalman"}
ESTIMATE = {**TYPICAL, "virtual_point": "estimate"}


def _sim(sensors: dict, n: int = 2, seed: int = 0) -> Simulator:
    sim = Simulator(SimConfig.from_kwargs(sensors=sensors, disturbance="paper"), n)
    sim.reset_rows(range(n), [np.random.default_rng(seed + i) for i in range(n)])
    return sim


def test_the_point_moves_at_the_estimates_speed_held_over_each_period():
    """On the helix (|p'| constant) the path parameter advances by exactly ṡ·Δt, with ṡ the
    estimated x_e's u_p over |p'| taken at the period's start; the plant's law (the default)
    moves it at the rate of the true x_e, which changes within the period."""
    held, plant = _sim(ESTIMATE), _sim(TYPICAL)
    dt = held.config.control_dt
    assert held.fleet.guidance is held.navigation.held_speed and plant.fleet.guidance is None
    gaps = {"held": [], "plant": []}
    for _ in range(200):
        for name, sim in (("held", held), ("plant", plant)):
            s0, s_dot = sim.state[:, STATE.s].copy(), sim.guid[:, GUIDE.s_dot].copy()
            if name == "held":  # the held speed is the estimate's u_p, the true row reports it
                np.testing.assert_array_equal(sim.navigation.held_speed, sim.guid[:, GUIDE.u_p])
                np.testing.assert_array_equal(
                    sim.navigation.held_speed, sim.navigation.guid[:, GUIDE.u_p]
                )
            sim.step(CRUISE.repeat(2, 0))
            gaps[name].append(np.abs(sim.state[:, STATE.s] - s0 - s_dot * dt).max())
    assert max(gaps["held"]) < 1e-12
    assert max(gaps["plant"]) > 1e-6


def test_exact_sensors_differ_from_the_plants_law_only_by_the_hold():
    """With exact sensors the estimate is the state: flown open loop (the vehicle never reads
    the point), the vehicles are equal bit for bit and the computer's point differs from the
    plant's by its hold over each 0.05-s control step alone: under 0.5 % of its progress over
    600 steps (30 s; 0.2 % measured)."""
    exact = {"fix_interval": 0.0}  # every error 0, a fix every step: the estimate is the state
    held, plant = _sim({**exact, "virtual_point": "estimate"}), _sim(exact)
    start = plant.state[:, STATE.s].copy()
    np.testing.assert_array_equal(held.state, plant.state)
    for _ in range(600):
        held.step(CRUISE.repeat(2, 0))
        plant.step(CRUISE.repeat(2, 0))
    vehicle = [j for j in range(held.state.shape[1]) if j != STATE.s]
    np.testing.assert_array_equal(held.state[:, vehicle], plant.state[:, vehicle])
    progress = plant.state[:, STATE.s] - start
    lag = np.abs(held.state[:, STATE.s] - plant.state[:, STATE.s])
    assert np.all(lag > 0.0) and np.all(lag < 0.005 * progress)


def _along_track(sensors: dict) -> tuple[float, float]:
    """RMS [m] of the true and of the estimated x_e over t ≥ 50 s of three 150-s episodes of
    the PID through the navigation filter on the paper helix."""
    recorder = _SeenErrors(controllers.make("pid_los"))  # x_e, y_e, z_e as observed
    flights = rollouts(recorder, [0, 1, 2], sensors=sensors, max_time=150.0)
    seen = np.stack(recorder.seen, axis=1)
    true, estimated = [], []
    for i, flight in enumerate(flights):
        assert flight.termination_reason == "time_limit"
        steps = len(flight.t) - 1
        window = flight.t[:steps] >= 50.0
        true.append(flight.samples["x_e"][:steps][window])
        estimated.append(seen[i, :steps, 0][window])
    return (
        math.sqrt(np.mean(np.concatenate(true) ** 2)),
        math.sqrt(np.mean(np.concatenate(estimated) ** 2)),
    )


def test_the_point_closes_the_error_its_law_reads_the_other_carries_the_navigation():
    """The plant's law keeps the true x_e near zero and leaves the estimate the navigation's
    along-track error; the guidance computer keeps the estimated x_e near zero and leaves the
    navigation's error in the true one (the distance the benchmark scores)."""
    plant_true, plant_seen = _along_track(TYPICAL)
    held_true, held_seen = _along_track(ESTIMATE)
    assert plant_true < 0.25 * plant_seen  # measured 0.023 against 0.211 m
    assert held_seen < 0.25 * held_true  # measured 0.034 against 0.211 m
    assert held_true > 5.0 * plant_true


def _mean_along_track(sensors: dict) -> float:
    """Mean true x_e [m] over t ≥ 40 s of two 80-s episodes of the PID on the paper helix."""
    flights = rollouts(controllers.make("pid_los"), [0, 1], sensors=sensors, max_time=80.0)
    return float(np.mean([f.samples["x_e"][f.t >= 40.0].mean() for f in flights]))


def test_a_delayed_estimate_puts_the_vehicle_its_delay_ahead_of_the_computers_point():
    """With exact sensors delayed k steps the estimate is k·Δt old against the point's present
    s, so the computer settles the vehicle about k·Δt·u_D ahead of its point (0.25 m for k = 5
    at 1 m/s, measured 0.244); the plant's law keeps it on the point."""
    delayed = {"fix_interval": 0.0, "delay": 5}
    assert abs(_mean_along_track(delayed)) < 0.02
    ahead = _mean_along_track({**delayed, "virtual_point": "estimate"})
    assert ahead == pytest.approx(5 * 0.05 * 1.0, rel=0.1)


# Two threads compile the threaded kernel with the guidance computer: the integration tier's.
@pytest.mark.parametrize("threads", [1, pytest.param(2, marks=pytest.mark.integration)])
def test_batched_equals_single_through_autoresets_and_snapshots(threads):
    """Three vehicles of 3-s episodes (autoresets throughout) equal three single envs bit for
    bit, and a snapshot taken mid-way resumes exactly: every reset path sets the held speed."""
    sensors = {"preset": "typical", "virtual_point": "estimate"}
    actions = np.random.default_rng(1).uniform(-0.6, 0.6, size=(120, 3, 3))
    vec = AUVPath3DVectorEnv(3, sensors=sensors, threads=threads, max_time=3.0)
    obs = flown_through_a_snapshot(vec, actions)
    for i in range(3):
        env = AUVPath3DEnv(sensors=sensors, max_time=3.0)
        single, ended, resets = [env.reset(seed=7 + i)[0]], False, 0
        for a in actions:  # NEXT_STEP: the step after an episode's end resets, its action unused
            if ended:
                single.append(env.reset()[0])
                ended, resets = False, resets + 1
            else:
                o, _, terminated, truncated, _ = env.step(a[i])
                single.append(o)
                ended = terminated or truncated
        assert resets >= 1  # an autoreset was compared, not only the first episode
        np.testing.assert_array_equal(obs[:, i], single)


def test_a_snapshot_keeps_the_held_speed_and_resumes_bit_for_bit():
    sim = _sim(ESTIMATE)
    for _ in range(37):
        sim.step(CRUISE.repeat(2, 0))
    assert "navigation.held_speed" in sim.snapshot()["arrays"]
    snapshot = sim.snapshot()
    for _ in range(50):
        sim.step(CRUISE.repeat(2, 0))
    after = sim.state.copy()
    sim.navigation.held_speed[:] = 0.0  # what the snapshot must bring back
    sim.restore(snapshot)
    for _ in range(50):
        sim.step(CRUISE.repeat(2, 0))
    np.testing.assert_array_equal(sim.state, after)
    # the plant's law saves no held speed: snapshots of earlier runs still restore
    assert "navigation.held_speed" not in _sim(TYPICAL).snapshot()["arrays"]


def test_a_source_other_than_true_or_estimate_is_refused_by_name():
    with pytest.raises(ValueError, match=r"sensors virtual_point 'guess'; valid: \['estimate'"):
        SensorConfig.from_spec({**TYPICAL, "virtual_point": "guess"})
    # "ideal" skips the sensor model: there is no estimate to advance the point from
    with pytest.raises(ValueError, match="preset 'ideal' means exact sensors"):
        SensorConfig(preset="ideal", virtual_point="estimate")
    # exact sensors through the model may drive it (the hold alone differs, above)
    exact = SensorConfig.from_spec({"preset": "ideal", "virtual_point": "estimate"})
    assert exact.preset == "custom" and exact.guidance_from_estimate
