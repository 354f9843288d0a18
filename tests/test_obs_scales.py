"""Observation entries at fixed scales (`obs_scales`, benchmarks/training/normalization.py): the
pinned entries keep mean 0 and scale² through updates, the others follow the running statistics
exactly, bad values are named, and a trained agent's saved statistics carry the pins."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from stable_baselines3.common.running_mean_std import RunningMeanStd

from benchmarks.training.normalization import (
    PinnedRunningMeanStd,
    parse_obs_scales,
    pin_observation_scales,
)


def test_pinned_entries_stay_and_the_others_follow_the_running_statistics():
    rng = np.random.default_rng(0)
    plain = RunningMeanStd(shape=(4,))
    pinned = PinnedRunningMeanStd(RunningMeanStd(shape=(4,)), np.array([1, 3]), np.array([0.5, 2]))
    for _ in range(5):
        batch = rng.normal(3.0, 4.0, size=(32, 4))
        plain.update(batch)
        pinned.update(batch)
    np.testing.assert_array_equal(pinned.mean[[1, 3]], [0.0, 0.0])
    np.testing.assert_array_equal(pinned.var[[1, 3]], [0.25, 4.0])
    np.testing.assert_array_equal(pinned.mean[[0, 2]], plain.mean[[0, 2]])
    np.testing.assert_array_equal(pinned.var[[0, 2]], plain.var[[0, 2]])
    assert pinned.count == plain.count


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ([0.5], "must be a non-empty mapping"),
        ({}, "must be a non-empty mapping"),
        ({"x_e": 0.0}, r"obs_scales\['x_e'\] must be a finite number > 0"),
        ({"x_e": float("nan")}, r"obs_scales\['x_e'\] must be a finite number > 0"),
        ({"x_e": True}, r"obs_scales\['x_e'\] must be a finite number > 0"),
        ({"x_e": "0.5"}, r"obs_scales\['x_e'\] must be a finite number > 0"),
    ],
)
def test_bad_scales_are_named(value, message):
    with pytest.raises(ValueError, match=message):
        parse_obs_scales(value, "cfg.yml: env")


def test_unknown_entries_are_named_with_the_valid_ones():
    class _Normalize:
        obs_rms = RunningMeanStd(shape=(2,))

    with pytest.raises(ValueError, match=r"unknown observation entries \['z_err'\].*'x_e', 'z_e'"):
        pin_observation_scales(_Normalize(), ["x_e", "z_e"], {"z_err": 0.5})


@pytest.mark.integration
@pytest.mark.rl
def test_a_trained_agent_normalises_its_errors_by_the_fixed_scale(
    tmp_path, train_tiny_preview_agent
):
    """A tiny PPO run with x_e, z_e at 0.5 m: the exported statistics hold mean 0, variance 0.25
    there, and the loaded agent feeds its network x_e/0.5 m."""
    from controllers.loader import load_policy

    train_tiny_preview_agent(tmp_path, obs_scales={"x_e": 0.5, "z_e": 0.5})
    stats = np.load(tmp_path / "agent" / "vecnormalize.npz")
    names = list(stats["obs_names"])
    for name in ("x_e", "z_e"):
        assert stats["mean"][names.index(name)] == 0.0
        assert stats["var"][names.index(name)] == 0.25
    assert stats["var"][names.index("y_e")] != 0.25  # running statistics
    policy = load_policy(tmp_path / "agent")
    obs = np.zeros(len(names), np.float32)
    obs[names.index("x_e")] = 0.5
    actor = getattr(policy, "base", policy)  # a residual wrapper would hold the actor
    assert actor.normalize(obs)[names.index("x_e")] == pytest.approx(1.0, rel=1e-7)
    meta = json.loads((tmp_path / "agent" / "metadata.json").read_text())
    assert meta["config"]["obs_scales"] == {"x_e": 0.5, "z_e": 0.5}
