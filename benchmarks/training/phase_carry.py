"""A schedule's selection across phases (``keep_earlier: true``, docs/design.md §3.20).

Each phase of a schedule selects each seed's agent among its own evaluations, so a phase that
makes every seed worse on its validation (the generalist's precision phase, whose finer error
scales cost the fin-share agents fin episodes they had passed) still hands on one of its own.
With ``keep_earlier`` a seed keeps the agent the phase started from when that agent scored
better on the very same validation episodes: the entry of the phase before (its agent, scores,
test summary) replaces the phase's own, marked ``kept_from`` with that phase's name, and the
choice among seeds is made again. Agents compare only when both were validated on the same
episodes by the same rule (the same recorded ``eval_env_kwargs``, ``eval_seeds``, evaluation
duration and ``selection``); otherwise the phase's own entry stands. Test episodes are never
used.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from controllers.agent import METADATA_FILE

__all__ = ["keep_earlier"]


def keep_earlier(
    previous: Mapping[str, Any], summary: Mapping[str, Any], previous_name: str
) -> dict[str, Any]:
    """``summary`` (a phase's `train_seeds` summary) with each seed's entry replaced by its
    entry in ``previous`` (the phase before, named ``previous_name``) where that one scored
    strictly lower on the same validation; ``selected_seed`` chosen again among the result."""
    from benchmarks.training.seeds import select

    before = {entry["seed"]: entry for entry in previous["seeds"]}
    seeds = []
    for entry in summary["seeds"]:
        earlier = before.get(entry["seed"])
        if earlier is not None and _same_validation(earlier, entry):
            if _score(earlier) < _score(entry):
                entry = {**earlier, "kept_from": earlier.get("kept_from", previous_name)}
        seeds.append(entry)
    return {**summary, "seeds": seeds, "selected_seed": select(seeds)["seed"]}


def _score(entry: Mapping[str, Any]) -> tuple[float, float]:
    score = entry.get("validation_score")
    if not score:
        return (math.inf, math.inf)
    return (float(score[0]), float(score[1]))


def _same_validation(a: Mapping[str, Any], b: Mapping[str, Any]) -> bool:
    validation = _validation_of(a)
    return validation is not None and validation == _validation_of(b)


def _validation_of(entry: Mapping[str, Any]) -> str | None:
    """What an entry's agent was validated on, as comparable text (None: not recorded)."""
    try:
        meta = json.loads((Path(entry["agent"]) / METADATA_FILE).read_text())
    except (OSError, KeyError, json.JSONDecodeError):
        return None
    env_kwargs, seeds = meta.get("eval_env_kwargs"), meta.get("eval_seeds")
    if env_kwargs is None or not seeds:
        return None
    record = {
        "eval_env_kwargs": env_kwargs,
        "eval_seeds": seeds,
        "eval_duration": (meta.get("options") or {}).get("eval_duration"),
        "selection": (meta.get("config") or {}).get("selection"),
    }
    return json.dumps(record, sort_keys=True, default=str)
