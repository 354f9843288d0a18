"""Every reference in the repository resolves inside the repository.

Checked over the repository's files (git's tracked and untracked-but-not-ignored files):

* Markdown links and images, ``[text](target)``, ``![alt](target)``, reference definitions and
  HTML ``src``/``href``: a relative target must be an existing path inside the repository; an
  ``#anchor`` into a Markdown file must name one of its headings (GitHub's heading slugs).
* Section citations ``docs/<file>.md §N[.M]`` (also ``…, §P.Q`` lists) in .py, .md, .toml, .yml
  and the other text files: the file exists and has a heading for every cited section. The
  manual's heading convention is ``## §N Title`` / ``### §N.M Title``.
* Bare ``§N.M`` references inside docs/*.md: a heading of the same file.
* Repository paths cited in text (``benchmarks/agents/README.md``, ``tests/test_x.py::test_y``):
  the path exists (and the test function or class exists), unless git ignores it (a run's
  output). Only paths whose first folder is one of the repository's own folders, or docs/, are
  taken for citations; ``RUN/…`` or ``out/…`` in a usage line are placeholders.
* The manual's tables of defaults (docs/model.md §2.2, §4.6): every field of `AUVParams` and
  `ControllerGains` has a row, and the value in it is the code's default.
* No reference leaves the repository: no path into the sibling ``shared`` folder, and no
  citation of the design files that live outside the repository by their upper-case names.
"""

from __future__ import annotations

import itertools
import math
import re
import subprocess
import unicodedata
from collections.abc import Iterable
from dataclasses import dataclass, fields
from pathlib import Path
from urllib.parse import unquote

import pytest

ROOT = Path(__file__).resolve().parents[1]
TEXT_SUFFIXES = {".py", ".md", ".toml", ".yml", ".yaml", ".sh", ".cfg", ".txt", ".ini"}
CITED_SUFFIXES = "md py toml yml yaml json csv png sh npz zip txt".split()
SKIPPED_DIRS = {".git", ".venv", "build", "out", "runs", "__pycache__", ".pytest_cache"}
# What the checker must refuse, spelt in pieces so that no file of the project contains them.
OUTSIDE = "../" + "shared"
OLD_MANUAL = "MODEL" + ".md"

HEADING = re.compile(r"^ {0,3}(#{1,6})[ \t]+(.*?)[ \t]*#*[ \t]*$", re.M)
SECTION_HEADING = re.compile(r"^§(\d+(?:\.\d+)*)(?=[ \t]|$)")
FENCE = re.compile(r"^ {0,3}(```|~~~).*?^ {0,3}\1[^\n]*$", re.M | re.S)
INLINE_CODE = re.compile(r"`[^`\n]*`")
LINK_TARGET = re.compile(r"\]\(\s*<?([^)\s>]*)>?(?:\s+(?:\"[^\"]*\"|'[^']*'))?\s*\)")
REFERENCE_DEFINITION = re.compile(r"^ {0,3}\[[^\]]+\]:[ \t]*<?(\S+?)>?(?:[ \t]|$)", re.M)
HTML_TARGET = re.compile(r"""\b(?:src|href)\s*=\s*["']([^"']+)["']""")
LINK_TO_FILE = re.compile(r"\[[^\]\n]*\]\(\s*[^)#\s][^)]*\)")
SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*:")
# A repository-relative path with at least one folder: benchmarks/x.md, tests/test_x.py.
PATH = r"(?<![\w./-])((?:[\w-]+/)+[\w.-]+\.(?:" + "|".join(CITED_SUFFIXES) + r"))(?![\w/-])"
SECTIONS = r"((?:[ \t]*\n?[ \t]*§\d+(?:\.\d+)*)(?:[ \t]*(?:,|;|and)\s*§\d+(?:\.\d+)*)*)?"
CITATION = re.compile(PATH + SECTIONS)
TEST_NAME = re.compile(r"::(\w+)")
SECTION_NUMBER = re.compile(r"§(\d+(?:\.\d+)*)")
FORBIDDEN = (
    (re.compile(r"\.\./shared\b|/work/shared\b"), "points outside the repository"),
    (
        re.compile(r"(?<![\w/.-])(?:MODEL|DESIGN|STYLE)\.md\b"),
        "cites a design file that is not in the repository (use docs/…)",
    ),
)


