"""The episode runners' command lines (`auv-gym compare`, `auv-gym suite`, `auv-gym video`)
generated from their option dataclasses: each default and help written once, in the dataclass."""

from __future__ import annotations

import dataclasses

import pytest

from benchmarks.options import flag_of, from_args
from benchmarks.reports import video
from benchmarks.runner import compare, evaluate_suite

CLIS = [
    (compare, compare.CompareOptions),
    (evaluate_suite, evaluate_suite.SuiteOptions),
    (video, video.VideoOptions),
]


@pytest.mark.parametrize(("module", "options"), CLIS, ids=["compare", "suite", "video"])
def test_parsed_defaults_are_the_dataclass_defaults(module, options) -> None:
    parser = module.build_parser()
    names = [f.name for f in dataclasses.fields(options)]
    assert from_args(options, parser.parse_args([]), names) == options()
    flags = {flag_of(f): f.metadata["help"] for f in dataclasses.fields(options)}
    by_flag = {a.option_strings[0]: a.help for a in parser._actions if a.option_strings}
    assert {k: by_flag[k] for k in flags} == flags  # one flag per field, with its help


def test_the_flags_of_before_stay() -> None:
    """Every former flag, its destination and default (scripts and the docs use them)."""
    ns = compare.build_parser().parse_args([])
    assert (ns.policies, ns.scenarios, ns.seeds, str(ns.out)) == (
        "fbsm,backstepping,ppo_generalist",
        "all",
        10,
        "out/compare",
    )
    assert (ns.no_figures, ns.quiet, ns.duration, ns.transient) == (False, False, 300.0, None)
    ns = compare.build_parser().parse_args(["--no-figures", "--quiet", "--seeds", "3"])
    assert (ns.no_figures, ns.quiet, ns.seeds) == (True, True, 3)
    ns = evaluate_suite.build_parser().parse_args([])
    assert (ns.sets, str(ns.out), ns.reps, ns.bootstrap_seed, ns.reference) == (
        "all",
        "out/suite",
        2000,
        0,
        None,
    )
    assert (ns.stats_only, ns.no_stats, ns.no_figures, ns.quiet) == (False,) * 4
    ns = evaluate_suite.build_parser().parse_args(["--stats-only", "--no-figures", "--reps", "9"])
    assert (ns.stats_only, ns.no_figures, ns.reps) == (True, True, 9)
    assert from_args(evaluate_suite.SuiteOptions, ns, ["figures", "stats"]) == (
        evaluate_suite.SuiteOptions(figures=False)
    )
    ns = video.build_parser().parse_args(["--quiet"])
    assert (ns.policy, ns.scenario, ns.seed, ns.every, ns.fps, str(ns.out), ns.quiet) == (
        "fbsm",
        "paper",
        0,
        5,
        20,
        "out/run.mp4",
        True,
    )


@pytest.mark.parametrize(
    ("module", "argv", "message"),
    [
        (compare, ["--seeds", "ten"], "argument --seeds: invalid int value: 'ten'"),
        (compare, ["--backend", "slurm"], "argument --backend: invalid choice: 'slurm'"),
        (evaluate_suite, ["--reps", "1.5"], "argument --reps: invalid int value: '1.5'"),
        (evaluate_suite, ["--duration", "x"], "argument --duration: invalid float value: 'x'"),
        (video, ["--fps", "fast"], "argument --fps: invalid int value: 'fast'"),
    ],
)
def test_a_bad_value_is_one_line_exit_2(capsys, module, argv, message) -> None:
    with pytest.raises(SystemExit) as stop:
        module.build_parser().parse_args(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and message in err and err.count("\n") == 1


def test_wave_depth_options_are_its_dataclass(capsys) -> None:
    from benchmarks.arguments import parse_options
    from benchmarks.reports import wave_depth

    parsed, _ = parse_options(wave_depth.Options, [], "prog", None)
    assert parsed == wave_depth.Options() and parsed.depths == (2.0, 5.0, 10.0, 20.0, 40.0)
    parsed, _ = parse_options(wave_depth.Options, ["--depths", "3", "7.5"], "prog", None)
    assert parsed.depths == (3.0, 7.5)
    for argv, message in (
        (["--path", "spiral"], "argument --path: invalid choice: 'spiral'"),
        (["--depths", "-1"], "--depths must be finite and >= 0 m, got [-1.0]"),
    ):
        with pytest.raises(SystemExit) as stop:
            wave_depth.main(argv)
        err = capsys.readouterr().err
        assert stop.value.code == 2 and message in err and err.count("\n") == 1
