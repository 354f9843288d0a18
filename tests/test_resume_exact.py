"""A paused (`stop_at`) or killed training run resumed with `resume=True` gives the run that
never stopped, bit for bit: weights, optimizer, normalisation statistics, learning-curve rows
(all but the wall time), checkpoints and the exported agent; for PPO (gSDE, reward
normalisation) and SAC (replay buffer, random warm-up actions, gSDE). Single thread."""

from __future__ import annotations

import csv
import io
import json
import shutil
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

pytestmark = pytest.mark.rl

COMMON = {
    "policy": "MlpPolicy",
    "n_envs": 4,
    "normalize": "dict(norm_obs=True, norm_reward=True)",
    "policy_kwargs": "dict(net_arch=[16, 16])",
    "env_kwargs": {"randomize_start": True, "max_time": 5.0},
}
# PPO: rollouts of 4 × 32 = 128 env steps; gSDE noise redrawn every 4 steps.
PPO = {
    **COMMON,
    "n_steps": 32,
    "batch_size": 64,
    "n_epochs": 2,
    "gamma": 0.99,
    "learning_rate": "lin_3e-4",
    "clip_range": "lin_0.2",
    "use_sde": True,
    "sde_sample_freq": 4,
}
# SAC: one step of 4 vehicles per collection; random actions (the action space's generator)
# for the first 200 steps.
SAC = {
    **COMMON,
    "learning_rate": 3e-4,
    "buffer_size": 5000,
    "learning_starts": 200,
    "batch_size": 32,
    "train_freq": 1,
    "gradient_steps": 1,
    "ent_coef": "auto",
    "use_sde": True,
    "sde_sample_freq": 8,
}
# PPO inside an envelope guard stage tight enough to act in 5-s episodes: its wrapper's last
# observations and memories are part of what a resume restores.
GUARDED = {
    **PPO,
    "stages": [
        {
            "name": "envelope_guard",
            "pitch_soft_deg": 2.0,
            "pitch_hard_deg": 6.0,
            "surge_soft": 0.3,
            "surge_hard": 0.6,
        }
    ],
}
CASES = {
    "ppo": ("AUVPath3D-v0", PPO, 768, 300),
    "sac": ("AUVPath3DSpeedLimit-v0", SAC, 512, 100),
    "ppo_guard": ("AUVPath3D-v0", GUARDED, 768, 300),
}


def small_run_options(config: Path, env_id: str, out: Path, seed: int = 3, **extra: Any):
    """`TrainOptions` of a tiny run of ``config``: evaluations and checkpoints every 256 env
    steps on two 2-s validation episodes, no progress bar (PPO unless ``algo`` is given)."""
    from benchmarks.training.train import TrainOptions

    return TrainOptions(
        **{"algo": "ppo", **extra},
        config=str(config),
        env_id=env_id,
        out=str(out),
        seed=seed,
        eval_freq=256,
        checkpoint_freq=256,
        eval_seeds=(100, 101),
        eval_duration=2.0,
        progress_bar=False,
    )


def _options(tmp_path: Path, algo: str, out: str, **extra: Any):
    env_id, section, n_timesteps, _ = CASES[algo]
    config = tmp_path / f"{algo}.yml"
    config.write_text(yaml.safe_dump({env_id: {**section, "n_timesteps": n_timesteps}}))
    return small_run_options(config, env_id, tmp_path / out, algo=algo.split("_")[0], **extra)


def _model_tensors(folder: Path) -> dict[str, Any]:
    """Every tensor of model.zip (policy and optimizer states, SAC's entropy coefficient)."""
    import torch

    tensors: dict[str, Any] = {}
    with zipfile.ZipFile(folder / "model.zip") as archive:
        for name in archive.namelist():
            if name.endswith(".pth"):
                state = torch.load(io.BytesIO(archive.read(name)), map_location="cpu")
                tensors.update(_flatten(name, state))
    return tensors


def _flatten(prefix: str, value: Any) -> dict[str, Any]:
    if isinstance(value, dict):
        out: dict[str, Any] = {}
        for key, item in value.items():
            out.update(_flatten(f"{prefix}/{key}", item))
        return out
    if isinstance(value, list | tuple):
        return _flatten(prefix, dict(enumerate(value)))
    return {prefix: value}


def _assert_same_agent(a: Path, b: Path) -> None:
    import torch

    ta, tb = _model_tensors(a), _model_tensors(b)
    assert ta.keys() == tb.keys()
    for key in ta:
        if isinstance(ta[key], torch.Tensor):
            assert torch.equal(ta[key], tb[key]), key
        else:
            assert ta[key] == tb[key], key
    sa, sb = np.load(a / "vecnormalize.npz"), np.load(b / "vecnormalize.npz")
    for key in sa.files:
        np.testing.assert_array_equal(sa[key], sb[key], err_msg=key)
    ma, mb = (json.loads((f / "metadata.json").read_text()) for f in (a, b))
    assert ma["num_timesteps"] == mb["num_timesteps"]
    assert ma["best"] == mb["best"]


def _curve(run: Path) -> list[list[str]]:
    """The learning-curve rows without the wall-time column."""
    with (run / "evaluations.csv").open(newline="") as f:
        return [row[:1] + row[2:] for row in csv.reader(f)]


