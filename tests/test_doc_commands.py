"""Every command the documentation shows names real things (tests/test_docs.py runs its Python).

The shell commands of the fenced blocks (```bash, ```sh, ```console and plain ``` blocks that
hold commands; backslash continuations joined as the shell joins them, trailing ``# comments``
dropped) and the inline ones (`` `auv-gym …` ``, `` `python -m benchmarks…` ``, `` `bash
scripts/…` ``) of README.md, docs/*.md and the agents' READMEs are checked without running them:

* the command exists: a subcommand of `benchmarks.cli` (``auv-gym X`` = ``python -m benchmarks
  X``), an importable module with a ``main`` (``python -m benchmarks.x.y``), a script of
  scripts/, whose own commands are checked too (with the doc's arguments where it passes
  ``"$@"``; a script that does not must read each argument the doc gives it);
* its arguments parse with the command's own argparse parser, taken from its ``main`` where it
  would parse (`command_parser`: nothing runs), every flag spelt in full;
* the values that name things exist: policies (`benchmarks.catalog.policies.PolicySpec`, the
  parser compare uses: a former name fails with its "renamed" message), agents (committed, as
  under benchmarks/agents/, or written earlier in the same block: ``--export runs/mine/agent``),
  scenarios (benchmarks/scenarios.toml), task sets (benchmarks/tasks.toml), env ids,
  hyper-parameter files (read and checked as training reads them, for the command's env id and
  algorithm);
* outputs go under out/ or runs/, never into the repository's own folders (a command of
  docs/results.md may rewrite the committed results it reproduces, under benchmarks/results/),
  also by a default the command leaves.

A template is checked for its command, its flags and the files and outputs it names in full:
an inline command with placeholders (``--config FILE``, ``…``) or that names a flag without its
value, and a block command with ``<name>`` placeholders. ``<agent>`` stands for each reference
agent, ``COMMAND`` for each subcommand and ``a|b`` for each alternative. The ``## History`` of
docs/results.md records commands as they were run, under the names of the time, and is not
checked. The cheap commands run: ``--help`` (each ``auv-gym COMMAND --help``), ``auv-gym docs``.

The count and the list of the reference agents the docs give are checked against
benchmarks/agents/, and `auv-gym export` refuses a former agent name as compare does.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import importlib
import importlib.util
import io
import itertools
import re
import shlex
import sys
import tempfile
import tomllib
from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path

import pytest

from benchmarks import cli
from controllers.ensemble import ENSEMBLE_FILE

ROOT = Path(__file__).resolve().parents[1]
AGENTS = ROOT / "benchmarks" / "agents"
DOCS = (
    "README.md",
    *sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "docs").glob("*.md")),
    "benchmarks/agents/README.md",
    *sorted(p.relative_to(ROOT).as_posix() for p in AGENTS.glob("*/README.md")),
)
# From this heading on, a doc records commands as they were run then (docs/results.md says so).
HISTORY = {"docs/results.md": "## History"}
# Wrong commands of docs the lead edits (docs/results.md, being remade with the reference agent):
# expected to fail until fixed there; then this entry goes (strict: the test says so).
KNOWN_WRONG = {}
# Where a documented command may write: the scratch folders of runs; and, for a command of
# docs/results.md, the committed results it reproduces.
OUTPUT_ROOTS = ("out/", "runs/")
RESULTS = ("docs/results.md", "benchmarks/results/")
# The options that name what a command writes (dests of the commands' parsers).
OUTPUT_DESTS = ("out", "export", "curve")
OUTPUT_FLAGS = tuple(f"--{dest}" for dest in OUTPUT_DESTS)

SHELL_BLOCKS = {"", "bash", "sh", "shell", "console", "zsh"}
# Programs a doc's shell block may run besides ours (not checked further).
EXTERNAL = {"mkdir", "pip", "cd", "export", "source", ".", "ray", "ros2", "du", "ss", "git"}
# First words of a shell command in a plain ``` block (other plain blocks hold diagrams, output).
COMMAND_WORDS = {"auv-gym", "python", "python3", "bash", *EXTERNAL}
PLACEHOLDER = re.compile(r"^[A-Z][A-Z0-9_]*(?:[.:][A-Za-z0-9]+)*$|…|\.\.\.|<|>")


# --- the commands of the docs -----------------------------------------------------------------


@dataclass(frozen=True)
class DocCommand:
    """One command as a doc shows it: its words, lines joined and the comment dropped."""

    doc: str
    line: int
    words: tuple[str, ...]
    block: int | None  # its fenced block's index in the doc; None for an inline command
    template: bool = False  # an expansion of a command with placeholders

    @property
    def where(self) -> str:
        return f"{self.doc}:{self.line}"

    @property
    def text(self) -> str:
        return shlex.join(self.words)


def _strip_comment(line: str) -> str:
    """``line`` without its comment: ``#`` unquoted at a word's start, as the shell reads it."""
    quote = None
    for i, char in enumerate(line):
        if quote:
            quote = None if char == quote else quote
        elif char in "'\"":
            quote = char
        elif char == "#" and (i == 0 or line[i - 1].isspace()):
            return line[:i].rstrip()
    return line


