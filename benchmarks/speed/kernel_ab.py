"""The simulator kernel of this tree against a baseline commit's, interleaved: vehicle-control
steps per second of `Simulator.step` at N vehicles, zero commands, in a configuration both trees
know (default: the paper's, `AUVPath3D-v0`'s defaults).

    python -m benchmarks.speed.kernel_ab                      # 5 rounds against e1c8230
    python -m benchmarks.speed.kernel_ab --baseline main --env '{"plant": "6dof"}'

Each round times the baseline, then this tree, each in a fresh interpreter whose ``PYTHONPATH``
points at its tree (the baseline extracted with ``git archive`` into a cache kept between runs,
`benchmarks.speed.training.extract`; its kernels compile once, on its first run), so the ratio
of a round is taken under one machine load; the median of the rounds' ratios is the figure,
in wall-clock time and in the process's CPU time (less sensitive to other load on the machine:
time spent waiting for a core is not counted).
The timed snippet uses only what both trees have: the env id's vector entry point and its
simulator's ``step``.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from benchmarks.arguments import parse_options, program_name
from benchmarks.options import option
from benchmarks.speed.training import TREE, extract

# Timed in the tree on PYTHONPATH; prints one JSON line. Compilation happens before the clock.
_SNIPPET = """
import json, sys, time
import gymnasium as gym
import numpy as np
import auv_gym  # registers the ids
n, seconds, threads = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
kwargs = json.loads(sys.argv[4])
env = gym.make_vec("AUVPath3D-v0", num_envs=n, vectorization_mode="vector_entry_point",
                   max_time=1e5, threads=threads, **kwargs)
env.reset(seed=0)
sim = env.unwrapped.sim if hasattr(env, "unwrapped") else env.sim
zeros = np.zeros((n, 3))
sim.step(zeros)  # compiled or loaded from the cache outside the clock
steps, start, cpu_start = 0, time.perf_counter(), time.process_time()
while time.perf_counter() - start < seconds:
    for _ in range(8):
        sim.step(zeros)
    steps += 8
wall, cpu = time.perf_counter() - start, time.process_time() - cpu_start
rates = {"control_steps_per_s": n * steps / wall, "control_steps_per_cpu_s": n * steps / cpu}
print(json.dumps({**rates, "batch_steps": steps}))
"""


@dataclass
class Options:
    """The command line of the kernel A/B benchmark."""

    baseline: str = option("e1c8230", "git ref of the baseline tree")
    n: int = option(4096, "vehicles")
    rounds: int = option(5, "interleaved rounds (baseline, this tree)")
    seconds: float = option(4.0, "timed wall clock per side and round")
    threads: int = option(1, "numba threads of the simulator (1: serial kernel)")
    env: str = option(
        "{}", "JSON object of extra env keyword arguments (both trees must know them)"
    )
    cache: str = option(
        os.path.join(tempfile.gettempdir(), "auv-gym-baselines"),
        "folder of the extracted baseline trees",
    )
    json: str | None = option(None, "also write every round to this file")


def time_tree(tree: Path, args: Options) -> dict[str, Any]:
    """One timing of ``tree``'s kernel in a fresh interpreter."""
    argv = [str(args.n), str(args.seconds), str(args.threads), args.env]
    out = subprocess.run(
        [sys.executable, "-c", _SNIPPET, *argv],
        cwd=tree,
        env={**os.environ, "PYTHONPATH": str(tree)},
        capture_output=True,
        text=True,
    )
    if out.returncode != 0:
        raise RuntimeError(f"timing in {tree} failed:\n{out.stderr[-2000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> dict[str, Any]:
    args, parser = parse_options(
        Options, argv, program_name("benchmarks.speed.kernel_ab"), __doc__, negatable=False
    )
    if args.n < 1 or args.rounds < 1 or args.threads < 1 or not args.seconds > 0:
        parser.error("--n, --rounds and --threads must be >= 1 and --seconds > 0")
    try:
        if not isinstance(json.loads(args.env), dict):
            raise ValueError("not an object")
    except ValueError as error:
        parser.error(f"--env must be a JSON object, got {args.env!r} ({error})")
    cache = Path(args.cache)
    cache.mkdir(parents=True, exist_ok=True)
    old = extract(args.baseline, cache)
    print(f"N = {args.n}, {args.threads} thread(s), env {args.env}, baseline {args.baseline}")
    print(
        f"{'round':>5} {'baseline steps/s':>17} {'this tree steps/s':>18} {'ratio':>7} "
        f"{'ratio (CPU time)':>17}"
    )
    rounds = []
    for k in range(args.rounds):
        base, new = time_tree(old, args), time_tree(TREE, args)
        ratio = new["control_steps_per_s"] / base["control_steps_per_s"]
        cpu_ratio = new["control_steps_per_cpu_s"] / base["control_steps_per_cpu_s"]
        rounds.append({"baseline": base, "tree": new, "ratio": ratio, "cpu_ratio": cpu_ratio})
        print(
            f"{k:>5} {base['control_steps_per_s']:>17,.0f} "
            f"{new['control_steps_per_s']:>18,.0f} {ratio:>7.1%} {cpu_ratio:>17.1%}",
            flush=True,
        )
    median = statistics.median(r["ratio"] for r in rounds)
    cpu_median = statistics.median(r["cpu_ratio"] for r in rounds)
    print(
        f"median ratio this tree / {args.baseline}: {median:.1%} (wall clock), "
        f"{cpu_median:.1%} (CPU time)"
    )
    result = {
        "baseline": args.baseline,
        "options": vars(args),
        "rounds": rounds,
        "median": median,
        "cpu_median": cpu_median,
    }
    if args.json:
        from auv_gym.support.files import write_json

        write_json(args.json, result, indent=2)
    return result


if __name__ == "__main__":
    main()
