"""The navigation split of the as-built test sets (`benchmarks.analysis.navigation_floor`): its
distance is the suite's, its parts are what the policy saw and what the estimate hid."""

from __future__ import annotations

import math

import numpy as np
import pytest

from auv_gym.rollout import evaluate, rollouts
from benchmarks.analysis import navigation_floor
from benchmarks.analysis.navigation_floor import error_split, markdown, target_rest
from benchmarks.catalog.policies import build_policy
from benchmarks.catalog.tasks import task_set
from benchmarks.runner.suite_chunks import Chunk, resolve_policy

SET = "test_as_built_tight_deep"
KINDS = ("true", "seen", "navigation")
DURATION, WINDOW = 104.0, 100.0  # [s]: four seconds of window keep the test short


def _env(spec: str) -> dict:
    policy = resolve_policy(spec)
    return Chunk(policy.name, policy.runs[0], task_set(SET), DURATION, WINDOW).env_kwargs


def test_distance_is_the_suites_and_the_navigation_share_is_measured():
    row = error_split("pid_as_built", SET, DURATION, WINDOW)
    env = _env("pid_as_built")
    policy = build_policy("pid_as_built", env, task_set(SET).controller)
    suite = evaluate(policy, list(task_set(SET).seeds), transient=WINDOW, **env)
    assert row["episodes"] == 10 and row["failed"] == 0
    assert row["rms_distance_m"] == np.mean([r["rms_distance"] for r in suite])
    # The filter's error is decimetres (docs/model.md §14.8): neither zero nor metres.
    assert 0.05 < row["rms_navigation_m"] < 1.0
    assert row["rms_seen_m"] != pytest.approx(row["rms_distance_m"], rel=1e-3)
    # Per episode RMS |n|² is the sum of the axes' RMS²; over episodes the means obey Minkowski.
    axes = row["rms_by_axis_m"]["navigation"]
    norm = math.sqrt(sum(v**2 for v in axes.values()))
    assert 0.8 * row["rms_navigation_m"] <= norm <= row["rms_navigation_m"] + 1e-12
    # Across the path (y_e, z_e) the share is part of the whole, and most of it on the helices.
    across = row["rms_navigation_across_m"]
    assert 0.5 * row["rms_navigation_m"] < across < row["rms_navigation_m"]
    # per episode it is hypot(RMS y_e, RMS z_e); over episodes the mean lies between these two
    assert math.hypot(axes["y_e"], axes["z_e"]) - 1e-12 <= across <= axes["y_e"] + axes["z_e"]


def test_seen_errors_are_the_observed_ones_and_e_minus_n_is_them():
    """Flown again by hand: the recorded e^ are the observation's x_e, y_e, z_e, so e − n = e^."""
    env = _env("pid_as_built")
    policy = build_policy("pid_as_built", env, task_set(SET).controller)
    recorder = navigation_floor._SeenErrors(policy)
    flight = rollouts(recorder, [0], **env)[0]
    seen = np.stack(recorder.seen, axis=1)[0]
    true = np.stack([flight.samples[f][:-1] for f in ("x_e", "y_e", "z_e")], axis=1)
    assert seen.shape == true.shape
    # Without navigation error the two would be equal; with the filter they differ by decimetres.
    gap = np.linalg.norm(true - seen, axis=1)
    assert 0.01 < float(np.sqrt(np.mean(gap**2))) < 1.0


def test_correlation_across_is_pooled_over_the_windows_and_completes_the_square():
    """ρ recomputed by hand from the set's flights: Σ e^·n / √(Σ|e^|² Σ|n|²) over y_e, z_e of
    every sample in the window, and with it |e_yz|² = |e^_yz|² + |n_yz|² + 2ρ|e^_yz||n_yz|."""
    row = error_split("pid_as_built", SET, DURATION, WINDOW)
    env = _env("pid_as_built")
    recorder = navigation_floor._SeenErrors(
        build_policy("pid_as_built", env, task_set(SET).controller)
    )
    flights = rollouts(recorder, list(task_set(SET).seeds), **env)
    seen_all = np.stack(recorder.seen, axis=1)
    true, seen = [], []
    for i, flight in enumerate(flights):
        steps = len(flight.t) - 1
        window = flight.t[:steps] >= WINDOW
        true.append(np.stack([flight.samples[f][:steps] for f in ("y_e", "z_e")], 1)[window])
        seen.append(seen_all[i, :steps, 1:][window])
    e, e_hat = np.concatenate(true), np.concatenate(seen)
    n = e - e_hat
    rho = np.sum(e_hat * n) / math.sqrt(np.sum(e_hat**2) * np.sum(n**2))
    assert row["corr_seen_navigation_across"] == pytest.approx(rho, rel=1e-12)
    assert -1.0 < rho < 1.0 and rho != 0.0
    square = np.sum(e_hat**2) + np.sum(n**2) + 2 * rho * math.sqrt(np.sum(e_hat**2) * np.sum(n**2))
    assert np.sum(e**2) == pytest.approx(square, rel=1e-9)


