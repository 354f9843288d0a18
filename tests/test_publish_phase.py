"""Publishing a warm-start phase (`benchmarks/training/publish_phase.py`): the runs' final agents
with the guard recorded, each seed's whole history as one learning curve (a phase of a phase
included), the summaries merged, and runs that are not one phase refused by name."""

from __future__ import annotations

import csv
import json
import shutil

import pytest
import yaml

pytest.importorskip("stable_baselines3")

from benchmarks.training.publish_phase import main

pytestmark = pytest.mark.rl

ENV_ID = "AUVPath3DPreview-v0"
TINY = {
    "n_envs": 4,
    "n_timesteps": 256,
    "policy": "MlpPolicy",
    "normalize": True,
    "n_steps": 64,
    "batch_size": 128,
    "n_epochs": 1,
    "policy_kwargs": "dict(net_arch=[16])",
    "env_kwargs": {"randomize_start": True, "max_time": 20.0, "actuator": "paper"},
}


def _train(folder, out, seeds, *extra):
    from benchmarks.training.seeds_cli import main as train_seeds

    config = folder / "tiny.yml"
    if not config.exists():
        config.write_text(yaml.safe_dump({ENV_ID: TINY}))
    assert (
        train_seeds(
            [
                "--algo",
                "ppo",
                "--config",
                str(config),
                "--env-id",
                ENV_ID,
                "--seeds",
                seeds,
                "--workers",
                "1",
                "--eval-seeds",
                "100",
                "--eval-freq",
                "256",
                "--eval-duration",
                "110",
                "--quiet",
                "--out",
                str(out),
                *extra,
            ]
        )
        == 0
    )
    return out


def _rows(path):
    with path.open() as f:
        return [[float(x) for x in row[:2]] for row in list(csv.reader(f))[1:]]


@pytest.fixture(scope="module")
def phase(tmp_path_factory):
    """A history (two seeds from scratch, `--results`) and one phase from it, its seeds
    trained in two invocations."""
    root = tmp_path_factory.mktemp("phase")
    history = root / "history"
    _train(root, root / "scratch", "0-1", "--results", str(history))
    init = ["--init-from", str(history / "agent_seed_{seed}")]
    runs = [_train(root, root / "run_a", "0-0", *init), _train(root, root / "run_b", "1-1", *init)]
    return root, history, runs


def test_a_phase_becomes_a_results_folder_with_whole_histories(phase, capsys):
    root, history, runs = phase
    out = root / "published"
    summary = main(["--runs", *map(str, runs), "--out", str(out), "--allocation"])
    assert f"2 seed(s) of the phase from {history} in {out}" in capsys.readouterr().out
    assert [e["seed"] for e in summary["seeds"]] == [0, 1]
    assert summary["history"] == str(history)
    assert [r["folder"] for r in summary["runs"]] == [str(r) for r in runs]
    assert summary["session_wall_time_s"] == pytest.approx(
        sum(json.loads((r / "summary.json").read_text())["session_wall_time_s"] for r in runs)
    )
    for seed, run in enumerate(runs):
        final = run / f"seed_{seed}" / "final"
        agent = out / f"agent_seed_{seed}"
        assert (agent / "model.zip").read_bytes() == (final / "model.zip").read_bytes()
        meta = json.loads((agent / "metadata.json").read_text())
        assert meta["envelope_guard"]["surge_hard"] == 1.95
        assert meta["actuator_allocation"] == "paper"
        assert meta["guarded_from"] == str(final)
        phase_rows = _rows(run / f"seed_{seed}" / "evaluations.csv")
        assert _rows(out / f"seed_{seed}_phase_curve.csv") == phase_rows
        start = json.loads((history / f"agent_seed_{seed}" / "metadata.json").read_text())
        before = [
            r
            for r in _rows(history / f"seed_{seed}_learning_curve.csv")
            if r[0] <= start["num_timesteps"]
        ]
        whole = _rows(out / f"seed_{seed}_learning_curve.csv")
        assert whole[: len(before)] == before
        shifted = whole[len(before) :]
        assert [r[0] - start["num_timesteps"] for r in shifted] == [r[0] for r in phase_rows]
        # wall time counted on from the end of the history agent's training, to 0.1 s
        for mine, theirs in zip(shifted, phase_rows, strict=True):
            assert mine[1] == pytest.approx(theirs[1] + start["wall_time_s"], abs=0.051)


