"""PPO baselines: training CLI (`benchmarks.training`), checkpoints and resume, loading
(`controllers.loader`) and its errors, the shipped agent.

Training here is tiny (a few hundred env steps); real training belongs to
benchmarks/training/train_cli.py.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from auv_gym.sim.observation import OBS_DIM, OBS_HIGH, OBS_LOW, OBS_NAMES

pytestmark = pytest.mark.rl

ROOT = Path(__file__).resolve().parent.parent
SHIPPED = ROOT / "benchmarks" / "agents" / "ppo_generalist"

TINY_YAML = """\
AUVPath3D-v0: &tiny
  n_envs: 2
  n_timesteps: 256
  policy: MlpPolicy
  normalize: "dict(norm_obs=True, norm_reward=True)"
  n_steps: 64
  batch_size: 64
  n_epochs: 1
  gamma: 0.99
  learning_rate: lin_3e-4
  policy_kwargs: "dict(net_arch=[16, 16], log_std_init=-1.0)"
  env_kwargs:
    randomize_start: true
    max_time: 5.0
    reward_weights: {distance: 2.0}
AUVPath3DSpeedLimit-v0: *tiny  # the training default
"""


def run_cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, "-m", "benchmarks.training.train_cli", *args],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )


TINY_ARGS = (
    "--n-timesteps",
    "256",
    "--checkpoint-freq",
    "128",
    "--eval-freq",
    "128",
    "--eval-seeds",
    "100,101",
    "--eval-duration",
    "2",
    "--no-progress-bar",
)


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 256-step run of the real CLI, then --resume to 512 steps (shared by the tests below)."""
    work = tmp_path_factory.mktemp("ppo")
    (work / "tiny.yml").write_text(TINY_YAML)
    out = work / "run"
    first = run_cli("--config", "tiny.yml", "--out", str(out), "--seed", "3", *TINY_ARGS, cwd=work)
    assert first.returncode == 0, first.stderr
    (work / "first_metadata.json").write_text((out / "metadata.json").read_text())
    second = run_cli(
        "--config",
        "tiny.yml",
        "--out",
        str(out),
        "--seed",
        "3",
        *TINY_ARGS[2:],
        "--n-timesteps",
        "512",
        "--resume",
        cwd=work,
    )
    assert second.returncode == 0, second.stderr
    return out


def test_cli_writes_complete_loadable_agents(tiny_run: Path) -> None:
    from controllers.loader import load_policy

    first = json.loads((tiny_run.parent / "first_metadata.json").read_text())
    assert first["num_timesteps"] == 256
    assert first["seed"] == 3
    assert first["obs_names"] == list(OBS_NAMES)
    assert first["config"]["n_envs"] == 2
    assert first["env_kwargs"]["reward_weights"] == {"distance": 2.0}
    assert "--config tiny.yml" in first["command"]
    assert set(first["versions"]) >= {"python", "torch", "stable-baselines3", "gymnasium"}
    assert first["wall_time_s"] > 0
    assert first["vec_env"] == "VecNormalize<VecMonitor<SB3VecEnv<AUVPath3DVectorEnv>>>"
    for folder in ("final", "best"):
        for name in ("model.zip", "vecnormalize.npz", "vecnormalize.pkl", "metadata.json"):
            assert (tiny_run / folder / name).is_file(), (folder, name)
    # Evaluations at 0, 128 and 256 steps, then 384 and 512 after the resume.
    rows = (tiny_run / "evaluations.csv").read_text().splitlines()
    assert rows[0].startswith("num_timesteps,wall_time_s,rms_distance_mean")
    assert [int(r.split(",")[0]) for r in rows[1:]] == [0, 128, 256, 384, 512]
    assert (tiny_run / "tb").is_dir() and any((tiny_run / "tb").rglob("events.out.tfevents*"))
    policy = load_policy(tiny_run / "final")
    action, state = policy.predict(np.zeros(OBS_DIM, dtype=np.float32))
    assert action.shape == (3,) and state is None
    assert np.all(np.abs(action) <= 1.0)


