"""SAC fine-tuning kept near a jump start (`benchmarks.training.demo_regularization`,
`benchmarks.training.demo_sac`): with β = 0 the update is SB3's SAC update bit for bit; a huge β
holds the actor at the demonstrated actions within a stated bound; the actor delay freezes the
actor and the entropy coefficient; the expert's labels of a SAC jump start reach the next
phase, whose agent loads with controllers.make("agent", path=...) and flies; bad values of the
new keys are refused in one line before any training step."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import TINY_SAC_SECTION

pytest.importorskip("stable_baselines3")
pytestmark = pytest.mark.rl

ENV_ID = "AUVPath3DPreview-v0"
ENV_KWARGS = {"observation": "preview_integral", "randomize_start": True, "max_time": 4.0}
SECTION = {
    **TINY_SAC_SECTION,
    "n_timesteps": 128,
    "action_bounds": [[-0.3, -1.0, -1.0], [0.3, 1.0, 1.0]],
    "env_kwargs": ENV_KWARGS,
}
JUMP = {"expert": "fbsm_colos", "steps": 640, "iterations": 1, "epochs": 2}
# A huge BC weight (β = 1000) holds SAC's deterministic action at the demonstrated one: after 200
# updates (Adam, learning rate 3e-4) the largest change at the 1000 demonstration states, in the
# normalised action space [-1, 1], stays below HELD; measured 0.018 (seeds 1 and 2 of `_model`:
# 0.013, 0.033), against 0.14 with β = 0 (0.39, 0.20), above MOVED. TD3+BC's β = 0.4 gives
# 0.14 (0.27, 0.17): at that weight the critic still moves the actor.
HELD = 0.05
MOVED = 0.1


@pytest.fixture(autouse=True)
def _one_thread():
    """One torch thread, as training runs (`--threads 1`); restored after."""
    from benchmarks.training.envs import thread_limit

    with thread_limit(1):
        yield


def _write(path: Path, data: dict) -> Path:
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def _model(cls, seed: int = 0, **kwargs):
    """A small gSDE SAC (the shipped recipe's kind) on Pendulum with 1000 random transitions in
    its n-step buffer, identical for a given seed."""
    import gymnasium as gym
    from stable_baselines3.common.logger import configure

    model = cls(
        "MlpPolicy",
        gym.make("Pendulum-v1"),
        seed=seed,
        batch_size=64,
        buffer_size=2000,
        learning_starts=0,
        n_steps=3,
        use_sde=True,
        policy_kwargs={"net_arch": [32, 32]},
        device="cpu",
        **kwargs,
    )
    model.set_logger(configure(None, []))
    rng = np.random.default_rng(seed)
    for t in range(1000):
        obs = rng.normal(size=(1, 3)).astype(np.float32)
        following = obs + 0.1 * rng.normal(size=(1, 3)).astype(np.float32)
        action = rng.uniform(-1, 1, size=(1, 1)).astype(np.float32)
        done = np.array([t % 200 == 199])
        infos = [{"TimeLimit.truncated": bool(done[0])}]
        model.replay_buffer.add(obs, following, action, rng.normal(size=1), done, infos)
    return model


def _demonstrations(model) -> dict[str, np.ndarray]:
    """The buffer's states labelled with the actor's own deterministic action there (what a
    jump start leaves: its actor fitted on the labels)."""
    import torch

    obs = model.replay_buffer.observations[:1000, 0]
    with torch.no_grad():
        mean, _, _ = model.actor.get_action_dist_params(torch.as_tensor(obs))
    return {"observations": obs, "labels": torch.tanh(mean).numpy()}


def _deterministic(model, obs: np.ndarray) -> np.ndarray:
    import torch

    with torch.no_grad():
        mean, _, _ = model.actor.get_action_dist_params(torch.as_tensor(obs))
    return torch.tanh(mean).numpy()


def _update(model, steps: int) -> None:
    import torch

    np.random.seed(1)  # noqa: NPY002 - SB3 samples its batches from the global generator
    torch.manual_seed(1)
    model.train(gradient_steps=steps, batch_size=64)


def _weights(model) -> dict[str, np.ndarray]:
    state = {f"policy.{k}": v.numpy().copy() for k, v in model.policy.state_dict().items()}
    state["log_ent_coef"] = model.log_ent_coef.detach().numpy().copy()
    return state


def test_with_bc_weight_zero_the_update_is_sacs_bit_for_bit():
    from stable_baselines3 import SAC

    from benchmarks.training.demo_regularization import DemoRegularization
    from benchmarks.training.demo_sac import DemoSAC

    plain, demo = _model(SAC), _model(DemoSAC)
    demo.attach_demonstrations(DemoRegularization(bc_weight=0.0), _demonstrations(demo))
    before = _weights(plain)
    for name, value in _weights(demo).items():
        np.testing.assert_array_equal(value, before[name], err_msg=name)
    _update(plain, 20)
    _update(demo, 20)
    after = _weights(plain)
    assert any(not np.array_equal(after[k], before[k]) for k in after)  # SAC did learn
    for name, value in _weights(demo).items():
        np.testing.assert_array_equal(value, after[name], err_msg=name)
    for name in ("actor", "critic"):  # the optimisers' moments too
        mine = getattr(demo, name).optimizer.state_dict()["state"]
        theirs = getattr(plain, name).optimizer.state_dict()["state"]
        for k, moments in theirs.items():
            for key, value in moments.items():
                np.testing.assert_array_equal(mine[k][key].numpy(), value.numpy())
    assert "demonstrations" in DemoSAC("MlpPolicy", "Pendulum-v1")._excluded_save_params()


def test_a_huge_bc_weight_holds_the_actor_at_the_demonstrated_actions():
    from benchmarks.training.demo_regularization import DemoRegularization
    from benchmarks.training.demo_sac import DemoSAC

    changes = {}
    for weight in (1000.0, 0.0):
        model = _model(DemoSAC)
        demos = _demonstrations(model)
        model.attach_demonstrations(DemoRegularization(bc_weight=weight), demos)
        _update(model, 200)
        moved = _deterministic(model, demos["observations"]) - demos["labels"]
        changes[weight] = float(np.abs(moved).max())
        if weight:
            assert model.logger.name_to_value["train/bc_weight"] == weight
            assert np.isfinite(model.logger.name_to_value["train/bc_loss"])
    assert changes[1000.0] < HELD < MOVED < changes[0.0], changes


def test_the_actor_delay_freezes_the_actor_and_the_entropy_coefficient():
    from benchmarks.training.demo_regularization import DemoRegularization
    from benchmarks.training.demo_sac import DemoSAC

    model = _model(DemoSAC)
    settings = DemoRegularization(bc_weight=1.0, actor_delay=100, demo_share=0.5)
    model.attach_demonstrations(settings, {**_demonstrations(model), **_stream(model)})
    before = _weights(model)
    _update(model, 10)  # num_timesteps 0 < 100: the critic alone
    after = _weights(model)
    frozen = [k for k in before if k.startswith("policy.actor.") or k == "log_ent_coef"]
    assert frozen and all(np.array_equal(before[k], after[k]) for k in frozen)
    critic = [k for k in before if k.startswith("policy.critic.")]
    assert any(not np.array_equal(before[k], after[k]) for k in critic)
    model.num_timesteps = 100  # the delay is over: the actor learns, with the BC term
    _update(model, 10)
    last = _weights(model)
    assert any(not np.array_equal(after[k], last[k]) for k in frozen)
    assert "train/bc_loss" in model.logger.name_to_value


def _stream(model) -> dict[str, np.ndarray]:
    """The model's 1000 buffered transitions as a transitions stream (for demo_share)."""
    from benchmarks.training.transitions import buffer_stream

    return buffer_stream(model.replay_buffer)


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ({"bc_weight": -1}, "bc_weight must be a finite number >= 0, got -1"),
        ({"demo_share": 1.0}, "demo_share must be a number in [0, 1), got 1.0"),
        ({"bc_decay_steps": 0.5}, "bc_decay_steps must be an integer >= 0, got 0.5"),
        ({"actor_delay": -5}, "actor_delay must be an integer >= 0, got -5"),
        ({"bc_batch_size": 0}, "bc_batch_size must be an integer >= 1, got 0"),
        ({"bc_wieght": 1}, "unknown keys ['bc_wieght']"),
        ([0.4], "must be a mapping of"),
    ],
)
def test_bad_values_are_refused_in_one_line(tmp_path, capsys, value, message):
    from benchmarks.training.seeds_cli import main

    config = _write(tmp_path / "recipe.yml", {ENV_ID: {**SECTION, "demo_regularization": value}})
    argv = ["--algo", "sac", "--config", str(config), "--env-id", ENV_ID, "--seeds", "1"]
    with pytest.raises(SystemExit) as stop:
        raise SystemExit(main([*argv, "--out", str(tmp_path / "run")]))
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1, err
    assert f"{config}: {ENV_ID}: demo_regularization" in err and message in err, err
    assert not (tmp_path / "run" / "seed_0").exists()