def test_a_phase_of_a_phase_counts_on_from_the_whole_history(phase):
    root, history, runs = phase
    first = root / "first"
    main(["--runs", *map(str, runs), "--out", str(first), "--no-guard", "--allocation"])
    run = _train(root, root / "run_c", "0-0", "--init-from", str(first / "agent_seed_{seed}"))
    second = root / "second"
    main(["--runs", str(run), "--out", str(second), "--no-guard", "--allocation"])
    whole = _rows(second / "seed_0_learning_curve.csv")
    # the history's agent (the best of its run: maybe not its last step), then 256 steps
    start = json.loads((history / "agent_seed_0" / "metadata.json").read_text())["num_timesteps"]
    offset = start + TINY["n_timesteps"]
    phase_rows = _rows(run / "seed_0" / "evaluations.csv")
    assert [r[0] for r in whole[-len(phase_rows) :]] == [r[0] + offset for r in phase_rows]
    assert whole[: -len(phase_rows)] == _rows(first / "seed_0_learning_curve.csv")
    assert [r[0] for r in whole] == sorted(r[0] for r in whole)
    assert [r[1] for r in whole] == sorted(r[1] for r in whole)


def _refused(capsys, argv):
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    return err[-1]


def test_runs_that_are_not_one_phase_are_refused_by_name(phase, tmp_path, capsys):
    root, _, runs = phase
    out = str(tmp_path / "out")
    err = _refused(capsys, ["--runs", str(runs[0]), str(runs[0]), "--out", out])
    assert f"seed 0 is in both {runs[0]} and {runs[0]}" in err
    err = _refused(capsys, ["--runs", str(root / "scratch"), "--out", out])
    assert f"{root / 'scratch'} is not a warm-start phase (its plan has no init_from)" in err
    other = tmp_path / "other"
    other.mkdir()
    summary = json.loads((runs[1] / "summary.json").read_text())
    summary["plan"]["config"] = {**summary["plan"]["config"], "n_epochs": 2}
    (other / "summary.json").write_text(json.dumps(summary))
    (other / "train_seeds.json").write_text(json.dumps(summary["plan"]))
    err = _refused(capsys, ["--runs", str(runs[0]), str(other), "--out", out])
    assert f"{other} is not of the same phase as {runs[0]}: config differ" in err
    err = _refused(capsys, ["--runs", str(tmp_path / "nowhere"), "--out", out])
    assert "nowhere/summary.json is missing: a finished `train_seeds` run's summary" in err
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "keep.txt").write_text("mine")
    err = _refused(capsys, ["--runs", str(runs[0]), "--out", str(tmp_path / "full")])
    assert f"--out {tmp_path / 'full'} is not empty" in err
    assert not (tmp_path / "out").exists()


def test_a_seed_that_cannot_be_published_leaves_no_folder(phase, tmp_path, capsys):
    """Seed 0 is written before seed 1's curve turns out missing: the folder appears whole or
    not at all."""
    _, _, runs = phase
    broken = tmp_path / "run_b"
    shutil.copytree(runs[1], broken)
    (broken / "seed_1" / "evaluations.csv").unlink()
    out = tmp_path / "out"
    err = _refused(capsys, ["--runs", str(runs[0]), str(broken), "--out", str(out)])
    assert f"{broken / 'seed_1' / 'evaluations.csv'} is missing: a seed's learning curve" in err
    assert not out.exists()
    assert [p.name for p in tmp_path.iterdir()] == ["run_b"]  # no temporary folder left
