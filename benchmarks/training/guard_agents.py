"""Copies of saved agents with an envelope guard (`controllers.envelope_guard`) and, with
``--allocation``, an actuator allocation (`controllers.actuator_allocation`) in their metadata.

The guard limits the pitch and surge commands near the vehicle's limits and is the identity
inside them; recorded in an agent's ``metadata.json`` it is part of the agent: every loader,
the benchmark and the test suite evaluate the guarded agent. ``--from`` is one agent folder or a
multi-seed results folder (``agent_seed_<k>/`` as `benchmarks.training.seeds_cli --results` writes);
``--out`` receives the same layout: each agent copied atomically (`checkpoints.export_agent`),
its model and statistics unchanged (git stores identical files once) and its metadata.json with
``envelope_guard`` added. A results folder's learning curves (``seed_<k>_learning_curve.csv``:
the networks' training, evaluated without the guard) are copied too, so that the suite's
statistics draw them; its test evaluations are not: they belong to the unguarded agents.
``--allocation`` records ``actuator_allocation: "paper"`` (the agent, trained on the paper's
actuator, commands its normalised τ; on "fins" or "realistic" the loader allocates it);
``--no-guard`` leaves the guard out (an agent guarded already keeps its own).

    python -m benchmarks.training.guard_agents --from benchmarks/results/seeds/ppo_paper_actuator \\
        --out benchmarks/results/seeds/ppo_paper_actuator_guard
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from auv_gym.files import write_text
from benchmarks.arguments import parse_options, program_name, usage_errors
from benchmarks.options import option
from benchmarks.training.checkpoints import SEED_AGENT_PREFIX, export_agent
from controllers.actuator_allocation import COMMANDED_ACTUATOR
from controllers.agent import MODEL_FILE, check_agent
from controllers.envelope_guard import EnvelopeGuard, check_envelope_guard

__all__ = ["guard_agent", "main"]


def agent_folders(source: Path) -> list[tuple[Path, str]]:
    """(agent folder, its name under --out) for one agent or a multi-seed results folder."""
    if (source / MODEL_FILE).is_file():
        return [(source, "")]
    seeds = sorted(p for p in source.glob(f"{SEED_AGENT_PREFIX}*") if p.is_dir())
    if not seeds:
        raise ValueError(
            f"--from {source} holds neither an agent (model.zip) nor agent_seed_<k>/ folders"
        )
    return [(p, p.name) for p in seeds]


def guard_agent(
    source: Path, target: Path, guard: EnvelopeGuard | None, allocation: bool = False
) -> Path:
    """Copy the agent ``source`` to ``target`` with ``guard`` (None: none added) and, with
    ``allocation``, the paper actuator's allocation recorded; returns ``target``."""
    files = check_agent(source)  # a corrupt agent is refused before anything is written
    metadata: dict[str, Any] = dict(files.metadata)
    if files.residual is not None:
        raise ValueError(
            f"{source}: a residual agent cannot take an envelope guard or an actuator allocation"
        )
    if guard is not None:
        if "envelope_guard" in metadata:
            raise ValueError(
                f"{source}: the agent already has an envelope guard {metadata['envelope_guard']}"
            )
        metadata["envelope_guard"] = guard.to_dict()
        metadata["guarded_from"] = str(source)
    if allocation:
        trained_on = (metadata.get("env_kwargs") or {}).get("actuator")
        if trained_on != COMMANDED_ACTUATOR:
            raise ValueError(
                f"{source}: actuator allocation needs an agent trained on the "
                f"{COMMANDED_ACTUATOR!r} actuator, this one: "
                f"{trained_on!r}"
            )
        metadata["actuator_allocation"] = COMMANDED_ACTUATOR
        metadata["allocated_from"] = str(source)
    export_agent(source, target, metadata)
    return target


@dataclass
class Options:
    """The command line of `python -m benchmarks.training.guard_agents`."""

    source: str = option(
        None, "agent folder or multi-seed results folder", flag="--from", required=True
    )
    out: str = option(None, "folder to write the guarded copies to", required=True)
    pitch_soft_deg: float = option(
        EnvelopeGuard.pitch_soft_deg, "pitch where the guard starts taking authority away [deg]"
    )
    pitch_hard_deg: float = option(
        EnvelopeGuard.pitch_hard_deg, "pitch of full counter-moment [deg]"
    )
    lookahead_s: float = option(EnvelopeGuard.lookahead_s, "pitch prediction θ + T·q, T [s]")
    surge_soft: float = option(EnvelopeGuard.surge_soft, "surge where thrust is cut [m/s]")
    surge_hard: float = option(EnvelopeGuard.surge_hard, "surge of full astern [m/s]")
    guard: bool = option(True, "record the envelope guard (--no-guard: leave it out)")
    allocation: bool = option(
        False, "record the actuator allocation (agents trained on the paper actuator)"
    )


def main(argv: list[str] | None = None) -> list[Path]:
    args, parser = parse_options(
        Options, argv, program_name("benchmarks.training.guard_agents"), __doc__
    )
    with usage_errors(parser):
        settings = {name: getattr(args, name) for name in EnvelopeGuard.__dataclass_fields__}
        guard = check_envelope_guard(settings, "options") if args.guard else None
        if guard is None and not args.allocation:
            raise ValueError("--no-guard without --allocation records nothing")
        source, out = Path(args.source), Path(args.out)
        if not source.is_dir():
            raise ValueError(f"--from {source} is not a folder")
        folders = agent_folders(source)
        if out.resolve() == source.resolve():
            raise ValueError("--out must differ from --from")
        written = [
            guard_agent(folder, out / name if name else out, guard, args.allocation)
            for folder, name in folders
        ]
        for curve in sorted(source.glob("seed_*_learning_curve.csv")) if folders[0][1] else ():
            write_text(out / curve.name, curve.read_text())
    added = {
        "envelope_guard": guard.to_dict() if guard else None,
        "actuator_allocation": COMMANDED_ACTUATOR if args.allocation else None,
    }
    print(f"{len(written)} agent(s) in {out}: {json.dumps(added)}")
    return written


if __name__ == "__main__":
    main()
