"""The `auv-gym` command behaves like the tools people know: --version, one command listing,
exit codes of the commands it runs, and a word about compiling on the first run."""

from __future__ import annotations

import re

import pytest

from auv_gym import __version__
from benchmarks import cli


def test_version_and_one_listing_of_the_commands(capsys):
    with pytest.raises(SystemExit) as stop:
        cli.main(["--version"])
    assert stop.value.code == 0 and capsys.readouterr().out.strip() == f"auv-gym {__version__}"
    with pytest.raises(SystemExit) as stop:
        cli.main(["--help"])
    listing = capsys.readouterr().out
    assert stop.value.code == 0
    for name in cli.COMMANDS:
        assert len(re.findall(rf"^ +{name}\b(?!-)", listing, re.M)) == 1, name  # listed once
    with pytest.raises(SystemExit) as stop:
        cli.main([])
    assert stop.value.code == 2 and "required: COMMAND" in capsys.readouterr().err


def test_a_commands_returned_exit_code_is_the_commands(capsys):
    # train-seeds returns 2 (instead of raising) for a bad option: the command must say so too.
    assert cli.main(["train-seeds", "--seeds", "0", "--out", "unused"]) == 2
    assert "--seeds" in capsys.readouterr().err


def test_ctrl_c_ends_a_command_with_one_line_and_exit_code_130(monkeypatch, capsys):
    """Was: Ctrl-C printed a traceback of 24-90 lines from wherever the command was."""

    def interrupted(module, prog, argv):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_run", interrupted)
    monkeypatch.setattr(cli, "_compile_notice", lambda: None)
    assert cli.main(["compare", "--policies", "fbsm"]) == 130
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("auv-gym compare: interrupted; finished ")


def test_first_run_says_it_is_compiling_and_remembers_when_done(monkeypatch, capsys):
    marked = []
    monkeypatch.setattr(cli, "kernels_are_cached", lambda *packages: False)
    monkeypatch.setattr(cli, "mark_kernels_cached", lambda *packages: marked.append(packages))
    monkeypatch.setattr(cli, "_run", lambda module, prog, argv: 0)
    assert cli.main(["compare", "--seeds", "1"]) == 0
    assert "compiling the simulation kernels" in capsys.readouterr().err
    assert len(marked) == 1  # remembered after a command that ran to its end
    monkeypatch.setattr(cli, "_run", lambda module, prog, argv: 2)
    assert cli.main(["compare", "--seeds", "1"]) == 2 and len(marked) == 1  # not after a failure
    capsys.readouterr()
    cli.main(["compare", "--help"])
    assert "compiling" not in capsys.readouterr().err  # help compiles nothing
    monkeypatch.setattr(cli, "kernels_are_cached", lambda *packages: True)
    monkeypatch.setattr(cli, "_run", lambda module, prog, argv: 0)
    assert cli.main(["compare"]) == 0 and "compiling" not in capsys.readouterr().err


def test_training_ends_with_a_summary_and_warns_about_an_untrained_best(tmp_path):
    import json

    from benchmarks.training.train_cli import training_report

    best = tmp_path / "run" / "best"
    best.mkdir(parents=True)
    summary = {"rms_distance_mean": 0.4321, "n_terminated": 1, "n_episodes": 32}
    (best / "metadata.json").write_text(
        json.dumps({"best": {"num_timesteps": 250_000, "summary": summary}})
    )
    line = training_report(tmp_path / "run", "agents/mine")
    assert line == (
        "training: best evaluation at step 250,000: mean RMS distance 0.4321 m, 1 of 32 "
        "episodes ended early; exported to agents/mine"
    )
    (best / "metadata.json").write_text(
        json.dumps({"best": {"num_timesteps": 0, "summary": summary}})
    )
    assert "WARNING: the best agent is the UNTRAINED network of step 0" in training_report(
        tmp_path / "run", "agents/mine"
    )
    assert "no evaluation ran" in training_report(tmp_path / "other")


def test_an_agent_on_a_base_install_is_refused_before_any_episode(monkeypatch, tmp_path, capsys):
    import importlib

    from benchmarks.catalog import policies
    from benchmarks.runner import compare

    real = importlib.import_module

    def without_torch(name, *args):
        if name == "torch":
            raise ModuleNotFoundError("No module named 'torch'", name="torch")
        return real(name, *args)

    monkeypatch.setattr(importlib, "import_module", without_torch)
    monkeypatch.setattr(compare, "run_jobs", lambda *a, **k: pytest.fail("an episode ran"))
    with pytest.raises(policies.MissingExtraError, match=r"pip install 'auv-gym\[rl\]'"):
        policies.check_policy_spec("ppo_generalist")
    code = cli.main(
        [
            "compare",
            "--policies",
            "fbsm,ppo_generalist",
            "--scenarios",
            "paper",
            "--seeds",
            "1",
            "--out",
            str(tmp_path / "out"),
        ]
    )
    assert code == 2
    assert "running an agent needs torch, from the 'rl' extra" in capsys.readouterr().err
    assert policies.check_policy_spec("fbsm").kind == "classical"  # classical ones still run


@pytest.mark.rl
def test_video_runs_a_speed_limited_agent_under_its_own_env(tmp_path):
    from benchmarks.reports.video import parse_args

    args = parse_args(["--policy", "ppo_residual", "--out", str(tmp_path / "v.mp4")])
    assert args.env_id == "AUVPath3DSpeedLimit-v0"
    assert parse_args(["--policy", "fbsm", "--out", str(tmp_path / "f.mp4")]).env_id == (
        "AUVPath3D-v0"
    )


def test_paper_figures_run_each_policy_under_its_env_id(tmp_path):
    from benchmarks.reports.paper_figures import make_figures
    from tests.test_plotting import LOSPolicy

    result = make_figures(
        {"plain": LOSPolicy(), "limited": LOSPolicy()},
        tmp_path,
        duration=4.0,
        seed=1,
        dpi=30,
        env_ids={"limited": "AUVPath3DSpeedLimit-v0"},
    )
    assert set(result["metrics"]) == {"plain", "limited"}
    from auv_gym.sim.trajectory import Trajectory

    plain = Trajectory.load(tmp_path / "trajectories" / "plain.npz")
    limited = Trajectory.load(tmp_path / "trajectories" / "limited.npz")
    assert limited.metadata["env_kwargs"]["surge_limit"] == "vehicle"  # REMUS 100: 2.0 m/s
    assert plain.metadata["env_kwargs"].get("surge_limit", float("inf")) == float("inf")


def test_docs_prints_the_manual_folder_and_its_pages(capsys):
    from pathlib import Path

    assert cli.main(["docs"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert (Path(lines[0]) / "model.md").is_file()
    assert any(line.split()[0] == "results.md" for line in lines[1:])
