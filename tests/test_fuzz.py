"""The long fuzz run (`benchmarks.checks.fuzz`): its configurations are valid; it sees violations.

The run itself (>= 10^7 vehicle-steps) is a benchmark; here a short one, and the same checks
against a vector env that misbehaves on purpose.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.sim.config import SimConfig
from benchmarks.checks import fuzz


def test_drawn_configurations_are_valid_and_span_the_ranges():
    drawn, refused = [], []
    for k in range(300):
        try:
            drawn.append(fuzz.draw_config(np.random.default_rng([0, k]), 1000))
        except ValueError as error:  # a constructor's named refusal of the path drawn
            refused.append(str(error))
    configs = [SimConfig.from_kwargs(**kw) for kw, _ in drawn]  # every other one accepted
    assert 0 < len(refused) < 15
    assert any("doubles back at waypoint" in text for text in refused)
    substeps = [c.substeps for c in configs]
    assert min(substeps) == 1 and max(substeps) > 1000
    assert all(c.max_steps == n for c, (_, n) in zip(configs, drawn, strict=True))
    steps = [n for _, n in drawn]
    assert all(
        n * s <= fuzz.EPISODE_PHYSICS or n == 1 for n, s in zip(steps, substeps, strict=True)
    )
    kinds = {
        type(kw["path"]).__name__ if not isinstance(kw["path"], str) else kw["path"]
        for kw, _ in drawn
    }
    assert kinds == {
        "helix",
        "line",
        "waypoints",
        "Helix",
        "StraightLine",
        "Spline",
        "FittedCurve",
        "random",
        "PathDistribution",
    }
    assert {(kw.get("surge_limit"), kw.get("observation")) for kw, _ in drawn} == {
        (None, None),
        ("vehicle", None),
        ("vehicle", "preview"),
        (None, "preview_integral"),
        ("vehicle", "preview_integral"),
    }
    # the vehicle as built and its ocean, each drawn in some configurations
    for option in ("depth_envelope", "waves", "current_profile", "sensors", "safety_cost"):
        assert sum(option in kw for kw, _ in drawn) >= 10, option
    assert sum(kw["actuator"] == "realistic" for kw, _ in drawn) >= 30
    deep = [
        c
        for c in configs
        if (c.waves is not None and c.surface_above_path is None) or c.depth_envelope is not None
    ]
    assert deep and all(c.path_offset[2] > 16.0 for c in deep)  # drawn paths moved down
    # or the surface placed above any path, the ocean preset, the navigation filter
    assert sum(c.surface_above_path is not None for c in configs) >= 10
    assert sum(c.noise.hold == 1.0 and c.noise.amplitude[3] == 0.3 for c in configs) >= 1
    assert sum(c.sensors.navigation == "kalman" for c in configs) >= 5
    limited = [kw for kw, _ in drawn if isinstance(kw.get("params"), dict)]
    assert limited and all(kw["param_uncertainty"] > 0 for kw in limited)
    corridors = [kw["corridor"] for kw, _ in drawn]
    assert min(corridors) < 0.1 and max(corridors) > 100


def test_actions_include_the_extremes():
    actions = np.concatenate([fuzz.draw_actions(np.random.default_rng(k), 512) for k in range(4)])
    assert np.all(np.isfinite(actions))
    assert np.abs(actions).max() == np.finfo(np.float64).max
    assert 0 < np.abs(actions[actions != 0]).min() < 1e-300  # denormals
    assert np.any(np.all(actions == 0.0, axis=1)) and np.any(np.all(np.abs(actions) == 1, axis=1))


def test_a_short_run_finds_no_violation_and_reports_counts():
    tally = fuzz.run(30_000, seed=5, physics_budget=100_000, max_vehicles=64, progress=False)
    assert tally.steps >= 30_000 and tally.episodes > 0 and tally.violations == 0
    assert sum(tally.reasons.values()) == tally.episodes
    text = fuzz.report(tally, 1.0)
    assert "wrong truncations:         0" in text
    assert text.splitlines()[-1].startswith("verdict: PASS")


def corrupt_step(kind: str):
    """A vector-env step that breaks one invariant on vehicle 0."""
    honest = AUVPath3DVectorEnv.step

    def step(self, actions):
        obs, reward, terminated, truncated, info = honest(self, actions)
        if kind == "nan":
            obs[0, 0] = math.nan
        elif kind == "reward":
            reward[0] = math.inf
        elif kind == "truncation":
            truncated[0] = not truncated[0]
        elif kind == "outside":
            obs[0, 0] = 1e4
        return obs, reward, terminated, truncated, info

    return step


@pytest.mark.parametrize(
    ("kind", "counter"),
    [
        ("nan", "nan_observations"),
        ("reward", "non_finite_rewards"),
        ("truncation", "wrong_truncations"),
        ("outside", "out_of_space_observations"),
    ],
)
def test_the_checks_catch_a_misbehaving_env(kind, counter, monkeypatch):
    monkeypatch.setattr(AUVPath3DVectorEnv, "step", corrupt_step(kind))
    tally = fuzz.Tally()
    kw = {"disturbance": "none", "max_time": 0.5}
    fuzz.fuzz_configuration(kw, 10, 4, 20, 1e9, np.random.default_rng(0), tally, "test")
    assert tally.counts[counter] >= 10 and tally.examples[0].startswith(counter)
    assert fuzz.report(tally, 1.0).splitlines()[-1].startswith("verdict: FAIL")


def test_an_exception_is_counted_not_raised(monkeypatch):
    def boom(self, actions):
        raise RuntimeError("kernel exploded")

    monkeypatch.setattr(AUVPath3DVectorEnv, "step", boom)
    tally = fuzz.Tally()
    fuzz.fuzz_configuration({}, 10, 2, 5, 1e9, np.random.default_rng(0), tally, "here")
    assert tally.counts["exceptions"] == 1 and "kernel exploded" in tally.examples[0]
