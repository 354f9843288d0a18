"""The ONNX parity check (`benchmarks.checks.onnx_parity`) on a two-set suite: the as-built
agent flies the set on its own actuator, with its export beside it, and not the fins set."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from benchmarks.catalog.tasks import test_suite
from benchmarks.checks import onnx_parity


@pytest.fixture
def two_sets(monkeypatch):
    """The suite cut to one episode of `fins` (paper-style moments) and one of
    `as_built_helix` (propeller and fins)."""
    wanted = ("scenario:fins", "scenario:as_built_helix")
    sets = [
        dataclasses.replace(task, seeds=range(task.seeds.start, task.seeds.start + 1))
        for task in test_suite()
        if task.name in wanted
    ]
    assert [task.name for task in sets] == list(wanted)
    monkeypatch.setattr(onnx_parity, "test_suite", lambda: sets)
    return sets


def test_the_as_built_agent_flies_only_its_actuator_and_its_export_agrees(two_sets, tmp_path):
    row = onnx_parity.check(onnx_parity.Exports("ppo_as_built", tmp_path), None, 20.0)
    assert row["not_flown"] == ["scenario:fins"]
    assert row["episodes"] == 1
    assert list(row["max_relative_rms_error_by_set"]) == ["scenario:as_built_helix"]
    assert row["observations"] == 400  # 20 s at the 0.05-s control period
    assert row["max_abs_command_error"] <= onnx_parity.COMMAND_TOLERANCE
    assert row["max_relative_rms_error"] <= onnx_parity.RMS_TOLERANCE


def test_rows_are_written_as_each_export_finishes(tmp_path):
    row = {
        "label": "ppo_as_built",
        "episodes": 1,
        "observations": 200,
        "max_abs_command_error": 2e-7,
        "surge_at_max_error": 1.0,
        "max_relative_rms_error": 0.0,
        "max_relative_rms_error_by_set": {"scenario:as_built_helix": 0.0},
        "nudged_relative_rms_difference_by_set": {"scenario:as_built_helix": 1e-8},
        "rms_target": "met",
        "not_flown": ["scenario:fins"],
    }
    onnx_parity.write_results(tmp_path, 20.0, [row])
    assert json.loads((tmp_path / "parity.json").read_text())["rows"] == [row]
    text = (tmp_path / "parity.md").read_text()
    assert "| ppo_as_built | 1 | 200 | 2e-07 | 1.00 | 0 | 1e-08 | met |" in text
    assert "ppo_as_built: scenario:fins" in text


def test_rms_verdict_tells_a_sensitive_loop_from_a_missed_export():
    tolerance = onnx_parity.RMS_TOLERANCE
    assert onnx_parity.rms_verdict({"a": tolerance / 2}, {"a": 0.0}) == "met"
    # beyond the tolerance where the nudged agent moves as far: rounding, not the export
    assert onnx_parity.rms_verdict({"a": 0.5, "b": 0.0}, {"a": 0.8, "b": 0.0}) == "sensitive"
    # beyond it where the nudged agent stays put: the export differs
    assert onnx_parity.rms_verdict({"a": 0.5, "b": 0.01}, {"a": 0.8, "b": 0.0}) == "missed"


def test_a_nudge_moves_every_command_by_its_size_within_the_bounds():
    class Fixed:
        env_kwargs = None  # read by the nudge, unused here

        def predict(self, observation, state=None, episode_start=None, deterministic=True):
            return np.array([[0.5, -1.0, 1.0]], np.float32), state

    nudged = onnx_parity.NudgedPolicy(Fixed(), 1e-3)
    moved = np.concatenate([nudged.predict(None)[0] for _ in range(50)])
    assert np.allclose(np.abs(moved[:, 0] - 0.5), 1e-3, atol=1e-7)
    assert set(np.sign(moved[:, 0] - 0.5).tolist()) == {-1.0, 1.0}  # both signs drawn
    assert moved[:, 1].min() >= -1.0 and moved[:, 2].max() <= 1.0  # kept in the box


def test_checking_some_agents_keeps_the_other_agents_rows(tmp_path, monkeypatch):
    """Was: re-checking one agent rewrote parity.json with that agent's row alone."""

    def fake_check(exports, actuator, duration, nudges):
        return {"agent": exports.agent, "actuator": actuator, **VERDICT}

    monkeypatch.setattr(onnx_parity, "check", fake_check)
    monkeypatch.setattr(onnx_parity, "table", lambda rows: "")
    monkeypatch.setattr(onnx_parity, "write_results", _write_rows)
    old = [
        {"label": "ppo_generalist", "agent": "ppo_generalist", "run": "old", **VERDICT},
        {"label": "ppo_as_built", "agent": "ppo_as_built", "run": "old", **VERDICT},
        {"label": "sac_generalist", "agent": "sac_generalist", "run": "old", **VERDICT},
    ]
    (tmp_path / "parity.json").write_text(json.dumps({"duration_s": 30.0, "rows": old}))
    argv = ["--out", str(tmp_path), "--duration", "30", "--agents", "ppo_as_built"]
    rows = onnx_parity.main(argv)
    written = json.loads((tmp_path / "parity.json").read_text())["rows"]
    assert written == rows
    assert [(r["agent"], r.get("run", "new")) for r in rows] == [
        ("ppo_generalist", "old"),
        ("ppo_as_built", "new"),
        ("sac_generalist", "old"),
    ]
    # rows of another episode length are not comparable: not kept
    onnx_parity.main(["--out", str(tmp_path), "--duration", "60", "--agents", "ppo_as_built"])
    assert [r["agent"] for r in json.loads((tmp_path / "parity.json").read_text())["rows"]] == [
        "ppo_as_built"
    ]


VERDICT = {"max_abs_command_error": 1e-7, "rms_target": "met"}


def _write_rows(out, duration, rows):
    (out / "parity.json").write_text(json.dumps({"duration_s": duration, "rows": list(rows)}))


def test_several_nudges_keep_the_largest_difference(two_sets, tmp_path, monkeypatch):
    """``nudges=K`` flies the nudged agent with sign seeds 0..K-1 on every set beyond the
    tolerance (here every set: the tolerance set below 0) and keeps the largest difference,
    never less than the first draw's alone."""
    seeds: list[int] = []

    class Recorded(onnx_parity.NudgedPolicy):
        def __init__(self, python, size, seed=0):
            seeds.append(seed)
            super().__init__(python, size, seed)

    monkeypatch.setattr(onnx_parity, "NudgedPolicy", Recorded)
    monkeypatch.setattr(onnx_parity, "RMS_TOLERANCE", -1.0)
    exports = onnx_parity.Exports("ppo_as_built", tmp_path)
    one = onnx_parity.check(exports, None, 20.0)
    three = onnx_parity.check(exports, None, 20.0, nudges=3)
    assert seeds == [0, 0, 1, 2]
    assert (one["nudges"], three["nudges"]) == (1, 3)
    first = one["nudged_relative_rms_difference_by_set"]["scenario:as_built_helix"]
    largest = three["nudged_relative_rms_difference_by_set"]["scenario:as_built_helix"]
    assert 0.0 < first <= largest


def test_a_nudge_count_out_of_range_is_refused(capsys):
    with pytest.raises(SystemExit) as exit_info:
        onnx_parity.main(["--nudges", "0", "--agents", "ppo_as_built"])
    assert exit_info.value.code == 2
    assert "--nudges: 0 nudged flights" in capsys.readouterr().err
