"""Actuator allocation for agents (`controllers.actuator_allocation`): hand-computed fin commands
and previous-action entries, the realistic actuators' allocation, the loader's wrapping by the
scenario's actuator, the fin-limited tracking it buys a shipped agent, and bad settings named."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from auv_gym.actuators import ActuatorParams
from auv_gym.observation import ObservationConfig
from controllers.actuator_allocation import AllocatedPolicy, check_actuator_allocation
from controllers.allocation import allocate

ROOT = Path(__file__).resolve().parents[1]
SEEDS = ROOT / "benchmarks" / "results" / "seeds" / "ppo_paper_actuator"
FINAL_8M = ROOT / "benchmarks" / "results" / "seeds" / "ppo_paper_start" / "final_agent_seed_1"
NAMES = ObservationConfig.from_spec("preview").names
U, V, W = (NAMES.index(n) for n in ("u", "v", "w"))
PREV = [NAMES.index(n) for n in ("a_X_prev", "a_M_prev", "a_N_prev")]
FIN_GAIN = 6.15 * math.pi / 6  # K·δ_max [kg] of REMUS 100: the fin moment at 1 m/s [N·m]


class Recorder:
    """An actor that returns fixed commands and keeps the observations it was given."""

    def __init__(self, commands):
        self.commands = np.float32(commands)
        self.seen = []

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        self.seen.append(np.array(observation))
        n = np.atleast_2d(observation).shape[0]
        return np.tile(self.commands, (n, 1)), state


def _obs(u: float, v: float = 0.0, w: float = 0.0, prev=(0.5, 0.5, 0.5)) -> np.ndarray:
    obs = np.zeros(len(NAMES), dtype=np.float32)
    obs[[U, V, W]] = u, v, w
    obs[PREV] = prev  # the env's fin commands: the allocation replaces them
    return obs


def test_fin_commands_and_previous_moments_by_hand():
    actor = Recorder([0.2, 0.1, -0.5])  # X = 10 N, M_d = 1 N·m, N_d = −5 N·m
    policy = AllocatedPolicy(actor, NAMES, "fins")
    obs = np.stack([_obs(1.0), _obs(2.0), _obs(0.0), _obs(-0.3)])
    first, state = policy.predict(obs, episode_start=np.ones(4, dtype=bool))
    authority = FIN_GAIN * np.array([1.0, 4.0, 0.0, 0.0])  # K·δ_max·max(u|u|, 0) [N·m]
    np.testing.assert_allclose(
        first[:2],
        [[0.2, 1.0 / authority[0], -1.0], [0.2, 1.0 / authority[1], -5.0 / authority[1]]],
        rtol=1e-6,
    )
    np.testing.assert_array_equal(first[2:], np.float32([[0.2, 1.0, -1.0]] * 2))  # no flow: sign
    np.testing.assert_array_equal(actor.seen[0][:, PREV], np.zeros((4, 3)))  # after a reset
    policy.predict(obs, state, episode_start=np.array([False, False, False, True]))
    delivered = np.array(
        [[0.2, 0.1, -authority[0] / 10.0], [0.2, 0.1, -0.5], [0.2, 0.0, 0.0], [0.0, 0.0, 0.0]]
    )
    np.testing.assert_allclose(actor.seen[1][:, PREV], delivered, rtol=1e-6)
    single, _ = policy.predict(_obs(1.0))
    assert single.shape == (3,) and single[1] == pytest.approx(1.0 / authority[0], rel=1e-6)


def test_realistic_actuators_get_the_classical_allocation_of_the_delivered_moments():
    actor = Recorder([0.4, -0.2, 0.9])  # X = 20 N, M_d = −2 N·m, N_d = 9 N·m (beyond the fins)
    policy = AllocatedPolicy(actor, NAMES, "realistic")
    obs = np.stack([_obs(1.2, 0.05, -0.02), _obs(1.6, -0.1, 0.1)])
    commands, _ = policy.predict(obs)
    u = obs[:, U].astype(np.float64)
    authority = FIN_GAIN * u * u
    tau = np.column_stack([np.full(2, 20.0), np.full(2, -2.0), np.minimum(9.0, authority)])
    expected = allocate(tau, obs[:, [U, V, W]], ActuatorParams())
    np.testing.assert_allclose(commands, expected, rtol=1e-6)


def test_bad_settings_are_named():
    with pytest.raises(ValueError, match="actuator_allocation must be 'paper'"):
        check_actuator_allocation("fins", "metadata.json")
    with pytest.raises(ValueError, match=r"allocates to \['fins', 'realistic'\]"):
        AllocatedPolicy(Recorder([0, 0, 0]), NAMES, "paper")
    with pytest.raises(ValueError, match=r"lacks \['v', 'w'\]"):
        AllocatedPolicy(Recorder([0, 0, 0]), ["u", "a_X_prev", "a_M_prev", "a_N_prev"], "fins")


@pytest.mark.rl
def test_an_allocated_agent_flies_the_fins_closer_to_the_path(tmp_path):
    """Seed 1 of the 8M paper-start generalist on the `fins` scenario (test seed 0, 200 s):
    with the allocation its commands reach the fins as moments and the RMS distance falls
    (0.042 → 0.018 m over the scenario's 300 s); on the paper's actuator the loader leaves it
    alone."""
    from auv_gym.metrics import compute_metrics
    from auv_gym.rollout import rollouts
    from benchmarks.training.evaluation import agent_env_kwargs
    from benchmarks.training.guard_agents import main
    from controllers.envelope_guard import GuardedPolicy
    from controllers.loader import load_policy

    (written,) = main(["--from", str(FINAL_8M), "--out", str(tmp_path / "a"), "--allocation"])
    metadata = json.loads((written / "metadata.json").read_text())
    assert metadata["actuator_allocation"] == "paper" and "envelope_guard" in metadata
    plain = load_policy(written)
    assert isinstance(plain, GuardedPolicy)  # no actuator told: no allocation
    assert isinstance(load_policy(written, base_kwargs={"actuator": "paper"}), GuardedPolicy)
    allocated = load_policy(written, base_kwargs={"actuator": "fins"})
    assert isinstance(allocated, AllocatedPolicy) and allocated.actuator == "fins"
    env = {
        **agent_env_kwargs(metadata["env_id"], metadata),
        "disturbance": "none",
        "actuator": "fins",
        "max_time": 200.0,
    }
    before, after = (compute_metrics(rollouts(p, [0], **env)[0]) for p in (plain, allocated))
    assert before["termination_reason"] == after["termination_reason"] == "time_limit"
    assert after["rms_distance"] < 0.6 * before["rms_distance"]


def test_the_loader_and_the_copier_refuse_what_cannot_be_allocated(tmp_path):
    from benchmarks.training.guard_agents import main
    from controllers.loader import load_policy

    agent = tmp_path / "agent"
    shutil.copytree(SEEDS / "agent_seed_1", agent)
    metadata = json.loads((agent / "metadata.json").read_text())
    (agent / "metadata.json").write_text(json.dumps({**metadata, "actuator_allocation": "fins"}))
    with pytest.raises(ValueError, match=r"metadata.json: actuator_allocation must be 'paper'"):
        load_policy(agent, base_kwargs={"actuator": "fins"})
    other = tmp_path / "random"
    shutil.copytree(SEEDS / "agent_seed_1", other)
    random_actuator = {**metadata, "env_kwargs": {**metadata["env_kwargs"], "actuator": "random"}}
    (other / "metadata.json").write_text(json.dumps(random_actuator))
    with pytest.raises(SystemExit):  # trained on either actuator: nothing to allocate from
        main(["--from", str(other), "--out", str(tmp_path / "x"), "--allocation"])
    with pytest.raises(SystemExit):  # records nothing
        main(["--from", str(SEEDS / "agent_seed_1"), "--out", str(tmp_path / "y"), "--no-guard"])
    assert not (tmp_path / "x").exists() and not (tmp_path / "y").exists()
