"""The low-pass baseline (controllers.lowpass): α = 0 is the base bit for bit, the filter
equation on a real rollout, restarts at episode starts, the actuator range, bad α."""

from __future__ import annotations

import numpy as np
import pytest

import controllers
from auv_gym.rollout import rollouts
from controllers.lowpass import LowPassPolicy

ENV = {"disturbance": "paper", "max_time": 4.0}  # 80 control steps


def test_alpha_zero_is_the_base_bit_for_bit():
    alone = rollouts(controllers.make("fbsm_colos"), [0, 1], **ENV)
    filtered = rollouts(controllers.make("lowpass", alpha=0.0), [0, 1], **ENV)
    for a, b in zip(alone, filtered, strict=True):
        for name in a.samples:
            np.testing.assert_array_equal(a.samples[name], b.samples[name], err_msg=name)


def test_filter_equation_and_restart_on_the_base_actions():
    base = controllers.make("fbsm_colos")
    policy = LowPassPolicy(controllers.make("fbsm_colos"), alpha=0.6)
    rng = np.random.default_rng(0)
    obs = rng.uniform(-1.0, 1.0, size=(6, 4, 15)).astype(np.float32)
    obs[..., 13] = 1.5  # u_D
    starts = np.zeros((6, 4), bool)
    starts[0] = True
    starts[3, 2] = True  # vehicle 2 starts a new episode at step 3
    base_state = state = None
    previous = None
    for k in range(6):
        b, base_state = base.predict(obs[k], state=base_state, episode_start=starts[k])
        a, state = policy.predict(obs[k], state=state, episode_start=starts[k])
        expected = (
            b.astype(np.float32)
            if previous is None
            else (0.6 * previous + 0.4 * b).astype(np.float32)
        )
        expected[starts[k]] = b[starts[k]]
        np.testing.assert_array_equal(a, expected)
        assert np.all(np.abs(a) <= 1.0)
        previous = a
    assert np.any(a != b)  # it filters


def test_the_named_preset_halves_chattering_on_the_paper_noise():
    kwargs = {**ENV, "max_time": 20.0}
    alone = rollouts(controllers.make("fbsm_colos"), [3], **kwargs)[0]
    smooth = rollouts(controllers.make("fbsm_colos_lowpass"), [3], **kwargs)[0]

    def variation(trajectory):
        tau = np.stack([trajectory.intervals[k] for k in ("a_X", "a_M", "a_N")], axis=1)
        return np.abs(np.diff(tau, axis=0)).sum()

    assert variation(smooth) < 0.6 * variation(alone)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"alpha": 1.0}, r"alpha must be a number in \[0, 1\) \(1 would freeze"),
        ({"alpha": float("nan")}, r"alpha must be a number in \[0, 1\)"),
        ({"alpha": "0.5"}, r"alpha must be a number in \[0, 1\), got '0.5'"),
        ({"base": "fbsm_colos_lowpass"}, "not an unfiltered classical controller"),
        ({"base": "ppo"}, "lowpass base 'ppo' is not an unfiltered classical controller"),
    ],
)
def test_bad_arguments_are_named(kwargs, message):
    with pytest.raises(ValueError, match=message):
        controllers.make("lowpass", **kwargs)
