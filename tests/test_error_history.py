"""The errors' history in the agent observation (``history_steps``, ``history_interval``): the
observed (x_e, y_e, z_e) k·interval seconds ago, last in the observation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

from auv_gym import AUVPath3DEnv, ObservationConfig
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.sim.observation import mirror_signs
from tests.test_vector_env import SHORT, run_parity

HISTORY = ObservationConfig(
    "preview",
    points=2,
    spacing=3.0,
    integral_time=10.0,
    integral_errors="xyz",
    integral_limit=1.0,
    history_steps=3,
    history_interval=0.5,
)
WITHOUT = ObservationConfig(
    "preview", points=2, spacing=3.0, integral_time=10.0, integral_errors="xyz", integral_limit=1.0
)
STRIDE = 10  # 0.5 s of 0.05-s control steps


def test_layout_names_units_bounds_mirror_and_metadata():
    assert HISTORY.extra_dim == WITHOUT.extra_dim + 9 and HISTORY.history == 9
    assert HISTORY.names[:-9] == WITHOUT.names
    assert HISTORY.names[-9:] == tuple(
        f"{error}_past{k}" for k in (1, 2, 3) for error in ("x_e", "y_e", "z_e")
    )
    assert {HISTORY.units[name] for name in HISTORY.names[-9:]} == {"m"}
    low, high = HISTORY.bounds()
    assert high[-9:].tolist() == [500.0] * 9 and low[-9:].tolist() == [-500.0] * 9
    # the cross-track error's past changes sign under the port-starboard reflection, as y_e does
    assert mirror_signs(HISTORY.names)[-9:].tolist() == [1.0, -1.0, 1.0] * 3
    assert HISTORY.to_dict()["history_steps"] == 3
    assert HISTORY.to_dict()["history_interval"] == 0.5
    assert ObservationConfig.from_spec(HISTORY.to_dict()) == HISTORY
    assert "history_steps" not in WITHOUT.to_dict()  # older metadata still matches


def test_history_holds_the_observed_errors_of_earlier_steps_with_sensors():
    """With the navigation estimate the past entries are the observation's own x_e, y_e, z_e of
    10, 20 and 30 steps before; before the episode is that old, the reset's errors; every other
    entry equals the observation without history bit for bit."""
    env = AUVPath3DEnv(observation=HISTORY, sensors="typical", max_time=20.0)
    plain = AUVPath3DEnv(observation=WITHOUT, sensors="typical", max_time=20.0)
    obs, _ = env.reset(seed=5)
    reference, _ = plain.reset(seed=5)
    np.testing.assert_array_equal(obs[:-9], reference)
    errors = [obs[:3].copy()]
    np.testing.assert_array_equal(obs[-9:], np.tile(obs[:3], 3))
    rng = np.random.default_rng(2)
    for _ in range(80):
        action = rng.uniform(-0.6, 0.6, size=3)
        obs, *_ = env.step(action)
        reference, *_ = plain.step(action)
        np.testing.assert_array_equal(obs[:-9], reference)
        errors.append(obs[:3].copy())
        now = len(errors) - 1
        past = [errors[max(now - STRIDE * k, 0)] for k in (1, 2, 3)]
        np.testing.assert_array_equal(obs[-9:], np.concatenate(past))
    assert abs(obs[-8] - obs[1]) > 1e-3  # the cross-track error moved: the past is not now
    obs, _ = env.reset(seed=6)
    np.testing.assert_array_equal(obs[-9:], np.tile(obs[:3], 3))  # the last episode forgotten


@pytest.mark.parametrize(
    "mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP], ids=lambda m: m.name
)
def test_batched_equals_single_bit_for_bit_with_autoresets(mode):
    """Rows reset while the others keep their ring: the vector env equals single envs."""
    counts = run_parity(4, mode, steps=100, seed=8, path="random", observation=HISTORY, **SHORT)
    assert counts["terminated"] + counts["truncated"] >= 4


def test_snapshot_carries_the_history():
    actions = np.random.default_rng(3).uniform(-0.6, 0.6, size=(90, 2, 3))
    venv = AUVPath3DVectorEnv(2, observation=HISTORY)
    venv.reset(seed=1)
    for a in actions[:45]:
        venv.step(a)
    snapshot = venv.snapshot()
    tail = [venv.step(a)[0] for a in actions[45:]]
    clone = AUVPath3DVectorEnv(2, observation=HISTORY)
    clone.reset(seed=99)
    clone.restore(snapshot)
    np.testing.assert_array_equal([clone.step(a)[0] for a in actions[45:]], tail)


@pytest.mark.parametrize(
    "bad, message",
    [
        ({"history_steps": -1}, "observation history_steps"),
        ({"history_steps": 1.5}, "observation history_steps"),
        ({"history_steps": 65}, "observation history_steps"),
        ({"history_steps": 2, "history_interval": 0.0}, "observation history_interval"),
        ({"history_steps": 2, "history_interval": math.nan}, "observation history_interval"),
        (
            {"history_steps": 2, "history_interval": 0.12},
            r"observation history_interval = 0.12 s must be a whole multiple of control_dt = 0.05",
        ),
        ({"kind": "paper", "history_steps": 2}, "needs the agent observation"),
    ],
)
def test_bad_history_arguments_name_the_argument(bad, message):
    with pytest.raises(ValueError, match=message):
        AUVPath3DEnv(observation=bad)


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        (
            {"history_interval": 0.5},
            "observation history_interval = 0.5 does nothing without a history "
            "(history_steps = 0): give history_steps > 0 or leave history_interval out",
        ),
        (
            {"history_steps": 0, "history_interval": 1.0},  # given, even at the default
            "observation history_interval = 1.0 does nothing without a history "
            "(history_steps = 0): give history_steps > 0 or leave history_interval out",
        ),
        (
            {"kind": "paper", "history_steps": 2},
            "observation history_steps = 2 needs the agent observation (kind 'preview'); the "
            "paper's 15 entries have no preview, error integrals or history",
        ),
    ],
)
def test_a_history_interval_without_a_history_is_refused(spec, message):
    """Was: accepted, and the observation identical to the one without it."""
    with pytest.raises(ValueError) as caught:
        ObservationConfig.from_spec(spec)
    assert str(caught.value) == message
    assert ObservationConfig.from_spec({"history_steps": 0}) == ObservationConfig("preview")