def test_a_run_without_labelled_transitions_and_other_algorithms_are_refused(tmp_path, capsys):
    from benchmarks.training.seeds_cli import main

    def refused(argv: list[str]) -> str:
        with pytest.raises(SystemExit) as stop:
            raise SystemExit(main([*argv, "--env-id", ENV_ID, "--seeds", "1"]))
        err = capsys.readouterr().err
        assert stop.value.code == 2 and err.count("\n") == 1, err
        return err

    section = {**SECTION, "demo_regularization": {"bc_weight": 0.4}}
    config = _write(tmp_path / "recipe.yml", {ENV_ID: section})
    out = ["--out", str(tmp_path / "run")]
    err = refused(["--algo", "sac", "--config", str(config), *out])
    assert "demo_regularization needs the expert's labelled transitions" in err
    err = refused(["--algo", "tqc", "--config", str(config), *out])
    assert "adds a behaviour-cloning term to SAC's update (sac), not tqc's" in err
    schedule = {  # the key in a phase that follows no jump start
        "options": {"algo": "sac", "eval_freq": 128, "eval_duration": 110.0},
        "phases": [{"name": "base"}, {"name": "tuned", "demo_regularization": {}}],
    }
    config = _write(tmp_path / "schedule.yml", {ENV_ID: SECTION, "schedule": schedule})
    err = refused(["--config", str(config), *out])
    assert "phase 'tuned': demo_regularization needs the labelled transitions" in err
    assert not (tmp_path / "run" / "phase_1_base").exists()


