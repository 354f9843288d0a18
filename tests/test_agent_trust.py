"""Agent folders are data: a pickle planted in one never runs (docs/usage.md, "Trusting agent
files")."""

from __future__ import annotations

import os
import pickle
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import controllers
from benchmarks.catalog.policies import AGENTS_DIR
from controllers.agent import check_agent

ROOT = Path(__file__).resolve().parents[1]


class Payload:
    """Unpickling this runs ``touch MARKER``: what a malicious vecnormalize.pkl would do."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (os.system, (f"touch {self.marker}",))


@pytest.fixture
def planted(tmp_path: Path) -> tuple[Path, Path]:
    """(an agent folder whose only statistics are a planted pickle, the marker it would make)."""
    agent = tmp_path / "agent"
    shutil.copytree(AGENTS_DIR / "ppo_helix", agent)
    (agent / "vecnormalize.npz").unlink()
    marker = tmp_path / "payload_ran"
    (agent / "vecnormalize.pkl").write_bytes(pickle.dumps(Payload(marker)))
    return agent, marker


def test_a_planted_pickle_is_refused_and_never_runs(planted):
    agent, marker = planted
    with pytest.raises(ValueError, match=r"never unpickles vecnormalize\.pkl .* can run code"):
        check_agent(agent)
    with pytest.raises(ValueError, match="stats_from_vecnormalize"):
        controllers.make("agent", path=str(agent))
    assert not marker.exists()


def test_compare_refuses_it_before_any_episode(planted, tmp_path):
    agent, marker = planted
    out = tmp_path / "run"
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "benchmarks",
            "compare",
            "--policies",
            f"fbsm,agent:{agent}",
            "--scenarios",
            "paper",
            "--seeds",
            "1",
            "--duration",
            "20",
            "--out",
            str(out),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 2
    assert len(done.stderr.strip().splitlines()) == 1 and "vecnormalize.pkl" in done.stderr
    assert not marker.exists() and not out.exists()
