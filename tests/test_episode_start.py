"""The training start distribution (`randomize_start`) and its heading spread
(`start_heading_spread`): the near-start half draws its heading error within ±spread, the
default (0.2 rad) keeps every earlier episode bit for bit, and bad spreads are named errors.
`start_rotation` turns the start about p(0): −π/2 is the paper helix's start on any path."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import auv_gym  # noqa: F401  (registers the ids)
from auv_gym.sim.observation import OBS
from auv_gym.vehicle.dynamics import STATE

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


def test_a_spread_without_random_starts_is_refused() -> None:
    """Was: accepted, and without randomize_start it changes nothing."""
    with pytest.raises(ValueError) as caught:
        gym.make("AUVPath3D-v0", start_heading_spread=1.0)
    assert str(caught.value) == (
        "start_heading_spread = 1 rad sets the heading error of randomize_start's draws; with "
        "randomize_start=False it would do nothing: drop it or give randomize_start=True"
    )
    gym.make("AUVPath3D-v0", start_heading_spread=0.2)  # the default, as the env passes it
    gym.make("AUVPath3D-v0", start_heading_spread=1.0, randomize_start=True)


@pytest.mark.parametrize("bad", [-0.1, 3.2, math.nan, math.inf])
def test_bad_spread_is_named(bad: float) -> None:
    with pytest.raises(ValueError, match="start_heading_spread"):
        gym.make("AUVPath3D-v0", start_heading_spread=bad)


# ---- start_rotation: the start turned about the vertical through p(0) ------------------------


def _reset(**kwargs) -> tuple[np.ndarray, np.ndarray]:
    env = gym.make("AUVPath3D-v0", **kwargs)
    obs, _ = env.reset(seed=3)
    state = env.unwrapped.state.copy()
    env.close()
    return obs, state


def test_a_quarter_turn_gives_a_line_the_paper_helix_start_geometry() -> None:
    # The paper's helix starts with ε(0) = (−15, 5, 8) m in the body frame and ψ − ψ_F = −π/2
    # (ψ = 0, ψ_F = π/2); the line's default start has the same ε(0) but heads along the line.
    paper_obs, _ = _reset()
    line = {"kind": "line", "direction": [0.6, 0.8, 0.0]}  # ψ_F = atan2(0.8, 0.6) = 0.9273 rad
    straight_obs, straight = _reset(path=line)
    turned_obs, turned = _reset(path=line, start_rotation=-math.pi / 2)
    assert straight_obs[OBS.psi_error] == pytest.approx(0.0, abs=1e-12)
    assert turned_obs[OBS.psi_error] == pytest.approx(-math.pi / 2, abs=1e-12)
    assert paper_obs[OBS.psi_error] == pytest.approx(-math.pi / 2, abs=1e-12)
    # Hand computation: p(0) = 0, the default offset R_z(ψ_F)(−15, 5) = (−13, −9) m, turned by
    # −90° to (−9, 13) m, 8 m deep; heading 0.9273 − π/2.
    np.testing.assert_allclose(straight[:3], [-13.0, -9.0, 8.0], atol=1e-12)
    np.testing.assert_allclose(turned[:3], [-9.0, 13.0, 8.0], atol=1e-12)
    assert turned[STATE.psi] == pytest.approx(math.atan2(0.8, 0.6) - math.pi / 2, abs=1e-15)
    # The body-frame errors turn with the vehicle: the paper's (−15, 5, 8) m in every case.
    for obs in (paper_obs, straight_obs, turned_obs):
        np.testing.assert_allclose(obs[[OBS.x_e, OBS.y_e, OBS.z_e]], [-15.0, 5.0, 8.0], atol=1e-9)


def test_zero_rotation_is_the_earlier_start_bit_for_bit() -> None:
    for kwargs in ({}, {"path": LINE, "randomize_start": True}):
        for seed in range(6):
            a = gym.make("AUVPath3D-v0", **kwargs)
            b = gym.make("AUVPath3D-v0", start_rotation=0.0, **kwargs)
            obs_a, _ = a.reset(seed=seed)
            obs_b, _ = b.reset(seed=seed)
            np.testing.assert_array_equal(obs_a, obs_b)
            np.testing.assert_array_equal(a.unwrapped.state, b.unwrapped.state)


def test_rotation_turns_random_starts_and_keeps_their_distance() -> None:
    plain = _starts(None, range(30))
    env = gym.make("AUVPath3D-v0", path=LINE, randomize_start=True, start_rotation=math.pi / 3)
    for seed, (obs_p, state_p) in enumerate(plain):
        obs_r, _ = env.reset(seed=seed)
        state_r = env.unwrapped.state
        # Same draws: the heading turns by π/3 in both halves, s and u are unchanged.
        assert state_r[STATE.psi] == pytest.approx(state_p[STATE.psi] + math.pi / 3, abs=1e-12)
        assert (state_r[STATE.s], state_r[STATE.u]) == (state_p[STATE.s], state_p[STATE.u])
        if _near_start(state_p):  # the near half turns about p(0) = 0: the same distance
            assert np.linalg.norm(state_r[:3]) == pytest.approx(np.linalg.norm(state_p[:3]))
            np.testing.assert_allclose(
                obs_r[[OBS.x_e, OBS.y_e, OBS.z_e]], obs_p[[OBS.x_e, OBS.y_e, OBS.z_e]], atol=1e-9
            )


def test_batched_rotated_starts_equal_single_ones() -> None:
    from auv_gym.envs.vector_env import AUVPath3DVectorEnv

    kwargs = {"path": "random", "start_rotation": -math.pi / 2}  # validation_paper_start's
    vec = AUVPath3DVectorEnv(4, **kwargs)
    vec_obs, _ = vec.reset(seed=11)  # vehicle i is the single env reset with seed 11 + i
    for i in range(4):
        single = gym.make("AUVPath3D-v0", **kwargs)
        obs, _ = single.reset(seed=11 + i)
        np.testing.assert_array_equal(vec_obs[i], obs)
        np.testing.assert_array_equal(vec.state[i], single.unwrapped.state)
        assert abs(obs[OBS.psi_error] + math.pi / 2) < 1e-6  # every drawn path: 90° across


@pytest.mark.parametrize("bad", [-3.2, 3.2, math.nan, math.inf, "quarter"])
def test_bad_rotation_is_named(bad: object) -> None:
    with pytest.raises(ValueError, match="start_rotation"):
        gym.make("AUVPath3D-v0", start_rotation=bad)


def test_a_rotation_range_draws_each_episode_its_own_rotation() -> None:
    line = {"kind": "line", "direction": [1.0, 0.0, 0.0]}
    env = gym.make("AUVPath3D-v0", path=line, start_rotation=[-math.pi / 2, math.pi / 4])
    drawn = []
    for seed in range(200):
        obs, _ = env.reset(seed=seed)
        drawn.append(float(obs[OBS.psi_error]))  # fixed start on the line: ψ − ψ_F = rotation
        np.testing.assert_allclose(obs[[OBS.x_e, OBS.y_e, OBS.z_e]], [-15.0, 5.0, 8.0], atol=1e-9)
    drawn = np.array(drawn)
    assert drawn.min() >= -math.pi / 2 - 1e-6 and drawn.max() <= math.pi / 4 + 1e-6
    # Uniform over 3π/4 rad: mean −π/8, quarters all populated.
    assert abs(drawn.mean() + math.pi / 8) < 0.15
    assert np.histogram(drawn, bins=4)[0].min() > 30
    # The same seed draws the same rotation; JSON's list and a tuple are the same argument.
    again = gym.make("AUVPath3D-v0", path=line, start_rotation=(-math.pi / 2, math.pi / 4))
    assert float(again.reset(seed=7)[0][OBS.psi_error]) == drawn[7]


@pytest.mark.parametrize("bad", [(0.5, -0.5), (-4.0, 0.0), (0.0, 1.0, 2.0), (0.0, math.nan)])
def test_a_bad_rotation_range_is_named(bad: tuple) -> None:
    with pytest.raises(ValueError, match="start_rotation"):
        gym.make("AUVPath3D-v0", start_rotation=bad)
