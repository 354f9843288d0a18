"""The speed benchmarks' command lines (`auv-gym speed ...`) generated from option dataclasses
(`benchmarks.options`): the parsed defaults are the dataclass's, a bad value is one line."""

from __future__ import annotations

import dataclasses
import importlib

import pytest

from benchmarks.arguments import parse_options
from benchmarks.cli import SPEED

MODULES = sorted({module for module, _ in SPEED.values()} | {"benchmarks.speed.residual"})


@pytest.mark.parametrize("name", MODULES)
def test_parsed_defaults_are_the_dataclass_defaults(name: str, capsys) -> None:
    module = importlib.import_module(name)
    parsed, parser = parse_options(module.Options, [], "prog", None)
    assert parsed == module.Options()
    fields = dataclasses.fields(module.Options)
    helps = {a.dest: a.help for a in parser._actions if a.option_strings}
    assert all(helps[f.name] == f.metadata["help"] and f.metadata["help"] for f in fields)
    with pytest.raises(SystemExit) as stop:  # --help of every field's flag, no error
        module.main(["--help"])
    flag = "--" + fields[0].name.replace("_", "-")
    assert stop.value.code == 0 and flag in capsys.readouterr().out


def test_the_former_flags_and_several_values_stay() -> None:
    from benchmarks.speed import training, vector

    argv = ["--sizes", "1", "64", "--ppo-envs", "--actuators", "fins", "--quick"]
    opts, _ = parse_options(vector.Options, argv, "p", None)
    assert (opts.sizes, opts.ppo_envs, opts.actuators, opts.quick) == ((1, 64), (), ("fins",), True)
    assert vector.Options().sizes == (1, 64, 1024, 4096, 16384)
    assert vector.Options().threads == (2, 1) and vector.Options().sensor_sizes == (4096,)
    opts, _ = parse_options(training.Options, ["--n-envs", "8", "16", "--n-steps", "4"], "p", None)
    assert (opts.n_envs, opts.n_steps, opts.batch_size) == ((8, 16), 4, (2048,))
    assert training.Options().n_envs == (32, 128, 512) and training.Options().n_steps is None


@pytest.mark.parametrize(
    ("name", "argv", "message"),
    [
        ("controllers", ["--steps", "x"], "argument --steps: invalid int value: 'x'"),
        ("controllers", ["--steps", "0"], "--steps and --vehicles must be positive"),
        ("env", ["--reference-steps", "0"], "--steps and --reference-steps must be >= 1"),
        ("render", ["--every", "1.5"], "argument --every: invalid int value: '1.5'"),
        ("residual", ["--train-steps", "0"], "--steps and --train-steps must be positive"),
        ("throughput", ["--sections", "gpu"], "--sections: unknown ['gpu']"),
        ("training", ["--warmup", "-1"], "--warmup >= 0"),
        ("off_policy", ["--replay-ratio", "0"], "--replay-ratio must be > 0, got 0.0"),
        ("off_policy", ["--algos", "ddpg"], "argument --algos: invalid choice: 'ddpg'"),
        ("vector", ["--actuators", "jet"], "argument --actuators: invalid choice: 'jet'"),
        ("onnx", ["--agent", "runs/x"], "--agent and --onnx go together"),
        (
            "onnx",
            ["--agent", "no_such_folder", "--onnx", "x.onnx"],
            "no_such_folder does not exist",
        ),
    ],
)
def test_a_bad_value_is_one_line_exit_2(name: str, argv: list[str], message: str, capsys) -> None:
    with pytest.raises(SystemExit) as stop:
        importlib.import_module(f"benchmarks.speed.{name}").main(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and message in err and err.count("\n") == 1, err


@pytest.mark.rl
def test_off_policy_cost_builds_each_learner_as_the_trainer_does() -> None:
    """CrossQ from the SAC file: no tau, the critic width asked for, the file's replay ratio
    (2 gradient steps per vector step of 8 vehicles); the rate follows from the two costs."""
    from benchmarks.speed import off_policy

    argv = ["--algos", "crossq", "--warmup", "64", "--gradient-steps", "2", "--critic", "32"]
    (row,) = off_policy.main(argv)
    assert row["critic"] == {"pi": [128, 128], "qf": [32, 32]} and row["replay_ratio"] == 0.25
    expected = 1.0 / (1.0 / row["collection_steps_per_s"] + 0.25e-3 * row["gradient_step_ms"])
    assert row["training_steps_per_s"] == pytest.approx(expected, rel=1e-12)
