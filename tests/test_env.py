"""The Gymnasium environment: API conformance, determinism, disturbances, bad input."""

from __future__ import annotations

import copy
import math
import pickle
import subprocess
import sys
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import auv_gym
from auv_gym import OBS_INDEX, OBS_NAMES, AUVPath3DEnv
from auv_gym.paths import StraightLine
from auv_gym.sim.observation import OBS_HIGH, OBS_LOW, OBS_UNITS
from auv_gym.sim.task import REWARD_TERMS

FOLLOW = np.array([0.45, 0.0, 0.0], dtype=np.float32)


def rollout(env, seed, actions):
    obs, _ = env.reset(seed=seed)
    log = {"obs": [obs], "reward": [], "dist": [], "disturbance": []}
    for a in actions:
        obs, reward, terminated, truncated, info = env.step(a)
        log["obs"].append(obs)
        log["reward"].append(reward)
        log["disturbance"].append(info["disturbance"])
        if terminated or truncated:
            break
    return {k: np.asarray(v) for k, v in log.items()}


def random_actions(seed, n=500):
    a = np.random.default_rng(seed).uniform(-1, 1, size=(n, 3)).astype(np.float32)
    a[:, 0] = 0.1 * np.abs(a[:, 0])  # below 2 m/s, where the Munk moment stays manageable
    a[:, 1:] *= 0.2
    return a


def test_gymnasium_check_env_without_warnings():
    env = gym.make("AUVPath3D-v0", render_mode="rgb_array", max_time=20.0).unwrapped
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env, skip_render_check=False)


def test_sb3_check_env():
    pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sb3_check_env(AUVPath3DEnv(max_time=20.0), warn=True)


def test_registration_is_idempotent_and_make_works():
    auv_gym._register()
    env = gym.make("AUVPath3D-v0")
    assert env.spec.max_episode_steps == 6000
    assert isinstance(env.unwrapped, AUVPath3DEnv)
    assert env.metadata["render_fps"] == 20
    assert gym.make("AUVPath3DNominal-v0").unwrapped.config.noise.amplitude == (0.0,) * 5
    assert gym.make("AUVPath3DFins-v0").unwrapped.config.actuator == "fins"
    code = "import gymnasium as gym; e = gym.make('auv_gym:AUVPath3D-v0'); print(e.spec.id)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "AUVPath3D-v0"


def test_observation_table_is_the_single_source():
    assert len(OBS_NAMES) == 15 and len(set(OBS_NAMES)) == 15
    assert set(OBS_UNITS) == set(OBS_NAMES)
    env = AUVPath3DEnv()
    assert env.observation_space.shape == (len(OBS_NAMES),)
    np.testing.assert_array_equal(env.observation_space.low, OBS_LOW)
    obs, info = env.reset(seed=0)
    assert obs[OBS_INDEX["x_e"]] == pytest.approx(info["x_e"])
    assert obs[OBS_INDEX["u_D"]] == 1.0
    assert np.all(obs >= OBS_LOW) and np.all(obs <= OBS_HIGH)


def test_paper_initial_condition_and_info_keys():
    env = AUVPath3DEnv()
    _, info = env.reset(seed=0)
    np.testing.assert_allclose(env.state[:5], [15, 5, 0, 0, 0])
    np.testing.assert_allclose(env.state[5:], 0.0)
    np.testing.assert_allclose([info["x_e"], info["y_e"], info["z_e"]], [-15, 5, 8])
    assert info["distance"] == pytest.approx(math.sqrt(15**2 + 5**2 + 8**2))
    _, _, _, _, info = env.step(FOLLOW)
    for key in ("x_e", "y_e", "z_e", "distance", "s", "u_p", "tau", "disturbance", "t"):
        assert key in info
    assert {f"reward_{t}" for t in REWARD_TERMS} <= set(info)
    np.testing.assert_allclose(info["tau"], [0.45 * 50, 0.0, 0.0], rtol=1e-6)
    assert np.all(np.abs(info["disturbance"]) <= 35.0)
    assert info["t"] == pytest.approx(0.05)


