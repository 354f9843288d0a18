"""The SB3 adapter: DummyVecEnv semantics bit for bit, PPO training and evaluate_policy on it."""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

from auv_gym import AUVPath3DEnv
from auv_gym.envs.vector_env import AUVPath3DVectorEnv

pytest.importorskip("stable_baselines3")
pytestmark = pytest.mark.rl

from stable_baselines3 import PPO  # noqa: E402
from stable_baselines3.common.evaluation import evaluate_policy  # noqa: E402
from stable_baselines3.common.monitor import Monitor  # noqa: E402
from stable_baselines3.common.vec_env import DummyVecEnv, VecMonitor  # noqa: E402

from auv_gym.envs.sb3 import SB3VecEnv, make_sb3_vec_env  # noqa: E402

SHORT = {"corridor": 18.0, "max_time": 2.5}


def random_actions(seed: int, steps: int, n: int) -> np.ndarray:
    a = np.random.default_rng(seed).uniform(-1, 1, size=(steps, n, 3)).astype(np.float32)
    a[..., 0] = 0.6 * a[..., 0] - 0.1  # often astern: the corridor ends some episodes
    a[..., 1:] *= 0.6
    return a


def dummy(n: int, **kwargs) -> DummyVecEnv:
    return DummyVecEnv([lambda: AUVPath3DEnv(**kwargs) for _ in range(n)])


def assert_info_equal(got: dict, want: dict, where: str) -> None:
    assert sorted(got) == sorted(want), where
    for key, value in want.items():
        if isinstance(value, np.ndarray):
            assert isinstance(got[key], np.ndarray) and got[key].dtype == value.dtype, key
            np.testing.assert_array_equal(got[key], value, err_msg=f"{where}/{key}")
        else:
            assert type(got[key]) is type(value) and got[key] == value, (where, key)


@pytest.mark.parametrize(
    "kwargs",
    [
        SHORT,
        {
            **SHORT,
            "param_uncertainty": 0.2,
            "randomize_start": True,
            "current": {"std": (0.1, 0.1, 0.0)},
        },
    ],
)
def test_step_semantics_match_dummy_vec_env(kwargs):
    n, steps = 4, 100
    native, ref = make_sb3_vec_env(n, **kwargs), dummy(n, **kwargs)
    assert native.seed(7) == ref.seed(7) == [7, 8, 9, 10]
    np.testing.assert_array_equal(native.reset(), ref.reset())
    for i in range(n):
        assert_info_equal(native.reset_infos[i], ref.reset_infos[i], f"reset {i}")
    ended = 0
    for t, a in enumerate(random_actions(3, steps, n)):
        obs, rew, dones, infos = native.step(a)
        ref_obs, ref_rew, ref_dones, ref_infos = ref.step(a)
        np.testing.assert_array_equal(obs, ref_obs, err_msg=f"obs step {t}")
        assert obs.dtype == ref_obs.dtype == np.float32
        assert rew.dtype == ref_rew.dtype == np.float32
        np.testing.assert_array_equal(rew, ref_rew)
        np.testing.assert_array_equal(dones, ref_dones)
        for i in range(n):
            assert_info_equal(infos[i], ref_infos[i], f"step {t} env {i}")
            assert_info_equal(native.reset_infos[i], ref.reset_infos[i], f"reset {t} env {i}")
        ended += int(dones.sum())
    assert ended >= 2 * n
    # Without a new seed, reset continues every vehicle's generator, as the single envs do.
    np.testing.assert_array_equal(native.reset(), ref.reset())


def test_terminal_observation_and_time_limit_flags():
    n = 3
    env = make_sb3_vec_env(n, seed=0, max_time=0.5, disturbance="none")
    env.reset()
    ahead = np.tile(np.array([0.8, 0.0, 0.0], np.float32), (n, 1))
    for _ in range(9):
        _, _, dones, infos = env.step(ahead)
        assert not dones.any() and all(not info["TimeLimit.truncated"] for info in infos)
    obs, _, dones, infos = env.step(ahead)
    assert dones.all()
    for i, info in enumerate(infos):
        assert info["TimeLimit.truncated"] is True
        assert info["t"] == pytest.approx(0.5)
        assert info["terminal_observation"].shape == (15,)
        assert info["terminal_observation"][6] > 0.1  # surge at the end, the new episode is at 0
        assert obs[i][6] == 0.0
        assert env.reset_infos[i]["t"] == 0.0
        assert "terminal_observation" not in env.reset_infos[i]


def test_attribute_access_and_wrapper_queries():
    n = 4
    env = make_sb3_vec_env(n, seed=1, max_time=5.0)
    ref = dummy(n, max_time=5.0)
    ref.seed(1)
    env.reset()
    ref.reset()
    for a in random_actions(0, 5, n):
        env.step(a)
        ref.step(a)
    assert env.get_attr("render_mode") == ref.get_attr("render_mode") == [None] * n
    for i in range(n):
        np.testing.assert_array_equal(env.get_attr("state", i)[0], ref.get_attr("state", i)[0])
    assert env.get_attr("observation_space", [0, 2]) == ref.get_attr("observation_space", [0, 2])
    assert env.get_attr("action_space") == ref.get_attr("action_space")
    generator = env.get_attr("np_random", 3)[0]
    assert generator.bit_generator.state == ref.get_attr("np_random", 3)[0].bit_generator.state
    assert env.get_attr("config", [1, 2]) == [env.venv.config] * 2
    assert env.env_is_wrapped(Monitor) == ref.env_is_wrapped(Monitor) == [False] * n
    assert env.env_is_wrapped(Monitor, indices=[1]) == [False]
    env.set_attr("render_vehicle", 2)
    assert env.venv.render_vehicle == 2
    with pytest.raises(ValueError, match="shared"):
        env.set_attr("render_vehicle", 1, indices=[0])
    with pytest.raises(ValueError, match="out of range"):
        env.get_attr("state", 7)
    assert env.env_method("render", indices=[0, 1]) == [None, None]
    assert env.has_attr("config") and not env.has_attr("no_such_attribute")


