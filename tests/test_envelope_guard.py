"""The envelope guard (`controllers.envelope_guard`, `benchmarks.training.guard_agents`):
hand-computed commands near the pitch and surge limits, the identity inside them, a guarded agent
loaded from its metadata, the pitch-over it prevents in a current, and bad settings named."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest

from controllers.envelope_guard import (
    EnvelopeGuard,
    GuardedPolicy,
    check_envelope_guard,
    guard_commands,
)

ROOT = Path(__file__).resolve().parents[1]
SEEDS = ROOT / "benchmarks" / "results" / "seeds" / "ppo_paper_actuator"
INDEX = (0, 1, 2)  # θ, q, u in the hand-made observations below
GUARD = EnvelopeGuard()  # pitch 35°–50°, T = 1 s, surge 1.8–1.95 m/s


def _obs(theta_deg: float, q_deg_s: float, u: float) -> np.ndarray:
    return np.array([math.radians(theta_deg), math.radians(q_deg_s), u])


def test_inside_the_soft_limits_the_guard_is_the_identity():
    commands = np.float32([[0.7, 1.0, -0.4], [-1.0, -1.0, 1.0]])
    obs = np.stack([_obs(20.0, 10.0, 1.2), _obs(-30.0, 4.0, 1.79)])  # θ + T·q = 30°, −26°
    np.testing.assert_array_equal(guard_commands(commands, obs, INDEX, GUARD), commands)


def test_hand_computed_guarded_commands():
    cases = [  # (θ [deg], q [deg/s], u [m/s], command, guarded)
        (42.5, 0.0, 1.0, [0.5, 1.0, 0.3], [0.5, 0.0, 0.3]),  # half way: nose-up capped at 0
        (30.0, 10.0, 1.0, [0.5, 1.0, 0.3], [0.5, 1.0 / 3.0, 0.3]),  # θ_p = 40°: 1 − 2·5/15
        (55.0, 0.0, 1.0, [0.5, 0.2, 0.3], [0.5, -1.0, 0.3]),  # past the hard limit: nose down
        (42.5, 0.0, 1.0, [0.5, -0.6, 0.3], [0.5, -0.6, 0.3]),  # nose-down stays allowed
        (-50.0, 0.0, 1.0, [0.5, -1.0, -1.0], [0.5, 1.0, -1.0]),  # mirrored: full nose up
        (0.0, 0.0, 1.875, [0.5, 0.1, 0.0], [0.0, 0.1, 0.0]),  # surge half way: thrust capped
        (0.0, 0.0, 1.875, [-0.3, 0.1, 0.0], [-0.3, 0.1, 0.0]),  # astern stays allowed
        (0.0, 0.0, 2.1, [1.0, 0.1, 0.0], [-1.0, 0.1, 0.0]),  # past u_hard: full astern
    ]
    for theta, q, u, command, expected in cases:
        single = guard_commands(np.float32(command), _obs(theta, q, u), INDEX, GUARD)
        assert single.shape == (3,) and single.dtype == np.float32
        np.testing.assert_allclose(single, expected, atol=1e-6)
    batch = guard_commands(
        np.float32([c[3] for c in cases]), np.stack([_obs(*c[:3]) for c in cases]), INDEX, GUARD
    )
    np.testing.assert_allclose(batch, [c[4] for c in cases], atol=1e-6)


class _Constant:
    """A Policy that always commands full nose-up and thrust."""

    path = None
    metadata: ClassVar[dict] = {}

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        n = np.atleast_2d(observation).shape[0]
        out = np.tile(np.float32([1.0, 1.0, 0.5]), (n, 1))
        return (out if np.ndim(observation) == 2 else out[0]), state


def test_a_guarded_policy_reads_its_inputs_by_name():
    names = ["x_e", "u", "theta", "q"]
    policy = GuardedPolicy(_Constant(), {"pitch_soft_deg": 30.0}, names)
    obs = np.array([0.0, 1.0, math.radians(40.0), 0.0])  # θ_p = 40° of 30°–50°: cap 0
    command, _ = policy.predict(obs)
    np.testing.assert_allclose(command, [1.0, 0.0, 0.5], atol=1e-6)
    with pytest.raises(ValueError, match=r"lacks \['q'\]"):
        GuardedPolicy(_Constant(), True, ["theta", "u"])


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ({"pitch_soft_deg": 50.0, "pitch_hard_deg": 40.0}, "soft limit must lie below"),
        ({"surge_soft": 2.0}, "soft limit must lie below"),
        ({"pitch_hard_deg": math.nan}, "pitch_hard_deg must be"),
        ({"lookahead_s": -1.0}, "lookahead_s must be"),
        ({"pitch": 40.0}, r"unknown keys \['pitch'\]"),
        ("yes", "must be true or a mapping"),
    ],
)
def test_bad_guards_are_named(value, message):
    with pytest.raises(ValueError, match=f"here: .*{message}"):
        check_envelope_guard(value, "here")


@pytest.mark.rl
def test_the_guard_stops_a_recorded_pitch_over(tmp_path):
    """Seed 3 of the paper-actuator generalist pitches over from the paper's start in the
    `current` scenario (test seed 0, docs/results.md); its guarded copy, made by
    `benchmarks.training.guard_agents`, reaches the path and keeps its pitch below 50°."""
    from auv_gym.rollout import rollouts
    from auv_gym.trajectory import TIME_LIMIT
    from benchmarks.training.evaluation import agent_env_kwargs
    from benchmarks.training.guard_agents import main
    from controllers.loader import load_policy

    written = main(["--from", str(SEEDS / "agent_seed_3"), "--out", str(tmp_path / "guarded")])
    metadata = json.loads((written[0] / "metadata.json").read_text())
    assert metadata["envelope_guard"] == GUARD.to_dict()
    plain, guarded = load_policy(SEEDS / "agent_seed_3"), load_policy(written[0])
    assert isinstance(guarded, GuardedPolicy)
    env = {
        **agent_env_kwargs(plain.metadata["env_id"], plain.metadata),
        "disturbance": "none",
        "current": {"mean": [0.0, 0.3, 0.0], "std": [0.05, 0.05, 0.0], "time_constant": 60.0},
        "max_time": 60.0,
    }
    (before,) = rollouts(plain, [0], **env)
    (after,) = rollouts(guarded, [0], **env)
    assert before.termination_reason == "pitch" and before.t[-1] < 40.0
    assert after.termination_reason == TIME_LIMIT and after.t[-1] == pytest.approx(60.0)
    assert np.degrees(np.abs(after["theta"])).max() < 50.0
    assert after["distance"][-1] < 1.0  # on the path after 60 s
    with pytest.raises(SystemExit):  # already guarded: a usage error, nothing written
        main(["--from", str(written[0]), "--out", str(tmp_path / "twice")])
    assert not (tmp_path / "twice").exists()


@pytest.mark.rl
def test_the_training_wrapper_guards_the_env_commands():
    """Full nose-up from rest: the wrapper lets it through until θ + T·q passes 35°, then the
    applied moment M (info "tau", N·m) falls to the ramp's value and the pitch stays below 50°."""
    from auv_gym.observation import ObservationConfig
    from benchmarks.training.envelope_guard import GuardedActions
    from benchmarks.training.train import make_training_env

    names = ObservationConfig.from_spec("preview").names
    venv = GuardedActions(
        make_training_env(
            2,
            0,
            {"disturbance": "none", "max_time": 60.0},
            kind="dummy",
            env_id="AUVPath3DPreview-v0",
        ),
        GUARD,
        names,
    )
    obs = venv.reset()
    it, iq = names.index("theta"), names.index("q")
    pitch, capped = [], 0
    for _ in range(600):
        predicted = obs[:, it] + obs[:, iq]  # θ + 1 s · q of the observation the guard reads
        obs, _, dones, infos = venv.step(np.float32([[0.05, 1.0, 0.0]] * 2))
        moment = np.array([info["tau"][1] for info in infos]) / 10.0  # normalised M
        expected = 1.0 - 2.0 * np.clip((predicted - math.radians(35.0)) / math.radians(15.0), 0, 1)
        np.testing.assert_allclose(moment, expected, atol=1e-5)
        capped += int((expected < 1.0).sum())
        pitch.append(np.degrees(obs[:, it]).max())
        assert not dones.any()
    assert capped > 100 and 35.0 < max(pitch) < 50.0
    venv.close()


