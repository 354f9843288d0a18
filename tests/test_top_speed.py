"""The vehicle's top speed (`AUVParams.max_surge`) reaches the overspeed metric, the suite's
surge target and the residual agent's observation bounds; REMUS 100's 2.0 m/s gives the former
numbers, and every shipped agent's observation space is still its env's."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from auv_gym import resolve_env_id
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.metrics import compute_metrics
from auv_gym.rollout import rollout
from auv_gym.sim.observation import OBS_HIGH, OBS_LOW
from auv_gym.sim.trajectory import INTERVAL_FIELDS, SAMPLE_FIELDS, Trajectory
from auv_gym.vehicle import remus100
from benchmarks.analysis.suite_markdown import stats_markdown
from benchmarks.analysis.suite_stats import target_table, top_speeds
from benchmarks.training.residual import ResidualTraining
from benchmarks.training.residual_env import ResidualVectorEnv
from controllers.agent import check_agent, load_actor
from controllers.pid import PIDLOS
from controllers.residual import RESIDUAL_FEATURES, residual_observation_bounds

AGENTS = Path(__file__).resolve().parents[1] / "benchmarks" / "agents"


def _trajectory(u: np.ndarray, **kwargs) -> Trajectory:
    samples = {name: np.zeros(u.size) for name in SAMPLE_FIELDS}
    samples["u"] = u
    intervals = {name: np.zeros(u.size - 1) for name in INTERVAL_FIELDS}
    return Trajectory(
        t=0.5 * np.arange(u.size), samples=samples, intervals=intervals, control_dt=0.5, **kwargs
    )


def test_overspeed_counts_above_the_vehicles_top_speed(tmp_path: Path) -> None:
    u = np.array([0.0, 1.0, 2.5, 2.0, 1.6, 1.5, 1.0])  # end samples above 1.5: 2.5, 2.0, 1.6
    remus = _trajectory(u)
    assert remus.top_speed == 2.0
    assert compute_metrics(remus, transient=0.0)["overspeed_fraction"] == 1 / 6
    slow = _trajectory(u, top_speed=1.5)
    assert compute_metrics(slow, transient=0.0)["overspeed_fraction"] == 3 / 6
    remus.save(tmp_path / "remus.npz")
    slow.save(tmp_path / "slow.npz")
    with np.load(tmp_path / "remus.npz") as data:  # a REMUS file as before: no new key
        assert "top_speed" not in json.loads(str(data["metadata"]))
    assert Trajectory.load(tmp_path / "remus.npz").top_speed == 2.0
    assert Trajectory.load(tmp_path / "slow.npz").top_speed == 1.5
    with pytest.raises(ValueError, match=r"top_speed must be a positive speed in m/s, got 0\.0"):
        _trajectory(u, top_speed=0.0)


def test_a_rollout_records_its_vehicles_top_speed() -> None:
    kwargs = {"max_time": 2.0}
    assert rollout(PIDLOS(), 0, **kwargs).top_speed == 2.0
    fast = rollout(PIDLOS(), 0, params=remus100().replace(max_surge=3.0), **kwargs)
    assert fast.top_speed == 3.0


def test_the_suite_target_is_each_sets_top_speed() -> None:
    suite = {"sets": {"remus": {"env": {}}, "slow": {"env": {"params": {"max_surge": 1.5}}}}}
    speeds = top_speeds(suite)
    assert speeds == {"remus": 2.0, "slow": 1.5}
    rows = [
        {"policy": p, "set": s, "termination_reason": "", "max_surge": 1.8}
        for p in ("ref", "new")
        for s in ("remus", "slow")
    ]
    scores = {"ref": np.ones((1, 2)), "new": np.ones((1, 2))}
    table = target_table(rows, scores, ["remus", "slow"], "ref", 2.0, speeds)
    assert [(t["set"], t["passed"]) for t in table] == [("remus", True), ("slow", False)]
    former = target_table(rows, scores, ["remus", "slow"], "ref", 2.0)  # REMUS 100's 2.0 m/s
    assert [t["passed"] for t in former] == [True, True]


def test_the_target_takes_each_sets_best_reference() -> None:
    rows = [
        {"policy": p, "set": s, "termination_reason": "", "max_surge": 1.5}
        for p in ("fbsm", "colos", "agent")
        for s in ("calm", "current")
    ]
    scores = {
        "fbsm": np.array([[0.10, 0.60]]),
        "colos": np.array([[0.12, 0.20]]),
        "agent": np.array([[0.14, 0.32]]),
    }
    table = target_table(rows, scores, ["calm", "current"], ["fbsm", "colos", "absent"], 1.5)
    assert [(t["set"], t["policy"], t["reference"]) for t in table] == [
        ("calm", "agent", "fbsm"),
        ("current", "agent", "colos"),
    ]
    assert [round(t["ratio"], 12) for t in table] == [1.4, 1.6]
    assert [t["passed"] for t in table] == [True, False]
    with pytest.raises(ValueError, match=r"target references \['x'\]: none was evaluated"):
        target_table(rows, scores, ["calm", "current"], ["x"], 1.5)


def test_the_target_ratio_has_a_paired_interval() -> None:
    """A policy at exactly 0.7× the reference on every episode has the CI [0.7, 0.7] whatever
    the episodes' spread (paired: each replicate resamples the same episodes for both); a noisy
    one's CI brackets its ratio and narrows with more episodes."""
    rng = np.random.default_rng(3)
    reference = rng.uniform(0.2, 0.6, size=(1, 40))
    scores = {"ref": reference, "scaled": 0.7 * reference}
    scores["noisy"] = 0.8 * reference * rng.lognormal(0.0, 0.2, size=(3, 40))
    rows = [{"policy": p, "set": "s", "termination_reason": "", "max_surge": 1.5} for p in scores]
    table = {t["policy"]: t for t in target_table(rows, scores, ["s"] * 40, "ref", 0.8, reps=500)}
    assert table["scaled"]["ratio_low"] == pytest.approx(0.7, abs=1e-12)
    assert table["scaled"]["ratio_high"] == pytest.approx(0.7, abs=1e-12)
    noisy = table["noisy"]
    assert noisy["ratio_low"] < noisy["ratio"] < noisy["ratio_high"]
    assert 0.02 < noisy["ratio_high"] - noisy["ratio_low"] < 0.3
    few = {p: x[:, :10] for p, x in scores.items()}
    narrow = noisy["ratio_high"] - noisy["ratio_low"]
    wide = target_table(rows, few, ["s"] * 10, "ref", 0.8, reps=500)[1]
    assert wide["ratio_high"] - wide["ratio_low"] > narrow
    again = target_table(rows, scores, ["s"] * 40, "ref", 0.8, reps=500)
    assert [t["ratio_low"] for t in again] == [t["ratio_low"] for t in table.values()]


