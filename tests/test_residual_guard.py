"""A residual agent's envelope guard (`controllers.residual`, ``envelope_guard``): the applied
action (base + correction) kept inside the vehicle's pitch and surge limits, the same at
inference, in the training wrapper and in the ONNX export; recorded only when there is one."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml

from auv_gym import VARIANTS
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.rollout import evaluate, rollouts
from auv_gym.sim.observation import OBS_INDEX
from benchmarks.training.residual import ResidualTraining
from benchmarks.training.residual_env import ResidualVectorEnv
from controllers.envelope_guard import ENV_GUARD_INDEX, EnvelopeGuard, guard_commands
from controllers.residual import (
    ResidualPolicy,
    ResidualSettings,
    make_residual,
    residual_action,
)

ROOT = Path(__file__).resolve().parent.parent
# Episodes end at 2.0 m/s (`surge_limit`): where a residual that adds thrust fails.
SPEED_LIMITED = {**VARIANTS["AUVPath3DSpeedLimit-v0"], "disturbance": "paper", "max_time": 10.0}


class FullAhead:
    """An agent whose correction is full ahead on X and nothing on M, N."""

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        return np.tile(np.float32([1.0, 0.0, 0.0]), (observation.shape[0], 1)), state


class Zero:
    """An agent that corrects nothing."""

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        return np.zeros((observation.shape[0], 3), np.float32), state


def test_settings_record_the_guard_only_when_there_is_one():
    plain = ResidualSettings(base="pid_los")
    assert "envelope_guard" not in plain.to_dict()
    assert "envelope_guard" not in ResidualTraining().to_dict()  # the shipped agents' record
    assert "bound_below" not in ResidualTraining().to_dict()  # symmetric: recorded as before
    guarded = ResidualSettings.from_dict({"base": "pid_los", "envelope_guard": True})
    assert guarded.envelope_guard == EnvelopeGuard()
    record = ResidualTraining.from_dict(
        {"envelope_guard": {"surge_soft": 1.7, "nose_up_command": -1.0}}
    ).to_dict()
    assert record["envelope_guard"]["surge_soft"] == 1.7
    assert record["envelope_guard"]["nose_up_command"] == -1.0
    again = ResidualSettings.from_dict(record, strict=False)
    assert again.envelope_guard == EnvelopeGuard(surge_soft=1.7, nose_up_command=-1.0)
    assert again.inference().envelope_guard == again.envelope_guard
    assert ResidualSettings.from_dict({"envelope_guard": False}).envelope_guard is None


@pytest.mark.parametrize(
    ("guard", "message"),
    [
        ({"surge_sof": 1.7}, r"residual: envelope_guard has unknown keys \['surge_sof'\]"),
        ({"surge_soft": 2.0, "surge_hard": 1.9}, "each soft limit must lie below its hard"),
        ("yes", "envelope_guard must be true or a mapping"),
    ],
)
def test_bad_guard_settings_are_named(guard, message):
    with pytest.raises(ValueError, match=message):
        ResidualTraining.from_dict({"envelope_guard": guard}, "file.yml: residual")


def test_a_residual_file_with_stages_points_to_the_residual_guard(tmp_path):
    from benchmarks.training.config import read_zoo_config

    section = {
        "n_envs": 4,
        "n_timesteps": 64,
        "policy": "MlpPolicy",
        "normalize": True,
        "residual": {"base": "pid_los"},
        "stages": [{"name": "envelope_guard"}],
    }
    path = tmp_path / "guarded.yml"
    path.write_text(yaml.safe_dump({"AUVPath3D-v0": section}))
    with pytest.raises(ValueError, match=r"residual: \{envelope_guard: \.\.\.\}"):
        read_zoo_config(path)
    del section["stages"]
    section["envelope_guard"] = True
    path.write_text(yaml.safe_dump({"AUVPath3D-v0": section}))
    with pytest.raises(ValueError, match=r"envelope_guard is now a residual setting"):
        read_zoo_config(path)


def test_the_guard_keeps_a_thrusting_residual_below_the_surge_limit():
    unguarded = make_residual(FullAhead(), base="pid_los", bound=(2.0, 0.5, 0.5))
    guarded = make_residual(FullAhead(), base="pid_los", bound=(2.0, 0.5, 0.5), envelope_guard=True)
    for episode in evaluate(unguarded, [0, 1], transient=0.0, **SPEED_LIMITED):
        assert episode["termination_reason"] == "overspeed" and episode["duration"] < 2.0
    for episode in evaluate(guarded, [0, 1], transient=0.0, **SPEED_LIMITED):
        assert episode["termination_reason"] == "time_limit" and episode["duration"] == 10.0
        assert 1.85 < episode["max_surge"] < EnvelopeGuard().surge_hard


def test_inside_the_envelope_the_guard_is_the_identity(assert_same_episodes):
    # 2.5 s of the paper's climb: the pitch predicted 1 s ahead stays below 35° (28° and 32°;
    # it passes 35° before 4 s)
    env = {"disturbance": "paper", "max_time": 2.5}
    plain = make_residual(Zero(), base="fbsm_colos")
    guarded = make_residual(Zero(), base="fbsm_colos", envelope_guard=True)
    episodes = rollouts(guarded, [0, 1], **env)
    assert_same_episodes(episodes, rollouts(plain, [0, 1], **env))
    guard = EnvelopeGuard()
    for t in episodes:
        predicted = np.degrees(t.samples["theta"] + guard.lookahead_s * t.samples["q"])
        assert 25.0 < np.max(predicted) < guard.pitch_soft_deg
        assert np.max(t.samples["u"]) < guard.surge_soft
    # a second longer, and the guard takes the nose-up moment away (M: 10 → 6.3 N·m, seed 0)
    longer = {**env, "max_time": 4.0}
    a, b = (rollouts(p, [0], **longer)[0] for p in (plain, guarded))
    assert b.intervals["M"][-1] < 0.7 * a.intervals["M"][-1]


def test_the_policy_guards_the_action_and_remembers_the_guarded_one():
    guard = EnvelopeGuard(surge_soft=1.0, surge_hard=1.5)
    settings = ResidualSettings(base="pid_los", bound=(2.0, 0.5, 0.5), envelope_guard=guard)
    policy = ResidualPolicy(settings.make_base(), FullAhead(), settings.bound, settings)
    obs = np.zeros((3, 15), np.float32)
    obs[:, OBS_INDEX["u"]] = (0.5, 1.25, 1.6)  # below, on and above the ramp [m/s]
    action, state = policy.predict(obs, episode_start=np.ones(3, bool))
    np.testing.assert_array_equal(action[:, 0], np.float32([1.0, 0.0, -1.0]))
    np.testing.assert_array_equal(state["previous"], action)  # a_{k−1}: what the env got


def test_the_training_wrapper_applies_the_guard_as_the_policy_does():
    settings = ResidualTraining(base="pid_los", bound=(2.0, 0.5, 0.5), envelope_guard=True)
    env = ResidualVectorEnv(AUVPath3DVectorEnv(3, **SPEED_LIMITED), settings)
    obs, _ = env.reset(seed=5)
    full = np.tile(np.float32([1.0, 0.0, 0.0]), (3, 1))
    speeds = []
    for _ in range(120):  # 6 s: unguarded, every vehicle passes 2 m/s in under 2 s
        want = residual_action(obs[:, 15:18], full, settings.bound)
        want = guard_commands(want, obs[:, :15], ENV_GUARD_INDEX, settings.envelope_guard)
        obs, _, terminated, truncated, _ = env.step(full)
        assert not (terminated | truncated).any()
        np.testing.assert_array_equal(obs[:, 18:21], want)  # a_{k−1} is the guarded action
        speeds.append(obs[:, OBS_INDEX["u"]])
    assert 1.85 < np.max(speeds) < settings.envelope_guard.surge_hard


@pytest.mark.rl
def test_a_guarded_residual_agent_saves_loads_and_exports_with_its_guard(
    tmp_path, save_tiny_residual_agent
):
    from controllers.loader import load_policy
    from controllers.onnx_export import export_onnx
    from controllers.onnx_policy import OnnxPolicy

    guard = EnvelopeGuard(surge_soft=1.0, surge_hard=1.4, pitch_soft_deg=5.0, pitch_hard_deg=10.0)
    settings = ResidualTraining(base="pid_los", bound=(0.5, 0.5, 0.5), envelope_guard=guard)
    save_tiny_residual_agent(settings, tmp_path / "agent", 3, {"max_time": 2.0})
    meta = json.loads((tmp_path / "agent" / "metadata.json").read_text())
    assert meta["residual"]["envelope_guard"]["surge_soft"] == 1.0
    loaded = load_policy(tmp_path / "agent")
    assert isinstance(loaded, ResidualPolicy) and loaded.guard == guard
    onnx_file, contract_file, parity = export_onnx(tmp_path / "agent", tmp_path / "g.onnx")
    assert parity["max_abs_error"] <= 1e-5
    assert json.loads(contract_file.read_text())["residual"]["envelope_guard"]["surge_hard"] == 1.4
    exported = OnnxPolicy(onnx_file)
    rng = np.random.default_rng(1)
    obs = rng.normal(0.0, 0.2, (64, 15)).astype(np.float32)
    obs[:, OBS_INDEX["u"]] = np.linspace(0.6, 1.8, 64)  # across the surge ramp [m/s]
    obs[:, OBS_INDEX["theta"]] = np.linspace(-0.3, 0.3, 64)  # across both pitch ramps [rad]
    start = np.ones(64, bool)
    want, _ = loaded.predict(obs, episode_start=start)
    got, _ = exported.predict(obs, episode_start=start)
    np.testing.assert_allclose(got, want, atol=1e-5)
    assert (want[obs[:, OBS_INDEX["u"]] > 1.4, 0] == -1.0).all()  # the guard acts on them
    # the agent without its guard commands otherwise on those rows
    bare = tmp_path / "bare"
    shutil.copytree(tmp_path / "agent", bare)
    del meta["residual"]["envelope_guard"]
    (bare / "metadata.json").write_text(json.dumps(meta))
    unguarded, _ = load_policy(bare).predict(obs, episode_start=start)
    assert np.abs(unguarded - want).max() > 0.1


def test_a_guard_of_the_wrong_pitch_sign_for_the_actuator_is_refused():
    """On the realistic actuator M is the stern-plane angle (positive nose-down): the guard's
    default sign would push the pitch further out there, so it is refused, naming the fix."""
    settings = ResidualSettings(base="pid_as_built", envelope_guard=True)
    with pytest.raises(ValueError, match=r"residual: on the realistic actuator .* -1, got 1"):
        settings.make_base(actuator="realistic")
    with pytest.raises(ValueError, match=r"on the realistic actuator"):
        ResidualVectorEnv(
            AUVPath3DVectorEnv(2, actuator="realistic", max_time=1.0),
            ResidualTraining(base="pid_as_built", envelope_guard=True),
        )
    stern = ResidualSettings(base="pid_as_built", envelope_guard={"nose_up_command": -1.0})
    stern.make_base(actuator="realistic")
    with pytest.raises(ValueError, match=r"on the fins actuator the M command is a nose-up"):
        stern.make_base(actuator="fins")


@pytest.mark.rl
def test_a_guarded_residual_trains_through_train_seeds_and_ships_its_guard(tmp_path):
    """The pilot's file (a residual on `pid_as_built` on the vehicle as built, guarded), tiny:
    its guard reaches the wrapper, the validation and the saved agent."""
    from benchmarks.training.seeds_cli import main
    from controllers.loader import load_policy

    pilot = ROOT / "benchmarks/results/seeds/residual_pid_as_built_pilot/pilot_bound_x025_guard.yml"
    config = yaml.safe_load(pilot.read_text())
    section = config["AUVPath3DSpeedLimit-v0"]
    section.update(n_envs=4, n_steps=64, batch_size=128, n_epochs=1)
    small = tmp_path / "guarded.yml"
    small.write_text(yaml.safe_dump(config))
    out = tmp_path / "run"
    argv = ["--config", str(small), "--seeds", "0-0", "--n-timesteps", "256"]
    argv += ["--eval-freq", "256", "--checkpoint-freq", "256", "--task-set"]
    argv += ["validation_as_built", "--eval-episodes", "2", "--eval-duration", "5"]
    assert main([*argv, "--out", str(out), "--quiet"]) == 0
    meta = json.loads((out / "seed_0" / "final" / "metadata.json").read_text())
    assert meta["residual"]["envelope_guard"]["nose_up_command"] == -1.0
    assert meta["residual"]["envelope_guard"]["surge_soft"] == 1.8
    policy = load_policy(out / "seed_0" / "final", base_kwargs={"actuator": "realistic"})
    assert isinstance(policy, ResidualPolicy) and policy.guard == EnvelopeGuard(
        nose_up_command=-1.0
    )
    summary = json.loads((out / "summary.json").read_text())
    assert summary["seeds"][0]["validation_summary"]["n_episodes"] == 2
    # trained on the propeller and fins, its base commands them unless told otherwise
    assert load_policy(out / "seed_0" / "final").base.actuator == "realistic"
    # on another actuator its commands mean nothing: refused naming the agent, before its base
    with pytest.raises(ValueError, match=r"final commands the propeller and fins .* 'paper'"):
        load_policy(out / "seed_0" / "final", base_kwargs={"actuator": "paper"})