@pytest.mark.rl
def test_a_file_trains_a_guarded_agent_that_loads_guarded(tmp_path, train_tiny_preview_agent):
    from controllers.loader import load_policy

    guard = {"pitch_soft_deg": 30.0, "pitch_hard_deg": 45.0}
    agent = train_tiny_preview_agent(tmp_path, envelope_guard=guard)
    recorded = json.loads((agent / "metadata.json").read_text())["envelope_guard"]
    assert recorded == EnvelopeGuard(**guard).to_dict()
    policy = load_policy(agent)
    assert isinstance(policy, GuardedPolicy) and policy.guard == EnvelopeGuard(**guard)
    import yaml

    from benchmarks.training.config import read_zoo_config

    config = tmp_path / "bad.yml"
    config.write_text(
        yaml.safe_dump(
            {
                "AUVPath3DPreview-v0": {
                    "n_envs": 2,
                    "n_timesteps": 64,
                    "policy": "MlpPolicy",
                    "normalize": True,
                    "envelope_guard": {"surge_soft": 3.0},
                }
            }
        )
    )
    with pytest.raises(
        ValueError,
        match=r"bad.yml: AUVPath3DPreview-v0: envelope_guard: each "
        r"soft limit must lie below its hard limit",
    ):
        read_zoo_config(config, "AUVPath3DPreview-v0", "ppo")


