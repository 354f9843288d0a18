from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from auv_gym.sim.config import SimConfig
from auv_gym.sim.simulator import Simulator

# sac_helix.yml's SAC keys scaled down for training tests (tests/test_jump_start_sac.py,
# tests/test_demo_sac.py: `from conftest import TINY_SAC_SECTION`); each adds its env_kwargs.
TINY_SAC_SECTION = {
    "n_envs": 4,
    "n_timesteps": 256,
    "policy": "MlpPolicy",
    "normalize": "dict(norm_obs=True, norm_reward=False)",
    "learning_rate": 3e-4,
    "buffer_size": 10000,
    "learning_starts": 500,
    "batch_size": 64,
    "tau": 0.005,
    "gamma": 0.995,
    "n_steps": 3,
    "train_freq": 1,
    "gradient_steps": 1,
    "ent_coef": "auto",
    "use_sde": True,
    "sde_sample_freq": 20,
    "use_sde_at_warmup": True,
    "policy_kwargs": "dict(net_arch=[64, 64])",
}


@pytest.fixture
def make_sim():
    """A seeded `Simulator` of n vehicles for the given env keyword arguments."""

    def _make(n: int = 1, seed: int = 0, **kwargs) -> Simulator:
        # The serial kernel at any n (the set-up compiles it; the threaded one is checked
        # against it in tests/test_simulation_core.py, integration tier).
        sim = Simulator(SimConfig.from_kwargs(**kwargs), n, parallel=False)
        for i in range(n):
            sim.reset_row(i, np.random.default_rng(seed + i))
        return sim

    return _make


def _assert_same_episodes(a, b) -> None:
    """Two lists of `auv_gym.rollout.Trajectory` are identical: end, samples and intervals."""
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert x.termination_reason == y.termination_reason
        for name in x.samples:
            np.testing.assert_array_equal(x.samples[name], y.samples[name], err_msg=name)
        for name in x.intervals:
            np.testing.assert_array_equal(x.intervals[name], y.intervals[name], err_msg=name)


def _single_env_observations(kwargs: dict, seed: int, actions: np.ndarray):
    """(observations, env) of one `AUVPath3DEnv` reset with ``seed`` and stepped with
    ``actions`` (steps, 3), resetting without a seed after an episode ends: what a vector env's
    NEXT_STEP autoreset gives its vehicle (the reset step's action is ignored)."""
    from auv_gym.envs.env import AUVPath3DEnv

    env = AUVPath3DEnv(**kwargs)
    single, done = [env.reset(seed=seed)[0]], False
    for a in actions:
        if done:
            obs, _ = env.reset()
            done = False
        else:
            obs, _, terminated, truncated, _ = env.step(a)
            done = terminated or truncated
        single.append(obs)
    return np.array(single), env


@pytest.fixture
def single_env_observations():
    """`_single_env_observations`: one vehicle of a NEXT_STEP vector env, run alone."""
    return _single_env_observations


@pytest.fixture
def assert_same_episodes():
    """`_assert_same_episodes`: bit-for-bit equality of two episode lists."""
    return _assert_same_episodes


@pytest.fixture
def save_tiny_residual_agent():
    """Train a tiny PPO residual agent (4 vehicles, 128 env steps) on ``env`` with ``settings``
    and save it to ``directory`` as the harness does: (settings, directory, seed, env) →
    (model, VecNormalize)."""
    pytest.importorskip("stable_baselines3")

    def _save(settings, directory, seed: int, env: dict):
        from stable_baselines3 import PPO
        from stable_baselines3.common.vec_env import VecNormalize

        from auv_gym.sim.observation import ObservationConfig
        from benchmarks.training.checkpoints import save_agent
        from benchmarks.training.residual_env import make_residual_sb3_env
        from controllers.residual import residual_observation_names

        venv = VecNormalize(make_residual_sb3_env(4, settings, seed=seed, **env))
        model = PPO(
            "MlpPolicy",
            venv,
            n_steps=32,
            batch_size=64,
            n_epochs=1,
            seed=0,
            device="cpu",
            policy_kwargs={"net_arch": [16, 16]},
        )
        model.learn(128)
        names = residual_observation_names(env.get("observation"))
        meta = {
            "algo": "ppo",
            "obs_names": list(names),
            "observation_shape": [len(names)],
            "action_shape": [settings.action_dim],
            "residual": settings.to_dict(),
        }
        if "observation" in env:  # recorded as the harness records it (the paper's: not)
            meta["observation"] = ObservationConfig.from_spec(env["observation"]).to_dict()
        save_agent(model, venv, directory, meta)
        return model, venv

    return _save