def shell_commands(line: str) -> Iterator[list[str]]:
    """The simple commands of one logical shell line (split at ``&&``, ``||``, ``;``, ``|``),
    each without its leading ``NAME=value`` assignments."""
    words: list[str] = []
    for word in [*shlex.split(_strip_comment(line)), ";"]:
        if word in ("&&", "||", ";", "|"):
            while words and re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*=.*", words[0]):
                words.pop(0)
            if words:
                yield words
            words = []
        else:
            words.append(word)


def block_commands(doc: str, lines: list[str]) -> Iterator[DocCommand]:
    """The commands of the fenced shell blocks of ``lines`` (a plain block's lines only where
    they start with a command's name; a console block's only after ``$``)."""
    fence: str | None = None
    block, kind, logical, start = -1, "", "", 0
    for number, line in enumerate(lines, 1):
        if fence is None:
            opening = re.match(r"^\s*(`{3,}|~{3,})\s*([\w+-]*)", line)
            if opening:
                fence, kind, block = opening[1], opening[2].lower(), block + 1
            continue
        if line.strip().startswith(fence):
            fence = None
            continue
        if kind not in SHELL_BLOCKS:
            continue
        if not logical:
            start = number
            if kind == "console":
                if not line.lstrip().startswith("$ "):
                    continue  # what the command printed
                line = line.lstrip()[2:]
        if line.endswith("\\"):  # the shell drops backslash-newline, joining what is around it
            logical += line[:-1]
            continue
        logical, text = "", logical + line
        for words in shell_commands(text):
            if kind or words[0] in COMMAND_WORDS:
                yield DocCommand(doc, start, tuple(words), block)


def inline_commands(doc: str, text: str) -> Iterator[DocCommand]:
    """The `` `auv-gym …` ``, `` `python -m benchmarks…` `` and `` `bash scripts/…` `` spans of
    ``text`` outside its fenced blocks (the program's bare name aside)."""
    prose = re.sub(r"^\s*```.*?^\s*```", lambda m: "\n" * m[0].count("\n"), text, flags=re.S | re.M)
    for match in re.finditer(r"`((?:auv-gym|python -m benchmarks|bash scripts/)[^`]*)`", prose):
        words = tuple(match[1].replace("\\|", "|").split())  # a table cell escapes its |
        if words != ("auv-gym",):
            yield DocCommand(doc, prose.count("\n", 0, match.start()) + 1, words, None)


@functools.cache
def doc_commands() -> tuple[DocCommand, ...]:
    """Every command of the docs, in order (the history of docs/results.md aside)."""
    found: list[DocCommand] = []
    for doc in DOCS:
        lines = (ROOT / doc).read_text(encoding="utf-8").splitlines()
        heading = HISTORY.get(doc)
        lines = lines[: next((i for i, s in enumerate(lines) if s == heading), len(lines))]
        found += block_commands(doc, lines)
        found += inline_commands(doc, "\n".join(lines))
    return tuple(sorted(found, key=lambda c: (DOCS.index(c.doc), c.line)))


def ours(words: tuple[str, ...] | list[str]) -> bool:
    """A command of this project: ``auv-gym``, ``python -m benchmarks…``, ``bash scripts/…``."""
    if words[0] == "auv-gym":
        return True
    if words[0] == "bash":
        return len(words) > 1 and words[1].startswith("scripts/")
    return (
        words[0] in ("python", "python3")
        and len(words) > 2
        and words[1] == "-m"
        and (words[2] == "benchmarks" or words[2].startswith("benchmarks."))
    )


