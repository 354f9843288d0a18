"""Multi-seed training (`benchmarks.training.seeds_cli`): bad input, an end-to-end smoke run with
both algorithms, SAC's replay buffer across a resume, a killed run resumed, and the Ray backend."""

from __future__ import annotations

import json
import os
import pickle
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from benchmarks.training.seeds import check_evaluation_window, parse_seeds
from benchmarks.training.seeds_cli import main

ROOT = Path(__file__).resolve().parent.parent
TINY = {
    "ppo": {
        "n_envs": 4,
        "n_timesteps": 256,
        "policy": "MlpPolicy",
        "normalize": True,
        "n_steps": 64,
        "batch_size": 128,
        "n_epochs": 1,
        "policy_kwargs": "dict(net_arch=[16, 16])",
    },
    "sac": {
        "n_envs": 4,
        "n_timesteps": 256,
        "policy": "MlpPolicy",
        "normalize": "dict(norm_obs=True, norm_reward=False)",
        "buffer_size": 2000,
        "learning_starts": 64,
        "batch_size": 64,
        "train_freq": 1,
        "gradient_steps": 1,
        "policy_kwargs": "dict(net_arch=[16, 16])",
    },
}
# sb3-contrib's off-policy learners: SAC's tiny file, CrossQ without target networks.
TINY["tqc"] = {**TINY["sac"], "top_quantiles_to_drop_per_net": 1}
TINY["crossq"] = {key: value for key, value in TINY["sac"].items() if key != "policy_kwargs"}
TINY["crossq"].update(policy_delay=2, policy_kwargs="dict(net_arch=dict(pi=[16, 16], qf=[32, 32]))")


def _shortest_eval_duration() -> float:
    """The shortest evaluation episode the metrics-window rule accepts, from a few candidates."""
    for duration in (10.0, 110.0):
        try:
            check_evaluation_window(duration)
            return duration
        except ValueError:
            continue
    raise AssertionError("no evaluation duration accepted")


def _config(tmp_path: Path, algo: str) -> Path:
    section = {**TINY[algo], "env_kwargs": {"randomize_start": True, "max_time": 20.0}}
    path = tmp_path / f"{algo}.yml"
    path.write_text(yaml.safe_dump({"AUVPath3DSpeedLimit-v0": section}))
    return path


def _args(tmp_path: Path, algo: str, out: str, *extra: str) -> list[str]:
    return [
        "--algo",
        algo,
        "--config",
        str(_config(tmp_path, algo)),
        "--out",
        str(tmp_path / out),
        "--eval-seeds",
        "100",
        "--eval-freq",
        "256",
        "--checkpoint-freq",
        "128",
        "--eval-duration",
        str(_shortest_eval_duration()),
        "--quiet",
        *extra,
    ]


