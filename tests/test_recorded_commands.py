"""Committed results record commands that exist: every module a results file names (a recorded
``python -m MODULE``, a JSON "command" or "argv", a ``benchmarks.*`` module in its text) imports
today, and every ``auv-gym COMMAND`` is a subcommand of `benchmarks.cli`, unless the file marks
the module historical.

When a module is renamed or removed, its results keep their provenance:

- **renamed**, and the current module takes the recorded options with the same meaning: the
  command is rewritten to the current name and the file says, once per module, what it recorded
  (`RENAME_NOTE`), as the value of a "command_note" key beside the command (JSON), a quote under
  the title (Markdown) or a comment on top (YAML)::

      Recorded as benchmarks.train_seeds, renamed benchmarks.training.seeds_cli after auv-gym
      0.1.0 (same options)

- **removed**: the command stays as recorded and the file says so (`HISTORICAL`; JSON: a
  "historical" key)::

      Historical: `benchmarks.training.guard_agents` was removed after auv-gym 0.1.0; the
      commands here that name it are not re-runnable

Machine paths anywhere in a committed file are test_committed_files' check (the same files);
here, a recorded command names no absolute path at all. The shipped agents' metadata
(benchmarks/agents) is not checked here.
"""

from __future__ import annotations

import importlib.util
import json
import re
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cache
from pathlib import Path

from test_committed_files import ROOT, committed_text_files

from benchmarks.cli import COMMANDS, SPEED

RESULTS = ROOT / "benchmarks" / "results"
# Former module names → today's (the alias modules left after auv-gym 0.1.0, CHANGELOG).
RENAMED = {
    "benchmarks.compare": "benchmarks.runner.compare",
    "benchmarks.evaluate_suite": "benchmarks.runner.evaluate_suite",
    "benchmarks.train_seeds": "benchmarks.training.seeds_cli",
    "benchmarks.tasks": "benchmarks.catalog.tasks",
}
MODULE = re.compile(r"(?<![\w./-])benchmarks(?:\.\w+)+")
PYTHON_M = re.compile(r"python3? -m +([\w.]+)")
SUBCOMMAND = re.compile(r"(?<![\w/-])auv-gym +([a-z][\w-]*)(?: +([a-z][\w-]*))?")
RENAME_NOTE = re.compile(
    r"recorded as `?(benchmarks(?:\.\w+)+)`?, renamed `?(benchmarks(?:\.\w+)+)`? "
    r"after auv-gym 0\.1\.0 \(same options\)",
    re.IGNORECASE,
)
HISTORICAL = re.compile(r"historical\W+(.*?)not re-runnable", re.IGNORECASE)
ABSOLUTE_PATH = re.compile(r"(?<![\w.:/<-])(?:/|~/)[\w.-]+/")


@cache
def exists(module: str) -> bool:
    """``module`` imports (its spec is found; its parent packages are imported, not itself)."""
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):
        return False


@dataclass(frozen=True)
class Recorded:
    """What one committed results file names, its notes apart."""

    path: Path
    text: str
    modules: frozenset[str]  # named outside the notes
    subcommands: tuple[tuple[str, str], ...]  # (auv-gym COMMAND, its first word)
    renames: tuple[tuple[str, str], ...]  # (former, current) of its rename notes
    historical: frozenset[str]  # named by its historical markers


def read(path: Path, text: str) -> Recorded:
    body = HISTORICAL.sub("", RENAME_NOTE.sub("", text))
    return Recorded(
        path.relative_to(ROOT) if path.is_relative_to(ROOT) else path,
        text,
        frozenset(MODULE.findall(body)) | frozenset(PYTHON_M.findall(body)),
        tuple(SUBCOMMAND.findall(body)),
        tuple((m.group(1), m.group(2)) for m in RENAME_NOTE.finditer(text)),
        frozenset(n for m in HISTORICAL.finditer(text) for n in MODULE.findall(m.group(1))),
    )


@cache
def _results() -> tuple[Recorded, ...]:
    """The committed results files that name a module or a command, read once (the episode
    tables, most of the bytes, name none)."""
    words = ("benchmarks.", "-m ", "auv-gym ", "historical", '"command"', '"argv"')
    texts = (
        (p, p.read_text(encoding="utf-8", errors="replace"))
        for p in committed_text_files([RESULTS])
    )
    return tuple(read(p, t) for p, t in texts if any(word in t for word in words))


