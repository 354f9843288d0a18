"""Reset speed: what an env reset costs per path family and length, and how building a spline
grows with its number of waypoints.

    auv-gym speed resets [--seeds 5] [--repeats 3] [--lengths 400 800 1600]
                         [--waypoints 100 200 400 800]

Resets: `gym.make("AUVPath3D-v0", path=...)`, each seed's reset timed ``--repeats`` times (the
fastest kept), the median over ``--seeds`` seeds printed, wall clock and CPU time of the process
(all its threads). Rows: the paper's helix, drawn lines and helices, drawn splines and lawnmowers
of each ``--lengths`` [m] (the distribution's defaults otherwise), and a lawnmower with wide turns
(879 m with 135-m turn radii, where every natural spline ends inside a turn and misses the
curvature limit: 20 natural builds, then the clamped one). "builds" counts the spline systems a
draw solves. Target: a drawn path's reset costs time proportional to its length (the µs/m
column flat), a spline build linear in its waypoints (about 2× per doubling).

Builds: `Spline` through n waypoints 5 m apart along a lawnmower track (natural ends, and clamped
to the track's tangents), each timed as a reset is.
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from benchmarks.arguments import parse_options, program_name
from benchmarks.options import option

LENGTHS = (400.0, 800.0, 1600.0)
WAYPOINTS = (100, 200, 400, 800)
# A drawn 879-m lawnmower with 135-m turn radii: it once took 1.2 s of CPU per reset (a dense
# solve of its spline system; docs/performance.md).
WIDE_TURN_LAWNMOWER = {"families": ["lawnmower"], "length": 879.0, "radius": [135.0, 135.0]}


def best_time(run: Callable[[], object], repeats: int) -> tuple[float, float]:
    """(wall, CPU) seconds of the fastest of ``repeats`` calls (by wall clock)."""
    best = (math.inf, math.inf)
    for _ in range(repeats):
        wall, cpu = time.perf_counter(), time.process_time()
        run()
        best = min(best, (time.perf_counter() - wall, time.process_time() - cpu))
    return best


def spline_builds(run: Callable[[], object]) -> int:
    """How many spline systems ``run`` solves (`auv_gym.paths.cubic.spline_second_derivatives`)."""
    from auv_gym.paths import cubic

    solve, count = cubic.spline_second_derivatives, [0]

    def counted(*args: np.ndarray) -> np.ndarray:
        count[0] += 1
        return solve(*args)

    cubic.spline_second_derivatives = counted
    try:
        run()
    finally:
        cubic.spline_second_derivatives = solve
    return count[0]


def reset_cost(path: object, seeds: int, repeats: int) -> dict[str, float]:
    """Median over seeds of the fastest reset of `AUVPath3D-v0` on ``path`` [ms], the drawn
    length [m] (nan for endless paths), waypoints and spline builds of seed 0's draw."""
    import gymnasium as gym

    import auv_gym  # noqa: F401  (registers the env)

    env = gym.make("AUVPath3D-v0", path=path).unwrapped
    env.reset(seed=0)  # loads the compiled kernels: not part of a reset
    walls, cpus = [], []
    for seed in range(seeds):
        wall, cpu = best_time(lambda seed=seed: env.reset(seed=seed), repeats)
        walls.append(wall)
        cpus.append(cpu)
    builds = spline_builds(lambda: env.reset(seed=0))
    drawn = env.sim.paths[0]
    env.close()
    return {
        "ms": 1e3 * statistics.median(walls),
        "cpu_ms": 1e3 * statistics.median(cpus),
        "length": drawn.s_end,
        "waypoints": len(getattr(drawn, "waypoints", ())),
        "builds": builds,
    }


def lawnmower_track(n: int) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """n waypoints 5 m apart along a lawnmower (100-m legs, 20-m turn radius, level) and the
    track's end tangents."""
    from auv_gym.sim.path_generator import _integrate

    legs = math.ceil(5.0 * n / (100.0 + math.pi * 20.0)) + 1
    lengths = [100.0, math.pi * 20.0] * legs
    curvatures = [x for k in range(legs) for x in (0.0, (-1.0) ** k / 20.0)]
    track, ends = _integrate(
        lengths, curvatures, [0.0] * (len(lengths) + 1), 0.0, 5.0 * (n - 1), 5.0
    )
    return track[:n], ends


