"""Exported agents carry the pickled VecNormalize, so SB3 and RL Zoo load them as they are."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from benchmarks.training.checkpoints import export_agent
from controllers.agent import METADATA_FILE, MODEL_FILE, STATS_FILE, VECNORM_FILE

pytestmark = pytest.mark.rl


def test_exported_agent_has_a_vecnormalize_that_sb3_loads(tmp_path):
    import gymnasium as gym
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    venv = VecNormalize(DummyVecEnv([lambda: gym.make("AUVPath3D-v0")]))
    venv.reset()
    for _ in range(5):
        venv.step(np.zeros((1, 3), dtype=np.float32))
    run = tmp_path / "best"
    run.mkdir()
    venv.save(str(run / VECNORM_FILE))
    for name in (MODEL_FILE, STATS_FILE, METADATA_FILE):
        (run / name).write_bytes(b"stand-in")  # copied as they are
    export_agent(run, tmp_path / "agent")
    names = sorted(p.name for p in (tmp_path / "agent").iterdir())
    assert names == sorted([MODEL_FILE, STATS_FILE, METADATA_FILE, VECNORM_FILE])
    loaded = VecNormalize.load(
        str(tmp_path / "agent" / VECNORM_FILE), DummyVecEnv([lambda: gym.make("AUVPath3D-v0")])
    )
    np.testing.assert_array_equal(loaded.obs_rms.mean, venv.obs_rms.mean)
    assert loaded.obs_rms.count == venv.obs_rms.count == pytest.approx(6.0, abs=1e-3)  # 1 + 5


def test_an_agent_folder_without_the_pickle_exports_without_it(tmp_path):
    run = tmp_path / "old"
    run.mkdir()
    for name in (MODEL_FILE, STATS_FILE, METADATA_FILE):
        (run / name).write_bytes(b"x")
    export_agent(run, tmp_path / "agent")
    assert not (tmp_path / "agent" / VECNORM_FILE).exists()


def test_a_pickle_rebuilt_from_the_stats_normalises_like_the_loader(tmp_path):
    import shutil

    import gymnasium as gym
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from benchmarks.training.checkpoints import write_vecnormalize_from_stats

    shipped = Path(__file__).resolve().parents[1] / "benchmarks" / "agents" / "ppo_generalist"
    assert (shipped / VECNORM_FILE).is_file()  # every agent folder loads in SB3 and RL Zoo
    agent = shutil.copytree(shipped, tmp_path / "agent")
    (agent / VECNORM_FILE).unlink()
    pickle = write_vecnormalize_from_stats(agent)
    stats = np.load(agent / STATS_FILE)
    env = DummyVecEnv([lambda: gym.make("AUVPath3DPreview-v0", observation="preview_integral")])
    venv = VecNormalize.load(str(pickle), env)
    obs = venv.venv.reset()
    expected = np.clip(
        (obs - stats["mean"]) / np.sqrt(stats["var"] + stats["epsilon"]),
        -stats["clip_obs"],
        stats["clip_obs"],
    )
    np.testing.assert_allclose(venv.normalize_obs(obs), expected, rtol=1e-6, atol=1e-6)
    assert not venv.training and not venv.norm_reward


def test_rebuilding_the_pickle_is_deterministic(tmp_path):
    import shutil

    from benchmarks.training.checkpoints import write_vecnormalize_from_stats

    agent = Path(__file__).resolve().parents[1] / "benchmarks" / "agents" / "ppo_generalist"
    copy = tmp_path / "agent"
    shutil.copytree(agent, copy)
    (copy / VECNORM_FILE).unlink(missing_ok=True)
    first = write_vecnormalize_from_stats(copy).read_bytes()
    assert write_vecnormalize_from_stats(copy).read_bytes() == first
