"""The navigation filter (sensors navigation="kalman", docs/model.md §14.8): its update against
the textbook matrix form, its consistency over long records, batched = single, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from auv_gym import AUVPath3DEnv
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.ocean.disturbances import standard_normal
from auv_gym.sim.config import SimConfig
from auv_gym.sim.navigation import CH_FIX, NAV, STRIDE
from auv_gym.sim.simulator import Simulator
from auv_gym.vehicle.sensors import SensorConfig

CRUISE = np.array([0.4, 0.0, 0.08])  # a steady turn: the heading error becomes observable


def _simulator(sensors, n, seed=0, **kwargs):
    sim = Simulator(SimConfig.from_kwargs(sensors=sensors, disturbance="none", **kwargs), n)
    sim.reset_rows(range(n), [np.random.default_rng(seed + i) for i in range(n)])
    return sim


def _covariance(nav_row):
    return nav_row[NAV.p00 : NAV.p00 + 16].reshape(4, 4)


def _filter_state(nav_row):
    return np.array(
        [
            nav_row[NAV.x_hat],
            nav_row[NAV.y_hat],
            nav_row[NAV.scale_error],
            nav_row[NAV.heading_error],
        ]
    )


def test_two_steps_match_the_textbook_matrix_form():
    """A prediction, then a prediction with a fix, against x⁻ = x + Δt·(v̄ − k v̄ − β J v̄),
    P⁻ = F P Fᵀ + Q and K = P⁻Hᵀ(HP⁻Hᵀ + R)⁻¹, x⁺ = x⁻ + K(z − Hx⁻), P⁺ = (I − KH)P⁻, written
    out with numpy matrices (fix every 2 control steps, so the second step has one)."""
    sensors = {"preset": "typical_kalman", "fix_interval": 0.1}
    sim = _simulator(sensors, 1, seed=3)
    config = sim.config.sensors
    dt = sim.config.control_dt
    velocity, bias, scale, heading = config.filter_model(sim.config.u_desired)
    q = np.diag([(velocity * dt) ** 2] * 2 + [bias**2 * dt] * 2)
    r = config.fix_noise**2
    for _ in range(6):  # past the start
        sim.step(CRUISE[None])
    for step in range(2):
        before = sim.navigation.nav[0].copy()
        sim.step(CRUISE[None])
        after = sim.navigation.nav[0]
        t = sim.step_index[0] // sim.config.substeps
        x, p = _filter_state(before), _covariance(before)
        vx = 0.5 * (before[NAV.x_dot_hat] + after[NAV.x_dot_hat])
        vy = 0.5 * (before[NAV.y_dot_hat] + after[NAV.y_dot_hat])
        k, beta = x[2], x[3]
        x = x + dt * np.array([vx - k * vx + beta * vy, vy - k * vy - beta * vx, 0.0, 0.0])
        f = np.eye(4)
        f[:2, 2:] = dt * np.array([[-vx, vy], [-vy, -vx]])
        p = f @ p @ f.T + q
        has_fix = t % 2 == 0
        assert has_fix == (step == 1)
        if has_fix:
            key = sim.navigation.keys[0, 0]
            noise = [
                config.fix_noise * standard_normal(key, STRIDE * t + CH_FIX + j) for j in range(2)
            ]
            z = sim.state[0, :2] + np.array(noise)
            h = np.hstack([np.eye(2), np.zeros((2, 2))])
            gain = p @ h.T @ np.linalg.inv(h @ p @ h.T + r * np.eye(2))
            x = x + gain @ (z - h @ x)
            p = (np.eye(4) - gain @ h) @ p
        np.testing.assert_allclose(_filter_state(after), x, rtol=1e-12, atol=1e-13)
        np.testing.assert_allclose(_covariance(after), p, rtol=1e-10, atol=1e-16)
    assert scale > 0.0 and heading > 0.0


def test_errors_are_consistent_with_the_filter_covariance_over_long_records():
    """64 vehicles, 300 s, every error the filter models (DVL noise, scale factor, heading
    noise and bias, fixes of 0.5 m every 10 s) and no other: the normalised estimation error
    squared (NEES, 2 position states) averages 2 and exceeds χ²₂'s 95 % point (5.99) about 5 %
    of the time (measured 1.90 and 5.4 %)."""
    sensors = {
        "dvl_noise": 0.01,
        "dvl_scale": 0.003,
        "heading_noise": 0.1 * math.pi / 180,
        "heading_bias": math.pi / 180,
        "fix_noise": 0.5,
        "fix_interval": 10.0,
        "navigation": "kalman",
    }
    sim = _simulator(sensors, 64, seed=11)
    nees = []
    for step in range(6000):
        sim.step(np.broadcast_to(CRUISE, (64, 3)))
        if step >= 2000 and step % 20 == 0:  # after 100 s, once a second
            nav = sim.navigation.nav
            error = nav[:, [NAV.x_hat, NAV.y_hat]] - sim.state[:, :2]
            p = nav[:, NAV.p00 : NAV.p00 + 16].reshape(-1, 4, 4)[:, :2, :2]
            nees.append(np.einsum("ni,nij,nj->n", error, np.linalg.inv(p), error))
    nees = np.concatenate(nees)
    assert 1.7 < nees.mean() < 2.4, nees.mean()
    assert 0.02 < (nees > 5.991).mean() < 0.09, (nees > 5.991).mean()


def test_the_filter_halves_dead_reckonings_error_on_a_turning_vehicle():
    """The typical suite (fixes of 0.5 m every 10 s): dead reckoning's error is the last fix's
    0.5 m per axis plus its drift; the filter averages the fixes and learns the drift (RMS
    over 32 vehicles after 100 s: 0.70 m against 0.19 m)."""
    rms = {}
    for navigation in ("dead_reckoning", "kalman"):
        sim = _simulator({"preset": "typical", "navigation": navigation}, 32, seed=5)
        errors = []
        for step in range(6000):
            sim.step(np.broadcast_to(CRUISE, (32, 3)))
            if step >= 2000:
                nav = sim.navigation.nav
                errors.append(nav[:, [NAV.x_hat, NAV.y_hat]] - sim.state[:, :2])
        rms[navigation] = math.sqrt(np.mean(np.square(errors)) * 2)
    assert rms["kalman"] < 0.5 * rms["dead_reckoning"], rms


def test_batched_equals_single_with_the_filter():
    actions = np.random.default_rng(2).uniform(-0.6, 0.6, size=(300, 3, 3))
    vec = AUVPath3DVectorEnv(3, sensors="typical_kalman", disturbance="ocean")
    obs = [vec.reset(seed=4)[0]] + [vec.step(a)[0] for a in actions]
    for i in range(3):
        env = AUVPath3DEnv(sensors="typical_kalman", disturbance="ocean")
        single = [env.reset(seed=4 + i)[0]] + [env.step(a[i])[0] for a in actions]
        np.testing.assert_array_equal(np.array(obs)[:, i], single)


def test_the_agents_ground_velocity_is_the_dvls():
    """With sensors the agent observation's velocity over ground is the DVL's sample, not the
    truth (no information a real vehicle lacks)."""
    env = AUVPath3DEnv(observation="preview", sensors="typical_kalman", disturbance="ocean")
    obs, _ = env.reset(seed=1)
    for _ in range(40):
        obs, *_ = env.step(np.array([0.3, 0.0, 0.0], np.float32))
    names = env.unwrapped.config.observation.names
    ground = obs[[names.index(n) for n in ("u_ground", "v_ground", "w_ground")]]
    dvl = env.unwrapped.sim.navigation.ground_velocity(np.array([0]))[0]
    np.testing.assert_allclose(ground, dvl.astype(np.float32))
    assert np.abs(ground - obs[[names.index(n) for n in ("u", "v", "w")]]).max() > 0.0


def test_dead_reckoning_sees_the_profiled_current_and_the_waves():
    """Exact sensors and no fixes after the start: dead reckoning over the DVL's velocity over
    ground follows the vehicle through a sheared current and waves (< 5 cm in 60 s; a DVL
    blind to them would drift with the 0.2 m/s profile, ~12 m)."""
    sim = _simulator(
        {"fix_interval": None},
        2,
        waves="sea_state_3",
        current_profile={"surface_speed": 0.3, "reference_depth": 100.0, "reference_speed": 0.1},
        surface_above_path=10.0,
    )
    for _ in range(1200):
        sim.step(np.broadcast_to(CRUISE, (2, 3)))
    error = sim.navigation.estimate[:, :2] - sim.state[:, :2]
    assert np.abs(error).max() < 0.05, error


@pytest.mark.parametrize(
    ("sensors", "message"),
    [
        ({"navigation": "kalman"}, r"navigation = 'kalman' blends position fixes"),
        ({"preset": "typical", "navigation": "ukf"}, r"sensors navigation"),
        (
            {"preset": "typical_kalman", "filter_bias_noise": 0.0},
            r"filter_bias_noise = 0.0 1/√s makes the navigation filter's covariance not "
            r"positive definite",
        ),
        (
            {"preset": "typical_kalman", "filter_initial_heading": -0.1},
            r"filter_initial_heading = -0.1 rad .* not positive definite",
        ),
        ({"preset": "typical_kalman", "filter_velocity_noise": math.nan}, r"filter_velocity"),
        ({"preset": "typical", "dvl_noise": math.inf}, r"dvl_noise"),
    ],
)
def test_bad_filter_settings_raise_one_named_line(sensors, message):
    with pytest.raises(ValueError, match=message):
        SensorConfig.from_spec(sensors)