def _markdown_target_line(speeds) -> str:
    stats = {
        "reference": "ref",
        "confidence": 0.95,
        "n_runs": {},
        "failure_score_m": {},
        "reps": 10,
        "seed": 0,
        "command": "c",
        "improvement_tables": {},
        "target": [],
        "verdicts": {},
        "learning_curve_notes": {},
    }
    text = stats_markdown(stats, {"iqm": {}, "mean": {}}, 2.0, speeds)
    return next(line for line in text.splitlines() if line.startswith("## Target"))


def test_the_suite_markdown_names_the_surge_target() -> None:
    former = "## Target: mean RMS distance within 2× ref, no failed episode, max surge ≤ 2 m/s"
    assert _markdown_target_line(None) == former
    assert _markdown_target_line({"a": 2.0, "b": 2.0}) == former
    assert _markdown_target_line({"a": 1.5}).endswith("max surge ≤ 1.5 m/s")
    assert _markdown_target_line({"a": 1.5, "b": 2.0}).endswith(
        "max surge ≤ the top speed of the set's vehicle"
    )


def test_residual_bounds_are_the_envs_for_its_vehicle() -> None:
    ones = np.ones(6, np.float32)
    low, high = residual_observation_bounds()
    np.testing.assert_array_equal(low, np.concatenate([OBS_LOW, -ones]))  # bit for bit
    np.testing.assert_array_equal(high, np.concatenate([OBS_HIGH, ones]))
    assert low.dtype == high.dtype == np.float32
    fast = remus100().replace(max_surge=3.0)  # speed bound 5 × 3 = 15 m/s, above REMUS's 10
    core = AUVPath3DVectorEnv(2, params=fast, max_time=2.0)
    env = ResidualVectorEnv(core, ResidualTraining())
    space, core_space = env.single_observation_space, core.single_observation_space
    np.testing.assert_array_equal(space.low[:15], core_space.low)
    np.testing.assert_array_equal(space.high[:15], core_space.high)
    assert space.high[6] == 15.0 and OBS_HIGH[6] == 10.0  # u
    np.testing.assert_array_equal(space.low, residual_observation_bounds(3.0)[0])
    env.close()


@pytest.mark.parametrize("name", sorted(p.parent.name for p in AGENTS.glob("*/model.zip")))
def test_shipped_agents_load_with_their_envs_observation_space(name: str) -> None:
    pytest.importorskip("stable_baselines3")
    files = check_agent(AGENTS / name)
    actor = load_actor(files)
    seen = {"observation": files.metadata["observation"]} if "observation" in files.metadata else {}
    env_kwargs = {**files.metadata.get("env_kwargs", {}), **seen}  # the env the agent carries
    env = gym.make(resolve_env_id(files.metadata["env_id"]), **env_kwargs)
    low, high = env.observation_space.low, env.observation_space.high
    if "residual" in files.metadata:  # the env's observation, then b and a_{k−1} in ±1
        ones = np.ones(len(RESIDUAL_FEATURES), np.float32)
        low, high = np.concatenate([low, -ones]), np.concatenate([high, ones])
    np.testing.assert_array_equal(actor.observation_space.low, low)
    np.testing.assert_array_equal(actor.observation_space.high, high)
    env.close()
