"""Saved agents scored on a validation set as `auv-gym train-seeds` selects: which would the rule
pick, an ensemble (`auv-gym ensemble`) or the seed it shipped?

    python -m benchmarks.analysis.validation_score \\
        --agents runs/x/results/agent_seed_1,runs/x/ensemble3 \\
        --task-set validation_as_built_plants --episodes 64 --duration 200 --out runs/x/validation

Per agent (an agent folder or an ensemble's): the first ``--episodes`` seeds of the validation
set (a set of role "validation": never the test episodes), ``--duration`` s each, under the
agent's own env (its env id's fixed arguments and its observation,
`benchmarks.catalog.policies.agent_run`); a set that varies the plant or the actuator flies each
in its own batch, the agent's stages or residual base built for it, as training's evaluation
does (`benchmarks.training.evaluation`). Then the summary and the score of the agent's own
selection rule (`benchmarks.training.selection_rule.rule_of`: terminated episodes, then the mean
RMS distance [m], plus a residual agent's chattering weight [m·s] × its mean chattering [1/s]).
Lower is better; the agent a run selected scores here what its summary.json records, the same
episodes flown again. Written to ``--out``/validation_score.json (agent paths as given).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from benchmarks.arguments import comma_names, parse_options, program_name, usage_errors
from benchmarks.options import option

__all__ = ["ValidationScoreOptions", "main", "validation_score"]

SCORE_FILE = "validation_score.json"


@dataclass
class ValidationScoreOptions:
    """The options of ``python -m benchmarks.analysis.validation_score``."""

    agents: str = option("", "comma-separated agent or ensemble folders")
    task_set: str = option("", "a validation set of benchmarks/tasks.toml")
    episodes: int = option(64, "its first N seeds (train-seeds' --eval-episodes)")
    duration: float = option(200.0, "episode length [s] (train-seeds' --eval-duration)")
    out: Path | None = option(None, "folder for validation_score.json", parse=Path)  # noqa: RUF009


def validation_score(agent: Path, task_set: str, episodes: int, duration: float) -> dict[str, Any]:
    """One agent's validation summary and selection score (module doc); ValueError naming the
    agent or the set otherwise."""
    import controllers
    from auv_gym import VARIANTS
    from benchmarks.catalog.policies import agent_run
    from benchmarks.catalog.tasks import task_set as named_set
    from benchmarks.training.evaluation import (
        chattering_mean,
        check_evaluation_duration,
        evaluate_policy_on_seeds,
        summarize,
        variant_groups,
    )
    from benchmarks.training.selection_rule import rule_of
    from controllers.agent import check_agent

    chosen = named_set(task_set)
    if chosen.role != "validation":
        raise ValueError(f"--task-set {task_set!r} is a {chosen.role} set, not a validation set")
    if not 1 <= episodes <= len(chosen.seeds):
        raise ValueError(f"--episodes must be 1-{len(chosen.seeds)} for {task_set!r}")
    check_evaluation_duration(duration)
    _, env_id, agent_env = agent_run(f"agent {agent}", agent)
    metadata = check_agent(agent).metadata
    residual = metadata.get("residual") or {}
    weight = float(residual.get("selection_chattering", 0.0))
    env = {**VARIANTS[env_id], **agent_env, **chosen.eval_env(), "max_time": float(duration)}
    seeds = tuple(chosen.seeds[:episodes])
    results = []
    for label, kwargs in variant_groups(env):
        policy = controllers.make("agent", env=kwargs, path=str(agent))
        rows = evaluate_policy_on_seeds(policy, seeds, extra_metrics=("chattering",), **kwargs)
        results += [row if label is None else {**row, "variant": label} for row in rows]
    summary = summarize(results)
    summary["chattering_mean"] = chattering_mean(results)
    return {
        "agent": str(agent),
        "score": list(rule_of(metadata).score(summary, weight)),
        "chattering_weight_m_s": weight,
        "summary": summary,
    }


def main(argv: Sequence[str] | None = None) -> dict[str, Any]:
    from auv_gym.support.files import write_json

    args, parser = parse_options(
        ValidationScoreOptions,
        argv,
        program_name("benchmarks.analysis.validation_score"),
        __doc__.split("\n\n")[0],
    )
    with usage_errors(parser):
        if args.out is None or not args.task_set:
            raise ValueError("--task-set and --out are required")
        agents = [Path(a) for a in comma_names(args.agents, "--agents")]
        scores = []
        for agent in agents:
            entry = validation_score(agent, args.task_set, args.episodes, args.duration)
            scores.append(entry)
            failed, value = entry["score"]
            print(f"{agent}: score ({failed}, {value:.4f})", flush=True)
    record = {
        "task_set": args.task_set,
        "episodes": args.episodes,
        "duration_s": args.duration,
        "agents": scores,
        "lowest": min(scores, key=lambda s: tuple(s["score"]))["agent"],
    }
    args.out.mkdir(parents=True, exist_ok=True)
    write_json(args.out / SCORE_FILE, record, indent=1)
    print(f"lowest score: {record['lowest']}; wrote {args.out / SCORE_FILE}")
    return record


if __name__ == "__main__":
    main()
