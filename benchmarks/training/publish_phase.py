"""The seeds of a warm-start training phase as a results folder, like `train_seeds --results`
writes for a run from scratch, with each agent's whole history.

A phase is one or more runs of `benchmarks.training.seeds_cli --init-from
'<history>/agent_seed_{seed}'` (seeds may be split over invocations: a seed's training does not
depend on the seeds beside it).
``--out`` receives, for every seed of the runs:

- ``agent_seed_<k>/``: the run's final agent, with the envelope guard and (``--allocation``)
  the actuator allocation recorded as `benchmarks.training.guard_agents` does (``--no-guard``:
  none);
- ``seed_<k>_phase_curve.csv``: the run's own validation curve (env steps counted from the
  warm start);
- ``seed_<k>_learning_curve.csv``: the agent's whole history: the history folder's curve (up
  to the agent the phase started from), then the phase's, its env steps and wall time counted
  on from where the history's agent ended (its own run's last evaluation, its agent's
  ``num_timesteps`` and ``wall_time_s``);
- ``summary.json``: the runs' summaries merged (their seeds, the training-time selection rule
  of `train_seeds`, each run's folder and wall time).

The history is the folder the runs' ``init_from`` names; every run must share its plan but for
the seeds. Validation of the published agents is a separate step
(`benchmarks.analysis.validation_ratio`), as is the whole suite.

    python -m benchmarks.training.publish_phase --runs runs/ppo_cross_track \\
        --out benchmarks/results/seeds/ppo_cross_track_guard_alloc --allocation
"""

from __future__ import annotations

import csv
import io
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from auv_gym.files import write_folder_atomic, write_json, write_text
from benchmarks.arguments import parse_options, program_name, usage_errors
from benchmarks.options import option
from benchmarks.training.checkpoints import SEED_AGENT_PREFIX, export_agent
from benchmarks.training.guard_agents import guard_agent
from benchmarks.training.learning_curve import EVAL_FILE, EVAL_HEADER
from benchmarks.training.seed_workers import seed_dir
from benchmarks.training.seeds import PLAN_FILE, SUMMARY_FILE, select
from controllers.agent import METADATA_FILE, check_agent
from controllers.envelope_guard import EnvelopeGuard

__all__ = ["main", "publish_phase"]

PHASE_CURVE = "seed_{seed}_phase_curve.csv"
LEARNING_CURVE = "seed_{seed}_learning_curve.csv"
# The plan entry that differs between the invocations of one phase.
PER_INVOCATION = ("seeds",)


@dataclass
class Options:
    """The command line of `python -m benchmarks.training.publish_phase`."""

    runs: tuple[str, ...] = option(
        (), "finished `train_seeds` run folders of one warm-start phase", nargs="+", required=True
    )
    out: str = option(None, "empty or new folder to write the results to", required=True)
    guard: bool = option(True, "record the envelope guard (--no-guard: leave it out)")
    allocation: bool = option(
        False, "record the actuator allocation (agents trained on the paper actuator)"
    )


def _read_json(path: Path, what: str) -> dict[str, Any]:
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise ValueError(f"{path} is missing: {what}") from None
    except json.JSONDecodeError as error:
        raise ValueError(f"{path} is not valid JSON ({error.msg}, line {error.lineno})") from None


def _read_curve(path: Path) -> list[list[str]]:
    """The rows of a learning-curve CSV (header checked, at least one row)."""
    try:
        rows = list(csv.reader(io.StringIO(path.read_text())))
    except FileNotFoundError:
        raise ValueError(f"{path} is missing: a seed's learning curve") from None
    if not rows or rows[0][: len(EVAL_HEADER)] != EVAL_HEADER or len(rows) < 2:
        raise ValueError(f"{path} is not a learning curve with rows ({','.join(EVAL_HEADER)})")
    return rows


def _curve_text(rows: list[list[str]]) -> str:
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerows(rows)
    return buffer.getvalue()


def history_end(history: Path, seed: int, whole: list[list[str]]) -> tuple[int, float]:
    """(env steps, wall time [s]) of the whole history ``whole`` (seed ``seed``'s learning-curve
    rows in ``history``) at the end of its agent: its own run's curve (the phase curve if the
    history is itself a phase) ends where the agent's ``num_timesteps`` and its training's
    ``wall_time_s`` are reached."""
    own_file = history / PHASE_CURVE.format(seed=seed)
    own = _read_curve(own_file)[-1] if own_file.is_file() else whole[-1]
    agent = history / f"{SEED_AGENT_PREFIX}{seed}"
    metadata = check_agent(agent).metadata  # a corrupt agent is named, as everywhere
    missing = [k for k in ("num_timesteps", "wall_time_s") if k not in metadata]
    if missing:
        raise ValueError(f"{agent / METADATA_FILE} records no {' or '.join(missing)}")
    step_offset = int(whole[-1][0]) - int(own[0])
    wall_offset = float(whole[-1][1]) - float(own[1])
    return step_offset + int(metadata["num_timesteps"]), wall_offset + metadata["wall_time_s"]