def expansions(command: DocCommand) -> list[DocCommand]:
    """``<agent>`` → each reference agent (the same throughout), ``COMMAND`` → each subcommand,
    ``a|b`` → each alternative; an expansion of a placeholder is a template."""
    words = command.words
    if any("<agent>" in word for word in words):
        return [
            replace(command, words=tuple(w.replace("<agent>", a) for w in words), template=True)
            for a in sorted(p.name for p in AGENTS.iterdir() if p.is_dir())
        ]
    for i, word in enumerate(words):
        if word == "COMMAND":
            names, template = list(cli.COMMANDS), True
        elif "|" in word and not word.startswith("-"):
            names, template = word.split("|"), command.template
        else:
            continue
        return [
            e
            for name in names
            for e in expansions(
                replace(command, words=(*words[:i], name, *words[i + 1 :]), template=template)
            )
        ]
    return [command]


# --- a command's parser, without running it ---------------------------------------------------


class _Parsing(BaseException):
    """Raised where a command's ``main`` parses its arguments: its parser."""

    def __init__(self, parser: argparse.ArgumentParser) -> None:
        super().__init__()
        self.parser = parser


class DocError(Exception):
    """What a documented command names does not exist."""


def _need(ok: object, message: str) -> None:
    if not ok:
        raise DocError(message)


class Refused(Exception):
    """The command's parser refused the arguments (its one-line error)."""


@functools.cache
def command_parser(module_name: str, prog: str) -> argparse.ArgumentParser:
    """The parser the ``main(argv)`` of ``module_name`` reads its arguments with: ``main`` runs
    up to its first ``parse_args`` and stops there. Its errors raise `Refused`."""
    module = importlib.import_module(module_name)
    _need(callable(getattr(module, "main", None)), f"{module_name} has no main(argv)")

    def stop(self: argparse.ArgumentParser, args=None, namespace=None):
        raise _Parsing(self)

    saved, argv0 = argparse.ArgumentParser.parse_args, sys.argv[0]
    argparse.ArgumentParser.parse_args = stop  # type: ignore[method-assign]
    sys.argv[0] = prog  # the program name of the commands' help and errors (cli._run)
    try:
        module.main(["--help"])
    except _Parsing as parsing:
        parser = parsing.parser
    else:
        raise DocError(f"{module_name}.main returned without parsing its arguments")
    finally:
        argparse.ArgumentParser.parse_args = saved  # type: ignore[method-assign]
        sys.argv[0] = argv0

    def refuse(message: str):
        raise Refused(f"{parser.prog}: error: {message}")

    parser.error = refuse  # type: ignore[method-assign]
    return parser


def _parse(parser: argparse.ArgumentParser, argv: list[str]) -> argparse.Namespace:
    """``argv`` parsed; --help (cheap: it runs) prints and gives an empty namespace."""
    with contextlib.redirect_stdout(io.StringIO()) as shown:
        try:
            return parser.parse_args(argv)
        except SystemExit as stop:
            _need(stop.code in (0, None), f"{parser.prog} {shlex.join(argv)}: exit {stop.code}")
    _need("usage:" in shown.getvalue(), f"{parser.prog} --help printed no usage")
    return argparse.Namespace()


def _option(parser: argparse.ArgumentParser, word: str) -> argparse.Action | None:
    return parser._option_string_actions.get(word.split("=")[0])


# --- what a command names ---------------------------------------------------------------------


@dataclass
class Written:
    """What the commands before the current one in its fenced block write."""

    paths: set[Path] = field(default_factory=set)

    def has(self, path: Path) -> bool:
        return any(path == p or p in path.parents for p in self.paths)

    def add(self, words: tuple[str, ...]) -> None:
        """The outputs of one command (`OUTPUT_FLAGS`, mkdir's folders), read from its words."""
        if words[0] == "mkdir":
            self.paths |= {Path(w) for w in words[1:] if not w.startswith("-")}
        for flag, value in itertools.pairwise(words):
            if flag in OUTPUT_FLAGS:
                self.paths.add(Path(value))
        self.paths |= {
            Path(w.split("=", 1)[1]) for w in words if w.split("=")[0] in OUTPUT_FLAGS and "=" in w
        }