@dataclass(frozen=True)
class Problem:
    file: str
    line: int
    message: str

    def __str__(self) -> str:
        return f"{self.file}:{self.line}: {self.message}"


def repository_files(root: Path) -> list[Path]:
    """The repository's files: git's tracked plus untracked-but-not-ignored, else a tree walk."""
    try:
        listed = subprocess.run(
            ["git", "ls-files", "--cached", "--others", "--exclude-standard", "-z"],
            cwd=root,
            capture_output=True,
            check=True,
            text=True,
        ).stdout
        names = [name for name in listed.split("\0") if name]
    except (OSError, subprocess.CalledProcessError):
        names = [
            str(p.relative_to(root))
            for p in root.rglob("*")
            if p.is_file() and not SKIPPED_DIRS.intersection(p.relative_to(root).parts)
        ]
    return sorted({root / name for name in names if (root / name).is_file()})


def text_files(root: Path, files: Iterable[Path]) -> list[Path]:
    """The files whose text is scanned: known text suffixes, or an executable script."""
    chosen = []
    for path in files:
        if path.suffix in TEXT_SUFFIXES:
            chosen.append(path)
        elif not path.suffix and path.read_bytes()[:2] == b"#!":
            chosen.append(path)
    return chosen


def git_ignored(root: Path, paths: Iterable[str]) -> set[str]:
    """The given repository-relative paths that git ignores (a run's outputs)."""
    paths = sorted(set(paths))
    if not paths:
        return set()
    try:
        out = subprocess.run(
            ["git", "check-ignore", "--no-index", "--stdin"],
            cwd=root,
            input="\n".join(paths),
            capture_output=True,
            text=True,
            check=False,
        ).stdout
    except OSError:
        return set()
    return set(out.split())


def line_of(text: str, offset: int) -> int:
    return text.count("\n", 0, offset) + 1


def blank_out(text: str, pattern: re.Pattern[str], keep_newlines: bool = True) -> str:
    """Replace every match by spaces (newlines kept), so offsets and line numbers stay valid."""
    return pattern.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)) if keep_newlines else "", text)


def github_slug(heading: str) -> str:
    """The anchor GitHub gives a heading: markup dropped, lower case, punctuation removed."""
    text = re.sub(r"`([^`]*)`", r"\1", heading)
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", text)
    kept = []
    for char in text.strip().lower():
        category = unicodedata.category(char)
        if char in " -" or category[0] in "LMN" or category == "Pc":
            kept.append(char)
    return "".join(kept).replace(" ", "-")


def headings(text: str) -> list[str]:
    """The ATX headings of a Markdown text, outside fenced code."""
    return [m.group(2) for m in HEADING.finditer(blank_out(text, FENCE))]


def anchors(text: str) -> set[str]:
    seen: dict[str, int] = {}
    found = set()
    for heading in headings(text):
        slug = github_slug(heading)
        count = seen.get(slug, 0)
        seen[slug] = count + 1
        found.add(slug if count == 0 else f"{slug}-{count}")
    return found


def sections(text: str) -> set[str]:
    """Section numbers of the headings that start with §N[.M] (the manual's convention)."""
    return {m.group(1) for h in headings(text) if (m := SECTION_HEADING.match(h))}


