"""Agents against the best classical policy on a validation task set: the time-to-target measure.

Issue targets such as "≤ 2× FBSM on validation within 15 min per seed" need a reference that
is fair to the classical side. The agents' own selection set, ``validation``, draws 'paper' or
'fins' actuators at random, and a classical controller built for 'paper' actuators is not told
which one it drives: there FBSM + CO-LOS scores 0.46 m, worse than any third-generation agent.
``validation_paper_actuator`` holds the same distribution with 'paper' actuators on seeds of
its own, where the classical controllers know their vehicle (FBSM + CO-LOS: 0.079 m). This
command runs policies on the first ``--episodes`` seeds of a validation set and prints each
one's mean RMS distance [m], its failures, its ratio to ``--reference`` and, for agents, the
env steps and wall time [s] of training its metadata records.

Each policy runs under the benchmark's env id for it, as in the test suite: a classical
controller under ``AUVPath3D-v0``, an agent under its training env id with the observation
its metadata records (so an ablation agent trained with an ``observation`` keyword runs too).
A set's ``controller`` arguments reach every policy as a scenario's do: ``validation_fins_start``
tells its actuator, as the `fins` scenario does, so classical controllers allocate to the fins
and agents recorded with an actuator allocation fly through it.

    python -m benchmarks.analysis.validation_ratio --task-set validation_paper_actuator \\
        --policies fbsm_colos,gen3=benchmarks/results/seeds/ppo_integral/agent_seed_0
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from auv_gym.files import write_json
from auv_gym.table_format import markdown_table
from benchmarks.arguments import parse_options, program_name, usage_errors, writable_location
from benchmarks.options import option


def policy_and_env(
    text: str, controller: dict[str, Any] | None = None
) -> tuple[str, Any, dict[str, Any], dict[str, Any]]:
    """(label, policy, env keyword arguments, training record) of ``label=agent-folder`` or a
    classical policy name, told a task set's ``controller`` keyword arguments as a scenario's
    are (a classical controller's, an agent's ``base_kwargs``); an agent's env is its training
    id's plus its recorded observation."""
    from auv_gym import ENV_ID, VARIANTS
    from benchmarks.catalog.policies import build_policy, check_policy_spec
    from benchmarks.training.evaluation import agent_env_kwargs
    from controllers.loader import load_policy

    label, _, path = text.partition("=")
    if not path:
        check_policy_spec(label)
        env_kwargs = dict(VARIANTS[ENV_ID])
        return label, build_policy(label, env_kwargs, controller), env_kwargs, {}
    policy = load_policy(path, base_kwargs=dict(controller or {}) or None)
    metadata = policy.metadata
    env_kwargs = agent_env_kwargs(metadata.get("env_id", ENV_ID), metadata)
    record = {
        "num_timesteps": metadata.get("num_timesteps"),
        "wall_time_s": metadata.get("wall_time_s"),
    }
    return label, policy, env_kwargs, record


def measure(
    policy: Any,
    env_kwargs: dict[str, Any],
    task_env: dict[str, Any],
    seeds: list[int],
    duration: float,
) -> dict[str, Any]:
    """Mean RMS distance [m] (failed episodes count with their RMS up to the failure, as in
    training's selection) and the number of failures over ``seeds``."""
    from benchmarks.training.evaluation import evaluate_policy_on_seeds, summarize

    results = evaluate_policy_on_seeds(
        policy, seeds, **{**env_kwargs, **task_env, "max_time": duration}
    )
    summary = summarize(results)
    return {
        "rms_distance_mean": summary["rms_distance_mean"],
        "n_terminated": summary["n_terminated"],
        "rms_distance": [r["rms_distance"] for r in results],
    }


@dataclass
class Options:
    """The command line of `python -m benchmarks.analysis.validation_ratio`."""

    policies: str = option("fbsm_colos", "comma-separated classical names or label=agent-folder")
    task_set: str = option("validation_paper_actuator", "a validation set of benchmarks/tasks.toml")
    episodes: int = option(32, "the set's first N seeds (training's selection uses 32)")
    duration: float = option(200.0, "episode length [s] (training's selection uses 200)")
    reference: str = option("fbsm_colos", "the policy (a --policies label) ratios are taken to")
    json: str | None = option(None, "also write the rows to this file")


def main(argv: list[str] | None = None) -> dict[str, dict[str, Any]]:
    from benchmarks.catalog.tasks import load_task_sets

    prog = program_name("benchmarks.analysis.validation_ratio")
    args, parser = parse_options(Options, argv, prog, __doc__)
    with usage_errors(parser):
        if args.json:
            writable_location(args.json, "--json", folder=False)
        sets = load_task_sets()
        validation = sorted(name for name, s in sets.items() if s.role == "validation")
        if args.task_set not in validation:
            raise ValueError(
                f"--task-set {args.task_set!r} is not a validation set; valid: {validation}"
            )
        chosen = sets[args.task_set]
        if not 1 <= args.episodes <= len(chosen.seeds):
            raise ValueError(f"--episodes must be 1-{len(chosen.seeds)}, got {args.episodes}")
        if not (math.isfinite(args.duration) and args.duration > 0.0):
            raise ValueError(
                f"--duration must be a positive number of seconds, got {args.duration}"
            )
        specs = [s for s in args.policies.split(",") if s]
        labels = [s.partition("=")[0] for s in specs]
        if args.reference not in labels:
            raise ValueError(f"--reference {args.reference!r} is not among --policies {labels}")
        built = [policy_and_env(spec, chosen.controller) for spec in specs]
    seeds = list(chosen.seeds[: args.episodes])
    rows: dict[str, dict[str, Any]] = {}
    for label, policy, env_kwargs, record in built:
        rows[label] = {
            **measure(policy, env_kwargs, dict(chosen.env), seeds, args.duration),
            **record,
        }
        print(f"{label}: {rows[label]['rms_distance_mean']:.4f} m", flush=True)
    reference = rows[args.reference]["rms_distance_mean"]
    for row in rows.values():
        row["ratio"] = row["rms_distance_mean"] / reference

    def known(value: Any, fmt: str) -> str:
        return "–" if value is None else format(value, fmt)

    header = [
        "policy",
        "mean RMS distance [m]",
        "failed",
        f"× {args.reference}",
        "env steps",
        "training wall time [s]",
    ]
    cells = [
        [
            label,
            f"{r['rms_distance_mean']:.4f}",
            f"{r['n_terminated']} of {len(seeds)}",
            f"{r['ratio']:.2f}",
            known(r.get("num_timesteps"), ","),
            known(r.get("wall_time_s"), ".0f"),
        ]
        for label, r in rows.items()
    ]
    print(f"Task set {args.task_set}, seeds {seeds[0]}-{seeds[-1]}, {args.duration:g}-s episodes")
    print(markdown_table(header, cells))
    if args.json:
        write_json(args.json, {"options": vars(args), "seeds": seeds, "rows": rows}, indent=2)
    return rows


if __name__ == "__main__":
    main()
