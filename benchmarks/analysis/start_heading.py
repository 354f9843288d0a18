"""Which starts a policy survives in a current: failed episodes against the start's heading error.

For each policy, on the paper's helix from the paper's start position (8 m below the path, 15 m
behind, 5 m to the side), in a steady current of ``--current-speed`` flowing toward
``--current-direction`` (earth frame, Gauss–Markov variation of 0.05 m/s, τ = 60 s, no white
noise: the `current` scenario's by default) and ``--duration``-s episodes, seeds 0…n−1:

    heading   failed episodes when the vehicle starts ``h`` degrees off the path's heading
              (the paper's start: h = 90°, ψ = 0 against the path's π/2), for each ``--headings``
    direction with ``--directions``: failed episodes at the paper's start heading for currents
              flowing toward each of those directions [deg, 0 = +x (north, the paper's start
              heading), 90 = +y (east, the path's heading at s = 0)]

Training starts draw heading errors within ±`start_heading_spread` (0.2 rad by default) near
the path's start, so a policy's failures at large ``h`` only are starts it never trained from
(docs/results.md, "Why the pitch-overs").

    python -m benchmarks.analysis.start_heading \\
        --policies s0=benchmarks/results/seeds/ppo_paper_actuator/agent_seed_0 --seeds 10
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from auv_gym.files import write_json
from auv_gym.paths import Helix
from auv_gym.table_format import markdown_table
from auv_gym.trajectory import FAILURE_REASONS
from benchmarks.analysis.steady_offset import policy_and_env
from benchmarks.arguments import parse_options, program_name, usage_errors, writable_location
from benchmarks.options import option

CURRENT_STD = (0.05, 0.05, 0.0)  # [m/s] the `current` scenario's Gauss–Markov variation
CURRENT_TIME_CONSTANT = 60.0  # [s]


def path_heading() -> float:
    """ψ_F(0) of the paper's helix [rad] (π/2)."""
    _, tangent, _ = Helix().evaluate(0.0)
    return math.atan2(tangent[1], tangent[0])


def current(speed: float, direction_deg: float) -> dict[str, Any]:
    """The env's `current` argument: ``speed`` [m/s] toward ``direction_deg`` plus variation."""
    angle = math.radians(direction_deg)
    return {
        "mean": [speed * math.cos(angle), speed * math.sin(angle), 0.0],
        "std": list(CURRENT_STD),
        "time_constant": CURRENT_TIME_CONSTANT,
    }


def failures(
    policy: Any,
    env_kwargs: dict[str, Any],
    seeds: int,
    duration: float,
    heading: float | None,
    flow: dict[str, Any],
) -> int:
    """Failed episodes of seeds 0…n−1 from the paper's start position with heading ``heading``
    [rad] (None: the paper's start heading, ψ = 0)."""
    from auv_gym.rollout import rollouts

    runs = rollouts(
        policy,
        list(range(seeds)),
        **{
            **env_kwargs,
            "disturbance": "none",
            "current": flow,
            "start_heading": heading,
            "max_time": duration,
        },
    )
    return sum(t.termination_reason in FAILURE_REASONS for t in runs)


@dataclass
class Options:
    """The command line of `python -m benchmarks.analysis.start_heading`."""

    policies: str = option("fbsm", "comma-separated classical names or label=agent-folder")
    headings: str = option("0,30,45,60,90", "start heading errors [deg], comma-separated")
    directions: str | None = option(None, "current directions [deg] at the paper's heading")
    current_speed: float = option(0.3, "current speed [m/s]")
    current_direction: float = option(90.0, "direction the current flows toward [deg]")
    seeds: int = option(10, "episodes per cell (seeds 0…)")
    duration: float = option(60.0, "episode length [s] (the pitch-overs come in the first 20 s)")
    json: str | None = option(None, "also write the rows to this file")


def _degrees(text: str | None, name: str) -> list[float]:
    try:
        values = [float(v) for v in (text or "").split(",") if v.strip()]
    except ValueError:
        values = []
    if not values or not all(math.isfinite(v) and -360.0 <= v <= 360.0 for v in values):
        raise ValueError(
            f"{name} must be a comma-separated list of angles in [-360, 360] deg, got {text!r}"
        )
    return values


def main(argv: list[str] | None = None) -> dict[str, dict[str, Any]]:
    prog = program_name("benchmarks.analysis.start_heading")
    args, parser = parse_options(Options, argv, prog, __doc__)
    with usage_errors(parser):
        if args.json:
            writable_location(args.json, "--json", folder=False)
        headings = _degrees(args.headings, "--headings")
        directions = _degrees(args.directions, "--directions") if args.directions else []
        if args.seeds < 1 or not (0.0 < args.duration <= 300.0):
            raise ValueError("--seeds must be >= 1 and --duration in (0, 300] s")
        if not (math.isfinite(args.current_speed) and 0.0 <= args.current_speed <= 1.0):
            raise ValueError(f"--current-speed must be in [0, 1] m/s, got {args.current_speed}")
        built = [policy_and_env(spec) for spec in args.policies.split(",") if spec]
    psi_f = path_heading()
    rows: dict[str, dict[str, Any]] = {}
    flow = current(args.current_speed, args.current_direction)
    for label, policy, env in built:
        row = {
            "heading": {
                f"{h:g}": failures(
                    policy, env, args.seeds, args.duration, psi_f - math.radians(h), flow
                )
                for h in headings
            }
        }
        if directions:
            row["direction"] = {
                f"{d:g}": failures(
                    policy, env, args.seeds, args.duration, None, current(args.current_speed, d)
                )
                for d in directions
            }
        rows[label] = row
    print(
        f"Failed of {args.seeds} episodes ({args.duration:g} s) from the paper's start in a "
        f"{args.current_speed:g} m/s current, by start heading error [deg] (current toward "
        f"{args.current_direction:g}°):"
    )
    cells = [[label, *map(str, r["heading"].values())] for label, r in rows.items()]
    print(markdown_table(["policy", *(f"{h:g}°" for h in headings)], cells))
    if directions:
        print(
            "\nBy the direction the current flows toward [deg], at the paper's start heading "
            "(90° off the path):"
        )
        print(
            markdown_table(
                ["policy", *(f"{d:g}°" for d in directions)],
                [[label, *map(str, r["direction"].values())] for label, r in rows.items()],
            )
        )
    if args.json:
        write_json(args.json, {"options": vars(args), "rows": rows}, indent=2)
    return rows


if __name__ == "__main__":
    main()
