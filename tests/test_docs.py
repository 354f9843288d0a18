"""The Python examples in the READMEs and the usage manual run as written (from the root)."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ("README.md", "docs/usage.md", "benchmarks/agents/README.md")


def _examples() -> list[tuple[str, int, str]]:
    found = []
    for doc in DOCS:
        blocks = re.findall(r"```python\n(.*?)```", (ROOT / doc).read_text(), re.S)
        found += [(doc, i, code) for i, code in enumerate(blocks)]
    return found


def test_every_readme_has_examples() -> None:
    assert {doc for doc, _, _ in _examples()} == set(DOCS)


# The agents README's example flies the generalist for 2 × 200 s (about 2 min on 2 cores): the
# integration tier's.
SLOW_DOCS = ("benchmarks/agents/README.md",)


def _marked(example: tuple[str, int, str]):
    marks = [pytest.mark.integration] if example[0] in SLOW_DOCS else []
    return pytest.param(*example, marks=marks)


@pytest.mark.parametrize(
    ("doc", "index", "code"), [_marked(e) for e in _examples()], ids=lambda v: str(v)[:30]
)
def test_readme_example_runs(doc: str, index: int, code: str, monkeypatch, capsys) -> None:
    monkeypatch.chdir(ROOT)  # the examples name files relative to the project root
    namespace: dict = {}
    exec(compile(code, f"{doc} example {index}", "exec"), namespace)
    # Every name the example binds (but "_") holds a value: a documented call that returns
    # nothing (None) where the example uses its result is a wrong example.
    bound = _bound_names(code)
    assert bound, "the example binds no name"
    empty = sorted(n for n in bound if n != "_" and namespace.get(n) is None)
    assert not empty, f"{doc} example {index}: {empty} are None after running it"


def _bound_names(code: str) -> set[str]:
    """Names bound by the example's top-level imports and assignments."""
    names: set[str] = set()
    for node in ast.parse(code).body:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            names |= {(a.asname or a.name).split(".")[0] for a in node.names}
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                names |= {n.id for n in ast.walk(target) if isinstance(n, ast.Name)}
    return names