def test_guarding_a_results_folder_copies_its_curves_not_its_test_evaluations(tmp_path):
    import shutil

    from benchmarks.training.guard_agents import main

    source = tmp_path / "seeds"
    shutil.copytree(SEEDS / "agent_seed_1", source / "agent_seed_1")
    shutil.copyfile(SEEDS / "seed_1_learning_curve.csv", source / "seed_1_learning_curve.csv")
    shutil.copyfile(SEEDS / "seed_1_test_evaluation.json", source / "seed_1_test_evaluation.json")
    main(["--from", str(source), "--out", str(tmp_path / "guarded")])
    names = sorted(p.name for p in (tmp_path / "guarded").iterdir())
    assert names == ["agent_seed_1", "seed_1_learning_curve.csv"]
    for name in ("model.zip", "vecnormalize.npz"):  # the network and statistics byte for byte
        assert (tmp_path / "guarded" / "agent_seed_1" / name).read_bytes() == (
            source / "agent_seed_1" / name
        ).read_bytes()
    with pytest.raises(SystemExit):
        main(["--from", str(tmp_path / "empty"), "--out", str(tmp_path / "x")])


def test_a_corrupt_guard_in_metadata_is_named_by_the_loader(tmp_path):
    import shutil

    from controllers.loader import load_policy

    agent = tmp_path / "agent"
    shutil.copytree(SEEDS / "agent_seed_1", agent)
    meta = json.loads((agent / "metadata.json").read_text())
    meta["envelope_guard"] = {"pitch_soft_deg": 60.0, "pitch_hard_deg": 50.0}
    (agent / "metadata.json").write_text(json.dumps(meta))
    with pytest.raises(ValueError, match=r"metadata.json: envelope_guard: each soft limit"):
        load_policy(agent)