def test_same_seed_gives_bit_identical_rollouts():
    actions = random_actions(0)
    a = rollout(AUVPath3DEnv(), 7, actions)
    b = rollout(AUVPath3DEnv(), 7, actions)
    assert len(a["reward"]) == 500
    for key in a:
        np.testing.assert_array_equal(a[key], b[key])
    c = rollout(AUVPath3DEnv(), 8, actions)
    assert not np.array_equal(a["obs"], c["obs"])


def test_disturbance_sequence_does_not_depend_on_actions():
    env = AUVPath3DEnv(
        current={"mean": (0.1, 0.3, 0.0), "std": (0.1, 0.1, 0.0)}, param_uncertainty=0.3
    )
    a = rollout(env, 3, random_actions(1, 300))
    params_a = env.sim.params.copy()
    b = rollout(env, 3, random_actions(2, 300))
    n = min(len(a["reward"]), len(b["reward"]))
    assert n > 100
    np.testing.assert_array_equal(a["disturbance"][:n], b["disturbance"][:n])
    np.testing.assert_array_equal(params_a, env.sim.params)
    assert not np.array_equal(a["obs"][:n], b["obs"][:n])


def test_noise_free_runs_do_not_depend_on_the_seed():
    """docs/model.md §8 check 10, second half."""
    actions = random_actions(4, 300)
    a = rollout(AUVPath3DEnv(disturbance="none"), 1, actions)
    b = rollout(AUVPath3DEnv(disturbance="none"), 99, actions)
    np.testing.assert_array_equal(a["obs"], b["obs"])
    assert np.all(a["disturbance"] == 0.0)


def test_white_noise_statistics_and_hold():
    env = AUVPath3DEnv(control_dt=0.01, max_time=1e4)
    env.reset(seed=5)
    f = np.array([env.step(np.zeros(3, np.float32))[4]["disturbance"] for _ in range(20000)])
    assert np.abs(f).max() <= 35.0
    assert np.abs(f).max() > 34.9
    np.testing.assert_allclose(f.mean(axis=0), 0.0, atol=4 * 35 / math.sqrt(3 * 20000))
    np.testing.assert_allclose(f.var(axis=0), 35.0**2 / 3, rtol=0.05)
    corr = np.corrcoef(f.T)
    assert np.abs(corr - np.eye(5)).max() < 0.05  # independent channels
    held = AUVPath3DEnv(control_dt=0.01, noise_hold=0.05)
    held.reset(seed=5)
    g = np.array([held.step(np.zeros(3, np.float32))[4]["disturbance"] for _ in range(100)])
    blocks = g.reshape(20, 5, 5)
    assert np.all(blocks == blocks[:, :1, :])  # constant over each 0.05-s hold
    assert np.all(np.diff(blocks[:, 0, 0]) != 0.0)


def test_constant_current_drifts_a_vehicle_at_rest(make_sim):
    sim = make_sim(disturbance="none", current=(0.0, 0.3, 0.0))
    y0 = sim.state[0, 1]
    for _ in range(200):  # 10 s
        sim.step(np.zeros((1, 3)))
    assert sim.state[0, 1] - y0 == pytest.approx(3.0, abs=1e-9)
    np.testing.assert_allclose(sim.state[0, 5:10], 0.0, atol=1e-12)  # no relative motion


def test_gauss_markov_current_has_its_stationary_spread(make_sim):
    sim = make_sim(
        n=2000,
        disturbance="none",
        current={"mean": (0.2, 0.0, 0.0), "std": (0.1, 0.05, 0.0), "time_constant": 20.0},
    )
    for _ in range(400):  # 20 s = one time constant
        sim.step(np.zeros((2000, 3)))
    np.testing.assert_allclose(sim.current.std(axis=0), [0.1, 0.05, 0.0], rtol=0.1, atol=1e-12)
    drift = sim.state[:, 0] - sim.state[0, 0]
    assert np.std(drift) > 0.1  # vehicles drift differently


