"""Tune the PID + LOS autopilot for a vehicle on validation seeds: a grid over the design speed
of the pole placement, the heading loop's natural frequency and the LOS gains (or any grid of
the PID's gains, ``--grid``), scored on the benchmark scenarios of that vehicle (or those of a
``--scenario-file``, e.g. your own vehicle's), never on their test seeds.

    python -m benchmarks.analysis.tune_pid --scenarios torpedo_helix,torpedo_survey,torpedo_as_built
    python -m benchmarks.analysis.tune_pid --base pid_as_built_climb \
        --scenarios as_built_helix,as_built_survey,as_built_coastal \
        --grid "pitch_wn=1.5,2,2.5,3;yaw_wn=1.5,2.5"
    python -m benchmarks.analysis.tune_pid --scenario-file my_scenarios.toml --scenarios my_helix

Each candidate flies the ``--base`` preset (`pid_as_built` by default: PID + current-observer
LOS, docs/model.md §4.9) with the scenario's controller settings and the candidate's gains on
the validation seeds (100-104 by default; never a test seed,
`benchmarks.catalog.tasks.test_seeds`). A candidate that fails an episode (corridor, pitch,
...) ranks below every one that fails none; among those, the lower mean over the scenarios of
the mean RMS distance [m] wins. The table of every candidate
and the winner's gains are printed (docs/vehicles.md §5: on the torpedo, 3 % over the derived
gains)."""

from __future__ import annotations

import itertools
import math
import os
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from benchmarks.arguments import comma_names, parse_options, program_name, usage_errors
from benchmarks.catalog.tasks import test_seeds
from benchmarks.options import option

__all__ = ["GRID", "candidate_policies", "check_base", "fly", "main", "parse_grid", "tune"]

# The grid: where the PID's poles are placed (u0 [m/s]), how fast the heading loop is [rad/s],
# and the LOS gains k_y, k_z [1/m] (docs/model.md §4.9).
GRID: dict[str, tuple[float, ...]] = {
    "design_speed": (1.0, 2.0),
    "yaw_wn": (1.5, 2.5, 4.0),
    "k_y": (0.1, 0.2),
    "k_z": (0.1, 0.5),
}
BASE = "pid_as_built"  # the PID + current-observer LOS preset


@dataclass
class TuneOptions:
    """The options of ``python -m benchmarks.analysis.tune_pid``."""

    scenarios: str = option("torpedo_helix,torpedo_survey,torpedo_as_built", "scenarios")
    scenario_file: str = option(
        "", "TOML file of named scenarios (default: the benchmark's, benchmarks/scenarios.toml)"
    )
    seeds: str = option("100,101,102,103,104", "validation seeds (not the test seeds)")
    duration: float = option(300.0, "episode length [s]")
    base: str = option(BASE, "the PID preset each candidate overrides (controllers.PRESETS)")
    grid: str = option(
        "",
        "the grid as NAME=V1,V2;NAME=V1,... over the PID's gains (default: design_speed, yaw_wn, "
        "k_y, k_z)",
    )


def _score(rms: Sequence[float], failed: int) -> tuple[int, float]:
    return failed, (sum(rms) / len(rms) if rms else math.inf)


def check_base(base: str) -> None:
    """ValueError unless ``base`` names a PID preset (`controllers.registry.PRESETS`)."""
    from controllers.registry import PRESETS

    if base not in PRESETS or PRESETS[base][0] != "pid_los":
        pids = sorted(name for name, (kind, _) in PRESETS.items() if kind == "pid_los")
        raise ValueError(f"--base: {base!r} is not a PID preset; valid: {pids}")


def parse_grid(text: str) -> dict[str, tuple[float, ...]]:
    """The grid of ``--grid`` (``NAME=V1,V2;NAME=...``): each name a numeric gain of the PID +
    LOS autopilot (`controllers.pid.PIDGains`, `GUIDANCE_GAINS`; the switches are not a grid's),
    each value a finite number; ValueError naming what is wrong."""
    from controllers.gains import ControllerGains
    from controllers.pid import GUIDANCE_GAINS, PIDGains

    guidance = [f for f in fields(ControllerGains) if f.name in GUIDANCE_GAINS]
    gains = {f.name for f in [*fields(PIDGains), *guidance] if isinstance(f.default, float)}
    grid: dict[str, tuple[float, ...]] = {}
    for axis in text.split(";"):
        name, sep, values = axis.partition("=")
        name = name.strip()
        if not sep or not name or not values.strip():
            raise ValueError(f"--grid: {axis!r} is not NAME=V1,V2,...")
        if name not in gains:
            raise ValueError(f"--grid: {name!r} is not a PID gain; valid: {sorted(gains)}")
        if name in grid:
            raise ValueError(f"--grid names {name!r} more than once")
        try:
            numbers = tuple(float(v) for v in comma_names(values, f"--grid {name}"))
        except ValueError as error:
            raise ValueError(f"--grid {name}: {error}") from None
        if not all(math.isfinite(v) for v in numbers):
            raise ValueError(f"--grid {name}: values must be finite, got {values!r}")
        grid[name] = numbers
    return grid