@pytest.mark.parametrize("algo", ["ppo", "sac", "ppo_guard"])
def test_paused_and_killed_runs_resume_bit_for_bit(tmp_path: Path, algo: str) -> None:
    from benchmarks.training.train import train

    _, _, n_timesteps, stop_at = CASES[algo]
    export = {"export": str(tmp_path / "agent_a")} if algo.startswith("ppo") else {}
    train(_options(tmp_path, algo, "a", **export))  # never stopped
    paused = _options(tmp_path, algo, "b", stop_at=stop_at)
    train(paused)
    meta = json.loads((tmp_path / "b" / "metadata.json").read_text())
    # PPO pauses at the first rollout start at or after 300 (3 × 128 steps); SAC at 100.
    assert meta["num_timesteps"] == (384 if algo.startswith("ppo") else 100)
    export = {"export": str(tmp_path / "agent_b")} if algo.startswith("ppo") else {}
    resumed = _options(tmp_path, algo, "b", resume=True, **export)
    train(resumed)
    assert json.loads((tmp_path / "b" / "metadata.json").read_text())["sessions"][1]["exact_resume"]
    rows = _curve(tmp_path / "a")
    assert [int(r[0]) for r in rows[1:]] == list(range(0, n_timesteps + 1, 256))
    assert _curve(tmp_path / "b") == rows
    for folder in ("final", "best"):
        _assert_same_agent(tmp_path / "a" / folder, tmp_path / "b" / folder)
    if algo.startswith("ppo"):
        _assert_same_agent(tmp_path / "agent_a", tmp_path / "agent_b")
    if algo == "ppo_guard":  # the exported agent carries its guard
        (guard,) = json.loads((tmp_path / "agent_b" / "metadata.json").read_text())["stages"]
        assert guard["name"] == "envelope_guard" and guard["pitch_hard_deg"] == 6.0
    # The pause left its checkpoint; the later ones are those of the run that never stopped.
    for step in range(512, n_timesteps + 1, 256):
        name = f"checkpoints/step_{step:010d}"
        _assert_same_agent(tmp_path / "a" / name, tmp_path / "b" / name)

    # A kill after the first checkpoint: later checkpoints and final/ never written, the rows
    # and best/ past the checkpoint left behind; resuming from the checkpoint is exact too.
    killed = tmp_path / "c"
    shutil.copytree(tmp_path / "a", killed)
    for folder in sorted((killed / "checkpoints").iterdir())[1:]:
        shutil.rmtree(folder)
    shutil.rmtree(killed / "final")
    train(_options(tmp_path, algo, "c", resume=True))
    assert _curve(killed) == rows
    for folder in ("final", "best"):
        _assert_same_agent(tmp_path / "a" / folder, killed / folder)


def test_vector_env_snapshot_restores_mid_episode(tmp_path: Path) -> None:
    """A snapshot mid-episode, restored into a fresh vector env built with the same arguments,
    continues bit for bit (random tasks, per-vehicle generators, autoresets included)."""
    from auv_gym.envs.sb3 import make_sb3_vec_env

    kwargs = {
        "randomize_start": True,
        "max_time": 2.0,
        "param_uncertainty": 0.3,
        "path": {"families": ["helix", "line", "spline"]},
    }
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, size=(90, 3, 3)).astype(np.float32)
    env = make_sb3_vec_env(3, seed=7, **kwargs)
    env.reset()
    for a in actions[:25]:
        env.step(a)
    snapshot = env.snapshot()
    clone = make_sb3_vec_env(3, seed=99, **kwargs)  # another seed: everything comes from it
    clone.restore(snapshot)
    ends = 0
    for a in actions[25:]:
        obs, reward, done, _ = env.step(a)
        obs2, reward2, done2, _ = clone.step(a)
        np.testing.assert_array_equal(obs, obs2)
        np.testing.assert_array_equal(reward, reward2)
        np.testing.assert_array_equal(done, done2)
        ends += int(done.sum())
    assert ends >= 3  # episodes of 40 steps: every vehicle autoreset at least once
    other = make_sb3_vec_env(4, seed=7, **kwargs)
    with pytest.raises(ValueError, match="snapshot of 3 vehicles, this vector env has 4"):
        other.restore(snapshot)


def test_checkpoint_without_training_state_resumes_and_says_it_is_not_exact(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A checkpoint written before the training state was kept still resumes (weights and
    step counter), with one line on stderr and ``exact_resume`` false in the sessions."""
    from benchmarks.training.checkpoints import TRAINING_STATE_FILE
    from benchmarks.training.train import train

    train(_options(tmp_path, "ppo", "old", stop_at=256))
    checkpoint = tmp_path / "old" / "checkpoints" / "step_0000000256"
    (checkpoint / TRAINING_STATE_FILE).unlink()
    capsys.readouterr()
    train(_options(tmp_path, "ppo", "old", resume=True))
    assert f"--resume: {checkpoint} holds no training state" in capsys.readouterr().err
    sessions = json.loads((tmp_path / "old" / "metadata.json").read_text())["sessions"]
    assert [s["exact_resume"] for s in sessions] == [None, False]
    assert [s["start_timesteps"] for s in sessions] == [0, 256]
