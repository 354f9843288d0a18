"""Sensors and navigation: error statistics, determinism, exact sensors, delay, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from auv_gym import AUVPath3DEnv
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.paths.guidance import wrap_angle
from auv_gym.sim.config import SimConfig
from auv_gym.sim.navigation import NAV
from auv_gym.sim.simulator import Simulator
from auv_gym.vehicle.dynamics import STATE
from auv_gym.vehicle.sensors import SENSOR_PRESETS, SensorConfig

# The measured entries of the state and the navigation estimate, in this order.
MEASURED = (
    STATE.x,
    STATE.y,
    STATE.z,
    STATE.theta,
    STATE.psi,
    STATE.u,
    STATE.v,
    STATE.w,
    STATE.q,
    STATE.r,
)
CRUISE = np.array([[0.4, 0.0, 0.05]])  # a steady, slowly turning vehicle: no terminations


def run(sensors, n: int, steps: int, seed: int = 0, actions=CRUISE, **kwargs):
    """(true state, estimate, DVL sample held in the navigation state) over ``steps`` control
    steps of n vehicles seeded seed + i, each (steps + 1, n, ...) from the reset on."""
    sim = Simulator(SimConfig.from_kwargs(sensors=sensors, disturbance="none", **kwargs), n)
    sim.reset_rows(range(n), [np.random.default_rng(seed + i) for i in range(n)])
    states, estimates, dvl = [], [], []
    for k in range(steps + 1):
        if k:
            sim.step(np.broadcast_to(actions[(k - 1) % len(actions)], (n, 3)))
        states.append(sim.state.copy())
        estimates.append(sim.navigation.estimate.copy())
        dvl.append(sim.navigation.nav[:, NAV.dvl_u].copy())
    return np.array(states), np.array(estimates), np.array(dvl)


def errors(states: np.ndarray, estimates: np.ndarray) -> np.ndarray:
    """Estimate − truth of the measured entries (heading wrapped), (steps, n, 10)."""
    e = estimates[..., MEASURED] - states[..., MEASURED]
    e[..., 4] = (e[..., 4] + math.pi) % (2 * math.pi) - math.pi
    return e


SIGMAS = {
    "dvl_noise": 0.01,
    "pitch_noise": 0.002,
    "heading_noise": 0.004,
    "rate_noise": 0.001,
    "depth_noise": 0.02,
    "fix_noise": 0.5,
}
# Error columns of each σ (position fixes every step: the fix noise is the x, y error).
COLUMNS = {
    "dvl_noise": (5, 6, 7),
    "pitch_noise": (3,),
    "heading_noise": (4,),
    "rate_noise": (8, 9),
    "depth_noise": (2,),
    "fix_noise": (0, 1),
}


def test_noise_standard_deviations_within_5_percent_of_the_configured_ones():
    states, estimates, _ = run(SIGMAS, n=100, steps=400)
    e = errors(states, estimates)[1:]
    for name, sigma in SIGMAS.items():
        measured = e[..., list(COLUMNS[name])].std()
        assert abs(measured / sigma - 1.0) < 0.05, (name, measured, sigma)
        assert abs(e[..., list(COLUMNS[name])].mean()) < 0.05 * sigma, name  # zero mean


BIASES = {
    "dvl_bias": 0.002,
    "pitch_bias": 0.005,
    "heading_bias": 0.017,
    "rate_bias": 5e-5,
    "depth_bias": 0.05,
}


# Compiles the threaded kernel with the sensor model (about 2.5 min on 2 cores).
@pytest.mark.integration
def test_turn_on_biases_are_constant_per_episode_with_the_configured_spread():
    """One episode's bias is a constant draw (the error never changes while the vehicle runs);
    over 3000 episodes their standard deviation is the configured one within 5 %; likewise the
    DVL's scale-factor errors."""
    states, estimates, _ = run(BIASES, n=3000, steps=3)
    e = errors(states, estimates)
    for name, cols in (
        ("dvl_bias", (6, 7)),
        ("pitch_bias", (3,)),
        ("heading_bias", (4,)),
        ("rate_bias", (8, 9)),
        ("depth_bias", (2,)),
    ):
        per_episode = e[..., list(cols)]
        np.testing.assert_allclose(per_episode, per_episode[:1].repeat(4, 0), atol=1e-12)
        spread = per_episode[0].std()
        assert abs(spread / BIASES[name] - 1.0) < 0.05, (name, spread)
    # the scale-factor errors k of u, v, w: one draw per axis and episode
    sim = Simulator(SimConfig.from_kwargs(sensors={"dvl_scale": 0.003}), 3000)
    sim.reset_rows(range(3000), [np.random.default_rng(i) for i in range(3000)])
    scale = sim.navigation.nav[:, [NAV.k_u, NAV.k_v, NAV.k_w]]
    assert abs(scale.std() / 0.003 - 1.0) < 0.05


