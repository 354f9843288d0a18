"""The metrics window rule (docs/design.md §3.9), shared by `compute_metrics`, the benchmark and
the training evaluation: never a silent NaN."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from test_evaluation import synthetic_trajectory

import controllers
from auv_gym.metrics import (
    MetricsWindowWarning,
    check_window,
    compute_metrics,
    window_start,
)
from auv_gym.rollout import rollout


@pytest.mark.parametrize(
    ("duration", "transient", "expected"),
    [
        (300.0, None, 100.0),
        (200.0, None, 100.0),
        (20.0, None, 10.0),
        (20.0, 3.0, 3.0),
        (300.0, 0.0, 0.0),
    ],
)
def test_window_start_rule(duration, transient, expected):
    assert window_start(duration, transient) == expected


@pytest.mark.parametrize(
    ("duration", "transient", "control_dt", "message"),
    [
        (20.0, 20.0, 0.05, "fewer than two samples"),
        (20.0, 19.99, 0.05, "transient ≤ 19.95 s"),
        (0.05, None, 0.05, "fewer than two samples"),
        (0.0, None, 0.05, "duration must be a positive"),
        (20.0, -1.0, 0.05, "transient must be a non-negative"),
        (20.0, math.nan, 0.05, "transient must be a non-negative"),
    ],
)
def test_check_window_refuses_windows_without_a_metric(duration, transient, control_dt, message):
    with pytest.raises(ValueError, match=message):
        check_window(duration, transient, control_dt)
    assert check_window(0.1, None, 0.05) == 0.05  # samples at 0.05 and 0.1 s: two


def test_default_window_follows_the_planned_length():
    """Without max_time in the metadata, the recorded duration (10 s) sets the window: t ≥ 5 s."""
    default = compute_metrics(synthetic_trajectory())
    explicit = compute_metrics(synthetic_trajectory(), transient=5.0)
    assert default["transient"] == 5.0 and default["window_samples"] == 6
    assert default == explicit
    # A recorded max_time of 300 s puts the window at 100 s even if the episode stopped at 10 s.
    stopped = synthetic_trajectory(metadata={"max_time": 300.0}, termination_reason="pitch")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a failed episode explains itself: no warning
        failed = compute_metrics(stopped)
    assert failed["transient"] == 100.0 and failed["window_samples"] == 0
    assert math.isnan(failed["rms_distance"]) and failed["termination_reason"] == "pitch"


def test_short_rollout_gets_finite_metrics():
    """The issue's case: a 20-s rollout used to give NaN (window fixed at 100 s)."""
    tr = rollout(controllers.make("backstepping"), 0, max_time=20.0, disturbance="none")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m = compute_metrics(tr)
    assert m["transient"] == 10.0 and m["window_samples"] == 201  # t = 10.00 … 20.00 s
    windowed = ("rms_distance", "rms_y_e", "max_distance_window", "chattering", "rms_speed_error")
    assert all(np.isfinite(m[k]) for k in windowed)
    # The old fixed window, asked for explicitly, is empty: NaN with a warning and a count of 0.
    with pytest.warns(MetricsWindowWarning, match=r"t ≥ 100 s holds 0 sample"):
        old = compute_metrics(tr, transient=100.0)
    assert old["window_samples"] == 0 and math.isnan(old["rms_distance"])


def test_training_refuses_an_evaluation_without_a_metric(tmp_path):
    pytest.importorskip("stable_baselines3")
    from benchmarks.training import TrainOptions, train
    from benchmarks.training.evaluation import check_evaluation_duration

    assert check_evaluation_duration(20.0) == 10.0
    out = tmp_path / "run"
    with pytest.raises(ValueError, match=r"evaluation duration 0\.04 s: .*fewer than two samples"):
        train(TrainOptions(out=str(out), eval_duration=0.04, n_timesteps=64))
    assert not out.exists()  # refused before anything started


def test_compare_refuses_a_transient_beyond_the_episode(tmp_path, capsys):
    from benchmarks.runner import compare

    with pytest.raises(SystemExit) as exit_info:  # a usage error: one line, exit code 2
        compare.main(
            [
                "--policies",
                "backstepping",
                "--scenarios",
                "nominal",
                "--seeds",
                "1",
                "--duration",
                "10",
                "--transient",
                "9.99",
                "--out",
                str(tmp_path / "c"),
                "--quiet",
                "--no-figures",
            ]
        )
    assert exit_info.value.code == 2
    assert "fewer than two samples" in capsys.readouterr().err
    assert not (tmp_path / "c").exists()