def test_agent_flies_with_its_own_observation():
    row = error_split("ppo_as_built=benchmarks/agents/ppo_as_built", SET, DURATION, WINDOW)
    assert row["policy"] == "ppo_as_built" and row["failed"] == 0
    assert 0.05 < row["rms_distance_m"] < 1.0


def test_markdown_ratio_is_navigation_over_the_references_distance():
    rows = [
        {
            "policy": "a",
            "set": "scenario:s",
            "episodes": 10,
            "failed": 0,
            "rms_distance_m": 0.4,
            "rms_seen_m": 0.3,
            "rms_navigation_m": 0.3,
            "rms_navigation_across_m": 0.2,
            "corr_seen_navigation_across": -0.031,
            "rms_by_axis_m": {k: {"x_e": 0.1, "y_e": 0.2, "z_e": 0.05} for k in KINDS},
            "rms_slow_by_axis_m": {k: {"x_e": 0.0, "y_e": 0.16, "z_e": 0.03} for k in KINDS},
            "rms_fast_by_axis_m": {k: {"x_e": 0.1, "y_e": 0.12, "z_e": 0.04} for k in KINDS},
        },
        {
            "policy": "b",
            "set": "scenario:s",
            "episodes": 10,
            "failed": 0,
            "rms_distance_m": 0.2,
            "rms_seen_m": 0.25,
            "rms_navigation_m": 0.1,
            "rms_navigation_across_m": 0.06,
            "corr_seen_navigation_across": 0.2,
            "rms_by_axis_m": {k: {"x_e": 0.01, "y_e": 0.02, "z_e": 0.005} for k in KINDS},
            "rms_slow_by_axis_m": {k: {"x_e": 0.0, "y_e": 0.0, "z_e": 0.0} for k in KINDS},
            "rms_fast_by_axis_m": {k: {"x_e": 0.01, "y_e": 0.02, "z_e": 0.005} for k in KINDS},
        },
    ]
    table = markdown(rows, ["a", "b"], "cmd")
    assert "| `s` | a | 0/10 | 0.400 | 0.300 | 0.300 | 0.75 | 0.200 | 0.50 | -0.03 |" in table
    assert "| `s` | b | 0/10 | 0.200 | 0.250 | 0.100 | 0.25 | 0.060 | 0.15 | +0.20 |" in table
    assert "| `s` | a | 0.100, 0.200, 0.050 | 0.100, 0.200, 0.050 | 0.100, 0.200, 0.050 |" in table
    assert "| `s` | a | 0.160, 0.120 | 0.160, 0.120 | 0.160, 0.120 |" in table


def _row(policy: str, set_name: str, distance: float, across: float) -> dict:
    return {
        "policy": policy,
        "set": set_name,
        "episodes": 10,
        "failed": 0,
        "rms_distance_m": distance,
        "rms_seen_m": distance,
        "rms_navigation_m": across,
        "rms_navigation_across_m": across,
        "corr_seen_navigation_across": 0.0,
        "rms_by_axis_m": {k: {"x_e": 0.0, "y_e": across, "z_e": 0.0} for k in KINDS},
        "rms_slow_by_axis_m": {k: {"x_e": 0.0, "y_e": across, "z_e": 0.0} for k in KINDS},
        "rms_fast_by_axis_m": {k: {"x_e": 0.0, "y_e": 0.0, "z_e": 0.0} for k in KINDS},
    }


