"""The training start distribution (`randomize_start`) and its heading spread
(`start_heading_spread`): the near-start half draws its heading error within ±spread, the
default (0.2 rad) keeps every earlier episode bit for bit, and bad spreads are named errors."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import auv_gym  # noqa: F401  (registers the ids)
from auv_gym.dynamics import STATE
from auv_gym.observation import OBS

LINE = {"kind": "line", "direction": [1.0, 0.0, 0.0]}  # default start heading: along the line


def _starts(spread: float | None, seeds: range) -> list[tuple[np.ndarray, np.ndarray]]:
    """(observation, state) after each reset of a randomised-start env on the line."""
    kwargs = {} if spread is None else {"start_heading_spread": spread}
    env = gym.make("AUVPath3D-v0", path=LINE, randomize_start=True, **kwargs)
    out = []
    for seed in seeds:
        obs, _ = env.reset(seed=seed)
        out.append((obs.copy(), env.unwrapped.state.copy()))
    env.close()
    return out


def _near_start(state: np.ndarray) -> bool:
    return state[STATE.s] == 0.0 and state[STATE.u] == 0.0  # the near-start half: s = 0, u = 0


def test_default_spread_is_the_earlier_distribution_bit_for_bit() -> None:
    implicit, explicit = _starts(None, range(40)), _starts(0.2, range(40))
    for (obs_a, state_a), (obs_b, state_b) in zip(implicit, explicit, strict=True):
        np.testing.assert_array_equal(obs_a, obs_b)
        np.testing.assert_array_equal(state_a, state_b)
    errors = [abs(obs[OBS.psi_error]) for obs, state in implicit if _near_start(state)]
    assert len(errors) > 10 and max(errors) <= 0.2


def test_a_wide_spread_scales_only_the_near_start_heading_error() -> None:
    narrow, wide = _starts(0.2, range(200)), _starts(math.pi / 2, range(200))
    near = 0
    for (obs_n, state_n), (obs_w, state_w) in zip(narrow, wide, strict=True):
        # The same draws: the same position, and the far half unchanged entirely.
        np.testing.assert_array_equal(state_n[:3], state_w[:3])
        if not _near_start(state_n):
            np.testing.assert_array_equal(obs_n, obs_w)
            continue
        near += 1
        # ψ error = −(spread · draw): (π/2)/0.2 times the narrow one (no wrap below π/2).
        ratio = (math.pi / 2) / 0.2
        assert obs_w[OBS.psi_error] == pytest.approx(ratio * obs_n[OBS.psi_error], rel=1e-5)
    errors = [abs(obs[OBS.psi_error]) for obs, state in wide if _near_start(state)]
    assert near > 60
    assert max(errors) <= math.pi / 2 + 1e-6
    assert np.mean(np.array(errors) > math.radians(60.0)) > 0.2  # the paper's 90° now reachable


@pytest.mark.parametrize("bad", [-0.1, 3.2, math.nan, math.inf])
def test_bad_spread_is_named(bad: float) -> None:
    with pytest.raises(ValueError, match="start_heading_spread"):
        gym.make("AUVPath3D-v0", start_heading_spread=bad)
