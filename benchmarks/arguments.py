"""Argument checks shared by the benchmark command lines: one-line errors, exit code 2.

Every check runs before any episode: a bad argument costs no compute and leaves no partial
output. `ArgumentParser` is argparse's, except that an error is one line on stderr,
``<prog>: error: <message>``, with exit code 2 (argparse's code for bad usage) and no traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import sys
import tempfile
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn

from auv_gym.support.files import output_lock
from benchmarks.options import add_options, from_args, option

__all__ = [
    "ArgumentParser",
    "EpisodeOptions",
    "comma_names",
    "exit_with_usage_error",
    "finite_number",
    "locked_folder",
    "parse_options",
    "program_name",
    "usage_errors",
    "writable_folder",
    "writable_location",
]


def program_name(module: str) -> str:
    """The program name for help and errors: ``auv-gym <command>`` when the installed command
    dispatches (it puts that name in ``sys.argv[0]``), else ``python -m <module>`` (argparse
    would say ``compare.py``, or ``-c`` inside a test worker)."""
    invoked = sys.argv[0] if sys.argv else ""
    return invoked if invoked.startswith("auv-gym") else f"python -m {module}"


def exit_with_usage_error(prog: str, error: BaseException | str) -> NoReturn:
    """Exit like `ArgumentParser.error`: ``prog: error: message`` on one line, exit code 2."""
    line = " ".join(str(error).split())
    sys.stderr.write(f"{prog}: error: {line}\n")
    raise SystemExit(2)


class ArgumentParser(argparse.ArgumentParser):
    """argparse with one-line errors: ``prog: error: message`` on stderr, exit code 2."""

    def error(self, message: str) -> NoReturn:
        exit_with_usage_error(self.prog, message)


@contextlib.contextmanager
def usage_errors(parser: argparse.ArgumentParser) -> Iterator[None]:
    """Inside the block, ValueError, TypeError and OSError (a missing file, an unwritable
    folder) become ``parser.error``: one line, exit code 2."""
    try:
        yield
    except (ValueError, TypeError, OSError) as error:
        parser.error(str(error))


def comma_names(text: str, flag: str) -> list[str]:
    """The names of a comma-separated list; ValueError for an empty list, an empty name or a name
    given twice (each would run nothing, or the same episodes twice)."""
    names = [name.strip() for name in text.split(",")]
    if not text.strip():
        raise ValueError(f"{flag} must name at least one, got {text!r}")
    if "" in names:
        raise ValueError(f"{flag} has an empty name in {text!r}")
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise ValueError(f"{flag} names {repeated} more than once")
    return names


def finite_number(
    flag: str,
    value: float,
    low: float,
    high: float = math.inf,
    *,
    low_open: bool = False,
    high_open: bool = False,
    unit: str = "",
) -> float:
    """``value`` if it is finite and within the bounds; else ValueError naming the flag."""
    below = value <= low if low_open else value < low
    above = value >= high if high_open else value > high
    if not math.isfinite(value) or below or above:
        left, right = "(" if low_open else "[", ")" if high_open or high == math.inf else "]"
        top = "∞" if high == math.inf else f"{high:g}"
        raise ValueError(
            f"{flag} must be a finite number in {left}{low:g}, {top}{right}"
            f"{' ' + unit if unit else ''}, got {value!r}"
        )
    return value


def writable_folder(path: Path, flag: str = "--out") -> Path:
    """Create ``path`` (and its parents) if needed and prove it writable with a temporary file;
    OSError naming the flag and the folder otherwise."""
    try:
        if path.exists() and not path.is_dir():
            raise NotADirectoryError(f"{path} is a file, not a folder")
        path.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path, prefix=".write-test-", suffix=".tmp"):
            pass
    except OSError as error:
        reason = error.strerror or str(error)
        raise OSError(f"{flag} {str(path)!r} is not a writable folder: {reason}") from None
    return path


def writable_location(path: str | os.PathLike, flag: str, folder: bool = True) -> Path:
    """Check, creating nothing, that ``path`` can be written later: a folder (``folder``) or a
    file that does not exist yet or exists as that kind, under an existing ancestor that is a
    writable folder (proved with a temporary file, removed). Missing parents are fine: the
    writer creates them. OSError naming the flag and the path otherwise, so a command refuses
    an output it could not write before its first episode or training step."""
    kind = "folder" if folder else "file"
    if isinstance(path, str) and not path.strip():
        raise OSError(
            f"{flag} {path!r} names no {kind}: give a path (an empty one would write into the "
            "current folder)"
        )
    target = Path(path)
    problem = None
    if folder and target.exists() and not target.is_dir():
        problem = "it is a file, not a folder"
    elif not folder and target.is_dir():
        problem = "it is a folder, not a file"
    ancestor = target if folder and target.is_dir() else target.parent
    while problem is None and not ancestor.exists():
        ancestor = ancestor.parent
    if problem is None and not ancestor.is_dir():
        problem = f"{ancestor} is a file, not a folder"
    if problem is None:
        try:
            with tempfile.NamedTemporaryFile(dir=ancestor, prefix=".write-test-", suffix=".tmp"):
                pass
        except OSError as error:
            problem = f"{ancestor} is not writable: {error.strerror or error}"
    if problem is not None:
        raise OSError(f"{flag} {str(target)!r} cannot be written as a {kind}: {problem}")
    return target


@contextlib.contextmanager
def locked_folder(prog: str, folder: Path, flag: str = "--out") -> Iterator[Path]:
    """`auv_gym.support.files.output_lock` on ``folder`` for the block; another live run holding it
    (or a folder that cannot be created) ends the command like a usage error: one line, exit 2."""
    stack = contextlib.ExitStack()
    try:
        held = stack.enter_context(output_lock(folder, flag))
    except OSError as error:
        exit_with_usage_error(prog, error)
    with stack:
        yield held


@dataclass
class EpisodeOptions:
    """The options of every episode runner (compare, the suite), inherited by their option
    dataclasses; `check_episode_arguments` checks them."""

    duration: float = option(300.0, "episode length [s]")
    transient: float | None = option(
        None, "metrics window start [s]; None: min(100, duration/2) (docs/design.md §3.9)"
    )
    workers: int = option(
        os.cpu_count() or 1, "local worker processes (results do not depend on it)"
    )
    backend: str = option(
        "local", "run the episodes in local processes or on a Ray cluster", choices=("local", "ray")
    )
    address: str | None = option(None, "Ray cluster address to join")


def check_episode_arguments(args: argparse.Namespace) -> None:
    """ValueError naming the option: ``--duration`` in (0, `MAX_EPISODE_TIME`] s,
    ``--transient`` in [0, duration) s, and the pool options (`benchmarks.runner.pool`)."""
    from auv_gym.sim.config import MAX_EPISODE_TIME
    from benchmarks.runner.pool import check_pool_options

    finite_number("--duration", args.duration, 0.0, MAX_EPISODE_TIME, low_open=True, unit="s")
    if args.transient is not None:
        finite_number("--transient", args.transient, 0.0, args.duration, high_open=True, unit="s")
    check_pool_options(args.workers, args.backend, args.address)


def parse_checked(
    parser: argparse.ArgumentParser,
    argv: Sequence[str] | None,
    check: Callable[[argparse.Namespace], None],
) -> argparse.Namespace:
    """``parser``'s arguments from ``argv``, then ``check(args)`` (which may add resolved
    values) inside `usage_errors`: every argument is checked before any work, a bad one exits
    with code 2 and one line."""
    args = parser.parse_args(argv)
    with usage_errors(parser):
        check(args)
    return args


def parse_options(
    cls: type,
    argv: Sequence[str] | None,
    prog: str,
    description: str | None,
    *,
    negatable: bool = True,
) -> tuple[Any, argparse.ArgumentParser]:
    """(``cls`` from the command line ``argv``, its parser): every `option` field of ``cls`` is
    an option (`benchmarks.options.add_options`); a bad value exits like `ArgumentParser`, on
    one line with code 2. The parser is returned for checks across options (``parser.error``)."""
    from benchmarks.cli import HelpFormatter

    parser = ArgumentParser(prog=prog, description=description, formatter_class=HelpFormatter)
    names = add_options(parser, cls, negatable=negatable)
    return from_args(cls, parser.parse_args(argv), names), parser
