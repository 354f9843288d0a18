"""`auv-gym export`: a saved agent as one ONNX graph and its contract (docs/usage.md, "Export").

    auv-gym export ppo_generalist --out out/policy.onnx             # the paper's actuator
    auv-gym export ppo_generalist --actuator realistic --out out/p.onnx # propeller and fins
    auv-gym export agent:runs/x/agent --out out/x.onnx
    auv-gym export runs/x/ensemble3 --out out/x3.onnx  # an ensemble: its members in one graph

Writes FILE.onnx and FILE.json (`controllers.onnx_export`), both or neither; the graph is run
against the Python agent before anything is written, and the contract states everything the
graph was built for (env with its actuator and settings, control period, plant, stages). Every
problem (an unknown agent, a damaged agent folder, an unknown stage, a missing normalisation
file, a missing output folder, an option that would not change the graph: --actuator for an
agent without an allocation stage, --actuator-params without an allocation to the propeller and
fins or naming settings it does not read) is one line naming the file or the option, exit code
2, with nothing written. Needs the rl extra (to read the network) and the onnx extra.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from benchmarks.arguments import ArgumentParser, program_name, usage_errors
from benchmarks.catalog.policies import (
    AGENT_PREFIX,
    FORMER_AGENT_PREFIX,
    REFERENCE_AGENTS,
    REMOVED_POLICIES,
    PolicySpec,
)
from benchmarks.cli import HelpFormatter
from controllers.onnx_export import ACTUATORS

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(
        prog=program_name("benchmarks.runner.export"),
        description=__doc__,
        formatter_class=HelpFormatter,
    )
    parser.add_argument(
        "agent",
        help=f"a reference agent ({', '.join(REFERENCE_AGENTS)}), {AGENT_PREFIX}PATH or a path",
    )
    parser.add_argument("--out", type=Path, required=True, help="the .onnx file to write")
    parser.add_argument(
        "--actuator",
        choices=ACTUATORS,
        default=None,
        help="the env actuator the commands are for (the allocation stage is built for it; "
        "another is refused for an agent without an allocation stage) (default: paper, or "
        "realistic for an agent trained on the propeller and fins)",
    )
    parser.add_argument(
        "--actuator-params",
        default=None,
        help="JSON of the realistic actuators' settings the allocation is built for "
        "(auv_gym.vehicle.actuators; only those it reads, with --actuator realistic) "
        "(default: the REMUS 100's)",
    )
    return parser


def agent_path(text: str) -> Path:
    """The folder of a reference agent name, ``agent:PATH`` or a plain path. A name of an
    earlier release (``ppo``, ``ppo:PATH``, an agent no longer shipped) is the one-line
    ValueError compare gives, naming what to type (`PolicySpec.parse`)."""
    former = text in REMOVED_POLICIES or text.startswith(FORMER_AGENT_PREFIX)
    if former or text in REFERENCE_AGENTS or text.startswith(AGENT_PREFIX):
        path = PolicySpec.parse(text).agent
        assert path is not None
        return path
    return Path(text)


def main(argv: Sequence[str] | None = None) -> dict[str, Any]:
    parser = build_parser()
    args = parser.parse_args(argv)
    from controllers.onnx_export import export_onnx

    start = time.perf_counter()
    with usage_errors(parser):
        params = None
        if args.actuator_params is not None:
            try:
                params = json.loads(args.actuator_params)
            except json.JSONDecodeError as exc:
                raise ValueError(f"--actuator-params is not JSON: {exc}") from None
        onnx_file, contract, parity = export_onnx(
            agent_path(args.agent), args.out, actuator=args.actuator, actuator_params=params
        )
    actuator = json.loads(contract.read_text())["actuator"]
    print(
        f"wrote {onnx_file} ({onnx_file.stat().st_size / 1024:.0f} KiB) and {contract}: "
        f"commands for actuator {actuator!r}, max |ONNX − agent| "
        f"{parity['max_abs_error']:.2g} over {parity['observations']} observations, "
        f"{time.perf_counter() - start:.1f} s"
    )
    return {"onnx": str(onnx_file), "contract": str(contract), **parity}


if __name__ == "__main__":
    main()
