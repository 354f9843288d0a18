"""How deep do waves stop mattering to a controller? RMS distance against path depth.

Runs one classical controller (default FBSM + CO-LOS) on a path at several depths below the
surface z = 0 (docs/model.md §13.1), with a sea state and without waves, on the same seeds, and
prints the mean RMS distance over the metrics window with 95 % bootstrap intervals:

    circle  the paper's helix made level (climb 0): R = 20 m, centre (10, 0, D), start
            (15, 5, D + 8) m, ψ = 0 — the paper's start relative to the path, at depth D
    helix   the paper's helix moved down so that its shallowest point in the episode
            (s ≈ 97 at 300 s) lies at depth D: it spans D to D + 97 m

    python -m benchmarks.reports.wave_depth --depths 2 5 10 20 40 --seeds 8
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from auv_gym.paths import Helix
from auv_gym.sim.trajectory import FAILURE_REASONS
from auv_gym.support.files import write_json
from benchmarks.analysis.stats import mean_interval
from benchmarks.arguments import parse_options, program_name, usage_errors, writable_location
from benchmarks.options import option
from benchmarks.reports.table_format import markdown_table

PAPER_CLIMB_SPAN = 97.0  # [m] the paper helix's climb in a 300-s episode (docs/model.md §13.1)


def path_at(kind: str, depth: float) -> dict[str, Any]:
    """Env keyword arguments of the path ``kind`` ("circle" or "helix") at ``depth`` [m]."""
    if kind == "circle":
        return {
            "path": Helix(climb=0.0, center=(10.0, 0.0, depth)),
            "start_position": (15.0, 5.0, depth + 8.0),
            "start_heading": 0.0,
        }
    shift = depth + PAPER_CLIMB_SPAN
    return {
        "path": Helix(center=(10.0, 0.0, -8.0 + shift)),
        "start_position": (15.0, 5.0, shift),
        "start_heading": 0.0,
    }


def measure(
    policy_name: str, kind: str, depth: float, waves: Any, seeds: list[int], max_time: float
) -> dict[str, Any]:
    """Mean RMS distance [m] with its 95 % interval, and the episodes that failed."""
    import controllers
    from auv_gym.rollout import evaluate

    env_kwargs = {"waves": waves, "max_time": max_time, **path_at(kind, depth)}
    policy = controllers.make(policy_name, env=env_kwargs)
    results = evaluate(policy, seeds, **env_kwargs)
    rms = np.array([[r["rms_distance"] for r in results]])
    ci = mean_interval(rms, key=f"{kind}|{depth}|{waves}")
    failed = sum(r["termination_reason"] in FAILURE_REASONS for r in results)
    return {
        "depth": depth,
        "waves": waves,
        "rms_distance": ci.value,
        "low": ci.low,
        "high": ci.high,
        "failed": failed,
        "episodes": len(results),
    }


@dataclass
class Options:
    """The command line of `python -m benchmarks.reports.wave_depth`."""

    depths: tuple[float, ...] = option(
        (2.0, 5.0, 10.0, 20.0, 40.0), "path depths D below the surface [m]", nargs="+"
    )
    path: str = option(
        "circle", "the path placed at each depth (module docstring)", choices=("circle", "helix")
    )
    sea_state: str = option("sea_state_4", "a waves preset")
    policy: str = option("fbsm_colos", "a classical controller")
    seeds: int = option(8, "episodes per depth (seeds 0…)")
    max_time: float = option(300.0, "episode length [s]")
    json: str | None = option(None, "also write the rows to this file")
    figure: str | None = option(None, "also plot RMS distance against depth to this PNG")


def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    args, parser = parse_options(
        Options, argv, program_name("benchmarks.reports.wave_depth"), __doc__
    )
    with usage_errors(parser):
        for flag in ("json", "figure"):
            if getattr(args, flag):
                writable_location(getattr(args, flag), f"--{flag}", folder=False)
        if min(args.depths) < 0.0 or not all(map(math.isfinite, args.depths)):
            raise ValueError(f"--depths must be finite and >= 0 m, got {list(args.depths)}")
    seeds = list(range(args.seeds))
    rows = []
    for depth in args.depths:
        for waves in (args.sea_state, None):
            rows.append(measure(args.policy, args.path, depth, waves, seeds, args.max_time))
    header = [
        "depth [m]",
        f"RMS distance, {args.sea_state} [m]",
        "RMS distance, no waves [m]",
        "failed (waves / none)",
    ]
    cells = []
    for wavy, calm in zip(rows[::2], rows[1::2], strict=True):
        cells.append(
            [
                f"{wavy['depth']:g}",
                f"{wavy['rms_distance']:.3f} [{wavy['low']:.3f}, {wavy['high']:.3f}]",
                f"{calm['rms_distance']:.3f} [{calm['low']:.3f}, {calm['high']:.3f}]",
                f"{wavy['failed']} / {calm['failed']} of {wavy['episodes']}",
            ]
        )
    print(
        f"{args.policy} on the {args.path} path, {args.seeds} seeds, {args.max_time:g}-s "
        "episodes, mean of the per-episode RMS distance with its 95 % bootstrap interval"
    )
    print(markdown_table(header, cells))
    if args.json:
        write_json(args.json, rows, indent=2)
    if args.figure:
        plot_depth(rows, args.figure, f"{args.policy} on the {args.path} path, {args.seeds} seeds")
    return rows


def plot_depth(rows: list[dict[str, Any]], file: str, title: str) -> None:
    """RMS distance [m] (log scale, 95 % intervals shaded) against path depth [m], with and
    without waves, written to ``file``."""
    from benchmarks.reports.plotting import new_figure, save_figure

    fig = new_figure(6.0, 4.0, layout="constrained")
    ax = fig.add_subplot()
    for label, group, colour in (("waves", rows[::2], "tab:blue"), ("no waves", rows[1::2], "0.4")):
        depth = [r["depth"] for r in group]
        if group[0]["waves"]:
            label = group[0]["waves"].replace("_", " ")
        ax.plot(depth, [r["rms_distance"] for r in group], "o-", color=colour, label=label)
        ax.fill_between(
            depth,
            [r["low"] for r in group],
            [r["high"] for r in group],
            color=colour,
            alpha=0.2,
            linewidth=0,
        )
    ax.set(
        xlabel="path depth below the surface [m]",
        ylabel="RMS distance [m]",
        yscale="log",
        title=title,
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    save_figure(fig, file)


if __name__ == "__main__":
    main()