def _train_tiny_preview_agent(tmp_path, **keys):
    """One seed of a tiny PPO run on AUVPath3DPreview-v0 with the extra hyper-parameter
    ``keys``, through `benchmarks.training.seeds_cli`; returns the exported agent's folder."""
    import yaml

    from benchmarks.training.seeds_cli import main

    section = {
        "n_envs": 4,
        "n_timesteps": 256,
        "policy": "MlpPolicy",
        "normalize": True,
        "n_steps": 64,
        "batch_size": 128,
        "n_epochs": 1,
        "policy_kwargs": "dict(net_arch=[16])",
        "env_kwargs": {"randomize_start": True, "max_time": 20.0},
        **keys,
    }
    config = tmp_path / "tiny.yml"
    config.write_text(yaml.safe_dump({"AUVPath3DPreview-v0": section}))
    agent = tmp_path / "agent"
    assert (
        main(
            [
                "--algo",
                "ppo",
                "--config",
                str(config),
                "--out",
                str(tmp_path / "run"),
                "--env-id",
                "AUVPath3DPreview-v0",
                "--seeds",
                "0-0",
                "--workers",
                "1",
                "--eval-seeds",
                "100",
                "--eval-freq",
                "256",
                "--eval-duration",
                "110",
                "--quiet",
                "--export",
                str(agent),
            ]
        )
        == 0
    )
    return agent


@pytest.fixture
def train_tiny_preview_agent():
    """`_train_tiny_preview_agent(tmp_path, **keys)`: a tiny exported agent (rl tests only)."""
    return _train_tiny_preview_agent


@pytest.fixture
def auv_gym_command():
    """Run ``python -m benchmarks ARGV`` (the `auv-gym` command) in a subprocess: (exit code,
    stderr without the one-time notice that the kernels compile, which is no error line)."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]

    def run(*argv: str, cwd: Path = root) -> tuple[int, str]:
        done = subprocess.run(
            [sys.executable, "-m", "benchmarks", *argv],
            cwd=cwd,
            capture_output=True,
            text=True,
            timeout=600,
        )
        lines = [x for x in done.stderr.splitlines() if "compiling the simulation kernels" not in x]
        return done.returncode, "\n".join(lines).strip()

    return run


def _tiny_paper_model(seed: int = 0):
    """An untrained 16-16 PPO on the paper's own observation (`AUVPath3D-v0`, 15 values, no
    previous action) with `VecNormalize` statistics from a short rollout: (model, venv)."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecNormalize

    kwargs = {"randomize_start": True, "max_time": 5.0}
    venv = VecNormalize(make_vec_env("AUVPath3D-v0", n_envs=2, seed=seed, env_kwargs=kwargs))
    model = PPO(
        "MlpPolicy",
        venv,
        n_steps=32,
        batch_size=32,
        n_epochs=1,
        seed=seed,
        policy_kwargs={"net_arch": [16, 16]},
        device="cpu",
    )
    model.learn(64)
    return model, venv


@pytest.fixture(scope="session")
def tiny_paper_model():
    """`_tiny_paper_model(seed)`: (model, venv) of an untrained paper-observation PPO (rl tests)."""
    return _tiny_paper_model


@pytest.fixture
def tiny_paper_agent(tmp_path):
    """A saved untrained agent on the paper's 15-value observation: what no shipped agent
    observes any more (rl tests only)."""
    from auv_gym.sim.observation import OBS_NAMES
    from benchmarks.training.checkpoints import save_agent

    model, venv = _tiny_paper_model()
    folder = tmp_path / "paper_agent"
    save_agent(model, venv, folder, {"obs_names": list(OBS_NAMES), "seed": 0})
    return folder


@pytest.fixture
def dead_pid() -> int:
    """The pid of a process that has ended: what a killed run's temporary files are named by."""
    script = "import os; print(os.getpid())"
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True
    )
    return int(done.stdout)