@pytest.mark.integration
def test_the_labels_reach_the_next_phase_whose_agent_loads_and_flies(tmp_path):
    import controllers
    from auv_gym.rollout import rollout
    from benchmarks.training.seeds_cli import main
    from benchmarks.training.transitions import TRANSITIONS_FILE, read_transitions

    schedule = {
        "options": {"algo": "sac", "eval_freq": 128, "eval_duration": 110.0},
        "phases": [
            {"name": "jump_start", "jump_start": JUMP},
            {"name": "tuned", "demo_regularization": {"bc_weight": 1.0, "demo_share": 0.5}},
        ],
    }
    config = _write(tmp_path / "schedule.yml", {ENV_ID: SECTION, "schedule": schedule})
    out = tmp_path / "run"
    argv = ["--config", str(config), "--seeds", "1", "--eval-seeds", "100", "--quiet"]
    assert main([*argv, "--checkpoint-freq", "128", "--out", str(out)]) == 0
    jump_run = out / "phase_1_jump_start" / "seed_0"
    names = json.loads((jump_run / "final" / "metadata.json").read_text())["obs_names"]
    stream = read_transitions(jump_run / TRANSITIONS_FILE, names, 3, "test")
    assert len(stream["labels"]) == 640 and np.all(np.abs(stream["labels"]) <= 1.0)
    # Round 0 flew the expert: its actions are its labels; round 1 flew the learner half the time.
    # one vehicle's 160 steps after another, round 0 first
    actions, labels = (stream[k].reshape(4, 160, 3) for k in ("actions", "labels"))
    np.testing.assert_array_equal(actions[:, :80], labels[:, :80])
    assert not np.array_equal(actions[:, 80:], labels[:, 80:])
    # The tuned phase read them from the selected jump-start agent and hands them on.
    tuned = out / "phase_2_tuned" / "seed_0"
    meta = json.loads((tuned / "final" / "metadata.json").read_text())
    assert meta["demo_regularization"]["transitions"] == 640
    assert meta["demo_regularization"]["bc_weight"] == 1.0
    assert meta["warm_start"]["replay_buffer"]["transitions"] == 640
    copied = (jump_run / TRANSITIONS_FILE).read_bytes()
    assert (tuned / TRANSITIONS_FILE).read_bytes() == copied
    selected = out / "phase_2_tuned" / "selected" / "agent_seed_0"
    assert (selected / TRANSITIONS_FILE).read_bytes() == copied
    # A plain SAC agent: it loads as any SAC agent and flies.
    policy = controllers.make("agent", path=str(selected))
    trajectory = rollout(policy, 100, max_time=5.0)
    assert trajectory.steps == 100 and trajectory.termination_reason in ("", None, "time_limit")