def test_render_draws_the_chosen_vehicle():
    env = make_sb3_vec_env(3, seed=4, render_mode="rgb_array", render_vehicle=1, max_time=5.0)
    env.reset()
    for a in random_actions(1, 5, 3):
        env.step(a)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3
    np.testing.assert_array_equal(frame, env.venv.render())
    assert env.render_mode == "rgb_array"


def test_rejects_a_vector_env_without_same_step_autoreset():
    with pytest.raises(ValueError, match="SAME_STEP"):
        SB3VecEnv(AUVPath3DVectorEnv(2))
    with pytest.raises(ValueError, match="AUVPath3DVectorEnv"):
        SB3VecEnv(dummy(2))
    env = SB3VecEnv(AUVPath3DVectorEnv(2, autoreset_mode=AutoresetMode.SAME_STEP))
    assert env.num_envs == 2
    with pytest.raises(RuntimeError, match="step_async"):
        env.step_wait()


def test_ppo_learns_on_the_adapter_and_evaluate_policy_matches_dummy_vec_env():
    import torch

    torch.set_num_threads(1)
    n = 8
    kwargs = {"max_time": 1.0, "randomize_start": True}
    env = VecMonitor(make_sb3_vec_env(n, seed=0, **kwargs))
    model = PPO("MlpPolicy", env, n_steps=32, batch_size=64, n_epochs=2, seed=0, device="cpu")
    before = [p.detach().clone() for p in model.policy.parameters()]
    model.learn(256)
    assert model.num_timesteps == 256
    # 32 steps per vehicle, episodes of 20 steps: every vehicle finished one episode.
    assert len(model.ep_info_buffer) == n
    assert {info["l"] for info in model.ep_info_buffer} == {20}
    changed = [
        not torch.equal(a, b) for a, b in zip(before, model.policy.parameters(), strict=True)
    ]
    assert any(changed)

    native, ref = make_sb3_vec_env(3, **kwargs), dummy(3, **kwargs)
    native.seed(40)
    ref.seed(40)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # "not wrapped with a Monitor"
        got = evaluate_policy(model, native, n_eval_episodes=5, return_episode_rewards=True)
        want = evaluate_policy(model, ref, n_eval_episodes=5, return_episode_rewards=True)
    assert got == want
    assert got[1] == [20] * 5 and len(got[0]) == 5


def test_missing_stable_baselines3_raises_import_error_naming_the_extra():
    code = (
        "import sys; sys.modules['stable_baselines3'] = None\n"
        "import gymnasium as gym, auv_gym\n"
        "gym.make_vec('AUVPath3D-v0', num_envs=2).reset(seed=0)\n"
        "assert 'torch' not in sys.modules\n"
        "try:\n"
        "    import auv_gym.envs.sb3\n"
        "except ImportError as e:\n"
        "    print(e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "pip install 'auv-gym[rl]'" in out.stdout


@pytest.mark.integration
def test_speed_benchmark_runs_with_a_tiny_budget(tmp_path):
    import json
    from pathlib import Path

    out = tmp_path / "speed.json"
    root = Path(__file__).resolve().parents[1]
    subprocess.run(
        [sys.executable, "-m", "benchmarks.speed.vector", "--quick", "--json", str(out)],
        cwd=root,
        check=True,
        capture_output=True,
        text=True,
    )
    results = json.loads(out.read_text())
    assert [(r["n"], r["actuator"]) for r in results["vector"]] == [
        (1, "paper"),
        (1, "realistic"),
        (64, "paper"),
        (64, "realistic"),
    ]
    for r in results["vector"]:
        assert r["physics_steps_per_s"] == pytest.approx(5 * r["vehicle_steps_per_s"])
        assert r["real_time_factor"] == pytest.approx(0.05 * r["vehicle_steps_per_s"])
        assert r["autoresets"] >= r["n"]  # every vehicle went through a NEXT_STEP autoreset
    assert results["memory"]["n"] == 1024 and results["memory"]["peak_bytes"] > 0
    assert [r["waves"]["n"] for r in results["waves"]] == [64]  # waves beside no waves
    assert [r["computer"]["n"] for r in results["guidance"]] == [64]  # beside the plant's law
    # The ratio is the row's own two rates (how fast waves are is a benchmark figure, not a
    # unit test's: a 0.2-s budget on shared cores put it at 2.6 once)
    row = results["waves"][0]
    rates = [row[label]["physics_steps_per_s"] for label in ("no_waves", "waves")]
    assert min(rates) > 0 and row["ratio"] == pytest.approx(rates[1] / rates[0])
    # the vehicle as built beside the paper configuration, both measured
    as_built = results["as_built"][0]
    assert as_built["as_built"]["actuator"] == "realistic"
    assert as_built["as_built"]["sensors"] == "typical_kalman"
    assert as_built["paper"]["actuator"] == "paper" and as_built["paper"]["sensors"] == "ideal"
    rates = [as_built[label]["physics_steps_per_s"] for label in ("paper", "as_built")]
    assert min(rates) > 0 and as_built["ratio"] == pytest.approx(rates[1] / rates[0])
    assert {r["backend"] for r in results["ppo"]} == {"adapter", "DummyVecEnv"}
    assert all(r["timesteps_per_s"] > 0 for r in results["ppo"])
