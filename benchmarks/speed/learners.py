"""PPO's learner in SB3 (torch) against SBX (JAX), side by side on the generalist configuration.

Would a compiled learner train faster? SBX (`pip install sbx-rl`, not a dependency of this
project) is the JAX port of Stable-Baselines3 by its maintainers: the same PPO, rollout buffer
and VecEnv interface, with each minibatch's forward, backward and Adam step compiled by XLA into
one program. Both learners run the same env (`benchmarks/hyperparams/ppo_generalist.yml`:
AUVPath3DSpeedLimit-v0, VecMonitor, VecNormalize), rollout shape, minibatch, epochs and 64-64
tanh networks, one thread each, as `benchmarks.speed.training` times them (`training_run.measure`
in a fresh interpreter per run, the learners alternating); printed in env steps per second:
collection, update and the training rate, and SBX ÷ SB3.

    auv-gym speed learners                     # about 2 minutes on 2 cores
    auv-gym speed learners --n-envs 128 --rollouts 8

The reading (docs/performance.md): SBX's update is about 1.5× SB3's at the generalist's shape,
its collection slower (one JAX dispatch per vector step), the training rate about the same.
"""

from __future__ import annotations

import importlib.util
import os
import statistics
from dataclasses import dataclass
from typing import Any

from auv_gym.files import write_json
from benchmarks.arguments import parse_options, program_name, usage_errors, writable_location
from benchmarks.options import option
from benchmarks.speed.training import N_ENVS, ROLLOUT_STEPS, SHIPPED_EPOCHS, TREE, run_in
from benchmarks.speed.training_run import CONFIG, ENV_ID

LEARNERS = ("sb3", "sbx")
RATES = ("total_per_s", "collect_per_s", "update_per_s")


@dataclass
class Options:
    """The command line of `auv-gym speed learners`."""

    n_envs: tuple[int, ...] = option(N_ENVS, "numbers of vehicles (training envs)", nargs="+")
    rollouts: int = option(4, "timed rollouts per run")
    warmup: int = option(2, "untimed rollouts first (XLA compiles the update in the first)")
    repeats: int = option(2, "runs per learner and N (alternating; medians are printed)")
    batch_size: int = option(2048, "minibatch size (the configuration's: 2048)")
    n_epochs: int = option(SHIPPED_EPOCHS, "PPO epochs per update (the configuration's: 10)")
    json: str | None = option(None, "also write every run to this file")


def table(results: dict[tuple[int, str], list[dict[str, Any]]]) -> str:
    """One row per N: each learner's median rates and SBX ÷ SB3."""
    head = f"{'N':>5} {'n_steps':>7}"
    for learner in LEARNERS:
        head += f" | {learner + ' total':>10} {'collect':>8} {'update':>8}"
    head += f" | {'sbx/sb3 total':>13} {'collect':>8} {'update':>7}"
    lines = [head, "-" * len(head)]
    for n in sorted({n for n, _ in results}):
        med = {
            (learner, key): statistics.median(r[key] for r in results[(n, learner)])
            for learner in LEARNERS
            for key in RATES
        }
        line = f"{n:>5} {results[(n, 'sb3')][0]['n_steps']:>7}"
        for learner in LEARNERS:
            total, collect, update = (med[(learner, key)] for key in RATES)
            line += f" | {total:>10,.0f} {collect:>8,.0f} {update:>8,.0f}"
        ratios = [med[("sbx", key)] / med[("sb3", key)] for key in RATES]
        line += f" | {ratios[0]:>12.2f}× {ratios[1]:>7.2f}× {ratios[2]:>6.2f}×"
        lines.append(line)
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    args, parser = parse_options(
        Options, argv, program_name("benchmarks.speed.learners"), __doc__, negatable=False
    )
    with usage_errors(parser):
        if args.json:  # written after the benchmark: refused now, not after minutes of timing
            writable_location(args.json, "--json", folder=False)
        if (
            min(args.n_envs) < 1
            or min(args.rollouts, args.repeats, args.batch_size, args.n_epochs) < 1
            or args.warmup < 0
        ):
            raise ValueError(
                "--n-envs, --rollouts, --repeats, --batch-size and --n-epochs must "
                "be >= 1, --warmup >= 0"
            )
        if importlib.util.find_spec("sbx") is None:
            raise ValueError(
                "SBX is not installed (pip install sbx-rl): this benchmark times "
                "its JAX learner against SB3's"
            )

    from tqdm import tqdm

    plan = []
    for repeat in range(args.repeats):
        for k, n in enumerate(args.n_envs):
            order = LEARNERS if (repeat + k) % 2 == 0 else LEARNERS[::-1]
            spec = {
                "n_envs": n,
                "n_steps": max(1, ROLLOUT_STEPS // n),
                "seed": 0,
                "batch_size": args.batch_size,
                "n_epochs": args.n_epochs,
                "rollouts": args.rollouts,
                "warmup": args.warmup,
                "update_threads": 1,
                "update_dtype": "float32",
                "net_arch": [],
            }
            plan += [{**spec, "learner": learner} for learner in order]
    print(
        f"PPO on {CONFIG} ({ENV_ID}), batch {args.batch_size}, {args.n_epochs} epochs; SB3 "
        f"(torch) and SBX (JAX), one thread each; {os.cpu_count()} CPUs, load average "
        f"{os.getloadavg()[0]:.2f} at start\n",
        flush=True,
    )
    results: dict[tuple[int, str], list[dict[str, Any]]] = {}
    for spec in tqdm(plan, desc="training runs"):
        results.setdefault((spec["n_envs"], spec["learner"]), []).append(run_in(TREE, spec))
    print("\nenv steps/s (medians of the runs); ratio = SBX / SB3, measured in this run")
    print(table(results))
    print(f"load average {os.getloadavg()[0]:.2f} at the end")
    out = {"runs": [r for rs in results.values() for r in rs]}
    if args.json:
        write_json(args.json, out, indent=2)
    return out


if __name__ == "__main__":
    main()