def test_parameter_uncertainty_is_per_episode_and_leaves_nominal_alone():
    env = AUVPath3DEnv(param_uncertainty=0.3)
    env.reset(seed=1)
    p1 = env.sim.params[0].copy()
    env.reset(seed=2)
    p2 = env.sim.params[0].copy()
    env.reset(seed=1)
    np.testing.assert_array_equal(env.sim.params[0], p1)
    assert not np.array_equal(p1, p2)
    assert env.config.params == auv_gym.remus100()


@pytest.mark.parametrize(
    "observation",
    [None, "preview_integral", {"kind": "preview", "history_steps": 3, "history_interval": 0.5}],
)
def test_pickle_round_trip_continues_identically(observation):
    """Also with error integrals and history, which live in views of one array: pickle and
    deepcopy stored them as arrays of their own, the steps updated those and the observation
    read stale ones (integrals 0.28 for 0.30 m·s at the first step after the copy)."""
    env = AUVPath3DEnv(observation=observation)
    env.reset(seed=4)
    for a in random_actions(0, 50):
        env.step(a)
    clones = [pickle.loads(pickle.dumps(env)), copy.deepcopy(env)]
    for a in random_actions(1, 50):
        out_a = env.step(a)
        for clone in clones:
            out_b = clone.step(a)
            np.testing.assert_array_equal(out_a[0], out_b[0])
            assert out_a[1] == out_b[1]
    observations = [e.reset(seed=4)[0] for e in (env, *clones)]
    for other in observations[1:]:  # the next episode: the integrals start from 0 again
        np.testing.assert_array_equal(observations[0], other)


def test_reward_prefers_following_over_idling():
    idle = rollout(
        AUVPath3DEnv(disturbance="none", max_time=60.0), 0, np.zeros((1200, 3), np.float32)
    )
    assert idle["reward"].mean() < -1.0
    follow = AUVPath3DEnv(
        disturbance="none", start_position=(30.0, 0.0, -8.0), start_heading=math.pi / 2
    )
    _, info = follow.reset(seed=0)
    assert info["distance"] == pytest.approx(0.0, abs=1e-12)
    _, reward, *_ = follow.step(np.array([1.62 / 50, 0, 0], np.float32))
    assert reward > 1.3  # progress + tracking − the speed error of a vehicle at rest
    assert reward > idle["reward"].max()


def test_truncation_at_max_time_and_termination_reasons():
    env = AUVPath3DEnv(max_time=1.0, disturbance="none")
    env.reset(seed=0)
    steps = [env.step(FOLLOW) for _ in range(20)]
    assert [s[3] for s in steps] == [False] * 19 + [True]
    assert not any(s[2] for s in steps)

    env = gym.make("AUVPath3D-v0", corridor=20.0, disturbance="none")
    env.reset(seed=0)
    for _ in range(200):  # full astern: away from the path
        _, _, terminated, _, info = env.step(np.array([-1, 0, 0], np.float32))
        if terminated:
            break
    assert terminated and info["termination_reason"] == "corridor"
    assert info["reward_termination"] == -100.0

    line = AUVPath3DEnv(
        path=StraightLine(length=5.0),
        disturbance="none",
        start_position=(0, 0, 0),
        start_heading=math.atan2(0.5, 1.0),
    )
    line.reset(seed=0)
    for _ in range(400):
        _, _, terminated, _, info = line.step(np.array([1.62 / 50 * 2, 0, 0], np.float32))
        if terminated:
            break
    assert info["termination_reason"] == "path_end"
    assert info["reward_termination"] == 0.0


def test_non_finite_state_terminates_with_last_finite_observation():
    env = AUVPath3DEnv()
    env.reset(seed=0)
    obs, *_ = env.step(FOLLOW)
    env.sim.state[0, 5] = 1e200  # blow the surge speed up
    obs2, _, terminated, _, info = env.step(FOLLOW)
    assert terminated and info["termination_reason"] == "non_finite"
    assert np.all(np.isfinite(obs2))
    np.testing.assert_array_equal(obs, obs2)