def candidate_policies(
    scenarios: Sequence[str],
    duration: float,
    grid: Mapping[str, Sequence[float]] = GRID,
    base: str = BASE,
    scenario_file: str | os.PathLike | None = None,
) -> list[tuple[dict[str, float], dict[str, tuple[Any, dict[str, Any]]]]]:
    """Each candidate of ``grid``: its gains and, per scenario of ``scenario_file`` (None: the
    benchmark's), the PID preset ``base`` built with them for the scenario's env (episodes of
    ``duration`` s). ValueError for an unknown scenario or gains the controller refuses, and
    OSError for an unreadable file, before anything flies."""
    import controllers
    from benchmarks.catalog.scenarios import SCENARIOS_FILE, load_scenarios
    from controllers.registry import reads_ground_velocity

    file = Path(scenario_file) if scenario_file else SCENARIOS_FILE
    try:
        table = load_scenarios(file)
    except OSError as error:
        raise OSError(f"--scenario-file {str(file)!r}: {error.strerror or error}") from None
    unknown = [name for name in scenarios if name not in table]
    if unknown:
        raise ValueError(f"--scenarios: unknown {unknown} in {file.name}; valid: {sorted(table)}")
    names = list(grid)
    built = []
    for values in itertools.product(*grid.values()):
        gains = dict(zip(names, values, strict=True))
        flights = {}
        for name in scenarios:
            scenario = table[name]
            env = {**scenario.env, "max_time": duration}
            if reads_ground_velocity(base, **scenario.controller, **gains):
                env["observation"] = "preview"  # the DVL's velocity over ground
            flights[name] = (controllers.make(base, env=env, **scenario.controller, **gains), env)
        built.append((gains, flights))
    return built


def tune(
    scenarios: Sequence[str],
    seeds: Sequence[int],
    duration: float,
    grid: Mapping[str, Sequence[float]] = GRID,
    progress: bool = True,
    base: str = BASE,
) -> list[dict[str, Any]]:
    """Every candidate of ``grid``'s per-scenario mean RMS distance [m] and failed episodes,
    best first (fewest failed episodes, then the lowest mean over the scenarios), each flying
    the PID preset ``base`` with its gains."""
    return fly(candidate_policies(scenarios, duration, grid, base), seeds, progress)


def fly(
    candidates: Sequence[tuple[dict[str, float], dict[str, tuple[Any, dict[str, Any]]]]],
    seeds: Sequence[int],
    progress: bool = True,
) -> list[dict[str, Any]]:
    """`tune` for candidates already built (`candidate_policies`)."""
    from auv_gym.rollout import evaluate
    from auv_gym.sim.trajectory import FAILURE_REASONS

    rows = []
    for k, (gains, flights) in enumerate(candidates):
        row: dict[str, Any] = {"gains": gains, "failed": 0, "rms": {}}
        for name, (policy, env) in flights.items():
            results = evaluate(policy, list(seeds), **env)
            finished = [r for r in results if r["termination_reason"] not in FAILURE_REASONS]
            row["failed"] += len(results) - len(finished)
            row["rms"][name] = (
                sum(r["rms_distance"] for r in finished) / len(finished) if finished else math.inf
            )
        row["score"] = _score(list(row["rms"].values()), row["failed"])
        rows.append(row)
        if progress:
            print(f"candidate {k + 1}/{len(candidates)}: {_line(row)}", file=sys.stderr)
    return sorted(rows, key=lambda r: r["score"])


def _line(row: dict[str, Any]) -> str:
    gains = ", ".join(f"{name} {value:g}" for name, value in row["gains"].items())
    rms = ", ".join(f"{name} {value:.3g} m" for name, value in row["rms"].items())
    return f"{gains}: {rms}; failed {row['failed']}"


def main(argv: Sequence[str] | None = None) -> list[dict[str, Any]]:
    args, parser = parse_options(
        TuneOptions, argv, program_name("benchmarks.analysis.tune_pid"), __doc__.split("\n\n")[0]
    )
    with usage_errors(parser):
        scenarios = comma_names(args.scenarios, "--scenarios")
        names = comma_names(args.seeds, "--seeds")
        try:
            seeds = [int(s) for s in names]
        except ValueError:
            raise ValueError(
                f"--seeds must be comma-separated integers, got {args.seeds!r}"
            ) from None
        if any(s < 0 for s in seeds):
            raise ValueError(f"--seeds must be integers >= 0, got {args.seeds!r}")
        reserved = sorted(set(seeds) & test_seeds())
        if reserved:
            raise ValueError(
                f"--seeds {reserved[:5]} are test seeds of the benchmark "
                "(`benchmarks.catalog.tasks.test_seeds`); tune on others"
            )
        if not 0.0 < args.duration <= 3600.0:
            raise ValueError(f"--duration must be in (0, 3600] s, got {args.duration}")
        check_base(args.base)
        grid = parse_grid(args.grid) if args.grid.strip() else GRID
        candidates = candidate_policies(
            scenarios, args.duration, grid, args.base, args.scenario_file
        )
    rows = fly(candidates, seeds)
    print(f"{len(rows)} candidates on {len(seeds)} validation seeds, best first:")
    for row in rows:
        print("  " + _line(row))
    best = rows[0]
    print(f"\nbest (controllers.make({args.base!r}, env=..., **gains)):")
    for name, value in best["gains"].items():
        print(f"{name} = {value!r}")
    return rows


if __name__ == "__main__":
    main()