def _check_output(value: object, what: str, doc: str) -> None:
    path = Path(str(value))
    roots = (*OUTPUT_ROOTS, RESULTS[1]) if doc == RESULTS[0] else OUTPUT_ROOTS
    _need(not path.is_absolute() and ".." not in path.parts, f"{what} {path} leaves the checkout")
    _need(
        f"{path.as_posix()}/".startswith(roots),
        f"{what} {path} is not under {', '.join(roots)}: it writes into the repository",
    )


def _agent_folder(folder: Path) -> bool:
    """A saved agent's folder (its metadata.json) or an ensemble's (its ensemble.json)."""
    return (folder / "metadata.json").is_file() or (folder / ENSEMBLE_FILE).is_file()


def _check_agent(path: Path, written: Written, what: str) -> None:
    _need(
        written.has(path) or _agent_folder(ROOT / path),
        f"{what}: {path} is neither a committed agent nor written earlier in its block",
    )


def _check_policy(spec: str, written: Written) -> None:
    """``spec`` as compare reads it (`PolicySpec.parse`: a former name fails with its "renamed"
    message), its files committed or written earlier in the block."""
    from benchmarks.catalog.policies import PolicySpec

    parsed = PolicySpec.parse(spec)
    if parsed.kind == "import":
        module = spec.partition(":")[0]
        top = module.split(".")[0]
        if importlib.util.find_spec(top) is None and top.startswith("my"):
            return  # the reader's own module (mypkg.mod:my_policy)
        import controllers

        controllers.import_policy(spec, instantiate=False)
    elif parsed.agent is not None:
        _check_agent(parsed.agent, written, f"policy {spec!r}")
    elif parsed.onnx is not None:
        _need(
            written.has(parsed.onnx) or (ROOT / parsed.onnx).is_file(),
            f"policy {spec!r}: {parsed.onnx} is neither committed nor written earlier",
        )


@functools.cache
def _toml_names(file: Path) -> tuple[str, ...]:
    """The tables of a scenario or task-set file (their contents are the loaders' tests'), and a
    task set's per-scenario sets ``scenario:<name>``."""
    tables = tomllib.loads(file.read_text())
    names = [*tables, *(f"scenario:{n}" for t in tables.values() for n in t.get("scenarios", ()))]
    return tuple(names)


@functools.cache
def _check_config(path: str, env_id: str | None, algo: str) -> None:
    """A hyper-parameter file as training reads it: a schedule with every phase's configuration
    checked, or an RL-Zoo file with its section for ``env_id`` (None: its only one)."""
    import yaml

    from benchmarks.training.config import read_zoo_config
    from benchmarks.training.schedule import check_schedule, read_schedule

    file = ROOT / path
    _need(file.is_file(), f"--config {path} does not exist")
    schedule = read_schedule(file)
    if schedule is not None:
        with tempfile.TemporaryDirectory() as scratch:
            check_schedule(schedule, schedule.options.get("algo", algo), Path(scratch))
        return
    if env_id is None:
        sections = list(yaml.safe_load(file.read_text()))
        _need(len(sections) == 1, f"--config {path} has {sections}: give --env-id")
        env_id = sections[0]
    read_zoo_config(file, env_id, algo)


def _check_values(
    module: str, ns: argparse.Namespace, given: set[str], written: Written, doc: str
) -> None:
    """The values of ``ns`` the command line gave that name things exist; what the command
    writes is where it may (also by its defaults)."""
    from auv_gym import VARIANTS

    values = vars(ns)
    scenario_file = Path(values.get("scenario_file") or ROOT / "benchmarks" / "scenarios.toml")
    scenarios = _toml_names(ROOT / scenario_file)
    for dest in sorted(given & set(values)):
        value = values[dest]
        flag = f"--{dest.replace('_', '-')}"
        if dest == "policies":
            for spec in str(value).split(","):
                _name, equals, folder = spec.partition("=")
                if equals and module == "benchmarks.runner.evaluate_suite":  # NAME=RUN_FOLDER
                    _need(written.has(Path(folder)) or (ROOT / folder).is_dir(), spec)
                else:
                    _check_policy(spec, written)
        elif dest == "policy":
            _check_policy(str(value), written)
        elif dest == "agent" and module == "benchmarks.runner.export":
            from benchmarks.runner.export import agent_path

            _check_agent(agent_path(str(value)), written, f"agent {value!r}")
        elif dest in ("init_from", "evaluate"):
            _check_agent(Path(value), written, flag)
        elif dest in ("scenarios", "scenario"):
            names = str(value).split(",") if value != "all" else []
            unknown = [n for n in names if n not in scenarios]
            _need(not unknown, f"{flag}: no scenario {unknown} in {scenario_file}")
        elif dest in ("task_set", "task"):
            _need(value in _toml_names(ROOT / "benchmarks" / "tasks.toml"), f"no task set {value}")
        elif dest == "env_id":
            _need(value in VARIANTS, f"--env-id {value!r}; valid: {sorted(VARIANTS)}")
        elif dest == "config":
            _check_config(str(value), values.get("env_id"), values.get("algo") or "ppo")
    for dest in OUTPUT_DESTS:
        if values.get(dest) is not None:
            what = f"--{dest}" if dest in given else f"--{dest} (its default)"
            _check_output(values[dest], what, doc)


