"""The check, analysis, report and training command lines generated from their option
dataclasses: the former flags and defaults stay, each default and help is written once (in the
dataclass), and a bad value is one line on stderr with exit code 2."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from benchmarks.analysis import action_bounds, suite_merge
from benchmarks.arguments import parse_options
from benchmarks.checks import fuzz, reproduction
from benchmarks.options import flag_of
from benchmarks.reports import paper_figures
from benchmarks.training import train_cli


def _helps(options: type, parser) -> None:
    """One flag per option field, with the field's help."""
    fields = [f for f in dataclasses.fields(options) if "help" in f.metadata]
    flags = {flag_of(f): f.metadata["help"] for f in fields}
    by_flag = {a.option_strings[0]: a.help for a in parser._actions if a.option_strings}
    assert {k: by_flag[k] for k in flags} == flags


def _usage_error(capsys, main, argv: list[str], message: str) -> None:
    with pytest.raises(SystemExit) as stop:
        main(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and message in err and err.count("\n") == 1, err


def test_fuzz_options(capsys) -> None:
    parsed, parser = parse_options(fuzz.FuzzOptions, [], "prog", None)
    assert parsed == fuzz.FuzzOptions() == fuzz.FuzzOptions(1e7, 0, 2e6, 512, True)
    _helps(fuzz.FuzzOptions, parser)
    ns = parser.parse_args(["--quiet", "--physics-budget", "1e4", "--max-vehicles", "8"])
    assert (ns.quiet, ns.physics_budget, ns.max_vehicles, ns.steps, ns.seed) == (
        True,
        1e4,
        8,
        1e7,
        0,
    )
    _usage_error(capsys, fuzz.main, ["--steps", "x"], "argument --steps: invalid float value")
    _usage_error(capsys, fuzz.main, ["--max-vehicles", "0"], "--max-vehicles must be in [1, 65536]")


def test_check_reproduction_options(capsys, tmp_path: Path) -> None:
    options = reproduction.ReproductionOptions
    parsed, parser = parse_options(options, [], "prog", None, negatable=False)
    assert parsed == options() and (parsed.workers, parsed.keep) == (2, None)
    assert parsed.results == reproduction.RESULTS and not parsed.agents and not parsed.allow_new
    _helps(options, parser)
    parsed, _ = parse_options(
        options, ["--agents", "--allow-new", "--keep", str(tmp_path)], "prog", None, negatable=False
    )
    assert (parsed.agents, parsed.allow_new, parsed.keep) == (True, True, tmp_path)
    _usage_error(
        capsys,
        reproduction.main,
        ["--workers", "two"],
        "argument --workers: invalid int value: 'two'",
    )
    _usage_error(capsys, reproduction.main, ["--workers", "0"], "--workers must be ≥ 1, got 0")


def test_suite_merge_options(capsys) -> None:
    options = suite_merge.MergeOptions
    argv = ["--from", "a", "--into", "b", "--policies", "x,y"]
    parsed, parser = parse_options(options, argv, "prog", None)
    assert parsed == options(source="a", target="b", policies="x,y") and parsed.rtol == 1e-12
    _helps(options, parser)
    _usage_error(
        capsys,
        suite_merge.main,
        ["--from", "a"],
        "the following arguments are required: --into, --policies",
    )
    _usage_error(
        capsys,
        suite_merge.main,
        [*argv, "--rtol", "tiny"],
        "argument --rtol: invalid float value: 'tiny'",
    )


def test_paper_figures_options(capsys, tmp_path: Path) -> None:
    out = tmp_path / "out"
    args = paper_figures.parse_args(["--out", str(out)])
    assert args == paper_figures.Args(out=out)
    assert (args.duration, args.seed, args.policies, args.control_dt, args.transient, args.dpi) == (
        300.0,
        0,
        ("fbsm", "backstepping"),
        0.05,
        None,
        150,
    )
    _helps(paper_figures.Args, parse_options(paper_figures.Args, [], "prog", None)[1])
    args = paper_figures.parse_args(["--out", str(out), "--policies", "fbsm, backstepping_ilos"])
    assert args.policies == ("fbsm", "backstepping_ilos")
    _usage_error(
        capsys,
        paper_figures.main,
        ["--out", str(out), "--dpi", "high"],
        "argument --dpi: invalid int value: 'high'",
    )
    _usage_error(
        capsys,
        paper_figures.main,
        ["--out", str(out), "--policies", "fbsm,fbsm"],
        "--policies names ['fbsm'] more than once",
    )


def test_action_bounds_options(capsys) -> None:
    parsed, parser = parse_options(action_bounds.Options, [], "prog", None)
    assert parsed == action_bounds.Options() == action_bounds.Options(32, 100.0, None)
    _helps(action_bounds.Options, parser)
    _usage_error(
        capsys,
        action_bounds.main,
        ["--episodes", "0"],
        "--episodes must be >= 1 and --duration > 0",
    )
    _usage_error(
        capsys,
        action_bounds.main,
        ["--duration", "long"],
        "argument --duration: invalid float value: 'long'",
    )


def test_train_command_options(capsys) -> None:
    _, extra = train_cli.parse_args([])
    assert extra == train_cli.CommandOptions() == train_cli.CommandOptions(None, False, None)
    _, extra = train_cli.parse_args(["--curve", "c", "--plot-only", "--evaluate", "agent"])
    assert extra == train_cli.CommandOptions("c", True, "agent")
    _usage_error(capsys, train_cli.parse_args, ["--plot-only"], "--plot-only needs --curve")
    _usage_error(
        capsys, train_cli.parse_args, ["--no-plot-only"], "unrecognized arguments: --no-plot-only"
    )


@pytest.mark.rl
def test_evaluate_flies_an_agent_under_the_env_id_it_records(tmp_path):
    """`auv-gym train --evaluate AGENT` evaluates under AGENT's own env id, as the reproduction
    check re-evaluates it: the residual agent records AUVPath3DSpeedLimit-v0, and its held-out
    file says so (it said AUVPath3D-v0, the held-out default, whatever the agent)."""
    import shutil

    from benchmarks.catalog.policies import AGENTS_DIR
    from benchmarks.training import HELD_OUT_FILE, held_out_evaluation

    agent = tmp_path / "ppo_residual"
    shutil.copytree(AGENTS_DIR / "ppo_residual", agent)
    (agent / HELD_OUT_FILE).unlink()
    train_cli.main(["--evaluate", str(agent), "--eval-duration", "20"])
    written = json.loads((agent / HELD_OUT_FILE).read_text())
    assert "defaults of AUVPath3DSpeedLimit-v0" in written["scenario"]
    expected = held_out_evaluation(agent, 20.0, "AUVPath3DSpeedLimit-v0")
    assert written["summary"]["rms_distance_mean"] == expected["summary"]["rms_distance_mean"]
    assert written["summary"]["n_episodes"] == 10
