"""`render_mode="rgb_array"` frames (`auv_gym.envs.rendering`): the fast path against the full
redraw.

Tolerance: the fast path draws the growing lines stretch by stretch over a cached layer, the
reference draws every line whole; antialiased pixels where two stretches meet may differ. Over a
whole episode at most 2 % of the pixels may differ, by 0.5/255 on average; the picture outside
the lines (axes, ticks, labels, path) is the same. Speed is measured by
`benchmarks/speed/render.py`, not here.
"""

from __future__ import annotations

import numpy as np
import pytest

import controllers
from auv_gym import AUVPath3DEnv
from auv_gym.envs.rendering import EpisodeRenderer
from auv_gym.paths import make_path


def _compare(fast: np.ndarray, slow: np.ndarray) -> tuple[float, float]:
    diff = np.abs(fast.astype(np.int16) - slow.astype(np.int16))
    return float((diff.max(axis=2) > 0).mean()), float(diff.mean())


@pytest.mark.integration
def test_fast_frames_match_the_full_redraw_over_an_episode():
    """FBSM on the paper scenario, 120 s, a frame every 20 control steps from both renderers."""
    env = AUVPath3DEnv(render_mode="rgb_array", max_time=120.0)
    policy = controllers.make("fbsm")
    reference = EpisodeRenderer(env.config.path, env.config.max_time, fast=False)
    obs, _ = env.reset(seed=3)
    sim = env.sim
    reference.reset(sim.state[0, 0:3], sim.guid[0, 0:3], sim.state[0, 10])
    state, start = None, np.ones(1, dtype=bool)
    worst = (0.0, 0.0)
    frames = 0
    for k in range(1, 2401):
        action, state = policy.predict(obs[None], state, start)
        start[:] = False
        obs, _, terminated, truncated, info = env.step(action[0])
        reference.append(sim.state[0, 0:3], sim.guid[0, 0:3], sim.state[0, 10], info["t"])
        if k % 20 == 0:
            fast, slow = env.render(), reference.frame()
            assert fast.shape == slow.shape == (320, 960, 3) and fast.dtype == np.uint8
            worst = max(worst, _compare(fast, slow))
            frames += 1
        if terminated or truncated:
            break
    assert frames == 120 and truncated
    share, mean = worst
    assert share <= 0.02 and mean <= 0.5, worst
    assert fast.std() > 10  # a picture, not a blank canvas


def test_fast_and_full_redraw_agree_on_the_first_frame_and_after_a_reset():
    path = make_path("line")
    fast, slow = EpisodeRenderer(path, 60.0), EpisodeRenderer(path, 60.0, fast=False)
    for episode in range(2):
        for r in (fast, slow):
            r.reset(np.array([0.0, 5.0, 8.0 + episode]), np.array([-1.0, 5.0, 8.0]), 0.0)
        np.testing.assert_array_equal(fast.frame(), slow.frame())
        for k in range(1, 101):
            position = np.array([0.5 * k * 0.05, 5.0 * np.exp(-k / 50), 8.0])
            for r in (fast, slow):
                r.append(position, np.array([0.0, position[1], 0.0]), 0.02 * k, 0.05 * k)
        share, mean = _compare(fast.frame(), slow.frame())
        assert share <= 0.02 and mean <= 0.5


def test_renderer_ignores_non_finite_steps_and_rejects_bad_sizes():
    r = EpisodeRenderer(make_path("helix"), 10.0)
    with pytest.raises(RuntimeError, match="before reset"):
        r.frame()
    r.reset(np.array([15.0, 5.0, 0.0]), np.array([-15.0, 5.0, 8.0]), 0.0)
    r.append(np.array([np.nan, 0.0, 0.0]), np.zeros(3), 0.1, 0.05)
    assert r.frame().shape == (320, 960, 3)
    with pytest.raises(ValueError, match="max_time"):
        EpisodeRenderer(make_path("helix"), 0.0)
    with pytest.raises(ValueError, match="frame size"):
        EpisodeRenderer(make_path("helix"), 10.0, width_px=4)