@pytest.mark.parametrize(
    ("action", "match"),
    [
        ([np.nan, 0, 0], "finite"),
        ([0, np.inf, 0], "finite"),
        ([0, 0], "shape"),
        (np.zeros((1, 3)), "shape"),
        ("abc", "real numbers"),
    ],
)
def test_bad_actions_raise(action, match):
    env = AUVPath3DEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError, match=match):
        env.step(action)


def test_saturation_is_the_only_clipping():
    env = AUVPath3DEnv(disturbance="none")
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.array([3.0, -2.0, 0.5]))
    np.testing.assert_allclose(info["tau"], [50.0, -10.0, 5.0])


def test_fin_actuator_authority_scales_with_speed_squared():
    env = AUVPath3DEnv(actuator="fins", disturbance="none")
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.array([0.0, 1.0, 1.0]))
    np.testing.assert_allclose(info["tau"][1:], 0.0)  # at rest the fins do nothing
    env.sim.state[0, 5] = 1.5
    _, _, _, _, info = env.step(np.array([0.0, 1.0, -1.0]))
    expected = 6.15 * (math.pi / 6) * 1.5**2
    np.testing.assert_allclose(info["tau"][1:], [expected, -expected], rtol=0.02)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"path": "spiral"}, "unknown path"),
        ({"disturbance": "storm"}, "unknown disturbance"),
        ({"actuator": "jets"}, "unknown actuator"),
        ({"control_dt": 0.015}, "whole multiple"),
        ({"noise_hold": 0.005}, "whole multiple"),
        ({"physics_dt": -0.01}, "physics_dt"),
        ({"param_uncertainty": 1.2}, "param_uncertainty"),
        ({"corridor": 0.0}, "corridor"),
        ({"current": (0.1, 0.2)}, "current mean"),
        ({"disturbance": -5.0}, "amplitude"),
        ({"render_mode": "human"}, "render_mode"),
        ({"max_time": float("nan")}, "max_time"),
    ],
)
def test_impossible_arguments_raise(kwargs, match):
    with pytest.raises(ValueError, match=match):
        AUVPath3DEnv(**kwargs)


def test_render_returns_an_rgb_picture():
    env = AUVPath3DEnv(render_mode="rgb_array")
    env.reset(seed=0)
    for _ in range(40):
        env.step(FOLLOW)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    assert frame.shape[0] >= 200 and frame.shape[1] >= 600
    assert frame.std() > 10  # not a blank canvas
    assert AUVPath3DEnv().render() is None
    assert AUVPath3DEnv(control_dt=0.1).metadata["render_fps"] == 10


_JIT_PARITY_SCRIPT = """
import json, warnings
import numpy as np, gymnasium as gym
import auv_gym
warnings.simplefilter("ignore")
env = gym.make("AUVPath3D-v0", path="waypoints", actuator="fins", param_uncertainty=0.2,
               current={"mean": (0.1, 0.2, 0.0), "std": (0.05, 0.05, 0.0)})
obs, _ = env.reset(seed=11)
rng = np.random.default_rng(2)
rows = []
for _ in range(60):
    a = rng.uniform(-1, 1, 3).astype(np.float32)
    obs, r, *_ = env.step(a)
    rows.append([*map(float, obs), float(r)])
print(json.dumps(rows))
"""


def test_the_kernels_run_as_plain_python_with_the_jit_off_and_agree() -> None:
    """NUMBA_DISABLE_JIT=1 (for debugging the physics) runs the same code to the same result."""
    import json
    import os

    runs = []
    for jit_off in ("0", "1"):
        env = {**os.environ, "NUMBA_DISABLE_JIT": jit_off}
        out = subprocess.run(
            [sys.executable, "-c", _JIT_PARITY_SCRIPT],
            env=env,
            capture_output=True,
            text=True,
            check=True,
        )
        runs.append(np.array(json.loads(out.stdout.strip().splitlines()[-1])))
    compiled, python = runs
    assert compiled.shape == (60, len(OBS_NAMES) + 1)
    np.testing.assert_allclose(python, compiled, rtol=1e-9, atol=1e-9)