def test_dvl_dropout_rate_and_hold():
    """A lost ping holds the last valid sample: with noise every valid one is new, so the
    fraction of repeated samples is the dropout rate (within 5 % over 40 000 pings)."""
    _, _, dvl = run({"dvl_noise": 0.01, "dvl_dropout": 0.2}, n=100, steps=400)
    repeated = (dvl[1:] == dvl[:-1]).mean()
    assert abs(repeated / 0.2 - 1.0) < 0.05, repeated


def test_sensor_errors_depend_on_the_seed_only_not_on_the_actions():
    sensors = {
        k: v
        for k, v in SENSOR_PRESETS["typical"].to_dict().items()
        if k not in ("preset", "dvl_scale", "fix_interval")
    }
    # errors independent of the trajectory, b + σn: fixes every step, no held DVL samples
    sensors["fix_interval"], sensors["dvl_dropout"] = 0.0, 0.0
    other = np.random.default_rng(9).uniform(-0.5, 0.5, size=(300, 3))
    e1 = errors(*run(sensors, n=3, steps=300, seed=4)[:2])
    e2 = errors(*run(sensors, n=3, steps=300, seed=4, actions=other)[:2])
    e3 = errors(*run(sensors, n=3, steps=300, seed=5)[:2])
    # the same draws; only the rounding of truth + error differs between the trajectories
    np.testing.assert_allclose(e1, e2, rtol=0, atol=1e-9)
    assert np.abs(e1 - e3).max() > 0.1  # another seed, other errors
    # the lost pings too: the same steps whatever the actions
    dropout = {"dvl_noise": 0.01, "dvl_dropout": 0.1}
    _, _, dvl1 = run(dropout, n=3, steps=300, seed=4)
    _, _, dvl2 = run(dropout, n=3, steps=300, seed=4, actions=other)
    lost1, lost2 = dvl1[1:] == dvl1[:-1], dvl2[1:] == dvl2[:-1]
    np.testing.assert_array_equal(lost1, lost2)
    assert 0.05 < lost1.mean() < 0.15


def test_exact_sensors_reproduce_the_ideal_observation_bit_for_bit():
    """The sensor model with every error 0 (a fix every step, no delay) runs its kernel and
    returns what "ideal" returns, observations, rewards and preview entries included."""
    rng = np.random.default_rng(3)
    actions = rng.uniform(-1, 1, size=(400, 4, 3))
    for observation in ("paper", {"kind": "preview", "integral_time": 5.0}):
        kwargs = {"observation": observation, "current": (0.1, 0.2, 0.0)}
        ideal = AUVPath3DVectorEnv(4, **kwargs)
        exact = AUVPath3DVectorEnv(4, sensors=SensorConfig(), **kwargs)
        assert exact.sim.navigation is not None and ideal.sim.navigation is None
        np.testing.assert_array_equal(exact.reset(seed=11)[0], ideal.reset(seed=11)[0])
        for a in actions:
            got, want = exact.step(a), ideal.step(a)
            for g, w in zip(got[:4], want[:4], strict=True):
                np.testing.assert_array_equal(g, w)


def test_reward_and_termination_read_the_true_state():
    ideal, typical = AUVPath3DEnv(), AUVPath3DEnv(sensors="typical")
    obs_i, _ = ideal.reset(seed=2)
    obs_t, _ = typical.reset(seed=2)
    assert np.abs(obs_i - obs_t).max() > 0.05
    for a in np.random.default_rng(0).uniform(-1, 1, size=(200, 3)):
        (_, ri, di, _, ii), (_, rt, dt, _, it) = ideal.step(a), typical.step(a)
        assert (ri, di, ii["distance"]) == (rt, dt, it["distance"])


def test_delay_returns_the_measurements_of_k_steps_before():
    states, estimates, _ = run({"delay": 3}, n=2, steps=40)
    np.testing.assert_array_equal(estimates[3:, :, MEASURED], states[:-3, :, MEASURED])
    np.testing.assert_array_equal(estimates[:4, :, MEASURED], states[:1, :, MEASURED].repeat(4, 0))
    np.testing.assert_array_equal(estimates[..., STATE.s], states[..., STATE.s])  # s: no delay


@settings(max_examples=15, deadline=None)
@given(delay=st.integers(0, 8), seed=st.integers(0, 2**31 - 1))
def test_any_delay_returns_the_exact_state_of_k_steps_before(delay, seed):
    states, estimates, _ = run({"delay": delay}, n=1, steps=20, seed=seed)
    lagged = states[np.maximum(np.arange(21) - delay, 0)]
    np.testing.assert_array_equal(estimates[..., MEASURED], lagged[..., MEASURED])