def test_target_rest_is_measured_against_the_best_classical_per_set():
    rows = [
        _row("pid", "s", 0.5, 0.3),
        _row("pid_fast", "s", 0.4, 0.3),  # the best classical on s: T = 0.32 m
        _row("agent", "s", 0.35, 0.3),
        _row("pid", "t", 0.3, 0.3),  # the floor alone exceeds T = 0.24 m: nothing allowed
        _row("pid_fast", "t", 0.6, 0.1),
        _row("agent", "t", 0.25, 0.3),
    ]
    out = {(t["policy"], t["set"]): t for t in target_rest(rows, ["pid", "pid_fast"])}
    agent = out[("agent", "s")]
    assert agent["best_classical"] == "pid_fast"
    assert agent["target_m"] == pytest.approx(0.32)
    assert agent["rest_m"] == pytest.approx(math.sqrt(0.35**2 - 0.09))  # 0.180 m
    assert agent["rest_allowed_m"] == pytest.approx(math.sqrt(0.32**2 - 0.09))  # 0.111 m
    assert agent["rest_ratio"] == pytest.approx(1.62, abs=0.005)
    assert out[("pid", "t")]["best_classical"] == "pid"
    assert out[("pid", "t")]["rest_m"] == 0.0
    assert out[("agent", "t")]["rest_allowed_m"] == 0.0
    assert out[("agent", "t")]["rest_ratio"] == math.inf
    # One classical policy: its own target is 0.8 x itself, its rest ratio above 1.
    alone = {(t["policy"], t["set"]): t for t in target_rest(rows, ["pid"])}
    assert alone[("pid_fast", "s")]["target_m"] == pytest.approx(0.4)
    assert alone[("pid", "s")]["rest_ratio"] == pytest.approx(0.4 / math.sqrt(0.07), abs=1e-9)
    table = markdown(rows, ["pid", "pid_fast", "agent"], "cmd", ["pid", "pid_fast"])
    assert "| `s` | agent | 0.350 | 0.320 (pid_fast) | 0.180 | 0.111 | 1.62 |" in table


def test_unknown_set_is_refused_by_name():
    with pytest.raises(ValueError, match="no_such_set"):
        error_split("pid_as_built", "no_such_set", DURATION, WINDOW)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--sets", "test_as_built_tight_deep,nope"], "nope"),
        (["--policies", "pid_as_built,no_such_policy"], "no_such_policy"),
        (["--policies", "pid_as_built,pid_as_built"], "pid_as_built"),
        (["--policies", "pid_as_built", "--classical", "pid_as_built_climb"], "pid_as_built_climb"),
    ],
)
def test_bad_names_are_one_line_errors_before_any_episode(argv, message, tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        navigation_floor.main([*argv, "--out", str(tmp_path / "out")])
    assert stop.value.code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_slow_part_keeps_a_drift_and_drops_the_waves():
    """A 0.005-Hz drift with an offset plus a 0.13-Hz wave motion (20 ms samples, 200 s): the
    slow part is the drift and offset to 1e-9 m, the parts add up to the series and their mean
    squares to its own (Parseval)."""
    t = np.arange(0.0, 200.0, 0.02)
    drift = 0.05 + 0.2 * np.sin(2 * np.pi * 0.005 * t)
    waves = 0.1 * np.sin(2 * np.pi * 0.13 * t)
    series = np.stack([drift + waves, waves], axis=1)
    slow = navigation_floor.slow_part(series, 0.02)
    assert np.max(np.abs(slow[:, 0] - drift)) < 1e-9 and np.max(np.abs(slow[:, 1])) < 1e-9
    fast = series - slow
    assert np.mean(series**2) == pytest.approx(np.mean(slow**2) + np.mean(fast**2), rel=1e-12)


def test_the_split_by_time_scale_brackets_each_axis():
    """Per episode RMS² = slow² + fast² (Parseval), so over episodes each axis's mean RMS lies
    between the larger part and the sum of the parts, for every kind and axis."""
    row = error_split("pid_as_built", SET, DURATION, WINDOW)
    for kind in KINDS:
        for axis in ("x_e", "y_e", "z_e"):
            total = row["rms_by_axis_m"][kind][axis]
            slow = row["rms_slow_by_axis_m"][kind][axis]
            fast = row["rms_fast_by_axis_m"][kind][axis]
            assert max(slow, fast) <= total * (1 + 1e-12) and total <= (slow + fast) * (1 + 1e-12)
            assert total > 0.0