@pytest.mark.parametrize(
    ("text", "seeds"),
    [("3", (0, 1, 2)), ("0-4", (0, 1, 2, 3, 4)), ("2-2", (2,)), ("5,1,7", (5, 1, 7))],
)
def test_parse_seeds(text, seeds):
    assert parse_seeds(text) == seeds


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--seeds", "0"], "a seed count must be at least 1, got 0"),
        (["--seeds", ""], "--seeds ''"),
        (["--seeds", "-1"], "a seed count must be at least 1, got -1"),
        (["--seeds=-3,2"], "seeds must be non-negative, got -3"),
        (["--seeds", "2", "--algo", "dqn"], "argument --algo: invalid choice: 'dqn'"),
        (["--seeds", "4-2"], "range '4-2' is empty"),
        (["--seeds", "1,1"], "repeats a seed"),
        (["--seeds", "2", "--n-timesteps", "0"], "n_timesteps must be a positive number"),
        (["--seeds", "2", "--n-timesteps", "-5"], "n_timesteps must be a positive number"),
        (["--seeds", "2", "--eval-seeds", "3,100"], "eval_seeds [3] overlap the held-out"),
        # was accepted: test_distribution flies seeds 0-19, the fresh as-built sets 300-309
        (["--seeds", "2", "--eval-seeds", "15,100"], "eval_seeds [15] overlap the held-out"),
        (["--seeds", "2", "--eval-seeds", "100,305"], "eval_seeds [305] overlap the held-out"),
        (
            ["--seeds", "2", "--task-set", "nope"],
            "task set 'nope' is not a validation set; valid: ['paper', 'validation', "
            "'validation_actuators_start', 'validation_actuators_start_light', "
            "'validation_as_built', 'validation_as_built_plants', "
            "'validation_as_built_plants_computer', 'validation_as_built_start', "
            "'validation_as_built_start_6dof', 'validation_as_built_start_plants', "
            "'validation_as_built_wide_plants', 'validation_cross_current', "
            "'validation_fins_start', 'validation_paper_actuator', 'validation_paper_start']",
        ),
        (["--seeds", "2", "--task-set", "test_steep"], "'test_steep' is not a validation set"),
        (
            ["--seeds", "2", "--task-set", "validation", "--eval-seeds", "5"],
            "eval seeds [5] lie outside task set 'validation' (seeds 100000-100099)",
        ),
        (
            ["--seeds", "2", "--task-set", "validation", "--eval-episodes", "101"],
            "eval_episodes must be 1-100 (the size of task set 'validation'), got 101",
        ),
        # was: accepted where the task set (the paper's default) does not draw episodes
        (["--seeds", "2", "--eval-episodes", "-5"], "eval_episodes must be >= 1, got -5"),
        (["--seeds", "2", "--eval-duration", "0.04"], "evaluation duration 0.04"),
        (["--seeds", "2", "--workers", "0"], "workers must be a positive integer, got 0"),
        (["--seeds", "2", "--checkpoint-freq", "0"], "checkpoint_freq must be a positive"),
        (
            ["--seeds", "2", "--env-id", "Nope-v0"],
            "no top-level key 'Nope-v0' (its env ids: ['AUVPath3DSpeedLimit-v0']; pass --env-id",
        ),
    ],
)
def test_bad_input_is_one_line_exit_2_before_training(tmp_path, capsys, argv, message):
    out = tmp_path / "run"
    config = _config(tmp_path, "ppo")
    with pytest.raises(SystemExit) as exit_info:
        code = main(["--config", str(config), "--out", str(out), "--quiet", *argv])
        raise SystemExit(code)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "Traceback" not in err
    assert not (out / "seed_0").exists()  # nothing trained


def test_unreachable_ray_address_and_occupied_output_are_refused(tmp_path, capsys):
    pytest.importorskip("ray")
    config = str(_config(tmp_path, "ppo"))
    base = ["--config", config, "--seeds", "2", "--quiet"]
    t0 = time.monotonic()
    code = main(
        [*base, "--out", str(tmp_path / "a"), "--backend", "ray", "--address", "127.0.0.1:9"]
    )
    assert code == 2 and time.monotonic() - t0 < 10
    assert "--address '127.0.0.1:9': no Ray cluster (GCS) answered" in capsys.readouterr().err
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "x").write_text("")
    assert main([*base, "--out", str(tmp_path / "b")]) == 2
    assert "is not empty; pass --resume" in capsys.readouterr().err
    assert main([*base, "--out", str(tmp_path / "c"), "--resume"]) == 2
    assert "holds no multi-seed run" in capsys.readouterr().err


def test_a_seed_folder_held_by_a_separate_train_is_refused_and_kept(tmp_path, capsys):
    """Was: `auv-gym train --out RUN/seed_0` and `train-seeds --out RUN` both wrote seed 0 (the
    seeds' run locks RUN only), and the worker's fresh start deleted the other run's files."""
    from dataclasses import asdict

    from auv_gym.support.files import output_lock
    from benchmarks.training.seed_workers import train_one_seed
    from benchmarks.training.train import TrainOptions

    seed_0 = tmp_path / "run" / "seed_0"
    with output_lock(seed_0):
        (seed_0 / "progress.csv").write_text("the other run's\n")
        code = main([*_args(tmp_path, "ppo", "run", "--seeds", "2"), "--workers", "1"])
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1
        assert f"--out '{seed_0}' is in use by another run (pid {os.getpid()})" in err
        assert not (tmp_path / "run" / "seed_1").exists()  # nothing started
        # The worker itself (a run started between the check and the spawn): refused, no file lost
        train_opts = asdict(TrainOptions(out=str(seed_0), config=str(_config(tmp_path, "ppo"))))
        with pytest.raises(OSError, match=rf"in use by another run \(pid {os.getpid()}\)"):
            train_one_seed(train_opts, "fresh")
        assert (seed_0 / "progress.csv").read_text() == "the other run's\n"