def test_resume_continues_step_counter(tiny_run: Path) -> None:
    meta = json.loads((tiny_run / "metadata.json").read_text())
    assert meta["num_timesteps"] == 512
    sessions = meta["sessions"]
    assert len(sessions) == 2
    assert sessions[0]["start_timesteps"] == 0
    assert sessions[1]["start_timesteps"] == 256
    assert sessions[1]["resumed_from"].endswith("step_0000000256")
    assert "--resume" in " ".join(sessions[1]["argv"])
    # Only the newest `keep_checkpoints` (3) checkpoints stay: 256, 384, 512.
    kept = sorted(p.name for p in (tiny_run / "checkpoints").iterdir())
    assert kept == ["step_0000000256", "step_0000000384", "step_0000000512"]
    ckpt = json.loads((tiny_run / "checkpoints" / "step_0000000512" / "metadata.json").read_text())
    assert ckpt["num_timesteps"] == 512


def test_resume_refuses_other_settings_than_the_run_started_with(tiny_run: Path, tmp_path: Path):
    """Was: --resume with another seed or another config's content trained on, recorded the
    new values in metadata.json as if the whole run had them, and called the resume exact."""
    before = (tiny_run / "metadata.json").read_text()
    (tmp_path / "tiny.yml").write_text(TINY_YAML)
    (tmp_path / "other.yml").write_text(TINY_YAML.replace("n_epochs: 1", "n_epochs: 2"))
    resume = ("--out", str(tiny_run), *TINY_ARGS[2:], "--n-timesteps", "640", "--resume")
    seed = run_cli("--config", "tiny.yml", "--seed", "5", *resume, cwd=tmp_path)
    assert seed.returncode == 2 and seed.stderr.count("\n") == 1, seed.stderr
    assert "--resume: seed was 3 in " in seed.stderr and "now 5; resume with" in seed.stderr
    config = run_cli("--config", "other.yml", "--seed", "3", *resume, cwd=tmp_path)
    assert config.returncode == 2 and config.stderr.count("\n") == 1, config.stderr
    assert "--resume: the settings of --config other.yml differ from the run's" in config.stderr
    assert (tiny_run / "metadata.json").read_text() == before
    assert not (tiny_run / "checkpoints" / "step_0000000640").exists()


def test_a_larger_budget_is_refused_when_the_best_agent_is_newer_than_the_checkpoint(
    tiny_run: Path, tmp_path: Path
) -> None:
    """Was: a killed run resumed with another --n-timesteps kept best/ from beyond its
    checkpoint (the stopped run's agent) unless a later evaluation beat the checkpoint's score."""
    import shutil

    from benchmarks.training.train import TrainOptions, check_resume

    run = tmp_path / "run"
    checkpoint = run / "checkpoints" / "step_0000000256"
    shutil.copytree(tiny_run / "checkpoints" / "step_0000000256", checkpoint)
    recorded = json.loads((checkpoint / "metadata.json").read_text())
    assert recorded["n_timesteps"] == 512 and recorded["num_timesteps"] == 256
    opts = TrainOptions(**recorded["options"])
    (run / "best").mkdir()
    for best_steps in (128, 256, 384):  # the stopped run saved its best agent at best_steps
        (run / "best" / "metadata.json").write_text(json.dumps({"num_timesteps": best_steps}))
        check_resume(checkpoint, opts, recorded["config"], 512)  # the same budget re-makes it
        if best_steps <= 256:
            check_resume(checkpoint, opts, recorded["config"], 640)
    with pytest.raises(
        ValueError, match=r"holds the agent of step 384, saved after the checkpoint"
    ):
        check_resume(checkpoint, opts, recorded["config"], 640)
    check_resume(checkpoint, opts, recorded["config"])  # no budget given: nothing to compare


