"""Jump start from the classical controllers: demonstrations as a Minari dataset (`auv-gym
demos`, `benchmarks.training.demonstrations`), the expert's commands in the agent's action
space (`benchmarks.training.expert`), behaviour cloning and DAgger (`benchmarks.training.dagger`)
as a schedule phase (`benchmarks.training.jump_start`). A tiny dataset round-trips value by
value; cloning it brings the imitation loss below a stated bound; a jump-start phase and a PPO
phase run end to end and the agent flies; bad datasets and jump starts are refused in one line
before any training step."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("minari")
pytestmark = pytest.mark.rl

ENV_ID = "AUVPath3DPreview-v0"
ENV_KWARGS = {"observation": "preview_integral", "randomize_start": True, "max_time": 4.0}
SECTION = {
    "n_envs": 4,
    "n_timesteps": 256,
    "policy": "MlpPolicy",
    "normalize": True,
    "n_steps": 64,
    "batch_size": 128,
    "n_epochs": 1,
    "learning_rate": "lin_3e-4",
    "gamma": 0.99,
    "policy_kwargs": "dict(net_arch=[64, 64], log_std_init=-1.0)",
    "env_kwargs": ENV_KWARGS,
}
# Behaviour cloning of the tiny dataset must bring the imitation loss (mean squared error of the
# actor's mean action, per entry of the normalised action) below this.
BC_BOUND = 0.01


def _recipe(tmp_path: Path, section: dict | None = None, name: str = "recipe.yml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump({ENV_ID: section or SECTION}, sort_keys=False))
    return path


def _demos(tmp_path: Path, *extra: str, recipe: Path | None = None, out: str = "demos") -> Path:
    from benchmarks.training.demos_cli import main

    folder = tmp_path / out
    argv = ["--config", str(recipe or _recipe(tmp_path)), "--out", str(folder), "--quiet"]
    assert (
        main(["--policy", "fbsm_colos", "--episodes", "3", "--vehicles", "2", *argv, *extra]) == 0
    )
    return folder


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    return _demos(tmp_path_factory.mktemp("demos"))


def test_a_tiny_dataset_round_trips_value_by_value(dataset):
    """What was recorded is what is read back: each episode replayed in a single env from its
    seed with the loaded actions gives the loaded observations and rewards bit for bit, and the
    expert flown alongside labels the loaded observations with the loaded actions."""
    import minari

    from auv_gym import VARIANTS
    from auv_gym.envs.env import AUVPath3DEnv
    from benchmarks.training.demonstrations import DemoSource, demo_seed, read_dataset
    from benchmarks.training.expert import ExpertLabels

    source = DemoSource(ENV_ID, ENV_KWARGS)
    demos = read_dataset(dataset, source.obs_names, source.interface)
    assert sorted(e["seed"] for e in demos.episodes) == [demo_seed(0, k) for k in range(3)]
    assert demos.steps == 3 * 80 and demos.meta["policy"] == "fbsm_colos"
    kwargs = {**VARIANTS[ENV_ID], **ENV_KWARGS}
    for episode in demos.episodes:
        env = AUVPath3DEnv(**kwargs)
        obs, _ = env.reset(seed=episode["seed"])
        expert = ExpertLabels("fbsm_colos", kwargs, source.obs_names)
        observed, rewards, ends = [obs], [], []
        for t, action in enumerate(episode["actions"]):
            label = expert.label(observed[-1][None], np.array([t == 0]))[0]
            np.testing.assert_array_equal(label, action)
            obs, reward, terminated, truncated, _ = env.step(action)
            observed.append(obs)
            rewards.append(reward)
            ends.append((terminated, truncated))
        np.testing.assert_array_equal(np.array(observed), episode["observations"])
        np.testing.assert_array_equal(np.array(rewards), episode["rewards"])
        assert ends[-1] == (episode["terminations"][-1], episode["truncations"][-1])
    # Minari reads it as a dataset of its own, and rebuilds the env it was recorded on.
    data = minari.MinariDataset(dataset / "data")
    assert data.total_episodes == 3 and data.total_steps == demos.steps
    assert data.id == "auv_gym/recipe-fbsm_colos-v0"
    assert data.recover_environment().observation_space.shape == (len(source.obs_names),)


def test_the_expert_on_fins_labels_in_the_paper_units_the_allocation_maps_back():
    """An agent trained inside the actuator allocation onto fins commands the paper's τ: its
    label passed through the allocation gives the fin command the expert gave (saturated
    commands included)."""
    from auv_gym import VARIANTS
    from auv_gym.envs.env import AUVPath3DEnv
    from benchmarks.training.expert import ExpertLabels
    from controllers.stages import apply_stages, check_stage_specs

    kwargs = {**VARIANTS[ENV_ID], **ENV_KWARGS, "actuator": "fins", "max_time": 20.0}
    env = AUVPath3DEnv(**kwargs)
    names = env.unwrapped.config.observation.names
    specs = check_stage_specs(["actuator_allocation"], "test")
    agent = ExpertLabels("fbsm_colos", kwargs, names, specs)
    alone = ExpertLabels("fbsm_colos", kwargs, names)
    obs, _ = env.reset(seed=3)
    checked = 0
    for t in range(200):
        label = agent.label(obs[None], np.array([t == 0]))
        command = alone.label(obs[None], np.array([t == 0]))
        memories = [stage.start(1) for stage in agent.stages]
        flown = apply_stages(agent.stages, label, obs[None], memories)
        if obs[names.index("u")] > 0.1:  # where the fins have authority (saturated or not)
            np.testing.assert_allclose(flown, command, atol=1e-5)
            checked += 1
        obs, *_ = env.step(command[0])
    assert checked > 100


def test_the_expert_labels_the_errors_the_vehicle_has_behind_observation_factors():
    """Inside an allocation with observation factors the agent sees its errors scaled; the
    expert labels the state the vehicle is in: on the scaled view, the labels it gives on the
    unscaled observation (within float32 rounding of the scaled errors)."""
    from auv_gym import VARIANTS
    from auv_gym.envs.env import AUVPath3DEnv
    from benchmarks.training.expert import ExpertLabels
    from controllers.stages import check_stage_specs, observe_stages

    kwargs = {**VARIANTS[ENV_ID], **ENV_KWARGS, "actuator": "fins", "max_time": 20.0}
    env = AUVPath3DEnv(**kwargs)
    names = env.unwrapped.config.observation.names
    factors = {"x_e": 0.125, "y_e": 0.25, "z_e": 0.25}
    spec = {"name": "actuator_allocation", "observation_factors": factors}
    factored = ExpertLabels("fbsm_colos", kwargs, names, check_stage_specs([spec], "test"))
    plain = ExpertLabels(
        "fbsm_colos", kwargs, names, check_stage_specs(["actuator_allocation"], "test")
    )
    memories = [stage.start(1) for stage in factored.stages]
    obs, _ = env.reset(seed=3)
    largest = 0.0
    for t in range(100):
        seen = observe_stages(factored.stages, obs[None], memories)
        errors = [names.index(n) for n in factors]
        assert not np.allclose(seen[0, errors], obs[errors])  # the agent's view is scaled
        label = factored.label(seen, np.array([t == 0]))
        expected = plain.label(
            observe_stages(plain.stages, obs[None], memories), np.array([t == 0])
        )
        np.testing.assert_allclose(label, expected, atol=1e-4)
        largest = max(largest, float(np.abs(obs[errors]).max()))
        obs, *_ = env.step(expected[0])
    assert largest > 0.05  # errors worth scaling [m]


def test_behaviour_cloning_brings_the_imitation_loss_below_its_bound(tmp_path, dataset):
    from benchmarks.training.train import TrainOptions, train
    from controllers.agent import METADATA_FILE

    jump = {"dataset": str(dataset), "epochs": 300, "batch_size": 64, "learning_rate": 0.003}
    section = {**SECTION, "jump_start": jump}
    out = train(
        TrainOptions(
            config=str(_recipe(tmp_path, section)),
            env_id=ENV_ID,
            out=str(tmp_path / "run"),
            eval_freq=0,
            progress_bar=False,
        )
    )
    meta = json.loads((out / "final" / METADATA_FILE).read_text())
    (round0,) = meta["jump_start"]["rounds"]
    assert round0["samples"] == 240 and round0["env_steps"] == 0
    assert round0["imitation_mse"] < BC_BOUND < round0["imitation_mse_before"]
    assert meta["num_timesteps"] == 240 and meta["jump_start"]["dataset_steps"] == 240
    assert np.isfinite(round0["value_mse"])


@pytest.mark.integration
def test_a_jump_start_phase_and_a_ppo_phase_run_end_to_end_and_the_agent_flies(tmp_path):
    import controllers
    from auv_gym.rollout import rollout
    from benchmarks.training.seeds_cli import main

    schedule = {
        "options": {"eval_freq": 128, "eval_duration": 110.0},
        "stages": ["envelope_guard"],
        "phases": [
            {
                "name": "jump_start",
                "jump_start": {"expert": "fbsm_colos", "steps": 640, "iterations": 1},
            },
            {"name": "base"},
        ],
    }
    config = tmp_path / "schedule.yml"
    config.write_text(yaml.safe_dump({ENV_ID: SECTION, "schedule": schedule}, sort_keys=False))
    out, agent = tmp_path / "run", tmp_path / "agent"
    argv = ["--config", str(config), "--seeds", "1", "--eval-seeds", "100", "--quiet"]
    assert main([*argv, "--checkpoint-freq", "128", "--out", str(out), "--export", str(agent)]) == 0
    first = json.loads(
        (out / "phase_1_jump_start" / "seed_0" / "final" / "metadata.json").read_text()
    )
    rounds = first["jump_start"]["rounds"]
    assert [r["env_steps"] for r in rounds] == [320, 320] and first["num_timesteps"] == 640
    assert rounds[1]["expert_share"] == 0.5 and rounds[1]["samples"] == 640
    second = json.loads((out / "phase_2_base" / "seed_0" / "final" / "metadata.json").read_text())
    assert second["warm_start"]["init_from"].endswith("phase_1_jump_start/selected/agent_seed_0")
    assert "jump_start" not in second and second["num_timesteps"] == 256
    policy = controllers.make("agent", path=str(agent))
    trajectory = rollout(policy, 100, max_time=5.0)
    assert trajectory.steps == 100 and trajectory.termination_reason in ("", None, "time_limit")


def _refused(tmp_path, capsys, jump_start, section: dict | None = None) -> str:
    from benchmarks.training.seeds_cli import main

    schedule = {
        "options": {"eval_freq": 128, "eval_duration": 110.0},
        "phases": [{"name": "jump_start", "jump_start": jump_start}, {"name": "base"}],
    }
    config = tmp_path / "schedule.yml"
    config.write_text(
        yaml.safe_dump({ENV_ID: section or SECTION, "schedule": schedule}, sort_keys=False)
    )
    out = tmp_path / "run"
    with pytest.raises(SystemExit) as stop:
        raise SystemExit(main(["--config", str(config), "--seeds", "1", "--out", str(out)]))
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1, err
    assert not (out / "phase_1_jump_start").exists()  # no training step
    return err


def test_a_jump_start_without_an_expert_or_a_dataset_is_refused(tmp_path, capsys):
    err = _refused(tmp_path, capsys, {"epochs": 3})
    assert "jump_start: needs an expert" in err and "or a dataset" in err
    err = _refused(tmp_path, capsys, {"dataset": str(tmp_path / "none")})
    assert f"dataset {str(tmp_path / 'none')!r} does not exist" in err
    (tmp_path / "empty").mkdir()
    err = _refused(tmp_path, capsys, {"dataset": str(tmp_path / "empty")})
    assert "no data/metadata.json" in err and str(tmp_path / "empty") in err
    err = _refused(tmp_path, capsys, {"expert": "ppo", "steps": 64})
    assert "expert 'ppo' is not a classical controller" in err


def test_datasets_of_another_observation_or_actuator_are_refused(tmp_path, capsys):
    other_obs = _recipe(
        tmp_path, {**SECTION, "env_kwargs": {**ENV_KWARGS, "observation": "preview"}}, "obs.yml"
    )
    folder = _demos(tmp_path, recipe=other_obs, out="preview_demos")
    err = _refused(tmp_path, capsys, {"dataset": str(folder)})
    assert f"{folder / 'data' / 'metadata.json'}: its observation" in err
    assert "only in the agent's ['x_e_integral', 'y_e_integral', 'z_e_integral']" in err
    other_act = _recipe(
        tmp_path, {**SECTION, "env_kwargs": {**ENV_KWARGS, "actuator": "fins"}}, "fins.yml"
    )
    folder = _demos(tmp_path, recipe=other_act, out="fins_demos")
    err = _refused(tmp_path, capsys, {"dataset": str(folder)})
    assert "its actions are 'fins' commands" in err and "the agent's are 'paper' commands" in err


def test_a_damaged_dataset_is_refused(tmp_path, capsys, dataset):
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(dataset, copy)
    data = copy / "data" / "main_data.hdf5"
    raw = bytearray(data.read_bytes())
    raw[len(raw) // 2] ^= 0xFF
    data.write_bytes(bytes(raw))
    err = _refused(tmp_path, capsys, {"dataset": str(copy)})
    assert f"{data}: damaged or changed since it was recorded" in err
    data.write_bytes(bytes(raw[: len(raw) // 3]))
    assert "damaged" in _refused(tmp_path, capsys, {"dataset": str(copy)})
    # a truncated copy whose recorded hash was rewritten to match: refused before any training
    # step too, as the HDF5 file it no longer is (was: in the worker, after the run began)
    meta_file = copy / "data" / "metadata.json"
    meta = json.loads(meta_file.read_text())
    meta["auv_gym"]["data_sha256"] = hashlib.sha256(data.read_bytes()).hexdigest()
    meta_file.write_text(json.dumps(meta))
    assert f"{data}: cannot be read as HDF5 (" in _refused(tmp_path, capsys, {"dataset": str(copy)})
    (copy / "data" / "metadata.json").write_text('{"dataset_id": ')
    err = _refused(tmp_path, capsys, {"dataset": str(copy)})
    assert f"{copy / 'data' / 'metadata.json'}: unreadable" in err


def test_demos_removes_a_killed_runs_temporaries_and_refuses_a_live_ones(tmp_path, dead_pid):
    """Was: a killed run's `.OUT.tmp<pid>` (up to the whole dataset) stayed, one per run, and a
    second run on the same --out ran to a crash at its end."""
    import subprocess
    import sys

    from benchmarks.training.demonstrations import _claim_temporaries

    out = tmp_path / "demos"
    stale = tmp_path / f".demos.tmp{dead_pid}"
    (stale / "data").mkdir(parents=True)
    other = tmp_path / ".other.tmp1"  # another --out's: not ours to touch
    other.mkdir()
    _claim_temporaries(out)
    assert not stale.exists() and other.exists()
    live = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        (tmp_path / f".demos.tmp{live.pid}").mkdir()
        with pytest.raises(
            ValueError, match=rf"is being written by another run \(process {live.pid}"
        ):
            _claim_temporaries(out)
    finally:
        live.kill()
        live.wait()


def test_demos_refuses_bad_arguments_in_one_line(tmp_path, capsys):
    from benchmarks.training.demos_cli import main

    recipe = str(_recipe(tmp_path))
    for argv, message in (
        (["--policy", "agent", "--config", recipe], "expert 'agent' is not a classical"),
        (["--task", "validation"], "demonstrations are training data"),
        (["--config", recipe, "--task", "train"], "give one of --config"),
        (["--config", recipe, "--episodes", "0"], "--episodes must be"),
        (["--config", recipe, "--phase", "x"], "has no schedule"),
        (["--config", str(tmp_path)], f"--config {str(tmp_path)!r} is a folder, not a hyper"),
        (["--config", str(tmp_path / "no.yml")], "no.yml' does not exist"),
        (
            ["--task", "train", "--observation", "nosuch"],
            "--observation: unknown observation 'nosuch'; valid: ['paper', 'preview', 'preview_i",
        ),
    ):
        with pytest.raises(SystemExit) as stop:
            main([*argv, "--out", str(tmp_path / "demos")])
        err = capsys.readouterr().err
        assert stop.value.code == 2 and err.count("\n") == 1 and message in err, err
    assert not (tmp_path / "demos").exists()


def test_an_agent_inside_the_allocation_onto_propeller_and_fins_has_no_expert_labels():
    from auv_gym import VARIANTS
    from auv_gym.sim.observation import ObservationConfig
    from benchmarks.training.expert import ExpertLabels
    from controllers.stages import check_stage_specs

    kwargs = {**VARIANTS[ENV_ID], **ENV_KWARGS, "actuator": "realistic"}
    names = ObservationConfig.from_spec("preview_integral").names
    specs = check_stage_specs(["actuator_allocation"], "test")
    with pytest.raises(ValueError, match="allocation onto the 'realistic' actuator"):
        ExpertLabels("pid_as_built", kwargs, names, specs, where="recipe.yml")
    drawn = {**kwargs, "actuator": "random"}  # each episode's actuator drawn: no one label
    with pytest.raises(ValueError, match=r"recipe.yml: .* drawn per episode \(actuator='random'\)"):
        ExpertLabels("fbsm_colos", drawn, names, specs, where="recipe.yml")
    box = ExpertLabels("pid_as_built", kwargs, names, (), ([-0.5, -1, -1], [0.5, 1, 1]))
    clipped = box.to_agent(np.array([[0.9, -1.0, 0.2]]), np.zeros((1, len(names))))
    np.testing.assert_array_equal(clipped, np.array([[0.5, -1.0, 0.2]], np.float32))


def test_the_progress_bar_of_a_jump_start_counts_the_steps_it_flies_and_reads(tmp_path, dataset):
    from benchmarks.training.config import read_zoo_config
    from benchmarks.training.demonstrations import read_metadata
    from benchmarks.training.seeds import progress_steps

    def steps_of(jump_start: dict | None) -> int:
        section = SECTION if jump_start is None else {**SECTION, "jump_start": jump_start}
        cfg = read_zoo_config(_recipe(tmp_path, section, "progress.yml"), ENV_ID, "ppo")
        return progress_steps(cfg, SECTION["n_timesteps"])

    recorded = sum(e["steps"] for e in read_metadata(dataset)["episodes"])
    assert recorded > 0
    assert steps_of(None) == 256  # PPO: its n_timesteps
    flown = {"expert": "fbsm_colos", "steps": 640, "iterations": 1}
    assert steps_of(flown) == 640  # two rounds of 320, not the section's 256
    assert steps_of({"dataset": str(dataset)}) == recorded
    assert steps_of({**flown, "dataset": str(dataset)}) == recorded + 640  # round 0 is the data


@pytest.mark.parametrize("option", [["--stop-at", "320"], ["--resume"]])
def test_a_jump_start_paused_or_resumed_is_refused_before_anything_is_built(
    tmp_path, capsys, option
):
    """Was: refused only after the env, the model and the warm start were built, as a traceback."""
    from benchmarks.training.train_cli import main

    section = {**SECTION, "jump_start": {"expert": "fbsm_colos", "steps": 640, "iterations": 1}}
    out = tmp_path / "run"
    argv = ["--env-id", ENV_ID, "--config", str(_recipe(tmp_path, section)), "--out", str(out)]
    with pytest.raises(SystemExit) as stop:
        main([*argv, *option])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1, err
    assert "a jump start runs whole, in one go (no --resume, no --stop-at)" in err
    assert not out.exists()
