"""PPO training speed on the generalist configuration, this tree against a baseline, side by side.

For each number of vehicles N (default 32, 128, 512) PPO trains on the generalist configuration
(`benchmarks/speed/training_workload.yml`: AUVPath3DSpeedLimit-v0 with the [train] task
distribution,
VecMonitor and VecNormalize, MlpPolicy [64, 64], batch 2048, 10 epochs) as
`benchmarks.training.train` builds it, once with this tree's code and once with the code of a
baseline git ref (default `b8de6c4`), each in a fresh subprocess whose ``PYTHONPATH`` points at
its tree. Old and new runs alternate so that a change in the machine's load hits both. Every run
first trains `--warmup` rollouts (kernel loading, torch's first calls; not timed), then times
`--rollouts` rollouts and prints, in env steps per wall-clock second:

- collection: `collect_rollouts` (policy forward, env step, VecMonitor, VecNormalize, buffer);
- update: `PPO.train` (n_epochs passes of minibatch gradient steps over the rollout);
- total: env steps over collection + update time, the training rate;
- floor: the update's bare arithmetic (`training_run.bare_update_seconds`: forward, backward,
  clipping and Adam on random minibatches, as many as the update takes; no SB3 bookkeeping),
  the ceiling of the update rate at this width, batch and precision. An update near its floor
  is bound by the networks' arithmetic: faster only with fewer or cheaper gradient steps.

The rollout holds 8192 env steps at every N (n_steps = 8192 / N: 256, 64, 16), so the update
does the same work per env step as the shipped configuration; `--n-steps`, `--batch-size` and
`--n-epochs` override the configuration for other trade-offs. torch and numba run on one thread
as in the trainer (`--update-threads 2` also times the update on two torch threads, for both trees).

    auv-gym speed training                      # about 3-5 minutes on 2 cores
    auv-gym speed training --quick              # smoke test
    python -m benchmarks.speed.training --n-envs 512 --baseline main --rollouts 8
    auv-gym speed training --n-envs 32 512 --batch-size 2048 8192 --update-dtype float32 bfloat16

The baseline's files come from ``git archive REF`` into a cache folder kept between runs (its
compiled kernels too); `--baseline none` times this tree only.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from auv_gym.support.files import write_json
from benchmarks.arguments import parse_options, program_name, usage_errors, writable_location
from benchmarks.options import option
from benchmarks.speed.training_run import CONFIG, ENV_ID

DEFAULT_BASELINE = "b8de6c4"
N_ENVS = (32, 128, 512)
ROLLOUT_STEPS = 8192  # env steps per rollout of the generalist configuration (32 × 256)
HERE = Path(__file__).resolve()
RUN_FILE = HERE.with_name("training_run.py")  # `measure`, run in each tree
SHIPPED_EPOCHS = 10  # PPO epochs per update of the generalist configuration
# (side, N, update threads, batch size, update dtype, epochs) → the runs of that tree and setting
Results = dict[tuple[str, int, int, int, str, int], list[dict[str, Any]]]
TREE = HERE.parents[2]  # this tree's root


def extract(ref: str, cache: Path) -> Path:
    """The tree of git ``ref`` (a commit-ish of this repository) in ``cache``/<commit>."""
    commit = subprocess.run(
        ["git", "rev-parse", "--verify", f"{ref}^{{commit}}"],
        cwd=TREE,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    folder = cache / commit
    if not (folder / "auv_gym" / "__init__.py").is_file():
        partial = Path(tempfile.mkdtemp(prefix=f"{commit[:12]}.", dir=cache))
        with tempfile.TemporaryFile() as archive:
            subprocess.run(
                ["git", "archive", "--format=tar", commit], cwd=TREE, stdout=archive, check=True
            )
            archive.seek(0)
            with tarfile.open(fileobj=archive) as tar:
                tar.extractall(partial, filter="data")
        partial.rename(folder)  # complete trees only
    return folder


def run_in(tree: Path, spec: dict[str, Any]) -> dict[str, Any]:
    """`measure(spec)` in a fresh interpreter that imports ``tree``'s auv_gym and benchmarks."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    code = (
        "import json, sys, runpy\n"
        f"m = runpy.run_path({str(RUN_FILE)!r})\n"
        "print(json.dumps(m['measure'](json.loads(sys.argv[1]))))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code, json.dumps(spec)],
        cwd=tree,
        env=env,
        capture_output=True,
        text=True,
    )
    if out.returncode != 0:
        raise RuntimeError(f"benchmark run in {tree} failed:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def _median(runs: list[dict[str, Any]], key: str) -> float:
    return statistics.median(r[key] for r in runs)


def _floor(runs: list[dict[str, Any]]) -> str:
    """The median bare-update rate [env steps/s], or "-" for runs made before it was timed."""
    floors = [r["floor_update_per_s"] for r in runs if "floor_update_per_s" in r]
    return f"{statistics.median(floors):,.0f}" if floors else "-"


def table(results: Results, sides: list[str]) -> str:
    """One row per setting (N, update threads, batch, dtype, epochs): each side's median rates
    and the new/old ratios."""
    head = f"{'N':>5} {'n_steps':>7} {'batch':>6} {'epochs':>6} {'upd thr':>7} {'dtype':>8}"
    for side in sides:
        head += f" | {side + ' total':>12} {'collect':>9} {'update':>8} {'floor':>8}"
    if len(sides) == 2:
        head += f" | {'ratio total':>11} {'collect':>8} {'update':>7}"
    lines = [head, "-" * len(head)]
    for setting in sorted({key[1:] for key in results}):
        runs = {side: results[(side, *setting)] for side in sides}
        n, t, b, d, e = setting
        line = f"{n:>5} {runs[sides[-1]][0]['n_steps']:>7} {b:>6} {e:>6} {t:>7} {d:>8}"
        for side in sides:
            line += (
                f" | {_median(runs[side], 'total_per_s'):>12,.0f} "
                f"{_median(runs[side], 'collect_per_s'):>9,.0f} "
                f"{_median(runs[side], 'update_per_s'):>8,.0f} "
                f"{_floor(runs[side]):>8}"
            )
        if len(sides) == 2:
            old, new = runs[sides[0]], runs[sides[1]]
            ratios = [
                _median(new, k) / _median(old, k)
                for k in ("total_per_s", "collect_per_s", "update_per_s")
            ]
            line += f" | {ratios[0]:>10.2f}× {ratios[1]:>7.2f}× {ratios[2]:>6.2f}×"
        lines.append(line)
    return "\n".join(lines)


def versus_shipped(results: Results) -> str:
    """Every new total against the old one of the first setting (the shipped configuration:
    N = 32, batch 2048, one thread, float32, with the defaults): code and settings together."""
    olds = [key[1:] for key in results if key[0] == "old" and key[4] == "float32"]
    first = min([k for k in olds if k[4] == SHIPPED_EPOCHS] or olds)
    ref = _median(results[("old", *first)], "total_per_s")
    cells = [
        f"N={n} b={b} ep={e} thr={t} {d}: {_median(runs, 'total_per_s') / ref:.2f}×"
        for (side, n, t, b, d, e), runs in sorted(results.items())
        if side == "new"
    ]
    n, t, b, d, e = first
    return f"new total / old total at N={n} b={b} ep={e} thr={t} {d}: " + ", ".join(cells)


@dataclass
class Options:
    """The command line of `auv-gym speed training`."""

    n_envs: tuple[int, ...] = option(N_ENVS, "numbers of vehicles (training envs)", nargs="+")
    baseline: str = option(
        DEFAULT_BASELINE, "git ref of the code to compare with; 'none': this tree only"
    )
    rollouts: int = option(4, "timed rollouts per run")
    warmup: int = option(1, "untimed rollouts first")
    repeats: int = option(2, "runs per tree and setting (alternating; medians are printed)")
    n_steps: int | None = option(None, f"steps per env and rollout (default {ROLLOUT_STEPS} / N)")
    batch_size: tuple[int, ...] = option(
        (2048,), "minibatch sizes (the configuration's: 2048); one row each", nargs="+"
    )
    update_threads: tuple[int, ...] = option(
        (1,), "torch threads of the update (collection: one); one row each", nargs="+"
    )
    net_arch: tuple[int, ...] = option(
        (), "hidden-layer widths of both networks (default: the configuration's 64 64)", nargs="+"
    )
    # Fewer epochs are fewer gradient steps per env step: a change of the algorithm, whose
    # learning has to be measured beside its rate (docs/performance.md).
    n_epochs: tuple[int, ...] = option(
        (SHIPPED_EPOCHS,),
        "PPO epochs per update (the configuration's: 10); one row each",
        nargs="+",
    )
    update_dtype: tuple[str, ...] = option(
        ("float32",),
        "precision of the update's matrix products (float32, bfloat16: torch.autocast; timed "
        "only, PPO does not learn with it, docs/performance.md); one row each",
        nargs="+",
    )
    cache: str = option(
        os.path.join(tempfile.gettempdir(), "auv-gym-baselines"),
        "folder of the extracted baseline trees",
    )
    quick: bool = option(False, "tiny budget (smoke test)")
    json: str | None = option(None, "also write every run to this file")


def main(argv: list[str] | None = None) -> dict[str, Any]:
    args, parser = parse_options(
        Options, argv, program_name("benchmarks.speed.training"), __doc__, negatable=False
    )
    if args.json:  # written after the benchmark: refused now, not after minutes of timing
        with usage_errors(parser):
            writable_location(args.json, "--json", folder=False)
    if args.quick:
        args.n_envs, args.rollouts, args.repeats, args.n_steps = (8,), 1, 1, 16
        args.batch_size = (64,)
    if min(args.n_envs) < 1 or args.rollouts < 1 or args.repeats < 1 or args.warmup < 0:
        parser.error("--n-envs, --rollouts and --repeats must be >= 1, --warmup >= 0")
    if min(args.n_epochs) < 1:
        parser.error(f"--n-epochs must be >= 1, got {list(args.n_epochs)}")
    try:
        args.net_arch = tuple(int(width) for width in args.net_arch)
    except ValueError:
        parser.error(f"--net-arch takes whole numbers, got {list(args.net_arch)}")
    if any(width < 1 for width in args.net_arch):
        parser.error(f"--net-arch widths must be >= 1, got {list(args.net_arch)}")
    unknown = sorted(set(args.update_dtype) - {"float32", "bfloat16"})
    if unknown:
        parser.error(f"--update-dtype must be float32 or bfloat16, got {unknown}")

    from tqdm import tqdm

    trees = {"new": TREE}
    if args.baseline.lower() != "none":
        cache = Path(args.cache)
        cache.mkdir(parents=True, exist_ok=True)
        try:
            trees = {"old": extract(args.baseline, cache), **trees}
        except (OSError, subprocess.CalledProcessError) as error:  # no git, not a checkout
            print(f"baseline {args.baseline!r} unavailable ({error}); timing this tree only")
    sides = list(trees)
    specs = [
        {
            "n_envs": n,
            "n_steps": args.n_steps or max(1, ROLLOUT_STEPS // n),
            "batch_size": b,
            "rollouts": args.rollouts,
            "warmup": args.warmup,
            "update_threads": t,
            "update_dtype": d,
            "n_epochs": e,
            "net_arch": list(args.net_arch),
            "seed": 0,
        }
        for e in args.n_epochs
        for d in args.update_dtype
        for b in args.batch_size
        for t in args.update_threads
        for n in args.n_envs
    ]
    plan = []
    for repeat in range(args.repeats):
        for k, spec in enumerate(specs):  # alternate which side goes first
            order = sides if (repeat + k) % 2 == 0 else sides[::-1]
            plan += [(side, spec) for side in order]
    print(
        f"PPO on {CONFIG} ({ENV_ID}"
        + (f", networks {list(args.net_arch)}" if args.net_arch else "")
        + f"); new = {TREE}"
        + (f", old = {args.baseline} ({trees['old'].name[:12]})" if "old" in trees else "")
        + f"; {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f} at start\n",
        flush=True,
    )
    results: Results = {}
    for side in tqdm(sides, desc="loading kernels", leave=False):  # compile once per tree
        run_in(
            trees[side],
            {**specs[0], "n_envs": 2, "n_steps": 8, "batch_size": 16, "rollouts": 1, "warmup": 0},
        )
    for side, spec in tqdm(plan, desc="training runs"):
        r = {"side": side, **run_in(trees[side], spec)}
        key = (
            side,
            spec["n_envs"],
            spec["update_threads"],
            spec["batch_size"],
            spec["update_dtype"],
            spec["n_epochs"],
        )
        results.setdefault(key, []).append(r)
    print("\nenv steps/s (medians of the runs); ratio = new / old, measured in this run")
    print(table(results, sides))
    if "old" in trees:
        print(versus_shipped(results))
    print(f"load average {os.getloadavg()[0]:.2f} at the end")
    out = {"baseline": args.baseline, "runs": [r for rs in results.values() for r in rs]}
    if args.json:
        write_json(args.json, out, indent=2)
    return out


if __name__ == "__main__":
    main()