def _runs(folders: tuple[str, ...]) -> tuple[dict[str, Any], list[tuple[Path, dict[str, Any]]]]:
    """(the shared plan, [(run folder, its summary)]) after checking the runs form one phase."""
    if not folders:
        raise ValueError("--runs names no run")
    runs, plan, seen = [], None, {}
    for folder in map(Path, folders):
        summary = _read_json(folder / SUMMARY_FILE, "a finished `train_seeds` run's summary")
        if not (folder / PLAN_FILE).is_file():
            raise ValueError(f"{folder} holds no multi-seed run ({PLAN_FILE} missing)")
        shared = {k: v for k, v in summary["plan"].items() if k not in PER_INVOCATION}
        if plan is None:
            plan = shared
            if not plan.get("init_from"):
                raise ValueError(
                    f"{folder} is not a warm-start phase (its plan has no "
                    "init_from); for a run from scratch: train_seeds --results"
                )
            if plan.get("stop_at") is not None:
                raise ValueError(
                    f"{folder} paused at stop_at {plan['stop_at']}: resume it to "
                    "its budget first (train_seeds --resume)"
                )
        elif shared != plan:
            differ = sorted(k for k in plan.keys() | shared.keys() if plan.get(k) != shared.get(k))
            raise ValueError(
                f"{folder} is not of the same phase as {runs[0][0]}: {', '.join(differ)} differ"
            )
        for entry in summary["seeds"]:
            if entry["seed"] in seen:
                raise ValueError(
                    f"seed {entry['seed']} is in both {seen[entry['seed']]} and {folder}"
                )
            seen[entry["seed"]] = folder
        runs.append((folder, summary))
    return plan, runs


def publish_phase(
    folders: tuple[str, ...], out: Path, guard: EnvelopeGuard | None, allocation: bool = False
) -> dict[str, Any]:
    """Write the phase's results folder ``out`` (module docstring); returns its summary."""
    plan, runs = _runs(folders)
    template = plan["init_from"]
    history = Path(template.format(seed=0)).parent
    if Path(template).parent != history or Path(template).name != f"{SEED_AGENT_PREFIX}{{seed}}":
        raise ValueError(
            f"init_from {template!r} is not '<results folder>/{SEED_AGENT_PREFIX}{{seed}}'"
        )
    if out.exists() and any(out.iterdir()):
        raise ValueError(f"--out {out} is not empty")
    if out.resolve() == history.resolve():
        raise ValueError("--out must differ from the history folder")
    entries = sorted((e for _, summary in runs for e in summary["seeds"]), key=lambda e: e["seed"])
    invocations = [
        {
            "folder": str(run),
            "seeds": summary["plan"]["seeds"],
            "session_wall_time_s": summary["session_wall_time_s"],
        }
        for run, summary in runs
    ]
    merged = {
        "plan": {**plan, "seeds": [e["seed"] for e in entries]},
        "seeds": entries,
        "selected_seed": select(entries)["seed"],
        "selection": runs[0][1]["selection"],
        "history": str(history),
        "runs": invocations,
        "session_wall_time_s": sum(r["session_wall_time_s"] for r in invocations),
    }

    def fill(folder: Path) -> None:
        for run, summary in runs:
            for entry in summary["seeds"]:
                _publish_seed(run, entry["seed"], history, folder, guard, allocation)
        write_json(folder / SUMMARY_FILE, merged, indent=2, sort_keys=True)

    write_folder_atomic(out, fill)  # the folder appears whole or not at all
    return merged


def _publish_seed(
    run: Path, seed: int, history: Path, out: Path, guard: EnvelopeGuard | None, allocation: bool
) -> None:
    """The agent and the two curves of one seed of ``run`` in ``out``."""
    final = seed_dir(run, seed) / "final"
    whole = _read_curve(history / LEARNING_CURVE.format(seed=seed))
    steps, wall = history_end(history, seed, whole[1:])
    phase = _read_curve(seed_dir(run, seed) / EVAL_FILE)
    # an agent chosen before its run ended (a best one) has no history after it
    whole = whole[:1] + [r for r in whole[1:] if int(r[0]) <= steps]
    shifted = [[str(int(r[0]) + steps), f"{float(r[1]) + wall:.1f}", *r[2:]] for r in phase[1:]]
    agent = out / f"{SEED_AGENT_PREFIX}{seed}"
    if guard is None and not allocation:
        export_agent(final, agent)
    else:
        guard_agent(final, agent, guard, allocation)
    write_text(out / PHASE_CURVE.format(seed=seed), _curve_text(phase))
    write_text(out / LEARNING_CURVE.format(seed=seed), _curve_text(whole + shifted))


def main(argv: list[str] | None = None) -> dict[str, Any]:
    args, parser = parse_options(
        Options, argv, program_name("benchmarks.training.publish_phase"), __doc__
    )
    with usage_errors(parser):
        guard = EnvelopeGuard() if args.guard else None
        summary = publish_phase(tuple(args.runs), Path(args.out), guard, args.allocation)
    print(f"{len(summary['seeds'])} seed(s) of the phase from {summary['history']} in {args.out}")
    return summary


if __name__ == "__main__":
    main()
