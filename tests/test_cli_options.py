"""Command lines generated from the option dataclasses (`benchmarks.options`): each TrainOptions
field has one flag per training CLI, with the dataclass default and help."""

from __future__ import annotations

import argparse
import dataclasses
from dataclasses import dataclass, fields

import pytest

from benchmarks.arguments import ArgumentParser
from benchmarks.options import add_options, from_args, option, whole_number
from benchmarks.training import seeds_cli, train_cli
from benchmarks.training.seeds_options import SeedsOptions
from benchmarks.training.train import TrainOptions


def _train_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser()
    add_options(parser, TrainOptions)
    return parser


def _actions(parser: argparse.ArgumentParser, dest: str) -> list[argparse.Action]:
    return [a for a in parser._actions if a.dest == dest]


@pytest.mark.parametrize(
    "field", [f for f in fields(TrainOptions) if f.name != "eval_env"], ids=lambda f: f.name
)
def test_every_train_option_has_one_flag_with_the_dataclass_default_and_help(field):
    parser = _train_parser()
    (action,) = _actions(parser, field.name)
    assert action.option_strings[0] == "--" + field.name.replace("_", "-")
    assert action.help == field.metadata["help"] and action.help
    parsed = getattr(parser.parse_args([]), field.name)
    expected = None if field.name == "config" else field.default  # None: the algorithm's file
    assert parsed == expected


def test_the_training_clis_default_to_the_dataclass_defaults():
    """No default restated: both CLIs give TrainOptions() unless an option is passed."""
    opts, _ = train_cli.parse_args([])
    assert opts == TrainOptions()
    seeds = seeds_cli.parse_args(["--seeds", "2", "--out", "x"])
    assert seeds.train == TrainOptions(progress_bar=False)
    assert seeds.train.keep_checkpoints == 3 and seeds.train.env_id == "AUVPath3DSpeedLimit-v0"
    assert seeds == SeedsOptions(train=seeds.train, seeds=(0, 1), out="x")


def test_train_seeds_flags_have_the_train_help_and_seeds_options_defaults():
    parser = seeds_cli.build_parser()
    for name in seeds_cli.TRAIN_FIRST + seeds_cli.TRAIN_BUDGET + seeds_cli.TRAIN_ENVS:
        (action,) = _actions(parser, name)
        assert action.help == TrainOptions.__dataclass_fields__[name].metadata["help"]
    (quiet,) = _actions(parser, "quiet")
    assert quiet.option_strings == ["--quiet"] and quiet.default is False
    assert seeds_cli.parse_args(["--seeds", "1", "--out", "x", "--quiet"]).progress is False
    assert [a.dest for a in parser._actions if a.required] == ["seeds", "out"]


@pytest.mark.parametrize(
    ("argv", "value"), [(["--n-timesteps", "2e6"], 2_000_000), (["--eval-freq", "1e5"], 100_000)]
)
def test_step_counts_read_scientific_notation_in_both_clis(argv, value):
    name = argv[0][2:].replace("-", "_")
    assert getattr(train_cli.parse_args(argv)[0], name) == value
    assert getattr(seeds_cli.parse_args(["--seeds", "1", "--out", "x", *argv]).train, name) == value


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--n-timesteps", "1.5"], "argument --n-timesteps: '1.5' is not a whole number"),
        (
            ["--eval-seeds", "1,x"],
            "argument --eval-seeds: expected comma-separated integers, got '1,x'",
        ),
        (["--vec-env", "fast"], "argument --vec-env: invalid choice: 'fast'"),
    ],
)
def test_bad_values_are_one_line_exit_2(capsys, argv, message):
    with pytest.raises(SystemExit) as stop:
        train_cli.parse_args(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and message in err and err.count("\n") == 1


@dataclass
class _Demo:
    steps: int | None = option(None, "steps", parse=whole_number)
    mode: str = option("a", "mode", choices=("a", "b"))
    verbose: bool = option(False, "talk")
    progress: bool = option(True, "silence", flag="--silent", invert=True)
    hidden: float = 1.0  # a plain field: no option


def test_a_dataclass_becomes_options_and_back():
    parser = ArgumentParser(prog="demo")
    names = add_options(parser, _Demo)
    assert names == ["steps", "mode", "verbose", "progress"]
    assert from_args(_Demo, parser.parse_args([]), names) == _Demo()
    parsed = parser.parse_args(["--steps", "3e3", "--mode", "b", "--verbose", "--silent"])
    assert from_args(_Demo, parsed, names, hidden=2.0) == _Demo(3000, "b", True, False, 2.0)
    assert parser.parse_args(["--no-verbose"]).verbose is False


def test_a_field_without_help_is_refused_by_name():
    with pytest.raises(TypeError, match=r"_Demo.hidden is no `option` field"):
        add_options(argparse.ArgumentParser(), _Demo, ["hidden"])
    with pytest.raises(ValueError, match=r"_Demo has no fields \['nope'\]"):
        add_options(argparse.ArgumentParser(), _Demo, ["nope"])
    assert dataclasses.fields(_Demo)[-1].metadata == {}


def test_the_episode_runners_take_their_options_from_episode_options():
    from benchmarks.arguments import EpisodeOptions
    from benchmarks.runner import compare

    parser = compare.build_parser()
    defaults = parser.parse_args([])
    for field in fields(EpisodeOptions):
        (action,) = _actions(parser, field.name)
        assert action.help == field.metadata["help"]
        assert getattr(defaults, field.name) == field.default
    assert defaults.duration == 300.0 and defaults.transient is None
    assert parser.parse_args(["--transient", "50"]).transient == 50.0