# --- checking one command ---------------------------------------------------------------------


def _check_module(
    module: str, prog: str, argv: list[str], command: DocCommand, written: Written
) -> None:
    parser = command_parser(module, prog)
    unknown = [w for w in argv if w.startswith("--") and _option(parser, w) is None]
    _need(not unknown, f"{prog} has no option {unknown} (a doc spells a flag out)")
    last = _option(parser, argv[-1]) if argv else None
    mention = command.block is None and (
        not argv or any(PLACEHOLDER.search(w) for w in argv) or (last and last.nargs != 0)
    )
    if argv == ["--help"]:  # cheap: it runs
        _parse(parser, argv)
        return
    if command.template or mention:
        for flag, value in itertools.pairwise(argv):  # what it names in full
            if PLACEHOLDER.search(value):
                continue
            if flag == "--config":
                _need((ROOT / value).is_file(), f"--config {value} does not exist")
            elif flag in OUTPUT_FLAGS:
                _check_output(value, flag, command.doc)
        return
    ns = _parse(parser, argv)
    given = {a.dest for w in argv if (a := _option(parser, w)) is not None}
    given |= {a.dest for a in parser._actions if not a.option_strings}  # positionals
    _check_values(module, ns, given, written, command.doc)


def _script_commands(script: Path) -> list[DocCommand]:
    lines = ["```bash", *script.read_text().splitlines(), "```"]
    return [c for c in block_commands(script.name, lines) if ours(c.words)]


def check_command(command: DocCommand, written: Written) -> None:
    """Everything ``command`` names exists (module docstring); DocError, ValueError,
    OSError or `Refused` (the parser's one-line error) otherwise."""
    words = list(command.words)
    if words[0] in ("python", "python3"):
        module, rest = words[2], words[3:]
        if module == "benchmarks":
            words = ["auv-gym", *rest]
        else:
            _need(importlib.util.find_spec(module) is not None, f"no module {module}")
            _check_module(module, f"python -m {module}", rest, command, written)
            return
    if words[0] == "bash":
        script = ROOT / words[1]
        _need(script.is_file(), f"no script {words[1]}")
        inner = _script_commands(script)
        forwards = [c for c in inner if "$@" in c.words]
        for c in inner:  # the script's own commands, the doc's arguments where it passes "$@"
            args = [w for w in c.words if w != "$@"] + (words[2:] if c in forwards else [])
            check_command(replace(c, words=tuple(args), block=0), Written())
        if not forwards:
            unread = [w for w in words[2:] if f'"{w}"' not in script.read_text()]
            _need(not unread, f"{words[1]} does not read {unread}")
        return
    _need(words[0] == "auv-gym", command.text)
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    _need(scripts.get("auv-gym") == "benchmarks.cli:main", "pyproject.toml installs no auv-gym")
    if len(words) == 1 or PLACEHOLDER.search(words[1]):
        return
    cheap = [["--help"], ["--version"], ["docs"], ["docs", "--help"], ["speed", "--help"]]
    if words[1:] in cheap:  # they run
        with contextlib.redirect_stdout(io.StringIO()) as shown, contextlib.suppress(SystemExit):
            _need(cli.main(words[1:]) == 0, f"{command.text} failed")
        _need(shown.getvalue(), f"{command.text} printed nothing")
        return
    name, rest = words[1], words[2:]
    _need(name in cli.COMMANDS, f"auv-gym has no command {name!r}; valid: {list(cli.COMMANDS)}")
    if name == "speed":
        if not rest or PLACEHOLDER.search(rest[0]):
            return
        _need(rest[0] in cli.SPEED, f"auv-gym speed has no {rest[0]!r}; valid: {list(cli.SPEED)}")
        module = cli.SPEED[rest[0]][0]
        name, rest = f"speed {rest[0]}", rest[1:]
    elif name == "docs":
        _need(PLACEHOLDER.search(rest[0]), f"auv-gym docs takes no arguments: {command.text}")
        return
    else:
        module = cli.COMMANDS[name][0]
    _check_module(module, f"auv-gym {name}", rest, command, written)


