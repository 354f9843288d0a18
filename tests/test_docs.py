"""The Python examples in the READMEs run as written (from the project root)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ("README.md", "benchmarks/agents/README.md")


def _examples() -> list[tuple[str, int, str]]:
    found = []
    for doc in DOCS:
        blocks = re.findall(r"```python\n(.*?)```", (ROOT / doc).read_text(), re.S)
        found += [(doc, i, code) for i, code in enumerate(blocks)]
    return found


def test_every_readme_has_examples() -> None:
    assert {doc for doc, _, _ in _examples()} == set(DOCS)


@pytest.mark.parametrize(("doc", "index", "code"), _examples(), ids=lambda v: str(v)[:30])
def test_readme_example_runs(doc: str, index: int, code: str, monkeypatch, capsys) -> None:
    monkeypatch.chdir(ROOT)  # the examples name files relative to the project root
    namespace: dict = {}
    exec(compile(code, f"{doc} example {index}", "exec"), namespace)
    assert namespace, "the example defined nothing"
