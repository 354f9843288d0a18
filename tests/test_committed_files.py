"""Committed results and agents record no machine's paths: a reader's checkout is elsewhere."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COMMITTED = [ROOT / "benchmarks" / "results", ROOT / "benchmarks" / "agents"]
TEXT_SUFFIXES = {".json", ".md", ".csv", ".yml", ".yaml", ".toml"}
# an absolute path into a home, a work or check-out folder of some machine
MACHINE_PATH = re.compile(r"(?<![\w.])/(?:work|home|Users|check|root|mnt|scratch)/[\w.-]+")


def test_no_committed_text_file_records_a_machine_path() -> None:
    found = []
    for folder in COMMITTED:
        for path in sorted(folder.rglob("*")):
            if path.suffix in TEXT_SUFFIXES and path.is_file():
                hit = MACHINE_PATH.search(path.read_text(encoding="utf-8", errors="replace"))
                if hit:
                    found.append(f"{path.relative_to(ROOT)}: {hit.group(0)}")
    assert found == []


def test_the_check_sees_a_machine_path() -> None:
    assert MACHINE_PATH.search('"out": "/work/main/runs/x"')
    assert MACHINE_PATH.search("written to /home/ana/auv-gym/out")
    assert not MACHINE_PATH.search('"out": "runs/x", "doc": "docs/model.md §2/work"')