def _tensors(folder: Path) -> dict[str, object]:
    """Every tensor of an agent's model.zip (policy, optimisers, entropy coefficient)."""
    import io
    import zipfile

    import torch

    found: dict[str, object] = {}
    with zipfile.ZipFile(folder / "model.zip") as archive:
        for name in archive.namelist():
            if name.endswith(".pth"):
                state = torch.load(io.BytesIO(archive.read(name)), map_location="cpu")
                stack = [(name, state)]
                while stack:
                    key, value = stack.pop()
                    if isinstance(value, dict):
                        stack += [(f"{key}/{k}", v) for k, v in value.items()]
                    elif isinstance(value, list | tuple):
                        stack += [(f"{key}/{k}", v) for k, v in enumerate(value)]
                    else:
                        found[key] = value
    return found


@pytest.mark.integration
# the resumed model rebuilds its n-step buffer itself: SB3 must not say n_steps is ignored
@pytest.mark.filterwarnings("error:`n_steps")
def test_a_paused_run_with_demonstrations_resumes_bit_for_bit(tmp_path):
    import shutil
    from dataclasses import replace

    import torch

    from benchmarks.training.train import TrainOptions, train
    from benchmarks.training.transitions import TRANSITIONS_FILE

    jump = _write(tmp_path / "jump.yml", {ENV_ID: {**SECTION, "jump_start": JUMP}})
    common = {"algo": "sac", "env_id": ENV_ID, "eval_freq": 0, "progress_bar": False}
    train(TrainOptions(config=str(jump), out=str(tmp_path / "jump"), **common))
    agent = tmp_path / "agent"
    shutil.copytree(tmp_path / "jump" / "final", agent)
    shutil.copy(tmp_path / "jump" / TRANSITIONS_FILE, agent / TRANSITIONS_FILE)
    settings = {"bc_weight": 1.0, "bc_decay_steps": 96, "demo_share": 0.5, "actor_delay": 32}
    section = {**SECTION, "demo_regularization": settings}
    tuned = _write(tmp_path / "tuned.yml", {ENV_ID: section})
    options = TrainOptions(
        config=str(tuned), init_from=str(agent), checkpoint_freq=64, **common, out=""
    )
    train(replace(options, out=str(tmp_path / "a")))  # never paused
    train(replace(options, out=str(tmp_path / "b"), stop_at=64))
    train(replace(options, out=str(tmp_path / "b"), resume=True))
    meta = json.loads((tmp_path / "b" / "metadata.json").read_text())
    assert meta["sessions"][1]["exact_resume"] and meta["num_timesteps"] == 128
    assert meta["demo_regularization"] == {**settings, "bc_batch_size": None, "transitions": 640}
    ours, theirs = _tensors(tmp_path / "a" / "final"), _tensors(tmp_path / "b" / "final")
    assert ours.keys() == theirs.keys()
    for key, value in ours.items():
        same = torch.equal(value, theirs[key]) if torch.is_tensor(value) else value == theirs[key]
        assert same, key