def _written_before(command: DocCommand) -> Written:
    """What the commands before ``command`` in its fenced block write."""
    written = Written()
    if command.block is None:
        return written
    for earlier in doc_commands():
        if earlier == command:
            break
        if earlier.doc == command.doc and earlier.block == command.block:
            written.add(earlier.words)
    return written


def _cases() -> list:
    cases = []
    for command in doc_commands():
        if ours(command.words):
            marks = []
            if command.where in KNOWN_WRONG:
                marks = [pytest.mark.xfail(reason=KNOWN_WRONG[command.where], strict=True)]
            cases.append(
                pytest.param(command, id=f"{command.where} {command.text}"[:80], marks=marks)
            )
    return cases


@pytest.mark.parametrize("command", _cases())
def test_documented_command(command: DocCommand, monkeypatch) -> None:
    monkeypatch.chdir(ROOT)  # the docs' commands run from the root
    written = _written_before(command)
    for expanded in expansions(command):
        problem = None
        try:
            check_command(expanded, written)
        except (DocError, ValueError, OSError, Refused) as error:
            problem = " ".join(str(error).split())
        if problem:
            pytest.fail(f"{command.where}: {expanded.text}\n  {problem}", pytrace=False)


def test_the_docs_show_commands_and_every_one_is_known() -> None:
    """The extraction finds the docs' commands, and a shell block runs ours or a known program
    (an unknown one would pass unchecked: a misspelt ``auv_gym``, say)."""
    commands = doc_commands()
    per_doc = {doc: sum(ours(c.words) for c in commands if c.doc == doc) for doc in DOCS}
    assert per_doc["README.md"] >= 6 and per_doc["docs/usage.md"] >= 20, per_doc
    for command in commands:
        words = command.words
        known = ours(words) or words[0] in EXTERNAL or words[:3] == ("python", "-m", "pytest")
        assert command.block is None or known, f"{command.where}: {command.text}"


def test_the_extraction_reads_shell_as_the_shell_does() -> None:
    lines = """
```bash
auv-gym compare --policies fbsm,\\
backstepping --out out/x   # a comment: --not-a-flag
python -m benchmarks.runner.compare \\
    --seeds 2 --out 'out/a b' && mkdir -p out  # two commands
```
```
support ──► paths
auv-gym docs
```
```console
$ X=1 auv-gym --help
usage: auv-gym ...
```
```python
auv-gym compare  # Python, not shell
```
""".splitlines()
    found = [(c.line, c.words) for c in block_commands("doc.md", lines)]
    assert found == [
        (3, ("auv-gym", "compare", "--policies", "fbsm,backstepping", "--out", "out/x")),
        (5, ("python", "-m", "benchmarks.runner.compare", "--seeds", "2", "--out", "out/a b")),
        (5, ("mkdir", "-p", "out")),
        (10, ("auv-gym", "docs")),
        (13, ("auv-gym", "--help")),
    ]
    prose = "Run `auv-gym speed env\\|all` or `python -m benchmarks.x --y 1`; `auv-gym` is it."
    assert [c.words for c in inline_commands("doc.md", prose)] == [
        ("auv-gym", "speed", "env|all"),
        ("python", "-m", "benchmarks.x", "--y", "1"),
    ]