def _recorded_commands(path: Path, text: str) -> Iterator[str]:
    """The commands a file records: its JSON "command" and "argv" values, its text from each
    ``python -m`` or ``auv-gym`` to the end of the line."""
    if path.suffix == ".json":
        stack = [json.loads(text)]
        while stack:
            item = stack.pop()
            if isinstance(item, dict):
                for key, value in item.items():
                    if key == "command" and isinstance(value, str):
                        yield value
                    elif key == "argv" and isinstance(value, list):
                        yield " ".join(map(str, value))
                    else:
                        stack.append(value)
            elif isinstance(item, list):
                stack.extend(item)
    else:
        for match in re.finditer(r"(?:python3? -m|(?<![\w/-])auv-gym) .*", text):
            yield match.group(0)


def test_every_recorded_module_and_command_exists_or_is_marked_historical() -> None:
    problems = []
    for file in _results():
        for module in sorted(file.modules):
            if exists(module) or module in file.historical:
                continue
            if module in RENAMED:
                problems.append(f"{file.path}: {module} was renamed {RENAMED[module]}: rewrite it")
            else:
                problems.append(f"{file.path}: {module} does not exist, is not marked historical")
        for command, name in file.subcommands:
            if command not in COMMANDS or (command == "speed" and name and name not in SPEED):
                problems.append(f"{file.path}: auv-gym {command} {name}".rstrip() + ": no such")
    assert problems == []


def test_rename_notes_and_historical_markers_are_true() -> None:
    """A note names a known rename whose current module the file uses; a marker names modules
    that are gone and that the file names."""
    problems = []
    for file in _results():
        for former, current in file.renames:
            if RENAMED.get(former) != current or exists(former) or not exists(current):
                problems.append(f"{file.path}: note 'recorded as {former}, renamed {current}'")
            elif current not in file.modules:
                problems.append(f"{file.path}: notes a rename to {current}, names no {current}")
        for module in sorted(file.historical):
            if exists(module) or module not in file.modules:
                problems.append(f"{file.path}: marks {module} historical: exists or not named")
    assert problems == []


def test_no_recorded_command_names_an_absolute_path() -> None:
    found = []
    for file in _results():
        for command in _recorded_commands(file.path, file.text):
            hit = ABSOLUTE_PATH.search(command)
            if hit:
                found.append(f"{file.path}: {hit.group(0)} in {command[:80]!r}")
    assert found == []


def test_the_checks_read_the_forms_they_document() -> None:
    json_note = (
        '{"command": "python -m benchmarks.training.seeds_cli --seeds 0-4", "command_note": '
        '"recorded as benchmarks.train_seeds, renamed benchmarks.training.seeds_cli after '
        'auv-gym 0.1.0 (same options)"}'
    )
    recorded = read(Path("x.json"), json_note)
    assert recorded.renames == (("benchmarks.train_seeds", "benchmarks.training.seeds_cli"),)
    assert recorded.modules == {"benchmarks.training.seeds_cli"}
    md = (
        "# Title\n\n"
        "> Recorded as `benchmarks.compare`, renamed `benchmarks.runner.compare` after "
        "auv-gym 0.1.0 (same options).\n>\n"
        "> Historical: `benchmarks.training.guard_agents` and `benchmarks.analysis.steady_offset`"
        " were removed after auv-gym 0.1.0; the commands here that name them are not "
        "re-runnable.\n\n"
        "`benchmarks.runner.compare --seeds 1` (benchmarks/runner/compare.py), then "
        "`python -m benchmarks.training.guard_agents --allocation` and `auv-gym speed training`."
    )
    recorded = read(Path("x.md"), md)
    assert recorded.renames == (("benchmarks.compare", "benchmarks.runner.compare"),)
    assert recorded.historical == {
        "benchmarks.training.guard_agents",
        "benchmarks.analysis.steady_offset",
    }
    assert recorded.modules == {"benchmarks.runner.compare", "benchmarks.training.guard_agents"}
    assert recorded.subcommands == (("speed", "training"),)
    json_marker = '"historical": "benchmarks.x.gone removed after auv-gym 0.1.0; not re-runnable"'
    assert read(Path("x.json"), json_marker).historical == {"benchmarks.x.gone"}
    assert not exists("benchmarks.compare") and exists("benchmarks.runner.compare")
    assert ABSOLUTE_PATH.search("--json /tmp/steady.json")
    assert not ABSOLUTE_PATH.search("--out runs/x --policies a=benchmarks/agents/b <out>/c")
