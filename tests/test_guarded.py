"""A classical controller inside the envelope guard (`controllers.guarded`, preset
`pid_as_built_guarded`): the base bit for bit inside the envelope, the guard's ramps at its edge,
the stern plane's sign on the realistic actuator, and a surge that stays below the top speed."""

from __future__ import annotations

import numpy as np
import pytest

import controllers
from auv_gym import VARIANTS
from auv_gym.rollout import evaluate, rollouts
from auv_gym.sim.observation import OBS_INDEX
from controllers.envelope_guard import EnvelopeGuard
from controllers.guarded import GuardedPolicy
from controllers.registry import _law, make_guarded

SPEED_LIMITED = {**VARIANTS["AUVPath3DSpeedLimit-v0"], "disturbance": "paper", "max_time": 10.0}


class FullAhead:
    """A controller that commands full thrust and nothing else."""

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        n = np.atleast_2d(observation).shape[0]
        return np.tile(np.float32([1.0, 0.0, 0.0]), (n, 1)), state


def test_inside_the_envelope_the_guarded_pid_is_the_pid(assert_same_episodes):
    # 1.2 s of the paper's climb; by 1.45 s (seed 1) the pitch 1 s ahead passes 35° and the
    # guard acts
    env = {"disturbance": "paper", "max_time": 1.2}
    plain = rollouts(controllers.make("pid_as_built"), [0, 1], **env)
    guarded = rollouts(controllers.make("pid_as_built_guarded"), [0, 1], **env)
    assert_same_episodes(guarded, plain)
    guard = EnvelopeGuard()
    for t in plain:  # the precondition: the PID never came near the guard's soft limits
        assert np.max(t.samples["u"]) < guard.surge_soft
        predicted = np.degrees(t.samples["theta"] + guard.lookahead_s * t.samples["q"])
        assert np.max(np.abs(predicted)) < guard.pitch_soft_deg


def test_the_guard_keeps_a_full_ahead_controller_below_the_top_speed():
    for episode in evaluate(FullAhead(), [0, 1], transient=0.0, **SPEED_LIMITED):
        assert episode["termination_reason"] == "overspeed" and episode["duration"] < 2.0
    guarded = GuardedPolicy(FullAhead(), EnvelopeGuard())
    for episode in evaluate(guarded, [0, 1], transient=0.0, **SPEED_LIMITED):
        assert episode["termination_reason"] == "time_limit"
        assert 1.8 < episode["max_surge"] < EnvelopeGuard().surge_hard


@pytest.mark.parametrize(("actuator", "sign"), [(None, 1.0), ("fins", 1.0), ("realistic", -1.0)])
def test_the_stern_plane_sign_follows_the_actuator(actuator, sign):
    kwargs = {} if actuator is None else {"actuator": actuator}
    policy = controllers.make("pid_as_built_guarded", **kwargs)
    assert policy.guard.nose_up_command == sign
    obs = np.zeros((2, 15), np.float32)
    obs[:, OBS_INDEX["theta"]] = np.radians(50.0)  # at the hard pitch limit: full nose-down
    obs[:, OBS_INDEX["u"]] = 1.0
    nose_up = GuardedPolicy(
        type("NoseUp", (), {"predict": lambda s, o, state=None, **k: (np.ones((2, 3)), state)})(),
        policy.guard,
    )
    action, _ = nose_up.predict(obs)
    # a full nose-up request becomes full nose-down: −1 as a moment, +1 as a stern-plane angle
    np.testing.assert_array_equal(action[:, 1], np.float32([-sign, -sign]))
    np.testing.assert_array_equal(action[:, 2], np.float32([1.0, 1.0]))  # yaw never touched


def test_bad_guarded_settings_are_named():
    with pytest.raises(ValueError, match="guarded base 'fbsm_colos_lowpass' is not an unwrapped"):
        make_guarded(base="fbsm_colos_lowpass")
    with pytest.raises(ValueError, match="guarded base 'pid_as_built_guarded' is not an unwrapped"):
        make_guarded(base="pid_as_built_guarded")
    with pytest.raises(ValueError, match=r"guarded: envelope_guard has unknown keys \['surge'\]"):
        make_guarded(envelope_guard={"surge": 1.0})
    with pytest.raises(ValueError, match="lowpass base 'pid_as_built_guarded' is not an"):
        controllers.make("lowpass", base="pid_as_built_guarded")
    with pytest.raises(ValueError, match=r"guarded: on the realistic actuator .* -1, got 1"):
        make_guarded(actuator="realistic", envelope_guard={"nose_up_command": 1.0})
    with pytest.raises(ValueError, match="guarded base must have predict"):
        GuardedPolicy(object(), EnvelopeGuard())


def test_make_guards_any_unwrapped_classical_controller():
    policy = controllers.make("guarded", base="pid_colos", envelope_guard={"surge_soft": 1.5})
    assert policy.guard == EnvelopeGuard(surge_soft=1.5)
    stern = controllers.make("guarded", base="command_filtered_colos", actuator="realistic")
    assert stern.guard.nose_up_command == -1.0
    with pytest.raises(ValueError, match=r"valid: \[.*'guarded'\]"):
        controllers.make("guard")


def test_the_guarded_pid_is_a_pid_law_and_keeps_its_diagnostics():
    assert _law("pid_as_built_guarded", {}) == "pid_los"  # flies vehicles without a 5-DOF model
    policy = controllers.make("pid_as_built_guarded")
    episode = rollouts(policy, [0], disturbance="paper", max_time=1.0)[0]
    plain = rollouts(controllers.make("pid_as_built"), [0], disturbance="paper", max_time=1.0)[0]
    assert sorted(episode.extras) == sorted(plain.extras)
