"""Choosing a schedule's seed on its agents as they ship (``select_on: shipped``).

A schedule's export stages (`benchmarks.training.schedule`: an envelope guard, a low-speed floor)
are added after training, so the training's own validation flies the bare network and ranks the
seeds without them. With ``select_on: shipped`` the seed is chosen on the agents as they ship:
each seed's agent of the last phase, with the export stages, flown on the very validation
episodes that phase selected on (the agent's recorded ``eval_env_kwargs`` and ``eval_seeds``),
scored like the training's validation (the run's `benchmarks.training.selection_rule`; by
default fewer terminated episodes, then lower mean RMS distance; ties: the lower seed). Test
episodes are never flown here.

Each seed's result is written to ``OUT/shipped_validation.json`` as soon as it is known
(atomically), so a resumed command flies only the seeds whose agent or stages changed.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from auv_gym.support.files import write_json
from benchmarks.training.evaluation import (
    evaluate_policy_on_seeds,
    summarize,
    variant_groups,
)
from benchmarks.training.selection_rule import rule_of
from controllers.agent import METADATA_FILE
from controllers.env_settings import policy_settings
from controllers.loader import load_policy
from controllers.stages import check_stage_specs

__all__ = ["SELECT_ON", "SHIPPED_FILE", "select_shipped", "shipped_validation"]

SELECT_ON = ("network", "shipped")  # the schedule's ``select_on`` values; the first is default
SHIPPED_FILE = "shipped_validation.json"


def shipped_validation(agent: Path, stages: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """``agent`` (a run's agent directory) inside the stages it trained with and then
    ``stages``, flown on the validation episodes recorded in its metadata, one batch per plant
    or actuator of a varied set (`variant_groups`); its summary (`summarize`) and score.

    ValueError naming the agent when its metadata records no validation episodes.
    """
    metadata = json.loads((agent / METADATA_FILE).read_text())
    env_kwargs, seeds = metadata.get("eval_env_kwargs"), metadata.get("eval_seeds")
    if not isinstance(env_kwargs, dict) or not seeds:
        raise ValueError(
            f"{agent / METADATA_FILE}: records no validation episodes (eval_env_kwargs, "
            "eval_seeds); it cannot be selected as shipped"
        )
    specs = _as_shipped(metadata, stages, agent)
    results = []
    for label, variant in variant_groups(env_kwargs):
        # the stages built for each plant, as the training's validation builds them
        policy = load_policy(agent, base_kwargs=policy_settings(variant), stages=list(specs))
        rows = evaluate_policy_on_seeds(policy, seeds, **variant)
        results.extend(rows if label is None else [{**row, "variant": label} for row in rows])
    summary = summarize(results)
    return {
        "agent": str(agent),
        "num_timesteps": metadata.get("num_timesteps"),
        "stages": specs,
        "eval_seeds": list(seeds),
        "summary": summary,
        "score": list(rule_of(metadata).score(summary)),
    }


def _as_shipped(
    metadata: dict[str, Any], stages: Sequence[dict[str, Any]], agent: Path
) -> list[dict[str, Any]]:
    """The stage specs of an agent as it ships: those it trained inside, then ``stages``."""
    inside = metadata.get("stages") or []
    specs = check_stage_specs([*inside, *stages], f"{agent}: stages as shipped")
    return json.loads(json.dumps([dict(s) for s in specs]))  # as the record reads them back


def select_shipped(
    out: Path,
    entries: Sequence[dict[str, Any]],
    stages: Sequence[dict[str, Any]],
    report: Callable[[str], None] | None = None,
) -> tuple[int, dict[str, Any]]:
    """The seed whose agent (``entries``: the last phase's summary entries, each with "seed"
    and "agent") scores lowest as shipped, and the record written to OUT/`SHIPPED_FILE`.

    A seed already in the record with the same agent, step count and stages is not flown again.
    ``report``: told one line per seed as it is scored (progress of a long selection).
    """
    path = out / SHIPPED_FILE
    record: dict[str, Any] = {"seeds": {}}
    if path.is_file():
        try:
            record = json.loads(path.read_text())
        except (OSError, json.JSONDecodeError):
            record = {"seeds": {}}  # a damaged record is flown again, never trusted
    done = record.get("seeds") if isinstance(record.get("seeds"), dict) else {}
    kept: dict[str, Any] = {}
    for entry in sorted(entries, key=lambda e: e["seed"]):
        seed, agent = entry["seed"], Path(entry["agent"])
        metadata = json.loads((agent / METADATA_FILE).read_text())
        rule = rule_of(metadata)  # one recipe's seeds: one rule
        earlier = done.get(str(seed))
        if not (
            isinstance(earlier, dict)
            and earlier.get("agent") == str(agent)
            and earlier.get("num_timesteps") == metadata.get("num_timesteps")
            and earlier.get("stages") == _as_shipped(metadata, stages, agent)
        ):
            earlier = shipped_validation(agent, stages)
        kept[str(seed)] = earlier
        record = {"seeds": kept}
        write_json(path, record, indent=2, sort_keys=True)
        if report is not None:
            n_term, mean = earlier["score"]
            report(f"seed {seed} as shipped: {n_term} terminated, mean rms {mean:.4f} m")
    chosen = min(kept, key=lambda s: (*kept[s]["score"], int(s)))
    record = {
        "seeds": kept,
        "selected_seed": int(chosen),
        "selection": "lowest validation score of the agents as shipped (export stages on): "
        f"{rule.describe()}, on the last phase's validation "
        "episodes; test episodes are never used to choose",
    }
    write_json(path, record, indent=2, sort_keys=True)
    return int(chosen), record