class Checker:
    """Finds broken references among the given files of a repository rooted at ``root``."""

    def __init__(
        self, root: Path, files: Iterable[Path] | None = None, exclude: Iterable[Path] = ()
    ) -> None:
        self.root = root.resolve()
        all_files = repository_files(self.root) if files is None else sorted(files)
        skipped = {p.resolve() for p in exclude}
        self.files = [p for p in text_files(self.root, all_files) if p.resolve() not in skipped]
        self.top_folders = {
            p.relative_to(self.root).parts[0]
            for p in all_files
            if len(p.relative_to(self.root).parts) > 1
        } | {"docs"}
        self._texts: dict[Path, str] = {}

    def text(self, path: Path) -> str:
        if path not in self._texts:
            self._texts[path] = path.read_text(encoding="utf-8")
        return self._texts[path]

    def rel(self, path: Path) -> str:
        return path.relative_to(self.root).as_posix()

    def markdown_files(self) -> list[Path]:
        return [p for p in self.files if p.suffix == ".md"]

    def link_problems(self) -> list[Problem]:
        problems = []
        for md in self.markdown_files():
            text = blank_out(blank_out(self.text(md), FENCE), INLINE_CODE)
            targets = [
                (m.start(1), m.group(1))
                for pattern in (LINK_TARGET, REFERENCE_DEFINITION, HTML_TARGET)
                for m in pattern.finditer(text)
            ]
            for offset, target in sorted(targets):
                message = self._target_problem(md, target)
                if message:
                    problems.append(Problem(self.rel(md), line_of(text, offset), message))
        return problems

    def _target_problem(self, md: Path, target: str) -> str | None:
        if not target or SCHEME.match(target):
            return None
        path_part, _, anchor = target.partition("#")
        if path_part:
            base = self.root if path_part.startswith("/") else md.parent
            resolved = (base / unquote(path_part.lstrip("/"))).resolve()
            if not resolved.is_relative_to(self.root):
                return f"link {target!r} leaves the repository"
            if not resolved.exists():
                return f"link {target!r}: no such file"
        else:
            resolved = md
        if anchor and resolved.suffix == ".md" and resolved.is_file():
            if unquote(anchor).lower() not in anchors(self.text(resolved)):
                return f"link {target!r}: {self.rel(resolved)} has no heading with that anchor"
        return None

    def citation_problems(self) -> list[Problem]:
        """Cited repository paths, their § sections and their ``::test`` names."""
        found: list[tuple[Path, int, str, list[str], str | None]] = []
        for path in self.files:
            text = self.text(path)
            if path.suffix == ".md":  # link targets are relative to the file: checked above
                text = blank_out(blank_out(text, LINK_TARGET), REFERENCE_DEFINITION)
            for m in CITATION.finditer(text):
                cited = m.group(1)
                if cited.split("/")[0] not in self.top_folders:
                    continue
                numbers = SECTION_NUMBER.findall(m.group(2) or "")
                test = TEST_NAME.match(text, m.end(1))
                found.append(
                    (
                        path,
                        line_of(text, m.start()),
                        cited,
                        numbers,
                        test.group(1) if test else None,
                    )
                )
        missing = {cited for _, _, cited, _, _ in found if not (self.root / cited).exists()}
        ignored = git_ignored(self.root, missing)
        problems = []
        for path, line, cited, numbers, test in found:
            target = self.root / cited
            where = (self.rel(path), line)
            if not target.exists():
                if cited not in ignored:
                    problems.append(Problem(*where, f"cites {cited}, which does not exist"))
                continue
            if numbers and target.suffix == ".md":
                have = sections(self.text(target))
                for number in numbers:
                    if number not in have:
                        problems.append(
                            Problem(
                                *where, f"cites {cited} §{number}: no heading '§{number} …' there"
                            )
                        )
            if test and target.suffix == ".py":
                if not re.search(
                    rf"^\s*(?:async\s+)?(?:def|class)\s+{test}\b", self.text(target), re.M
                ):
                    problems.append(Problem(*where, f"cites {cited}::{test}, which is not there"))
        return problems

    def inner_section_problems(self) -> list[Problem]:
        """Bare §N.M references in docs/*.md must be headings of the same file."""
        problems = []
        for md in self.markdown_files():
            if self.rel(md).split("/")[0] != "docs":
                continue
            text = self.text(md)
            have = sections(text)
            scan = blank_out(text, CITATION)  # citations of other files are checked above
            scan = blank_out(scan, LINK_TO_FILE)  # so are links into other files
            scan = blank_out(scan, HEADING)
            for m in SECTION_NUMBER.finditer(scan):
                if m.group(1) not in have:
                    message = f"§{m.group(1)} is not a heading of this file"
                    problems.append(Problem(self.rel(md), line_of(text, m.start()), message))
        return problems

    def forbidden_problems(self) -> list[Problem]:
        problems = []
        for path in self.files:
            text = self.text(path)
            for pattern, message in FORBIDDEN:
                for m in pattern.finditer(text):
                    problems.append(
                        Problem(
                            self.rel(path), line_of(text, m.start()), f"{m.group(0)!r} {message}"
                        )
                    )
        return problems