def build_cost(n: int, repeats: int) -> dict[str, float]:
    """The fastest natural and clamped `Spline` build through ``n`` waypoints [ms]."""
    from auv_gym.paths.shapes import Spline

    track, ends = lawnmower_track(n)
    natural, _ = best_time(lambda: Spline(track), repeats)
    clamped, _ = best_time(lambda: Spline(track, end_tangents=ends), repeats)
    return {"natural_ms": 1e3 * natural, "clamped_ms": 1e3 * clamped}


@dataclass
class Options:
    """The command line of `auv-gym speed resets`."""

    seeds: int = option(5, "seeds per row (the median is printed)")
    repeats: int = option(3, "timed calls per seed or build (the fastest is kept)")
    lengths: tuple[float, ...] = option(
        LENGTHS, "lengths of the drawn splines and lawnmowers [m], in [50, 2000]", nargs="+"
    )
    waypoints: tuple[int, ...] = option(
        WAYPOINTS, "waypoint counts of the spline builds, in [2, 1000]", nargs="+"
    )


def main(argv: list[str] | None = None) -> dict[str, list[dict[str, float]]]:
    args, parser = parse_options(Options, argv, program_name("benchmarks.speed.resets"), __doc__)
    if args.seeds < 1 or args.repeats < 1:
        parser.error("--seeds and --repeats must be >= 1")
    if not all(50.0 <= x <= 2000.0 for x in args.lengths):
        parser.error(f"--lengths must lie in [50, 2000] m, got {list(args.lengths)}")
    if not all(2 <= n <= 1000 for n in args.waypoints):
        parser.error(f"--waypoints must lie in [2, 1000], got {list(args.waypoints)}")
    rows: list[tuple[str, object]] = [
        ("helix (AUVPath3D-v0)", "helix"),
        ("drawn line", {"families": ["line"]}),
        ("drawn helix", {"families": ["helix"]}),
    ]
    for family in ("spline", "lawnmower"):
        rows += [(f"drawn {family}", {"families": [family], "length": x}) for x in args.lengths]
    rows.append(("lawnmower, 135-m turns", WIDE_TURN_LAWNMOWER))
    resets = []
    print(
        f"\nenv reset, AUVPath3D-v0: median over {args.seeds} seeds of the best of {args.repeats}"
    )
    print(
        f"{'path':<22} {'length m':>9} {'waypoints':>9} {'builds':>6} {'ms/reset':>9} "
        f"{'CPU ms':>8} {'µs/m':>6}"
    )
    for name, path in rows:
        r = reset_cost(path, args.seeds, args.repeats)
        resets.append({"path": name, **r})
        finite = math.isfinite(r["length"])
        length = f"{r['length']:9.0f}" if finite else f"{'endless':>9}"
        per_metre = f"{1e3 * r['ms'] / r['length']:6.2f}" if finite else f"{'-':>6}"
        print(
            f"{name:<22} {length} {r['waypoints']:>9} {r['builds']:>6} {r['ms']:>9.2f} "
            f"{r['cpu_ms']:>8.2f} {per_metre}"
        )
    builds = []
    print(f"\nSpline build through n waypoints 5 m apart (lawnmower track), best of {args.repeats}")
    print(f"{'n':>5} {'natural ms':>11} {'clamped ms':>11} {'× per doubling':>15}")
    previous = None
    for n in sorted(args.waypoints):
        b = build_cost(n, args.repeats)
        builds.append({"waypoints": n, **b})
        growth = ""
        if previous is not None:
            doublings = math.log2(n / previous[0])
            growth = f"{(b['natural_ms'] / previous[1]) ** (1.0 / doublings):15.2f}"
        print(f"{n:>5} {b['natural_ms']:>11.3f} {b['clamped_ms']:>11.3f} {growth}")
        previous = (n, b["natural_ms"])
    return {"resets": resets, "builds": builds}


if __name__ == "__main__":
    main()
