"""Committed results and agents record no machine's paths: a reader's checkout is elsewhere."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COMMITTED = [ROOT / "benchmarks" / "results", ROOT / "benchmarks" / "agents"]
TEXT_SUFFIXES = {".json", ".md", ".csv", ".yml", ".yaml", ".toml"}
# an absolute path into a home, a work or check-out folder of some machine
MACHINE_PATH = re.compile(r"(?<![\w.])/(?:work|home|Users|check|root|mnt|scratch)/[\w.-]+")


def committed_text_files(folders: list[Path] | None = None) -> list[Path]:
    """The text files (`TEXT_SUFFIXES`) under ``folders`` (default `COMMITTED`), sorted."""
    return [
        path
        for folder in (COMMITTED if folders is None else folders)
        for path in sorted(folder.rglob("*"))
        if path.suffix in TEXT_SUFFIXES and path.is_file()
    ]


def test_no_committed_text_file_records_a_machine_path() -> None:
    found = []
    for path in committed_text_files():
        hit = MACHINE_PATH.search(path.read_text(encoding="utf-8", errors="replace"))
        if hit:
            found.append(f"{path.relative_to(ROOT)}: {hit.group(0)}")
    assert found == []


def test_the_check_sees_a_machine_path() -> None:
    assert MACHINE_PATH.search('"out": "/work/main/runs/x"')
    assert MACHINE_PATH.search("written to /home/ana/auv-gym/out")
    assert not MACHINE_PATH.search('"out": "runs/x", "doc": "docs/model.md §2/work"')
