"""Running the seeds of a multi-seed training (`benchmarks.training.seeds`): a seed's folder and
status, training and testing one seed, and the two ways to run many: supervised local processes
(spawned, ``workers`` at once, dying with the parent, output in OUT/logs/seed_<k>.log) or Ray
tasks (`benchmarks.runner.pool.connect_ray`). A failed seed does not stop the others."""

from __future__ import annotations

import json
import multiprocessing
import os
import shutil
import sys
from collections.abc import Sequence
from dataclasses import replace
from multiprocessing.connection import wait
from pathlib import Path
from typing import Any

from auv_gym.support.files import LOCK_FILE, output_lock
from benchmarks.runner.pool import connect_ray, die_with_parent
from benchmarks.training.checkpoints import latest_checkpoint, list_checkpoints
from benchmarks.training.evaluation import HELD_OUT_FILE
from benchmarks.training.learning_curve import EVAL_FILE
from benchmarks.training.train import TrainOptions
from controllers.agent import METADATA_FILE, MODEL_FILE

__all__ = [
    "LOGS",
    "run_local",
    "run_ray",
    "seed_dir",
    "seed_entry",
    "seed_progress",
    "seed_status",
    "train_one_seed",
]

LOGS = "logs"  # OUT/logs/seed_<k>.log: the output of each local worker


def seed_dir(out: str | os.PathLike, seed: int) -> Path:
    """The run folder of training seed ``seed`` under the multi-seed run ``out``."""
    return Path(out) / f"seed_{seed}"


def seed_progress(run: Path) -> int:
    """Env steps a seed's run folder holds: its newest checkpoint or its final agent (0: none)."""
    steps = [n for n, _ in list_checkpoints(run)]
    final = run / "final" / METADATA_FILE
    if final.is_file():
        steps.append(int(json.loads(final.read_text()).get("num_timesteps", 0)))
    return max(steps, default=0)


def seed_status(out: Path, seed: int, n_timesteps: int) -> str:
    """ "done" (trained to ``n_timesteps``, this invocation's target, and tested), "trained"
    (trained, test evaluation missing), "resume" (a checkpoint to continue from) or "fresh"."""
    run = seed_dir(out, seed)
    final = run / "final" / METADATA_FILE
    meta = json.loads(final.read_text()) if final.is_file() else {}
    # A jump start (imitation, `benchmarks.training.jump_start`) runs whole: its final is done.
    if final.is_file() and (meta.get("num_timesteps", 0) >= n_timesteps or "jump_start" in meta):
        best = run / "best"
        return "done" if (best / HELD_OUT_FILE).is_file() else "trained"
    return "resume" if latest_checkpoint(run) is not None else "fresh"


def train_one_seed(train_opts: dict[str, Any], status: str) -> dict[str, Any]:
    """Train (or resume) one seed and evaluate its best agent on the test episodes.

    Module-level and picklable: the local processes and the Ray tasks run it. Returns the
    seed's entry of the summary.
    """
    from benchmarks.training.evaluation import write_held_out_evaluation
    from benchmarks.training.train import train

    opts = TrainOptions(**train_opts)
    run = Path(opts.out)
    # Held while the seed trains and tests: an `auv-gym train --out` on this folder is refused
    # (and this seed fails naming that run) rather than both writing one run.
    with output_lock(run, "--out"):
        if status == "fresh":
            empty_folder(run)  # killed before its first checkpoint: nothing to keep
        if status in ("fresh", "resume"):
            train(
                replace(opts, resume=status == "resume", export=None),
                argv=["benchmarks.training.seeds_cli", f"--seed={opts.seed}"],
            )
        best = run / "best" if (run / "best" / MODEL_FILE).is_file() else run / "final"
        if not (best / HELD_OUT_FILE).is_file():
            write_held_out_evaluation(best, opts.eval_duration, opts.env_id)
        return seed_entry(run)


def empty_folder(run: Path) -> None:
    """Remove everything in ``run`` but its lock file, which the caller holds."""
    for entry in run.iterdir():
        if entry.name == LOCK_FILE:
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry)
        else:
            entry.unlink()