def test_a_damaged_checkpoint_is_named_or_passed_over(tiny_run: Path, tmp_path: Path) -> None:
    """A model.zip cut short is no complete checkpoint (--resume takes the one before); a
    damaged training state or VecNormalize pickle is named. Was: a bare "invalid literal for
    int()" naming no file."""
    from benchmarks.training.checkpoints import latest_checkpoint, read_training_state

    run = shutil.copytree(tiny_run, tmp_path / "run")
    newest = run / "checkpoints" / "step_0000000512"
    assert latest_checkpoint(run) == newest
    whole = (newest / "model.zip").read_bytes()
    (newest / "model.zip").write_bytes(whole[: len(whole) // 2])
    assert latest_checkpoint(run) == run / "checkpoints" / "step_0000000384"
    state = run / "checkpoints" / "step_0000000384" / "training_state.pkl"
    state.write_text("garbage\n")
    with pytest.raises(ValueError, match=rf"{state} cannot be read .*: a damaged checkpoint"):
        read_training_state(state.parent)


@pytest.mark.integration
def test_cli_refuses_to_overwrite_and_to_resume_nothing(tiny_run: Path, tmp_path: Path) -> None:
    (tmp_path / "tiny.yml").write_text(TINY_YAML)
    again = run_cli("--config", "tiny.yml", "--out", str(tiny_run), *TINY_ARGS, cwd=tmp_path)
    assert again.returncode != 0 and "is not empty" in again.stderr
    empty = run_cli(
        "--config", "tiny.yml", "--out", str(tmp_path / "new"), "--resume", *TINY_ARGS, cwd=tmp_path
    )
    assert empty.returncode != 0 and "no complete checkpoint" in empty.stderr


def _random_obs(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    scale = np.minimum(np.abs(OBS_LOW), OBS_HIGH).clip(max=5.0)
    return (rng.uniform(-1, 1, (n, OBS_DIM)) * scale).astype(np.float32)


@pytest.fixture(scope="module")
def saved_agent(tmp_path_factory: pytest.TempPathFactory, tiny_paper_model):
    from benchmarks.training.checkpoints import save_agent

    model, venv = tiny_paper_model()
    folder = tmp_path_factory.mktemp("agent") / "agent"
    save_agent(model, venv, folder, {"obs_names": list(OBS_NAMES), "seed": 0})
    return model, venv, folder


def test_save_load_identical_deterministic_predictions(saved_agent) -> None:
    from controllers.loader import load_policy

    model, venv, folder = saved_agent
    obs = _random_obs(64)
    expected, _ = model.predict(venv.normalize_obs(obs), deterministic=True)
    policy = load_policy(folder)
    actions, state = policy.predict(obs, None, np.ones(64, dtype=bool), True)
    assert state is None
    np.testing.assert_array_equal(actions, expected)
    single, _ = policy.predict(obs[5])  # one row: same up to float32 matmul rounding
    assert single.shape == (3,)
    np.testing.assert_allclose(single, expected[5], rtol=1e-5, atol=1e-7)
    # The pickled VecNormalize alone (RL Zoo's layout) is refused, never unpickled; converted
    # once by its owner (`stats_from_vecnormalize`), it gives the same agent.
    from benchmarks.training.checkpoints import stats_from_vecnormalize

    zoo = folder.parent / "zoo"
    zoo.mkdir()
    shutil.copy2(folder / "model.zip", zoo / "model.zip")
    shutil.copy2(folder / "vecnormalize.pkl", zoo / "vecnormalize.pkl")
    with pytest.raises(ValueError, match=r"never unpickles vecnormalize\.pkl"):
        load_policy(zoo / "model.zip")
    stats_from_vecnormalize(zoo / "vecnormalize.pkl")
    from_pickle, _ = load_policy(zoo / "model.zip").predict(obs)
    np.testing.assert_array_equal(from_pickle, expected)


def test_policy_rejects_bad_observation_shape(saved_agent) -> None:
    from controllers.loader import load_policy

    policy = load_policy(saved_agent[2])
    with pytest.raises(ValueError, match="observation must have shape"):
        policy.predict(np.zeros(OBS_DIM + 1, dtype=np.float32))


def _copy_agent(src: Path, dst: Path, skip: tuple[str, ...] = ()) -> Path:
    dst.mkdir(parents=True)
    for p in src.iterdir():
        if p.name not in skip:
            shutil.copy2(p, dst / p.name)
    return dst


def test_missing_statistics_named(saved_agent, tmp_path: Path) -> None:
    from controllers.loader import load_policy

    agent = _copy_agent(
        saved_agent[2], tmp_path / "a", skip=("vecnormalize.npz", "vecnormalize.pkl")
    )
    with pytest.raises(FileNotFoundError, match=r"normalisation statistics missing") as err:
        load_policy(agent)
    assert str(agent / "model.zip") in str(err.value)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        load_policy(tmp_path / "nowhere")


@pytest.mark.parametrize("damage", ["garbage", "truncated"])
def test_corrupt_zip_named(saved_agent, tmp_path: Path, damage: str) -> None:
    from controllers.loader import load_policy

    agent = _copy_agent(saved_agent[2], tmp_path / "a")
    data = (agent / "model.zip").read_bytes()
    (agent / "model.zip").write_bytes(
        b"not a zip" * 100 if damage == "garbage" else data[: len(data) // 2]
    )
    with pytest.raises(ValueError, match=r"model\.zip") as err:
        load_policy(agent)
    assert any(m in str(err.value) for m in ("not a valid zip", "damaged", "cannot be loaded"))


def test_other_observation_layout_named(saved_agent, tmp_path: Path) -> None:
    from controllers.loader import load_policy

    agent = _copy_agent(saved_agent[2], tmp_path / "a")
    meta = json.loads((agent / "metadata.json").read_text())
    meta["obs_names"] = [*OBS_NAMES[:-1], "depth"]
    (agent / "metadata.json").write_text(json.dumps(meta))
    with pytest.raises(ValueError, match="observation layout") as err:
        load_policy(agent)
    assert "metadata.json" in str(err.value)
    # Statistics of another size.
    agent2 = _copy_agent(saved_agent[2], tmp_path / "b", skip=("vecnormalize.pkl",))
    with np.load(agent2 / "vecnormalize.npz") as d:
        stats = dict(d)
    stats["mean"], stats["var"] = np.zeros(OBS_DIM - 1), np.ones(OBS_DIM - 1)
    stats.pop("obs_names")
    np.savez(agent2 / "vecnormalize.npz", **stats)
    with pytest.raises(ValueError, match=r"vecnormalize.npz: statistics of shape \(14,\)"):
        load_policy(agent2)


def test_other_observation_space_named(saved_agent, tmp_path: Path) -> None:
    import gymnasium as gym
    from stable_baselines3 import PPO

    from controllers.loader import load_policy

    agent = _copy_agent(saved_agent[2], tmp_path / "a", skip=("metadata.json", "model.zip"))
    PPO("MlpPolicy", gym.make("Pendulum-v1"), n_steps=32, batch_size=32, device="cpu").save(
        agent / "model.zip"
    )
    # without its metadata.json the agent is read as the paper's observation, and the error says so
    expected = (
        r"observation space shape \(3,\), expected \(15,\) \(layout .*\); there is no "
        r"metadata\.json beside it, so it is read as the paper's observation$"
    )
    with pytest.raises(ValueError, match=expected):
        load_policy(agent)


def test_zoo_config_errors(tmp_path: Path) -> None:
    from benchmarks.training.config import read_zoo_config

    cfg = read_zoo_config(ROOT / "benchmarks" / "hyperparams" / "ppo_helix.yml")
    assert cfg.normalize["norm_obs"] is True
    assert cfg.normalize["gamma"] == cfg.algo_kwargs["gamma"]  # copied, as RL Zoo does
    assert cfg.env_kwargs["randomize_start"] is True
    bad = tmp_path / "bad.yml"
    bad.write_text(TINY_YAML.replace("n_epochs: 1", "n_epochs: 1\n  frame_stack: 4"))
    with pytest.raises(ValueError, match=r"unsupported keys .*frame_stack"):
        read_zoo_config(bad)
    bad.write_text(TINY_YAML.replace('"dict(norm_obs=True, norm_reward=True)"', "false"))
    with pytest.raises(ValueError, match="normalize must be enabled"):
        read_zoo_config(bad)
    with pytest.raises(ValueError, match="no top-level key 'Other-v0'"):
        read_zoo_config(bad, "Other-v0")
    bad.write_text("AUVPath3D-v0: a comment that lost its hash\n")  # a section that is a string
    with pytest.raises(
        ValueError, match="AUVPath3D-v0 must be a mapping of hyper-parameters, got str 'a comment"
    ):
        read_zoo_config(bad)
    with pytest.raises(FileNotFoundError, match=r"missing\.yml"):
        read_zoo_config(tmp_path / "missing.yml")


def test_shipped_agent_follows_helix_briefly() -> None:
    """The shipped generalist on held-out seed 0 (paper scenario), 60 s: no termination, closes
    in."""
    from auv_gym.rollout import evaluate
    from controllers.loader import load_policy

    policy = load_policy(SHIPPED)
    assert policy.metadata["obs_names"][:OBS_DIM] == list(OBS_NAMES)  # the paper's, then more
    size = sum(p.stat().st_size for p in SHIPPED.iterdir())
    assert size < 5e6
    (metrics,) = evaluate(policy, [0], transient=40.0, max_time=60.0)
    assert metrics["termination_reason"] == "time_limit"
    assert metrics["max_distance_window"] < 30.0  # inside the corridor over 40-60 s
    assert metrics["rms_distance"] < 0.5  # already on the path (starts 17.7 m away; 0.052 m)


@pytest.mark.slow  # ten 300-s episodes
def test_shipped_agent_meets_acceptance_on_held_out_seeds() -> None:
    """Issue acceptance: paper scenario, seeds 0-9, 300 s: mean rms_distance (t ≥ 100 s) ≤ 1 m and
    no episode leaves the corridor; the numbers recorded beside the agent are reproduced."""
    from benchmarks.training import HELD_OUT_FILE, held_out_evaluation

    recorded = json.loads((SHIPPED / HELD_OUT_FILE).read_text())
    env_id = json.loads((SHIPPED / "metadata.json").read_text())["env_id"]
    fresh = held_out_evaluation(SHIPPED, recorded["duration_s"], env_id)
    assert fresh["scenario"] == recorded["scenario"]
    assert fresh["summary"]["n_terminated"] == 0
    assert fresh["summary"]["rms_distance_mean"] <= 1.0
    # Bit-identical on the machine that trained it; elsewhere BLAS rounding may perturb the
    # closed loop slightly, so compare the statistics, not the bits.
    np.testing.assert_allclose(
        [r["rms_distance"] for r in fresh["results"]],
        [r["rms_distance"] for r in recorded["results"]],
        rtol=0.05,
    )


def test_controllers_make_dispatches_to_load_policy() -> None:
    import controllers
    from controllers.agent import AgentPolicy
    from controllers.loader import load_policy

    policy = controllers.make("agent", path=str(SHIPPED))
    assert isinstance(policy.actor, AgentPolicy)  # under its stages (the envelope guard)
    obs = np.random.default_rng(1).uniform(-1.0, 1.0, (8, policy.obs_dim)).astype(np.float32)
    np.testing.assert_array_equal(policy.predict(obs)[0], load_policy(SHIPPED).predict(obs)[0])