@pytest.mark.parametrize(
    "words, problem",
    [
        (("auv-gym", "compare", "--policies", "ppo"), "'ppo' is no longer shipped"),
        (("auv-gym", "compare", "--scenario", "paper"), "has no option ['--scenario']"),
        (("auv-gym", "compare", "--scenarios", "papr", "--out", "out/x"), "no scenario ['papr']"),
        (("auv-gym", "compare", "--out", "x"), "it writes into the repository"),
        (("auv-gym", "compare", "--out", "benchmarks/results/x"), "it writes into the repository"),
        (("auv-gym", "record", "--scenario", "paper"), "--out (its default) run.mcap"),
        (("auv-gym", "compare", "--policies", "agent:runs/x", "--out", "out/x"), "neither a"),
        (("auv-gym", "train", "--config", "runs/missing.yml", "--out", "runs/x"), "missing.yml"),
        (("auv-gym", "train-seeds", "--seeds", "0", "--out", "runs/x"), "must be at least 1"),
        (("auv-gym", "vid"), "no command 'vid'"),
        (("python", "-m", "benchmarks.runner.comparison"), "no module"),
        (("bash", "scripts/test.sh", "--fast"), "does not read ['--fast']"),
    ],
)
def test_a_wrong_command_is_named(words, problem, monkeypatch) -> None:
    monkeypatch.chdir(ROOT)
    with pytest.raises((DocError, ValueError, OSError, Refused), match=re.escape(problem)):
        check_command(DocCommand("doc.md", 1, words, 0), Written())


# --- the reference agents ---------------------------------------------------------------------

SHIPPED = sorted(p.name for p in AGENTS.iterdir() if _agent_folder(p))
NUMBERS = "one two three four five six seven eight nine ten".split()
COUNT = re.compile(rf"\b({'|'.join(NUMBERS)}|\d+)\s+(?:reference|shipped|trained)\s+agents\b", re.I)
AGENT_NAME = r"`(?:ppo|sac)_[a-z0-9_]+`"
AGENT_LIST = re.compile(rf"{AGENT_NAME}(?:,?\s+(?:and\s+)?{AGENT_NAME})+")
# Counts of docs the lead edits, wrong until then (as KNOWN_WRONG).
KNOWN_WRONG_COUNTS = {}


def _agent_statements() -> list:
    """Each count of the reference agents ("five reference agents") and each list of three or
    more agent names in the docs (docs/results.md's history aside)."""
    found = []
    for doc in DOCS:
        text = (ROOT / doc).read_text(encoding="utf-8")
        if doc in HISTORY:
            text = text.split(f"\n{HISTORY[doc]}\n")[0]
        for match in [*COUNT.finditer(text), *AGENT_LIST.finditer(text)]:
            statement = " ".join(match[0].split())
            if match.re is AGENT_LIST and statement.count("`") < 6:
                continue
            where = f"{doc}:{text.count(chr(10), 0, match.start()) + 1}"
            marks = []
            if where in KNOWN_WRONG_COUNTS:
                marks = [pytest.mark.xfail(reason=KNOWN_WRONG_COUNTS[where], strict=True)]
            found.append(
                pytest.param(where, statement, id=f"{where} {statement[:40]}", marks=marks)
            )
    return found


def test_the_reference_agents_are_the_folders_of_benchmarks_agents() -> None:
    from benchmarks.catalog.policies import REFERENCE_AGENTS

    assert sorted(REFERENCE_AGENTS) == SHIPPED
    table = (AGENTS / "README.md").read_text()
    rows = re.findall(r"^\| \[`([a-z0-9_]+)`\]\(\1/README\.md\)", table, re.M)
    assert sorted(rows) == SHIPPED, "benchmarks/agents/README.md has one row per agent"


@pytest.mark.parametrize(("where", "statement"), _agent_statements())
def test_a_count_or_list_of_the_reference_agents_is_the_shipped_one(where, statement) -> None:
    names = re.findall(r"`([^`]+)`", statement)
    if names:
        assert sorted(names) == SHIPPED, f"{where}: {statement!r} lists {len(names)} agents"
    else:
        number = COUNT.match(statement)[1].lower()
        count = NUMBERS.index(number) + 1 if number in NUMBERS else int(number)
        assert count == len(SHIPPED), f"{where}: {statement!r}; benchmarks/agents/ holds {SHIPPED}"


def test_export_refuses_a_former_agent_name_as_compare_does(tmp_path, capsys) -> None:
    """`auv-gym export ppo` says what to type instead, in compare's words (`PolicySpec.parse`)."""
    pytest.importorskip("onnx")
    from benchmarks.catalog.policies import PolicySpec
    from benchmarks.runner import export

    for name in ("ppo", "ppo:runs/x", "sac_helix"):
        with pytest.raises(ValueError) as compare_says:
            PolicySpec.parse(name)
        with pytest.raises(SystemExit) as stop:
            export.main([name, "--out", str(tmp_path / "x.onnx")])
        assert stop.value.code == 2
        assert capsys.readouterr().err.strip().endswith(f"error: {compare_says.value}")
    assert list(tmp_path.iterdir()) == []
