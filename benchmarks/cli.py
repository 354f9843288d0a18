"""`auv-gym`: the one installed command, dispatching to the benchmark command lines.

    auv-gym compare --policies fbsm,backstepping --scenarios paper --seeds 3 --duration 150
    auv-gym suite --policies fbsm,ppo_generalist=runs/ppo/results   # whole test suite + statistics
    auv-gym train --algo sac --config …      # needs the rl extra
    auv-gym train-seeds --algo ppo --seeds 5 --out runs/x   # several seeds, selection
    auv-gym demos --policy fbsm_colos --config …  --out runs/demos   # Minari dataset, rl extra
    auv-gym paper-figures --out out/paper
    auv-gym speed env|vector|controllers|render|resets|training|off-policy|all [options]
    auv-gym video --policy fbsm --scenario paper --out out/run.mp4   # needs the video extra
    auv-gym record --policy fbsm --scenario paper --out out/run.mcap   # ROS 2 MCAP, mcap extra
    auv-gym export ppo_generalist --out out/policy.onnx   # one ONNX graph (rl and onnx extras)
    auv-gym ensemble --results runs/x/results --best 3 --out runs/x/ensemble   # mean of 3 seeds

Each subcommand is the `main(argv)` of a module that also runs as ``python -m <module>`` (e.g.
``python -m benchmarks.runner.compare``; the modules are listed in `COMMANDS` and `SPEED`) and shows
its options, defaults and choices with ``--help``. Data the commands read (scenarios,
hyper-parameters, the shipped agent) is package data, found beside the modules, so every command
works from any folder; outputs go to paths relative to the current folder.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence
from pathlib import Path

from auv_gym.support.numba_cache import kernels_are_cached, mark_kernels_cached

__all__ = ["COMMANDS", "SPEED", "HelpFormatter", "main"]


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter, argparse.RawDescriptionHelpFormatter):
    """Help that shows every option's default and keeps the description's line breaks; an
    option whose help states its default already ("(default: ...)") shows it once."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        return text if "(default:" in text else super()._get_help_string(action)


# Subcommand → (module whose main(argv) runs it, one-line description).
COMMANDS: dict[str, tuple[str, str]] = {
    "compare": ("benchmarks.runner.compare", "policies on seeded scenarios: tables and figures"),
    "suite": (
        "benchmarks.runner.evaluate_suite",
        "every policy and seed on the test suite: statistics",
    ),
    "train": (
        "benchmarks.training.train_cli",
        "train or evaluate an RL agent, --algo ppo|sac (rl extra)",
    ),
    "train-seeds": (
        "benchmarks.training.seeds_cli",
        "N training seeds, selection on validation (rl extra)",
    ),
    "demos": (
        "benchmarks.training.demos_cli",
        "a classical policy's demonstrations for an agent recipe, as a Minari dataset (rl extra)",
    ),
    "paper-figures": (
        "benchmarks.reports.paper_figures",
        "the paper's Figs. 3-9, FBSM vs backstepping, and two more (adaptive weights, distance)",
    ),
    "export": (
        "benchmarks.runner.export",
        "an agent as one ONNX graph with its contract (rl and onnx extras)",
    ),
    "ensemble": (
        "benchmarks.runner.ensemble",
        "several agents of one recipe as one policy, their mean action",
    ),
    "compile": (
        "benchmarks.runner.compile_kernels",
        "compile and cache the simulation kernels (set-up runs it)",
    ),
    "speed": ("", "speed benchmarks that print figures (auv-gym speed --help)"),
    "video": ("benchmarks.reports.video", "an episode's video: 3-D track and errors (video extra)"),
    "record": (
        "benchmarks.reports.record",
        "an episode as MCAP with ROS 2 messages, for Foxglove and ros2 bag (mcap extra)",
    ),
    "docs": ("", "where the manual is (docs/*.md: model, design, usage, results)"),
}
# `auv-gym speed NAME` → (module, one-line description).
SPEED: dict[str, tuple[str, str]] = {
    "all": ("benchmarks.speed.throughput", "every section below, in one run"),
    "env": ("benchmarks.speed.env", "single env through gym.make, against the JIT-off reference"),
    "vector": ("benchmarks.speed.vector", "native vector env, peak memory, SB3 data collection"),
    "controllers": ("benchmarks.speed.controllers", "FBSM and backstepping predict cost"),
    "render": ("benchmarks.speed.render", "rgb_array frames per second, fast and full redraw"),
    "resets": ("benchmarks.speed.resets", "env reset cost per path family and length"),
    "training": ("benchmarks.speed.training", "PPO training env steps/s, against a baseline ref"),
    "off-policy": ("benchmarks.speed.off_policy", "SAC, TQC and CrossQ gradient-step cost"),
    "onnx": ("benchmarks.speed.onnx", "ONNX export vs torch policy: latency per step, batch 1"),
}
# Modules of the optional extras: a missing one is named with the extra that installs it.
EXTRAS = {
    "stable_baselines3": "rl",
    "torch": "rl",
    "yaml": "rl",
    "rich": "rl",
    "tensorboard": "rl",
    "minari": "rl",
    "h5py": "rl",
    "moviepy": "video",
    "imageio_ffmpeg": "video",
    "ray": "ray",
    "rliable": "stats",
    "arch": "stats",
    "pandas": "stats",
    "onnx": "onnx",
    "onnxruntime": "onnx",
    "mcap": "mcap",
    "mcap_ros2": "mcap",
}


def _table(entries: dict[str, tuple[str, str]]) -> str:
    width = max(map(len, entries))
    return "\n".join(f"  {name:<{width}}  {text}" for name, (_, text) in entries.items())


def _current_folder_importable() -> None:
    """Make modules of the current folder importable, as ``python -m`` does.

    ``python -m benchmarks`` puts the current folder first on ``sys.path``; the installed
    script puts its own bin folder there instead, so ``--policies mymod:policy`` would not find
    ./mymod.py. The folder goes last: it adds the user's modules without shadowing an installed
    package. Spawned workers inherit ``sys.path``.
    """
    here = os.getcwd()
    if "" not in sys.path and here not in sys.path:
        sys.path.append(here)


def _run(module: str, prog: str, argv: list[str]) -> int:
    """``module.main(argv)`` with ``prog`` as the program name of its help and errors; its exit
    code (a ``main`` that returns one instead of raising SystemExit)."""
    saved = sys.argv[0]
    sys.argv[0] = prog  # argparse names the program after sys.argv[0]
    try:
        code = importlib.import_module(module).main(argv)
    finally:
        sys.argv[0] = saved
    return code if isinstance(code, int) else 0


def _speed(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(
        prog="auv-gym speed",
        description="Speed benchmarks; each prints its figures (and the machine they ran on).\n\n"
        + _table(SPEED),
        epilog="`auv-gym speed NAME --help` lists the options of one benchmark.",
        formatter_class=HelpFormatter,
    )
    parser.add_argument("benchmark", choices=list(SPEED), help="which benchmark to run")
    parser.add_argument("options", nargs=argparse.REMAINDER, help="that benchmark's options")
    args = parser.parse_args(argv)
    return _run(SPEED[args.benchmark][0], f"auv-gym speed {args.benchmark}", args.options)


def docs_folder() -> Path | None:
    """The manual's folder: installed with the package (``<prefix>/share/doc/auv-gym``), or
    ``docs/`` of the source tree an editable install runs from; None if neither exists."""
    installed = Path(sys.prefix) / "share" / "doc" / "auv-gym" / "docs"
    source = Path(__file__).resolve().parents[1] / "docs"
    return next((p for p in (installed, source) if (p / "model.md").is_file()), None)


def _docs(argv: list[str]) -> int:
    """Print the manual's folder and its pages (the help texts cite them as docs/<page>.md)."""
    parser = argparse.ArgumentParser(prog="auv-gym docs", description=_docs.__doc__)
    parser.parse_args(argv)
    folder = docs_folder()
    if folder is None:
        print(
            "auv-gym docs: error: no manual found (expected share/doc/auv-gym/docs under "
            f"{sys.prefix}, or docs/ in the source tree)",
            file=sys.stderr,
        )
        return 2
    print(folder)
    for page in sorted(folder.glob("*.md")):
        title = page.read_text(encoding="utf-8").lstrip().splitlines()[0].lstrip("# ").strip()
        print(f"  {page.name:<16} {title}")
    return 0


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("auv-gym")
    except PackageNotFoundError:  # run from a source tree without installing
        import auv_gym

        return auv_gym.__version__


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="auv-gym",
        description="3-D path following of an underactuated AUV: benchmark, training, figures, "
        "speed and video.",
        epilog="`auv-gym COMMAND --help` lists a command's options with their defaults; help "
        "texts cite the manual as docs/<page>.md, which `auv-gym docs` finds.",
        formatter_class=HelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"auv-gym {_version()}")
    commands = parser.add_subparsers(
        dest="command", metavar="COMMAND", title="commands", required=True
    )
    for name, (_, text) in COMMANDS.items():
        # Each command parses its own options (its module's main): the subparser only names it.
        commands.add_parser(name, help=text, add_help=False)
    return parser


def _compile_notice() -> Path | None:
    """Say, once per install or edit of the physics, why the first episodes take a while."""
    import auv_gym
    import controllers

    packages = (Path(auv_gym.__file__).parent, Path(controllers.__file__).parent)
    if kernels_are_cached(*packages):
        return None
    notice = (
        "auv-gym: compiling the simulation kernels the command flies (first run after an "
        "install or an edit of the physics: up to about 2 min on 2 cores, measured; cached "
        "afterwards; `auv-gym compile --all` compiles them all ahead)"
    )
    print(notice, file=sys.stderr, flush=True)
    return packages


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``auv-gym COMMAND [options]``; errors in the arguments end with one line, exit 2."""
    args = list(sys.argv[1:] if argv is None else argv)
    parsed, rest = _parser().parse_known_args(args[:1])
    command, rest = parsed.command, [*rest, *args[1:]]
    _current_folder_importable()
    compiled = None
    try:
        if command == "speed":
            code = _speed(rest)
        elif command == "docs":
            return _docs(rest)
        else:
            if command != "compile" and not {"-h", "--help"} & set(rest):
                compiled = _compile_notice()
            code = _run(COMMANDS[command][0], f"auv-gym {command}", rest)
    except ModuleNotFoundError as error:
        extra = EXTRAS.get((error.name or "").split(".")[0])
        if extra is None:
            raise
        print(
            f"auv-gym {command}: needs {error.name}, from the {extra!r} extra: "
            f"pip install 'auv-gym[{extra}]'",
            file=sys.stderr,
        )
        return 2
    except (ValueError, FileNotFoundError) as error:
        print(f"auv-gym {command}: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # Ctrl-C: what is written is whole (atomic writes), one line
        print(
            f"auv-gym {command}: interrupted; finished outputs are kept, and the same command "
            "resumes (with --resume where the command has it)",
            file=sys.stderr,
        )
        return 130
    except SystemExit as stop:  # a command's usage error: its exit code, as for errors above
        if isinstance(stop.code, int) and stop.code != 0:
            return stop.code
        raise
    if code:
        return code
    if compiled:
        mark_kernels_cached(*compiled)
    return 0


if __name__ == "__main__":
    sys.exit(main())