def _summary(out: Path) -> dict:
    return json.loads((out / "summary.json").read_text())


@pytest.mark.rl
@pytest.mark.parametrize(
    "algo",
    [
        "ppo",
        pytest.param("sac", marks=pytest.mark.integration),
        pytest.param("tqc", marks=pytest.mark.integration),
        pytest.param("crossq", marks=pytest.mark.integration),
    ],
)
def test_smoke_two_seeds_end_to_end(tmp_path, capsys, algo):
    """2 seeds, 256 env steps each, as two local processes: per-seed run directories, test
    evaluations and learning curves, the selection on validation, the exported agent."""
    outputs = ["--export", str(tmp_path / "agent"), "--results", str(tmp_path / "results")]
    args = _args(tmp_path, algo, "run", "--seeds", "2", "--workers", "2", *outputs)
    assert main(args) == 0
    summary = _summary(tmp_path / "run")
    assert [e["seed"] for e in summary["seeds"]] == [0, 1]
    for entry in summary["seeds"]:
        assert entry["num_timesteps"] == 256
        assert entry["validation_summary"]["n_episodes"] == 1  # the validation seed 100 only
        assert entry["test_summary"]["n_episodes"] == 10  # the test seeds 0-9
        seed = entry["seed"]
        curve = (tmp_path / "results" / f"seed_{seed}_learning_curve.csv").read_text()
        assert [line.split(",")[0] for line in curve.splitlines()] == ["num_timesteps", "0", "256"]
        test = json.loads((tmp_path / "results" / f"seed_{seed}_test_evaluation.json").read_text())
        assert test["seeds"] == list(range(10))
        seed_agent = json.loads(
            (tmp_path / "results" / f"agent_seed_{seed}" / "metadata.json").read_text()
        )
        assert seed_agent["seed"] == seed
        assert seed_agent["num_timesteps"] == entry["validation_num_timesteps"]  # its best
    scores = {e["seed"]: e["validation_score"] for e in summary["seeds"]}
    assert summary["selected_seed"] == min(scores, key=lambda s: (*scores[s], s))
    meta = json.loads((tmp_path / "agent" / "metadata.json").read_text())
    assert meta["seed"] == summary["selected_seed"] and meta["algo"] == algo
    from controllers.loader import load_policy

    assert load_policy(tmp_path / "agent").metadata["env_id"] == "AUVPath3DSpeedLimit-v0"
    # Everything finished: a resumed run trains nothing and reports the same seeds.
    assert main([*args[:-4], "--resume"]) == 0
    again = _summary(tmp_path / "run")
    assert again["seeds"] == summary["seeds"]


@pytest.mark.rl
def test_smoke_on_the_agent_observation(tmp_path):
    """One seed on AUVPath3DPreview-v0 with a custom preview (K = 3, Δs = 4 m): the agent records
    its 36-entry observation, loads, and acts on the env it was trained on."""
    import gymnasium as gym
    import numpy as np

    from benchmarks.catalog.policies import agent_run
    from controllers.loader import load_policy

    section = {
        **TINY["ppo"],
        "env_kwargs": {
            "randomize_start": True,
            "max_time": 20.0,
            "observation": {"points": 3, "spacing": 4.0},
        },
    }
    config = tmp_path / "preview.yml"
    config.write_text(yaml.safe_dump({"AUVPath3DPreview-v0": section}))
    args = _args(
        tmp_path,
        "ppo",
        "run",
        "--seeds",
        "0-0",
        "--workers",
        "1",
        "--export",
        str(tmp_path / "agent"),
    )
    args[args.index("--config") + 1] = str(config)
    assert main([*args, "--env-id", "AUVPath3DPreview-v0"]) == 0
    meta = json.loads((tmp_path / "agent" / "metadata.json").read_text())
    assert meta["observation"] == {"kind": "preview", "points": 3, "spacing": 4.0}
    assert meta["observation_shape"] == [36] and meta["obs_names"][-1] == "preview3_torsion"
    assert meta["eval_env_kwargs"]["observation"] == {"points": 3, "spacing": 4.0}
    held_out = json.loads((tmp_path / "agent" / "held_out_evaluation.json").read_text())
    assert held_out["summary"]["n_episodes"] == 10  # the test report ran on its observation
    _, env_id, agent_env = agent_run("agent", tmp_path / "agent")  # it carries its observation
    assert env_id == "AUVPath3DPreview-v0"
    assert agent_env == {"observation": {"kind": "preview", "points": 3, "spacing": 4.0}}
    policy = load_policy(tmp_path / "agent")
    env = gym.make("AUVPath3DPreview-v0", observation={"points": 3, "spacing": 4.0})
    obs, _ = env.reset(seed=0)
    action, _ = policy.predict(obs)
    assert action.shape == (3,) and np.all(np.abs(action) <= 1.0)


