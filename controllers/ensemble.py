"""An ensemble of saved agents: several training seeds of one recipe flown as one policy.

Seeds of one recipe differ by more than their mean: on the vehicle as built, the ten seeds of a
residual recipe span 0.76–1.04× the best classical policy on one test set (docs/results.md).
An ensemble flies the mean of its members' actions,

    a(o) = (1/K) Σ_k π_k(o),

each member applying its own observation normalisation; everything around the network (a
residual agent's base and bound, an agent's stages) is the members' own, which must agree.

An ensemble is a folder holding ``ensemble.json``::

    {"members": ["../agent_seed_1", "../agent_seed_4", "../agent_seed_7"]}

each entry an agent folder (or model zip), relative to the ensemble folder or absolute; at least
two, no repeats, none an ensemble itself. `controllers.agent.check_agent` checks the members and
that they agree (algorithm, observation layout, actions, residual section, stages, env);
`controllers.loader.load_policy` flies it, so ``agent:FOLDER`` works wherever an agent does
(docs/usage.md "Ensembles of agents"), and `controllers.onnx_export` writes it as one graph.
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym.support.files import write_text

__all__ = [
    "ENSEMBLE_FILE",
    "MIN_MEMBERS",
    "EnsembleActor",
    "ensemble_members",
    "ensemble_paths",
    "write_ensemble",
]

ENSEMBLE_FILE = "ensemble.json"
MIN_MEMBERS = 2


def ensemble_members(folder: Path) -> tuple[Path, ...] | None:
    """The member paths ``folder``'s ensemble.json lists (resolved against the folder), or None
    when it holds none; ValueError naming the file when it is not a valid list of members."""
    spec = folder / ENSEMBLE_FILE
    if not spec.is_file():
        return None
    try:
        data = json.loads(spec.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"ensemble {spec} is unreadable: {exc}") from None
    if not isinstance(data, dict) or set(data) != {"members"}:
        raise ValueError(f"ensemble {spec} must be a JSON object with one key, 'members'")
    return ensemble_paths(spec, data["members"])


def ensemble_paths(spec: Path, members: Any) -> tuple[Path, ...]:
    """``members`` (paths relative to the folder of ``spec``, or absolute) resolved, after the
    rules of a member list: strings, at least `MIN_MEMBERS`, none twice, each existing and none
    an ensemble itself; ValueError (FileNotFoundError for a missing member) naming ``spec``."""
    if not isinstance(members, list) or not all(isinstance(m, str) and m for m in members):
        raise ValueError(f"ensemble {spec}: 'members' must be a list of agent paths (strings)")
    if len(members) < MIN_MEMBERS:
        raise ValueError(
            f"ensemble {spec} lists {len(members)} member(s); an ensemble needs {MIN_MEMBERS} "
            "or more (fly a single agent as agent:PATH)"
        )
    paths = tuple((spec.parent / m).resolve() for m in members)
    repeated = sorted({m for m, p in zip(members, paths, strict=True) if paths.count(p) > 1})
    if repeated:
        raise ValueError(f"ensemble {spec} lists {repeated} more than once")
    for member, path in zip(members, paths, strict=True):
        if not path.exists():
            raise FileNotFoundError(f"ensemble {spec}: member {member!r} ({path}) does not exist")
        if path.is_dir() and (path / ENSEMBLE_FILE).is_file():
            raise ValueError(f"ensemble {spec}: member {member!r} is an ensemble itself")
        if not path.is_dir() and path.suffix != ".zip":
            raise ValueError(
                f"ensemble {spec}: member {member!r} is neither an agent folder nor a model zip"
            )
    return paths


def write_ensemble(folder: str | os.PathLike, members: Sequence[str | os.PathLike]) -> Path:
    """Write ``folder``/ensemble.json listing ``members`` (stored relative to ``folder``, so the
    folder and its members move together) atomically, after the list's rules
    (`ensemble_paths`); the file's path. The members' agent files are checked when the ensemble
    is loaded (`controllers.agent.check_agent`), or before with
    `controllers.agent.check_ensemble`."""
    root = Path(folder)
    listed = [os.path.relpath(Path(m).resolve(), root.resolve()) for m in members]
    ensemble_paths(root / ENSEMBLE_FILE, listed)
    root.mkdir(parents=True, exist_ok=True)
    text = json.dumps({"members": listed}, indent=2) + "\n"
    return write_text(root / ENSEMBLE_FILE, text)


class EnsembleActor:
    """The mean action of several actors (`controllers.agent.AgentPolicy`) on one observation
    layout: the Policy protocol. Stateless like its members; ``obs_dim``, ``metadata`` and
    ``env_kwargs`` are the first member's (the members agree on them, `check_agent`)."""

    def __init__(self, members: Sequence[Any]) -> None:
        if len(members) < MIN_MEMBERS:
            raise ValueError(f"an ensemble needs {MIN_MEMBERS} or more actors, got {len(members)}")
        dims = sorted({int(m.obs_dim) for m in members})
        if len(dims) > 1:
            raise ValueError(f"ensemble actors observe different widths: {dims}")
        self.members = tuple(members)
        first = self.members[0]
        self.obs_dim = dims[0]
        self.metadata = dict(getattr(first, "metadata", {}) or {})
        self.env_kwargs = dict(getattr(first, "env_kwargs", {}) or {})
        self.observation_space = getattr(first, "observation_space", None)
        self.action_space = getattr(first, "action_space", None)
        self.path = getattr(first, "path", None)

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """The members' mean action (float32, the members' shape) for observations (d,) or
        (n, d)."""
        actions = [
            np.asarray(m.predict(observation, deterministic=deterministic)[0], dtype=np.float32)
            for m in self.members
        ]
        return np.mean(np.stack(actions), axis=0, dtype=np.float32), state

    def __repr__(self) -> str:
        return f"EnsembleActor({len(self.members)} members, first={self.path!r})"