def seed_entry(run: Path) -> dict[str, Any]:
    """A finished seed: validation score of its agent, test summary, steps and wall time."""
    best = run / "best" if (run / "best" / MODEL_FILE).is_file() else run / "final"
    final = json.loads((run / "final" / METADATA_FILE).read_text())
    report = json.loads((best / HELD_OUT_FILE).read_text())
    validation = final.get("best", {})
    return {
        "seed": final["seed"],
        "agent": str(best),
        "num_timesteps": final["num_timesteps"],
        "wall_time_s": final["wall_time_s"],
        "validation_score": validation.get("score"),
        "validation_num_timesteps": validation.get("num_timesteps"),
        "validation_summary": validation.get("summary"),
        "test_summary": report["summary"],
    }


def _child(train_opts: dict[str, Any], status: str, log: str, parent_pid: int) -> None:
    die_with_parent(parent_pid)  # no orphaned training
    fd = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    os.dup2(fd, 1)
    os.dup2(fd, 2)
    sys.stdout = os.fdopen(1, "w", buffering=1, closefd=False)
    sys.stderr = os.fdopen(2, "w", buffering=1, closefd=False)
    try:
        train_one_seed(train_opts, status)
    except BaseException:
        import traceback

        traceback.print_exc()
        sys.stderr.flush()
        os._exit(1)


def _steps_done(out: Path, seed: int) -> int:
    """Env steps of a seed as far as its learning curve shows (for the progress bar)."""
    curve = seed_dir(out, seed) / EVAL_FILE
    try:
        lines = curve.read_text().strip().splitlines()
        return int(lines[-1].split(",")[0]) if len(lines) > 1 else 0
    except (OSError, ValueError, IndexError):
        return 0


def run_local(
    jobs: list[tuple[int, dict[str, Any], str]], workers: int, out: Path, bar: Any, poll_s: float
) -> dict[int, str]:
    """Run the jobs as spawned processes, ``workers`` at once; seed → error text (failures)."""
    ctx = multiprocessing.get_context("spawn")  # numba's threads are not fork-safe
    pending = list(jobs)
    running: dict[Any, tuple[int, Any]] = {}
    failures: dict[int, str] = {}
    try:
        while pending or running:
            while pending and len(running) < workers:
                seed, train_opts, status = pending.pop(0)
                log = out / LOGS / f"seed_{seed}.log"
                log.parent.mkdir(parents=True, exist_ok=True)
                proc = ctx.Process(
                    target=_child, args=(train_opts, status, str(log), os.getpid()), daemon=False
                )
                proc.start()
                running[proc.sentinel] = (seed, proc)
            for sentinel in wait(list(running), timeout=poll_s):
                seed, proc = running.pop(sentinel)
                proc.join()
                if proc.exitcode != 0:
                    failures[seed] = (
                        f"seed {seed} failed (exit code {proc.exitcode}); see "
                        f"{out / LOGS / f'seed_{seed}.log'}"
                    )
            _update(bar, out, [s for s, *_ in jobs])
    finally:
        for _, proc in running.values():  # an exception or Ctrl-C here: stop the workers
            proc.kill()
            proc.join()
    return failures


def run_ray(
    jobs: list[tuple[int, dict[str, Any], str]],
    address: str | None,
    workers: int,
    out: Path,
    bar: Any,
    poll_s: float,
) -> dict[int, str]:
    """Train the (seed, train options, status) ``jobs`` as Ray tasks of one CPU each, on a new
    local instance of ``workers`` CPUs or the cluster at ``address``, polling every ``poll_s``
    [s] to advance ``bar``; returns the failed seeds' messages."""
    # a new local instance gets ``workers`` CPUs; a cluster has its own
    local = {"num_cpus": workers, "include_dashboard": False} if address is None else {}
    ray = connect_ray(address, **local)
    remote = ray.remote(num_cpus=1, max_retries=0)(train_one_seed)
    refs = {remote.remote(train_opts, status): seed for seed, train_opts, status in jobs}
    failures: dict[int, str] = {}
    while refs:
        done, _ = ray.wait(list(refs), num_returns=1, timeout=poll_s)
        for ref in done:
            seed = refs.pop(ref)
            try:
                ray.get(ref)
            except Exception as exc:  # a failed seed does not stop the others
                failures[seed] = f"seed {seed} failed on Ray: {str(exc).splitlines()[0]}"
        _update(bar, out, [s for s, *_ in jobs])
    return failures


def _update(bar: Any, out: Path, seeds: Sequence[int]) -> None:
    if bar is not None:
        bar.n = bar.initial + sum(_steps_done(out, s) for s in seeds)
        bar.refresh()