@pytest.mark.rl
def test_an_agent_trained_on_a_users_vehicle_is_validated_and_tested_on_it(tmp_path):
    """Was: the validation and the held-out test flew the REMUS 100 whatever vehicle the
    training env named, so `best/` was chosen on another vehicle."""
    from auv_gym.vehicle.record import VEHICLE_DIRECTORY
    from benchmarks.training.evaluation import evaluate_policy_on_seeds
    from controllers.loader import load_policy

    text = (VEHICLE_DIRECTORY / "remus100.toml").read_text()
    weak = tmp_path / "weak.toml"  # a fifth of the REMUS 100's yaw and pitch moments
    weak.write_text(
        text.replace('name = "remus100"', 'name = "weak"')
        .replace("M_max = 10.0", "M_max = 2.0")
        .replace("N_max = 10.0", "N_max = 2.0")
    )
    section = {**TINY["ppo"], "env_kwargs": {"randomize_start": True, "max_time": 20.0}}
    section["env_kwargs"]["vehicle"] = str(weak)
    config = tmp_path / "weak.yml"
    config.write_text(yaml.safe_dump({"AUVPath3DSpeedLimit-v0": section}))
    args = _args(tmp_path, "ppo", "run", "--seeds", "0-0", "--workers", "1")
    args[args.index("--config") + 1] = str(config)
    assert main([*args, "--export", str(tmp_path / "agent")]) == 0
    meta = json.loads((tmp_path / "agent" / "metadata.json").read_text())
    assert meta["eval_env_kwargs"]["vehicle"] == str(weak)
    held_out = json.loads((tmp_path / "agent" / "held_out_evaluation.json").read_text())
    assert held_out["scenario"].endswith(f", vehicle '{weak}')")
    policy = load_policy(tmp_path / "agent")
    duration = held_out["duration_s"]
    seeds = held_out["seeds"]  # the same batch: the network's sums are batch-size dependent
    own = evaluate_policy_on_seeds(policy, seeds, max_time=duration, vehicle=str(weak))
    remus = evaluate_policy_on_seeds(policy, seeds, max_time=duration)
    rms = [row["rms_distance"] for row in held_out["results"]]
    assert rms == [row["rms_distance"] for row in own]
    assert rms != [row["rms_distance"] for row in remus]


@pytest.mark.rl
def test_validation_on_a_task_set(tmp_path):
    """--task-set validation: the agent is selected on the validation set's env (its path
    distribution, current, noise, actuators) on its first --eval-episodes seeds, recorded in the
    plan and the agent's metadata; the per-seed test report stays the paper scenario."""
    from benchmarks.catalog.tasks import task_set

    validation = task_set("validation")
    args = _args(tmp_path, "ppo", "run", "--seeds", "0-0", "--workers", "1")
    args[args.index("--eval-seeds") : args.index("--eval-seeds") + 2] = []
    assert main([*args, "--task-set", "validation", "--eval-episodes", "3"]) == 0
    plan = json.loads((tmp_path / "run" / "train_seeds.json").read_text())
    assert plan["task_set"] == "validation" and plan["eval_env"] == validation.env
    assert plan["eval_seeds"] == [100_000, 100_001, 100_002]
    meta = json.loads((tmp_path / "run" / "seed_0" / "final" / "metadata.json").read_text())
    assert meta["eval_env_kwargs"]["path"] == validation.env["path"]
    assert meta["eval_env_kwargs"]["surge_limit"] == "vehicle"  # the id's: REMUS 100, 2.0 m/s
    entry = _summary(tmp_path / "run")["seeds"][0]
    assert entry["validation_summary"]["n_episodes"] == 3
    assert entry["test_summary"]["n_episodes"] == 10
    # Resuming with another validation set is refused: selection must not change mid-run.
    assert main([*args, "--task-set", "paper", "--eval-seeds", "100", "--resume"]) == 2