def report(problems: list[Problem]) -> str:
    return f"{len(problems)} broken reference(s):\n" + "\n".join(map(str, problems))


@pytest.fixture(scope="module")
def checker() -> Checker:
    # This file's own examples below are broken on purpose.
    return Checker(ROOT, exclude=[Path(__file__)])


def test_markdown_links_and_images_resolve(checker):
    assert checker.markdown_files(), "no Markdown files found"
    problems = checker.link_problems()
    assert not problems, report(problems)


def test_cited_paths_sections_and_tests_exist(checker):
    problems = checker.citation_problems()
    assert not problems, report(problems)


def test_section_references_inside_the_docs_resolve(checker):
    problems = checker.inner_section_problems()
    assert not problems, report(problems)


def test_nothing_refers_outside_the_repository(checker):
    problems = checker.forbidden_problems()
    assert not problems, report(problems)


# The manual keeps the section numbers that the code's citations were written against.
MANUAL_SECTIONS = (
    "0",
    "1",
    "2",
    "2.1",
    "2.2",
    "2.3",
    "2.4",
    "2.5",
    "2.6",
    "2.7",
    "3",
    "3.1",
    "3.2",
    "3.3",
    "3.4",
    "3.5",
    "4",
    "4.1",
    "4.2",
    "4.3",
    "4.4",
    "4.5",
    "4.6",
    "4.7",
    "4.8",
    "4.9",
    "5",
    "6",
    "7",
    "8",
    *(f"8.{k}" for k in range(1, 11)),
    "9",
    "10",
    *(f"10.{k}" for k in range(1, 8)),
)


def test_model_manual_keeps_its_section_numbers():
    have = sections((ROOT / "docs" / "model.md").read_text(encoding="utf-8"))
    assert set(MANUAL_SECTIONS) <= have, sorted(set(MANUAL_SECTIONS) - have)


TABLE_CELL_NAME = re.compile(r"^`([\w.]+)`$")
TABLE_NUMBER = re.compile(r"^[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")


def documented_defaults(text: str, names: set[str]) -> dict[str, list[float | bool]]:
    """Values given in Markdown table rows as `| `name` | value |`, for the given names."""
    found: dict[str, list[float | bool]] = {}
    for line in text.splitlines():
        if not line.startswith("|"):
            continue
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        for name_cell, value_cell in itertools.pairwise(cells):
            m = TABLE_CELL_NAME.match(name_cell)
            if not (m and m.group(1) in names):
                continue
            value = value_cell.replace("\u2212", "-")
            if value in ("true", "false"):
                found.setdefault(m.group(1), []).append(value == "true")
            elif number := TABLE_NUMBER.match(value):
                found.setdefault(m.group(1), []).append(float(number.group(0)))
    return found


def code_defaults() -> dict[str, float | bool]:
    """The defaults of `AUVParams`, `ActuatorParams` and `ControllerGains`, membership sets as
    `surge_mf.p` etc."""
    from auv_gym.vehicle import AUVParams
    from auv_gym.vehicle.actuators import ActuatorParams
    from controllers.gains import ControllerGains, MembershipSet

    defaults: dict[str, float | bool] = {}
    for obj in (AUVParams(), ActuatorParams(), ControllerGains()):
        for f in fields(obj):
            value = getattr(obj, f.name)
            if isinstance(value, MembershipSet):
                defaults.update(
                    {f"{f.name}.{g.name}": getattr(value, g.name) for g in fields(value)}
                )
            else:
                assert f.name not in defaults, f"field name {f.name} is ambiguous in the tables"
                defaults[f.name] = value
    return defaults


