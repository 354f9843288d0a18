"""Agent directories of a training run: saving, checkpoints, resuming and export.

Every agent directory (`final/`, `best/`, `checkpoints/step_<num_timesteps>/`, an exported agent)
is complete on its own — model, normalisation statistics, metadata — in the layout
`controllers.ppo.load_policy` reads, and each is written through `auv_gym.files.
write_folder_atomic`, so a killed run never leaves a half-written agent.
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym.files import write_folder_atomic, write_json
from auv_gym.observation import OBS_NAMES
from controllers.ppo import METADATA_FILE, MODEL_FILE, STATS_FILE, VECNORM_FILE

__all__ = [
    "CHECKPOINTS",
    "REPLAY_FILE",
    "SEED_AGENT_PREFIX",
    "export_agent",
    "latest_checkpoint",
    "list_checkpoints",
    "prune_checkpoints",
    "save_agent",
    "write_metadata",
]

CHECKPOINTS = "checkpoints"  # folder of a run holding step_<num_timesteps>/ agent directories
REPLAY_FILE = "replay_buffer.pkl"  # off-policy checkpoints (SAC): the replay buffer, for resuming
SEED_AGENT_PREFIX = "agent_seed_"  # multi-seed results: <prefix><k>/ is training seed k's agent


def write_metadata(path: Path, metadata: dict[str, Any]) -> None:
    """An agent's or a run's metadata.json (sorted keys, 2-space indent), atomically."""
    write_json(path, metadata, indent=2, sort_keys=True)


def save_agent(model: Any, vec_normalize: Any, folder: Path, metadata: dict[str, Any],
               replay_buffer: bool = False) -> None:  # fmt: skip
    """Write model.zip, vecnormalize.pkl/.npz and metadata.json as the folder ``folder``
    (and, with ``replay_buffer``, the off-policy replay buffer as replay_buffer.pkl). The .npz
    names the observation layout ``metadata["obs_names"]`` (default: the env's).

    The folder is filled beside its place and then swapped in (`write_folder_atomic`), so
    readers see either the previous complete agent or the new one.
    """

    def fill(tmp: Path) -> None:
        model.save(tmp / MODEL_FILE)
        vec_normalize.save(str(tmp / VECNORM_FILE))
        rms = vec_normalize.obs_rms
        np.savez(
            tmp / STATS_FILE, mean=rms.mean, var=rms.var, count=np.float64(rms.count),
            clip_obs=np.float64(vec_normalize.clip_obs),
            epsilon=np.float64(vec_normalize.epsilon),
            obs_names=np.array(metadata.get("obs_names", OBS_NAMES)),
        )  # fmt: skip
        write_metadata(tmp / METADATA_FILE, metadata)
        if replay_buffer:
            model.save_replay_buffer(tmp / REPLAY_FILE)

    write_folder_atomic(folder, fill)


def export_agent(source: Path, target: Path) -> None:
    """Copy an agent directory (model.zip, vecnormalize.npz, metadata.json) atomically.

    The pickled VecNormalize is left out: a shipped agent needs only the .npz statistics.
    """

    def fill(tmp: Path) -> None:
        for name in (MODEL_FILE, STATS_FILE, METADATA_FILE):
            shutil.copy2(source / name, tmp / name)

    write_folder_atomic(target, fill)


def list_checkpoints(out: Path) -> list[tuple[int, Path]]:
    """(num_timesteps, folder) of the complete checkpoints of a run, oldest first."""
    found = []
    folder = out / CHECKPOINTS
    if folder.is_dir():
        for p in folder.iterdir():
            m = re.fullmatch(r"step_(\d+)", p.name)
            if m and (p / MODEL_FILE).is_file() and (p / VECNORM_FILE).is_file():
                found.append((int(m.group(1)), p))
    return sorted(found)


def latest_checkpoint(out: str | os.PathLike) -> Path | None:
    """The newest complete checkpoint directory of a run, or None."""
    found = list_checkpoints(Path(out))
    return found[-1][1] if found else None


def checkpoint_folder(out: Path, num_timesteps: int) -> Path:
    """Where the checkpoint at ``num_timesteps`` env steps goes."""
    return out / CHECKPOINTS / f"step_{num_timesteps:010d}"


def prune_checkpoints(out: Path, keep: int) -> None:
    """Delete all but the newest ``keep`` (at least one) checkpoints."""
    for _, old in list_checkpoints(out)[: -max(1, keep)]:
        shutil.rmtree(old, ignore_errors=True)