@pytest.mark.rl
def test_validation_on_both_plants(tmp_path):
    """A validation set on two plants (validation_as_built_start_plants): every validation seed
    flies once per plant, the score is the mean over both, and the learning curve and the
    summary carry each plant's figures."""
    from benchmarks.catalog.tasks import task_set

    as_built = {"actuator": "realistic", "sensors": "typical_kalman", "disturbance": "ocean"}
    section = {**TINY["ppo"], "env_kwargs": {**as_built, "randomize_start": True, "max_time": 20.0}}
    config = tmp_path / "as_built.yml"
    config.write_text(yaml.safe_dump({"AUVPath3DSpeedLimit-v0": section}))
    args = _args(tmp_path, "ppo", "run", "--seeds", "0-0", "--workers", "1")
    args[args.index("--eval-seeds") : args.index("--eval-seeds") + 2] = []
    args[args.index("--config") + 1] = str(config)
    both = ["--task-set", "validation_as_built_start_plants", "--eval-episodes", "1"]
    assert main([*args, *both]) == 0
    plan = json.loads((tmp_path / "run" / "train_seeds.json").read_text())
    assert plan["eval_env"]["plant"] == ["5dof", "6dof"]
    assert plan["eval_seeds"] == [task_set("validation_as_built_start_plants").seeds.start]
    entry = _summary(tmp_path / "run")["seeds"][0]
    validation = entry["validation_summary"]
    assert validation["n_episodes"] == 2 and set(validation["per_variant"]) == {"5dof", "6dof"}
    per_plant = [validation["per_variant"][p]["rms_distance_mean"] for p in ("5dof", "6dof")]
    assert all(np.isfinite(per_plant)) and per_plant[0] != per_plant[1]
    assert validation["rms_distance_mean"] == pytest.approx(np.mean(per_plant), rel=1e-12)
    curve = (tmp_path / "run" / "seed_0" / "evaluations.csv").read_text().splitlines()
    header = curve[0].split(",")
    assert header[-4:] == [
        "rms_distance_mean_5dof",
        "n_terminated_5dof",
        "rms_distance_mean_6dof",
        "n_terminated_6dof",
    ]
    assert [line.split(",")[0] for line in curve[1:]] == ["0", "256"]


@pytest.mark.integration
@pytest.mark.rl
def test_stop_at_pauses_on_the_full_schedule_and_resume_continues(tmp_path, capsys):
    """--stop-at pauses every seed with the schedules still running over --n-timesteps (the
    learning rate's progress is that of the full budget), and a --resume with a larger stop
    continues the same run to the new target."""
    from stable_baselines3 import PPO

    args = _args(tmp_path, "ppo", "run", "--seeds", "0-0", "--workers", "1", "--n-timesteps", "768")
    assert main([*args, "--stop-at", "384"]) == 0
    paused = _summary(tmp_path / "run")["seeds"][0]
    # SB3 collects whole rollouts of 4 × 64 steps: the pause comes at the first rollout start
    # at or after 384, with two rollouts trained, at the progress of 512 of 768 steps.
    assert paused["num_timesteps"] == 512
    final = tmp_path / "run" / "seed_0" / "final" / "model.zip"
    assert PPO.load(final, device="cpu")._current_progress_remaining == pytest.approx(1 / 3)
    assert main([*args, "--stop-at", "10"]) == 2  # not a multiple of n_envs = 4
    # a pause only moves forward: the seed is at 512 steps already
    capsys.readouterr()
    assert main([*args, "--stop-at", "256", "--resume"]) == 2
    err = capsys.readouterr().err
    assert "seed 0 has already trained 512 env steps, past the target 256" in err
    assert main([*args, "--resume"]) == 0
    done = _summary(tmp_path / "run")["seeds"][0]
    assert done["num_timesteps"] == 768
    assert PPO.load(final, device="cpu")._current_progress_remaining <= 0.0


