"""`auv-gym ensemble`: several saved agents of one recipe as one policy, their mean action.

    auv-gym ensemble --out runs/x/ensemble runs/x/results/agent_seed_1 runs/x/results/agent_seed_4
    auv-gym ensemble --out runs/x/ensemble3 --results runs/x/results --best 3

Writes OUT/ensemble.json (`controllers.ensemble`): the members given, or with ``--results`` the
``--best`` K seeds of a multi-seed results folder (`auv-gym train-seeds --results`) by their
validation score in its summary.json, the score the shipped seed is selected by (fewer
terminated validation episodes, then the lower score; the test episodes are never used); for a
schedule's results folder, by the score its schedule.json selected on (the last phase's
validation, or with ``select_on: shipped`` every seed's score as shipped). The
folder then flies wherever an agent does (``agent:OUT``, ``NAME=OUT`` in `auv-gym suite`).
Every member is checked first (`controllers.agent.check_agent`: the files, and that they agree
on everything but their network); a problem is one line naming the file, exit code 2, with
nothing written. Needs no extra to write; flying it needs the rl extra.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from auv_gym.support.files import output_lock
from benchmarks.arguments import ArgumentParser, program_name, usage_errors
from benchmarks.cli import HelpFormatter
from benchmarks.training.checkpoints import SEED_AGENT_PREFIX
from benchmarks.training.schedule import SCHEDULE_FILE
from benchmarks.training.seeds import SUMMARY_FILE, selection_key
from controllers.agent import check_ensemble
from controllers.ensemble import (
    ENSEMBLE_FILE,
    MIN_MEMBERS,
    ensemble_members,
    ensemble_paths,
    write_ensemble,
)

__all__ = ["best_seeds", "build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(
        prog=program_name("benchmarks.runner.ensemble"),
        description=__doc__,
        formatter_class=HelpFormatter,
    )
    parser.add_argument("members", nargs="*", type=Path, help="agent folders (or model zips)")
    parser.add_argument("--out", type=Path, required=True, help="the ensemble folder to write")
    parser.add_argument(
        "--results",
        type=Path,
        default=None,
        help="a multi-seed results folder (agent_seed_<k>/ and summary.json, or a schedule's "
        "schedule.json) to take the members from, instead of listing them",
    )
    parser.add_argument(
        "--best",
        type=int,
        default=None,
        help=f"with --results: how many seeds, the best by validation ({MIN_MEMBERS} or more)",
    )
    return parser


def best_seeds(results: Path, k: int) -> list[int]:
    """The first ``k`` seeds of a multi-seed results folder in the order the run's selection
    ranks them (`benchmarks.training.seeds.selection_key`: terminated validation episodes, then
    the score; ties by seed) from its summary.json; ValueError naming the file when it is
    unreadable, lacks the seeds' entries or holds fewer than ``k`` seeds."""
    summary_file = results / SUMMARY_FILE
    if not summary_file.exists() and (results / SCHEDULE_FILE).exists():
        summary_file = results / SCHEDULE_FILE
    try:
        summary = json.loads(summary_file.read_text(encoding="utf-8"))
        if summary_file.name == SCHEDULE_FILE:
            summary = _schedule_ranking(summary)
        scored = [(selection_key(entry), int(entry["seed"])) for entry in summary["seeds"]]
    except FileNotFoundError:
        raise FileNotFoundError(f"--results: {summary_file} does not exist") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ValueError(f"--results: {summary_file} is unreadable ({error})") from None
    except (OSError, ValueError, KeyError, TypeError) as error:
        problem = f"holds no validation scores ({error})"
        raise ValueError(f"--results: {summary_file} {problem}") from None
    if len(scored) < k:
        raise ValueError(f"--best {k}: {summary_file} lists {len(scored)} seeds")
    return [seed for _, seed in sorted(scored)[:k]]


def _schedule_ranking(schedule: dict[str, Any]) -> dict[str, Any]:
    """The seeds' entries a schedule selected on, as a summary.json holds them: with
    ``select_on: shipped`` every seed's score as shipped, else the last phase's summary."""
    shipped = schedule.get("shipped_selection")
    if shipped is None:
        return schedule["phases"][-1]["summary"]
    return {
        "seeds": [
            {
                "seed": int(seed),
                "validation_score": entry["score"],
                "validation_summary": entry["summary"],
            }
            for seed, entry in shipped["seeds"].items()
        ]
    }


def _members(args: argparse.Namespace) -> list[Path]:
    if args.results is None:
        if args.best is not None:
            raise ValueError("--best needs --results")
        if len(args.members) < MIN_MEMBERS:
            raise ValueError(f"an ensemble needs {MIN_MEMBERS} or more members")
        return list(args.members)
    if args.members:
        raise ValueError("give the members or --results with --best, not both")
    if args.best is None or args.best < MIN_MEMBERS:
        raise ValueError(f"--results needs --best K with K >= {MIN_MEMBERS}, got {args.best}")
    return [args.results / f"{SEED_AGENT_PREFIX}{s}" for s in best_seeds(args.results, args.best)]


def _refuse_stale_export(out: Path, members: Sequence[Path]) -> None:
    """ValueError when ``out`` holds an ONNX export of an ensemble and ``members`` are not the
    ones it lists now: rewriting the list would leave a graph of other networks beside it."""
    exports = sorted(out.glob("*.onnx")) if out.is_dir() else []
    if not exports:
        return
    listed = ensemble_members(out) if (out / ENSEMBLE_FILE).is_file() else None
    if listed is None or sorted(listed) != sorted(Path(m).resolve() for m in members):
        raise ValueError(
            f"--out {out} holds an export ({exports[0].name}) of another member list, which "
            "this list would leave beside it: choose a new folder, or remove the export first"
        )


def main(argv: Sequence[str] | None = None) -> dict[str, Any]:
    parser = build_parser()
    args = parser.parse_args(argv)
    with usage_errors(parser):
        members = _members(args)
        if args.out.exists() and not args.out.is_dir():
            raise ValueError(f"--out {args.out} is a file; an ensemble is a folder")
        if (args.out / "model.zip").is_file():
            raise ValueError(f"--out {args.out} holds an agent; an ensemble needs its own folder")
        _refuse_stale_export(args.out, members)
        # every member checked, and checked to agree, before anything is written
        spec = args.out / ENSEMBLE_FILE
        files = check_ensemble(spec, ensemble_paths(spec, [str(m.resolve()) for m in members]))
        args.out.mkdir(parents=True, exist_ok=True)
        with output_lock(args.out):
            written = write_ensemble(args.out, members)
    seeds = [f.metadata.get("seed") for f in files.members]
    print(f"wrote {written}: {len(members)} members (training seeds {seeds})")
    return {"ensemble": str(args.out / ENSEMBLE_FILE), "members": [str(m) for m in members]}


if __name__ == "__main__":
    main()