def test_position_fixes_reset_dead_reckoning_at_their_interval():
    """Exact fixes every 2 s (40 steps); between them the position is dead-reckoned on a DVL
    with a 0.05 m/s offset, drifting by about that speed times the time since the fix."""
    states, estimates, _ = run({"dvl_bias": 0.05, "fix_interval": 2.0}, n=50, steps=120)
    drift = np.hypot(*(estimates[..., :2] - states[..., :2]).transpose(2, 0, 1))
    np.testing.assert_array_equal(drift[[0, 40, 80, 120]], 0.0)
    late = drift[[39, 79, 119]]  # 1.95 s after a fix: |b_xy| 1.95 s, b ~ N(0, 0.05²) per axis
    expected = 0.05 * math.sqrt(math.pi / 2) * 1.95  # E|b_xy| for a 2-D normal offset
    assert 0.85 < late.mean() / expected < 1.15, late.mean()
    # without errors, dead reckoning drifts only by its trapezoidal rule: < 2 mm in 60 s
    states, estimates, _ = run({"fix_interval": None}, n=2, steps=1200)
    assert np.abs(estimates[..., :2] - states[..., :2]).max() < 2e-3


def flown_through_a_snapshot(vec: AUVPath3DVectorEnv, actions: np.ndarray) -> np.ndarray:
    """The observations of ``vec`` reset with seed 7 and stepped through ``actions`` (steps,
    n, 3), with a snapshot taken half-way: the second half is flown twice, from the snapshot
    the second time, and must repeat bit for bit."""
    half = len(actions) // 2
    obs = [vec.reset(seed=7)[0]]
    for a in actions[:half]:
        obs.append(vec.step(a)[0])
    snap = vec.snapshot()
    tail = [vec.step(a)[0] for a in actions[half:]]
    vec.restore(snap)
    np.testing.assert_array_equal([vec.step(a)[0] for a in actions[half:]], tail)
    return np.array(obs + tail)


# Two threads compile the threaded kernel with the sensor model (about 2.5 min on 2 cores): the
# integration tier's; the serial kernel is the set-up's.
@pytest.mark.parametrize("threads", [1, pytest.param(2, marks=pytest.mark.integration)])
def test_batched_equals_single_and_snapshots_resume_exactly(threads):
    actions = np.random.default_rng(1).uniform(-0.6, 0.6, size=(120, 3, 3))
    obs = flown_through_a_snapshot(
        AUVPath3DVectorEnv(3, sensors="typical", threads=threads), actions
    )
    for i in range(3):
        env = AUVPath3DEnv(sensors="typical")
        single = [env.reset(seed=7 + i)[0]] + [env.step(a[i])[0] for a in actions]
        np.testing.assert_array_equal(obs[:, i], single)


def test_heading_estimate_stays_wrapped():
    assert wrap_angle(math.pi + 0.1) == pytest.approx(-math.pi + 0.1)
    _, estimates, _ = run(
        {"heading_bias": 0.3}, n=20, steps=200, actions=np.array([[0.5, 0.0, 1.0]])
    )
    assert np.all(np.abs(estimates[..., STATE.psi]) <= math.pi)


_FINITE = "must be a finite number in"


@pytest.mark.parametrize(
    ("sensors", "message"),
    [
        ({"dvl_noise": -0.1}, rf"sensors dvl_noise {_FINITE} \[0, 1\] m/s, got -0.1"),
        ({"heading_bias": math.nan}, rf"sensors heading_bias {_FINITE} \[0, 0.5\] rad, got nan"),
        ({"rate_noise": math.inf}, rf"sensors rate_noise {_FINITE} \[0, 0.5\] rad/s, got inf"),
        ({"dvl_dropout": 1.0}, rf"sensors dvl_dropout {_FINITE} \[0, 0.99\], got 1.0"),
        ({"fix_interval": -1.0}, rf"sensors fix_interval {_FINITE} \[0, 1e\+06\] s"),
        ({"fix_interval": math.inf}, rf"sensors fix_interval {_FINITE} .* got inf"),
        (
            {"fix_interval": 0.07},
            r"sensors fix_interval = 0.07 s must be a whole multiple of control_dt = 0.05 s",
        ),
        ({"delay": -1}, r"sensors delay must be an integer in \[0, 1000\], got -1"),
        ({"delay": 1.5}, r"sensors delay must be an integer in \[0, 1000\], got 1.5"),
        (
            "perfect",
            r"unknown sensors preset 'perfect'; valid: \['ideal', 'typical', 'typical_kalman'\]",
        ),
        (
            {"preset": "best"},
            r"unknown sensors preset 'best'; valid: \['ideal', 'typical', 'typical_kalman'\]",
        ),
        ({"gps": 1.0}, r"sensors has unknown key\(s\) \['gps'\]"),
        (3, r"sensors must be None, one of \['ideal', 'typical', 'typical_kalman'\], a dict"),
    ],
)
def test_bad_sensor_arguments_raise_one_named_line(sensors, message):
    with pytest.raises(ValueError, match=message):
        AUVPath3DEnv(sensors=sensors)


def test_presets_and_dict_overrides():
    assert SensorConfig.from_spec(None) is SENSOR_PRESETS["ideal"]
    custom = SensorConfig.from_spec({"preset": "typical", "delay": 2})
    assert custom.delay == 2 and custom.heading_bias == SENSOR_PRESETS["typical"].heading_bias
    assert not custom.ideal and SensorConfig.from_spec("ideal").ideal
    with pytest.raises(ValueError, match="sensors preset 'ideal' means exact sensors"):
        SensorConfig(dvl_noise=0.1, preset="ideal")