def test_manual_tables_match_the_code_defaults():
    defaults = code_defaults()
    documented = documented_defaults(
        (ROOT / "docs" / "model.md").read_text(encoding="utf-8"), set(defaults)
    )
    missing = sorted(set(defaults) - set(documented))
    assert not missing, f"docs/model.md has no table row for {missing}"
    wrong = [
        f"{name}: manual {value}, code {defaults[name]}"
        for name, values in documented.items()
        for value in values
        if not (
            value is defaults[name]
            if isinstance(defaults[name], bool)
            else not isinstance(value, bool)
            and math.isclose(value, defaults[name], rel_tol=5e-4, abs_tol=1e-12)
        )
    ]
    assert not wrong, "docs/model.md disagrees with the code:\n" + "\n".join(wrong)


def test_documented_defaults_reads_numbers_signs_and_flags():
    text = "| a | `x` | −1.5 | kg |\n| `flag` | true |\n| `y` | 0.5236 (π/6) |\n`z` | 3 |\n"
    assert documented_defaults(text, {"x", "flag", "y", "z"}) == {
        "x": [-1.5],
        "flag": [True],
        "y": [0.5236],
    }


# The checker itself, on a small repository with one broken reference of each kind.
def _write(root: Path, name: str, text: str) -> None:
    (root / name).parent.mkdir(parents=True, exist_ok=True)
    (root / name).write_text(text, encoding="utf-8")


def test_checker_reports_each_kind_of_broken_reference(tmp_path):
    _write(
        tmp_path,
        "docs/guide.md",
        "# Guide\n\n## §1 Frames\n\n### §1.2 Signs\n\nSee §1.2, "
        "§1.3 and [frames](#1-frames), [nowhere](#2-gone), [§9 of the README](../README.md).\n",
    )
    _write(
        tmp_path,
        "README.md",
        "[guide](docs/guide.md) ![fig](img/missing.png)\n"
        "[up](../outside.md) [web](https://example.org/x.md)\n```\n[code](not/checked.md)\n"
        "```\n`[inline](not/checked.md)`\n[ref]: docs/absent.md\n",
    )
    module = (
        '"""Law of docs/guide.md §1.2, §1.5; docs/guide.md §7 and docs/guide.md.\n'
        "Tests: tests/test_a.py::test_there, tests/test_a.py::test_gone; pkg/none.md; "
        "RUN/out.json; out/x.md.\n"
        f'Old: {OLD_MANUAL} §2, {OUTSIDE}/x.\n"""\n'
    )
    _write(tmp_path, "pkg/mod.py", module)
    _write(tmp_path, "tests/test_a.py", "def test_there():\n    pass\n")
    checker = Checker(tmp_path, [p for p in tmp_path.rglob("*") if p.is_file()])

    links = sorted(str(p) for p in checker.link_problems())
    assert links == [
        "README.md:1: link 'img/missing.png': no such file",
        "README.md:2: link '../outside.md' leaves the repository",
        "README.md:7: link 'docs/absent.md': no such file",
        "docs/guide.md:7: link '#2-gone': docs/guide.md has no heading with that anchor",
    ]
    citations = sorted(str(p) for p in checker.citation_problems())
    assert citations == [
        "pkg/mod.py:1: cites docs/guide.md §1.5: no heading '§1.5 …' there",
        "pkg/mod.py:1: cites docs/guide.md §7: no heading '§7 …' there",
        "pkg/mod.py:2: cites pkg/none.md, which does not exist",
        "pkg/mod.py:2: cites tests/test_a.py::test_gone, which is not there",
    ]
    inner = [str(p) for p in checker.inner_section_problems()]
    assert inner == ["docs/guide.md:7: §1.3 is not a heading of this file"]
    forbidden = sorted(str(p) for p in checker.forbidden_problems())
    assert len(forbidden) == 2
    assert forbidden[0].startswith(f"pkg/mod.py:3: '{OUTSIDE}'")
    assert forbidden[1].startswith(f"pkg/mod.py:3: '{OLD_MANUAL}' cites a design file")


def test_github_slugs_of_manual_headings():
    assert github_slug("§2.1 Equations of motion (paper (1)–(2))") == (
        "21-equations-of-motion-paper-12"
    )
    assert github_slug("`AUVParams`: REMUS 100 values") == "auvparams-remus-100-values"
    assert anchors("# A\n## A\n```\n# not a heading\n```\n") == {"a", "a-1"}
