"""Agent folders are data: a pickle planted in one never runs (docs/usage.md, "Trusting agent
files")."""

from __future__ import annotations

import json
import os
import pickle
import shutil
from pathlib import Path

import pytest

import controllers
from benchmarks.catalog.policies import AGENTS_DIR
from controllers.agent import check_agent


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
    shutil.copytree(AGENTS_DIR / "ppo_generalist", agent)
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


def test_compare_refuses_it_before_any_episode(planted, tmp_path, auv_gym_command):
    agent, marker = planted
    out = tmp_path / "run"
    episodes = "--scenarios paper --seeds 1 --duration 20".split()
    code, err = auv_gym_command(
        "compare", "--policies", f"fbsm,agent:{agent}", *episodes, "--out", str(out)
    )
    assert code == 2
    assert len(err.splitlines()) == 1 and "vecnormalize.pkl" in err
    assert not marker.exists() and not out.exists()


@pytest.mark.rl
def test_a_warm_start_reads_the_npz_and_never_the_pickle(planted, tmp_path):
    """Was: `train --init-from` always unpickled the agent's vecnormalize.pkl."""
    import numpy as np

    from benchmarks.training.warm_start import check_warm_start

    agent, marker = planted
    meta = json.loads((agent / "metadata.json").read_text())
    (agent / "metadata.json").write_text(json.dumps({**meta, "algo": "ppo"}))
    source = np.load(AGENTS_DIR / "ppo_generalist" / "vecnormalize.npz")
    stats = {
        key: source[key] for key in source.files if not key.startswith(("ret_", "gamma", "clip_r"))
    }
    np.savez(agent / "vecnormalize.npz", **stats)  # as saved before the return statistics were
    with pytest.raises(ValueError, match=r"lacks \['ret_mean', 'ret_var', 'ret_count'\]"):
        check_warm_start(agent, "ppo")
    np.savez(agent / "vecnormalize.npz", **stats, ret_mean=0.0, ret_var=4.0, ret_count=10.0)
    assert check_warm_start(agent, "ppo")["obs_names"]  # the metadata, checked
    assert not marker.exists()  # the planted pickle beside it was never opened
