"""What was removed from auv-gym is refused with one line naming it, not silently ignored: the
training features no kept agent used (hyper-parameter keys, agent metadata stages)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

import controllers
from benchmarks.training.config import REMOVED_KEYS
from controllers.agent import REMOVED_STAGES

ROOT = Path(__file__).resolve().parent.parent
AGENT = ROOT / "benchmarks" / "agents" / "ppo_generalist"
CONFIG = """AUVPath3D-v0:
  n_envs: 2
  n_timesteps: 64
  policy: MlpPolicy
  normalize: true
  {key}: {value}
"""
REMOVED_VALUES = {
    "action_increment": "0.1",
    "action_scale": "[0.15, 1.0, 1.0]",
    "action_std_schedule": "{start: 0.5, final: 0.05}",
    "cost_penalty": "10.0",
}


@pytest.mark.parametrize("key", sorted(REMOVED_KEYS))
def test_a_hyper_parameter_file_with_a_removed_key_is_refused_naming_it(tmp_path, key):
    pytest.importorskip("yaml")
    from benchmarks.training.config import read_zoo_config

    path = tmp_path / "old.yml"
    path.write_text(CONFIG.format(key=key, value=REMOVED_VALUES[key]))
    with pytest.raises(ValueError) as error:
        read_zoo_config(path)
    message = str(error.value)
    assert "\n" not in message
    assert message == (
        f"{path}: AUVPath3D-v0: key {key!r} ({REMOVED_KEYS[key]}) was removed from auv-gym; "
        "delete it from the file"
    )


@pytest.mark.parametrize("key", sorted(REMOVED_STAGES))
def test_an_agent_whose_metadata_names_a_removed_stage_is_refused(tmp_path, key):
    agent = tmp_path / "old_agent"
    shutil.copytree(AGENT, agent)
    metadata = agent / "metadata.json"
    recorded = json.loads(metadata.read_text())
    recorded[key] = 0.1 if key == "action_increment" else [0.15, 1.0, 1.0]
    metadata.write_text(json.dumps(recorded))
    with pytest.raises(ValueError) as error:
        controllers.make("agent", path=str(agent))
    message = str(error.value)
    assert "\n" not in message
    assert message.startswith(f"{metadata}: {key!r} ({REMOVED_STAGES[key]}) was removed")