@pytest.mark.rl
def test_sac_resume_restores_the_replay_buffer(tmp_path):
    from benchmarks.training.train import TrainOptions, train

    opts = TrainOptions(
        algo="sac",
        config=str(_config(tmp_path, "sac")),
        env_id="AUVPath3DSpeedLimit-v0",
        out=str(tmp_path / "run"),
        n_timesteps=128,
        checkpoint_freq=128,
        eval_freq=0,
        progress_bar=False,
    )
    train(opts)
    train(TrainOptions(**{**opts.__dict__, "n_timesteps": 256, "resume": True}))
    last = tmp_path / "run" / "checkpoints" / "step_0000000256" / "replay_buffer.pkl"
    with last.open("rb") as f:
        buffer = pickle.load(f)
    # Checkpoints are taken between SB3's collections, with every step stored: 128/4 = 32 rows
    # of 4 vehicles at step 128, 64 at step 256 (32 without the restored buffer).
    assert buffer.n_envs == 4 and buffer.size() == 64


@pytest.mark.integration
@pytest.mark.rl
def test_killed_run_resumes_every_unfinished_seed(tmp_path):
    """SIGKILL the command once both seeds have a checkpoint: no worker survives it, and
    --resume continues each seed from its newest checkpoint.

    The budget is far beyond what the seeds reach before the kill, so that neither can finish
    first however fast the machine (a CI run once saw a 2048-step seed end before the other's
    first checkpoint); the resume pauses a little past the newest checkpoint instead."""
    budget = 1_000_000
    args = _args(
        tmp_path, "ppo", "run", "--seeds", "2", "--workers", "2", "--n-timesteps", str(budget)
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    command = [sys.executable, "-m", "benchmarks.training.seeds_cli", *args]
    proc = subprocess.Popen(
        command, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    run = tmp_path / "run"
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline:
        if all(len(list((run / f"seed_{s}" / "checkpoints").glob("step_*"))) >= 1 for s in (0, 1)):
            break
        time.sleep(0.2)
    children = subprocess.run(["pgrep", "-P", str(proc.pid)], capture_output=True, text=True)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    time.sleep(2)
    for pid in children.stdout.split():
        assert not Path(f"/proc/{pid}").exists() or "zombie" in _state(pid), pid
    saved = {}
    for s in (0, 1):
        steps = [int(p.name[5:]) for p in (run / f"seed_{s}" / "checkpoints").glob("step_*")]
        saved[s] = max(steps)
        assert not (run / f"seed_{s}" / "final").exists()
    stop_at = max(saved.values()) + 256  # checkpoints come at multiples of 128 = 32 × n_envs
    assert main([*args, "--resume", "--stop-at", str(stop_at)]) == 0
    for entry in _summary(run)["seeds"]:
        meta = json.loads((run / f"seed_{entry['seed']}" / "final" / "metadata.json").read_text())
        # the pause target, completed to a whole rollout of 4 × 64 steps (as PPO does)
        assert stop_at <= meta["num_timesteps"] < stop_at + 256
        resumed = meta["sessions"][-1]["start_timesteps"]
        assert resumed >= saved[entry["seed"]]  # at most one checkpoint interval lost
        assert resumed > 0  # from the checkpoint, not from scratch


def _state(pid: str) -> str:
    try:
        return Path(f"/proc/{pid}/status").read_text().lower()
    except OSError:
        return "zombie"


@pytest.mark.integration
@pytest.mark.rl
def test_ray_backend_runs_the_same_seeds(tmp_path, monkeypatch):
    ray = pytest.importorskip("ray")
    monkeypatch.setenv("PYTHONPATH", str(ROOT))  # Ray workers import this checkout
    local = _args(tmp_path, "ppo", "local", "--seeds", "1", "--workers", "1")
    assert main(local) == 0
    ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False)
    try:
        assert main(_args(tmp_path, "ppo", "ray", "--seeds", "1", "--backend", "ray")) == 0
    finally:
        ray.shutdown()
    a, b = _summary(tmp_path / "local")["seeds"], _summary(tmp_path / "ray")["seeds"]
    assert [e["test_summary"] for e in a] == [e["test_summary"] for e in b]
    assert [e["validation_summary"] for e in a] == [e["validation_summary"] for e in b]


SHIPPED_CONFIGS = [  # file, algorithm, env id, gamma, precision weight
    ("ppo_helix.yml", "ppo", "AUVPath3D-v0", 0.995, None),
    ("ppo_helix.yml", "ppo", "AUVPath3DSpeedLimit-v0", 0.995, None),
    ("ppo_residual.yml", "ppo", "AUVPath3DSpeedLimit-v0", 0.98, None),
    ("sac_helix.yml", "sac", "AUVPath3DPreview-v0", 0.995, 3.0),
    ("ppo_generalist.yml", "ppo", "AUVPath3DPreview-v0", 0.995, 3.0),
    ("sac_generalist.yml", "sac", "AUVPath3DPreview-v0", 0.995, 3.0),
    ("ppo_as_built.yml", "ppo", "AUVPath3DPreview-v0", 0.995, 3.0),
]


@pytest.mark.rl
@pytest.mark.parametrize(("file", "algo", "env_id", "gamma", "precision"), SHIPPED_CONFIGS)
def test_shipped_configs_build_their_algorithm(file, algo, env_id, gamma, precision):
    """The YAML files parse and their hyper-parameters construct the SB3 model (on a small
    helix env: the task-distribution env_kwargs belong to the env), inside the action box the
    file sets."""
    from stable_baselines3.common.vec_env import VecNormalize

    from benchmarks.training.action_box import ActionBox
    from benchmarks.training.config import ALGORITHMS, read_zoo_config
    from benchmarks.training.train import make_training_env

    cfg = read_zoo_config(ROOT / "benchmarks" / "hyperparams" / file, env_id, algo)
    weights = {"distance": 3.0, "termination": 300.0, "tracking": 3.0}
    if precision is not None:
        weights["precision"] = precision
    assert cfg.env_kwargs["reward_weights"] == weights
    kwargs = cfg.model_kwargs()
    if algo == "sac":
        kwargs["buffer_size"] = 1000  # the real buffer allocates ~100 MB
    seen = {k: v for k, v in cfg.env_kwargs.items() if k == "observation"}  # the agent's
    venv = make_training_env(2, 0, {"max_time": 5.0, **seen}, env_id=env_id)
    if cfg.action_bounds is not None:
        venv = ActionBox(venv, *cfg.action_bounds)
    venv = VecNormalize(venv, **cfg.normalize)
    if cfg.obs_scales is not None:  # the names it pins exist in the id's observation
        from benchmarks.training.agent_interface import pin_scales
        from benchmarks.training.train import observation_layout_of

        pin_scales(venv, cfg, observation_layout_of(env_id, cfg.env_kwargs).names)
    model = ALGORITHMS[algo].sb3_class()(
        cfg.policy, venv, policy_kwargs=cfg.policy_kwargs, device="cpu", **kwargs
    )
    assert model.gamma == gamma
    assert model.observation_space.shape == venv.observation_space.shape
    if cfg.action_bounds is not None:
        np.testing.assert_array_equal(model.action_space.low, np.float32(cfg.action_bounds[0]))
        model.learn(64)  # acts inside the box (ActionBox refuses anything else)
    venv.close()


@pytest.mark.rl
def test_action_box_refuses_actions_outside_it_and_boxes_outside_the_env(tmp_path):
    from benchmarks.training.action_box import ActionBox
    from benchmarks.training.config import read_zoo_config
    from benchmarks.training.train import make_training_env

    venv = ActionBox(make_training_env(2, 0, {"max_time": 5.0}), (-0.3, -1, -1), (0.3, 1, 1))
    venv.reset()
    with pytest.raises(ValueError, match=r"vehicle 1\) is outside the agent's box"):
        venv.step(np.array([[0.1, 0.0, 0.0], [0.5, 0.0, 0.0]], np.float32))
    with pytest.raises(ValueError, match="is not inside the env's"):
        ActionBox(make_training_env(2, 0, {"max_time": 5.0}), (-2, -1, -1), (0.3, 1, 1))
    bad = tmp_path / "bad.yml"
    bad.write_text(
        yaml.safe_dump(
            {"AUVPath3D-v0": {**TINY["sac"], "action_bounds": [[0.5, 0, 0], [0.2, 1, 1]]}}
        )
    )
    with pytest.raises(ValueError, match="action_bounds must be"):
        read_zoo_config(bad, "AUVPath3D-v0", "sac")
