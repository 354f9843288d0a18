"""Multi-seed training: N seeds of one configuration, as local processes or Ray tasks, resumable.

Layout of a multi-seed run directory OUT::

    OUT/train_seeds.json          the plan (algorithm, env id, config, budget, seeds, evaluation)
    OUT/seed_<k>/                 the run directory of seed k (`benchmarks.training.train`)
    OUT/logs/seed_<k>.log         its output (local backend)
    OUT/seed_<k>/best/held_out_evaluation.json   the seed's agent on the test episodes
    OUT/summary.json              every seed's validation score, test summary, wall time, and
                                  the selected seed

Every seed is an independent `train` run with its own checkpoints, so a killed multi-seed run
is continued with the same command plus ``--resume``: finished seeds are kept, every unfinished
seed restarts from its newest checkpoint (losing at most one checkpoint interval), and a seed
killed before its first checkpoint starts again from scratch.

Selection: each seed's `best/` agent is its best evaluation on the validation seeds
(`eval_seeds`, never the test seeds); the shipped agent is the seed whose best validation score
(`evaluation.score`: fewer terminated episodes, then lower mean rms distance) is lowest. The test
episodes (`HELD_OUT_SEEDS` of the task set) are evaluated for every seed and reported, never used
to choose.

Workers (`seed_workers`): local processes that die with the parent, or Ray tasks running the
same function on a cluster whose nodes share OUT.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import time
from collections.abc import Sequence
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

from auv_gym.support.files import LOCK_FILE, output_lock, replace_outputs, write_json, write_text
from benchmarks.arguments import writable_location
from benchmarks.runner.pool import check_pool_options, check_ray_address
from benchmarks.training.checkpoints import SEED_AGENT_PREFIX, check_export_folder, export_agent
from benchmarks.training.config import read_zoo_config
from benchmarks.training.demo_regularization import check_demonstrations
from benchmarks.training.evaluation import EVAL_SEEDS, HELD_OUT_FILE, score
from benchmarks.training.learning_curve import EVAL_FILE
from benchmarks.training.seed_workers import (
    LOGS,
    run_local,
    run_ray,
    seed_dir,
    seed_entry,
    seed_progress,
    seed_status,
)
from benchmarks.training.seeds_options import (  # the options, importable from here too
    DEFAULT_EVAL_EPISODES,
    MAX_SEED,
    MAX_SEEDS,
    TASK_SETS,
    SeedsOptions,
    parse_seeds,
)
from benchmarks.training.selection_rule import rule_of
from benchmarks.training.train import agent_observation_names, check_options, target_timesteps
from benchmarks.training.warm_start import (
    agent_for_seed,
    check_initial_agents,
    check_network_size,
)
from controllers.agent import ACTION_DIM

__all__ = [
    "DEFAULT_EVAL_EPISODES",
    "MAX_SEED",
    "MAX_SEEDS",
    "PLAN_FILE",
    "SUMMARY_FILE",
    "TASK_SETS",
    "SeedsOptions",
    "check_out_folder",
    "check_ray_address",
    "check_seeds_options",
    "parse_seeds",
    "resolve_validation",
    "seed_status",
    "selection_key",
    "train_seeds",
    "validation_set",
]

PLAN_FILE = "train_seeds.json"
SUMMARY_FILE = "summary.json"
# Plan entries that must match when a run is resumed (the rest may change: workers, backend).
PLAN_KEYS = (
    "algo",
    "env_id",
    "config",
    "n_timesteps",
    "eval_seeds",
    "eval_duration",
    "eval_freq",
    "checkpoint_freq",
    "task_set",
    "eval_env",
    "vec_env",
)


def check_seeds_options(opts: SeedsOptions) -> dict[str, Any]:
    """Validate everything before any training starts; returns the plan (PLAN_FILE content).

    ValueError (one line) for: no or negative seeds, bad budgets or evaluation seeds
    (`check_options`), an evaluation duration that cannot produce a metric, an unknown task
    set, unknown backend, workers < 1, an unreachable Ray address or a missing Ray, an output
    folder that holds another run (or no run to resume).
    """
    if not opts.seeds or min(opts.seeds) < 0:
        raise ValueError(f"seeds must be non-empty and non-negative, got {list(opts.seeds)}")
    check_out_folder(opts.out)
    opts = resolve_validation(opts)
    if not (isinstance(opts.workers, int) and opts.workers >= 1):
        raise ValueError(f"workers must be a positive integer, got {opts.workers!r}")
    if opts.backend not in ("local", "ray"):
        raise ValueError(f"backend must be 'local' or 'ray', got {opts.backend!r}")
    train = opts.train
    check_options(replace(train, init_from=None))  # each seed's agent is checked below
    if train.eval_freq < 1:
        raise ValueError(
            "eval_freq must be positive: the shipped agent is selected on the "
            "validation evaluations"
        )
    check_evaluation_window(train.eval_duration)
    if opts.backend == "ray" or opts.address is not None:  # `benchmarks.runner.pool`: Ray
        check_pool_options(1, opts.backend, opts.address)  # installed, its address answering
    cfg = read_zoo_config(train.config, train.env_id, train.algo)
    check_obs_scales(cfg, train.env_id, str(train.config))
    # The network every seed builds, and each seed's initial agent loaded into it, as the
    # workers will: before any of them starts (a failure there says only "see log").
    residual = cfg.residual
    obs_names = agent_observation_names(cfg, train.env_id)
    action_dim = ACTION_DIM if residual is None else residual.action_dim
    check_network_size(cfg.policy_kwargs, len(obs_names), action_dim, str(train.config))
    agents = [agent_for_seed(train.init_from, s) for s in opts.seeds] if train.init_from else []
    check_initial_agents(
        agents,
        train.algo,
        obs_names,
        action_dim,
        cfg.policy_kwargs,
        str(train.config),
        bool(cfg.algo_kwargs.get("use_sde", False)),
    )
    check_demonstrations(cfg, agents, obs_names, action_dim, str(train.config))
    n_timesteps = cfg.n_timesteps if train.n_timesteps is None else int(train.n_timesteps)
    if train.stop_at is not None and train.stop_at % cfg.n_envs:
        raise ValueError(
            f"stop_at {train.stop_at} is not a multiple of the config's n_envs "
            f"({cfg.n_envs}): a run pauses after whole vector steps"
        )
    plan = {
        "algo": train.algo,
        "env_id": train.env_id,
        "config": cfg.raw,
        "config_file": str(train.config),
        "n_timesteps": n_timesteps,
        "stop_at": train.stop_at,
        "eval_seeds": list(train.eval_seeds),
        "eval_duration": float(train.eval_duration),
        "eval_freq": train.eval_freq,
        "checkpoint_freq": train.checkpoint_freq,
        "task_set": opts.task_set,
        "eval_env": train.eval_env,
        "vec_env": train.vec_env,
        "seeds": list(opts.seeds),
        "init_from": train.init_from,
        "progress_steps": progress_steps(cfg, n_timesteps),
    }
    out = Path(opts.out)
    plan_file = out / PLAN_FILE
    if opts.resume:
        if not plan_file.is_file():
            raise ValueError(f"--resume: {out} holds no multi-seed run ({PLAN_FILE} missing)")
        previous = json.loads(plan_file.read_text())
        for key in PLAN_KEYS:
            if previous.get(key) != plan[key]:
                raise ValueError(
                    f"--resume: {key} was {previous.get(key)!r} in {plan_file}, "
                    f"now {plan[key]!r}; resume with the same settings"
                )
        # A pause only moves forward: a lower target than last time must not leave seeds past
        # it (a run itself may end up to one rollout past its target, as PPO collects them).
        target = target_timesteps(n_timesteps, train.stop_at)
        before = target_timesteps(previous["n_timesteps"], previous.get("stop_at"))
        for seed in opts.seeds if target < before else ():
            done = seed_progress(seed_dir(out, seed))
            if done > target:
                raise ValueError(
                    f"--resume: seed {seed} has already trained {done} env steps, "
                    f"past the target {target}; use --stop-at >= {done}"
                )
    elif holds_work(out):
        raise ValueError(f"output folder {out} is not empty; pass --resume or another --out")
    _check_writable(out)
    for flag, folder in (("--export", opts.export), ("--results", opts.results)):
        if folder is not None:  # written at the end: refused now, not after the training
            try:
                writable_location(folder, flag)
            except OSError as error:
                raise ValueError(str(error)) from None
    if opts.export is not None:
        check_export_folder(opts.export, "--export", out)
    return plan


def check_obs_scales(cfg: Any, env_id: str, where: str) -> None:
    """The observation entries a config pins (``obs_scales``) exist in the observation of its
    env (id and env_kwargs): checked before any worker starts; ValueError naming ``where``."""
    if cfg.obs_scales is None:
        return
    names = agent_observation_names(cfg, env_id)
    unknown = sorted(set(cfg.obs_scales) - set(names))
    if unknown:
        raise ValueError(
            f"{where}: obs_scales names {unknown}, which the observation of {env_id} does not "
            f"have; its entries: {list(names)}"
        )


def check_out_folder(out: str | Path) -> None:
    """ValueError naming --out when it names no folder ("": the current folder) or a file."""
    if isinstance(out, str) and not out.strip():
        raise ValueError(
            f"--out {out!r} names no folder: give the run's folder (an empty path would write "
            "into the current folder)"
        )
    if Path(out).exists() and not Path(out).is_dir():
        raise ValueError(f"--out {str(out)!r} is a file, not a folder: give the run's folder")


def holds_work(out: Path) -> bool:
    """Whether ``out`` holds anything a fresh start would lose: a file or folder other than
    what a start that failed before any training leaves (the lock, the plan, logs, seed folders
    without a checkpoint or final agent), which a corrected command may replace."""
    if not out.is_dir():
        return out.exists()
    for entry in out.iterdir():
        if entry.name in (LOCK_FILE, PLAN_FILE, LOGS):
            continue
        is_seed = entry.is_dir() and entry.name.startswith("seed_")
        if not is_seed or seed_progress(entry) > 0 or (entry / "final").exists():
            return True
    return False


def validation_set(name: Any, label: str = "task set") -> Any:
    """The task file's validation set ``name`` (a `TaskSet`), None for a built-in one
    (`TASK_SETS`); ValueError "<label> <name> is not a validation set; valid: [...]" otherwise."""
    if isinstance(name, str) and name in TASK_SETS:
        return None
    from benchmarks.catalog.tasks import load_task_sets

    sets = load_task_sets()
    if not isinstance(name, str) or name not in sets or sets[name].role != "validation":
        validation = sorted(n for n, s in sets.items() if s.role == "validation")
        raise ValueError(
            f"{label} {name!r} is not a validation set; valid: {sorted(TASK_SETS) + validation}"
        )
    return sets[name]


def resolve_validation(opts: SeedsOptions) -> SeedsOptions:
    """`opts` with the validation episodes of its task set filled in (`TrainOptions.eval_env`
    and `eval_seeds`); ValueError (one line) for an unknown set, a set that is not a validation
    set, or evaluation seeds outside the set's range."""
    chosen = validation_set(opts.task_set)
    if opts.eval_episodes < 1:  # refused whichever set: was accepted when the set ignores it
        raise ValueError(f"eval_episodes must be >= 1, got {opts.eval_episodes}")
    if chosen is None:
        return opts
    seeds = tuple(opts.train.eval_seeds)
    if seeds == tuple(EVAL_SEEDS):  # the paper default: take the set's own seeds
        if not 1 <= opts.eval_episodes <= len(chosen.seeds):
            raise ValueError(
                f"eval_episodes must be 1-{len(chosen.seeds)} (the size of task set "
                f"{chosen.name!r}), got {opts.eval_episodes}"
            )
        seeds = tuple(chosen.seeds[: opts.eval_episodes])
    outside = sorted(set(seeds) - set(chosen.seeds))
    if outside:
        raise ValueError(
            f"eval seeds {outside[:5]} lie outside task set {chosen.name!r} (seeds "
            f"{chosen.seeds.start}-{chosen.seeds.stop - 1})"
        )
    train = replace(opts.train, eval_env=chosen.eval_env(), eval_seeds=seeds)
    return replace(opts, train=train)


def check_evaluation_window(duration: float) -> None:
    """Evaluation episodes of ``duration`` [s] must leave samples in the metrics window."""
    try:  # the shared window rule of auv_gym.metrics, where this checkout has it
        from benchmarks.training.evaluation import check_evaluation_duration
    except ImportError:
        from auv_gym.metrics import DEFAULT_TRANSIENT

        if not duration > DEFAULT_TRANSIENT + 0.05:
            raise ValueError(
                f"evaluation duration {duration!r} s leaves no sample in the metrics window "
                f"t ≥ {DEFAULT_TRANSIENT:g} s: use an eval duration above it"
            ) from None
        return
    check_evaluation_duration(duration)


def _check_writable(out: Path) -> None:
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / f".write_test_{os.getpid()}"
        probe.write_text("")
        probe.unlink()
    except OSError as exc:
        raise ValueError(f"output folder {out} is not writable: {exc}") from None


def _chattering_clause(plan: dict[str, Any]) -> str:
    residual = plan["config"].get("residual") or {}
    weight = residual.get("selection_chattering", 0.0) if isinstance(residual, dict) else 0.0
    return f" + {weight:g} m·s × mean chattering" if weight else ""


def selection_key(entry: dict[str, Any]) -> tuple[float, float, int]:
    """How a summary entry ranks, lowest first: its validation score (`evaluation.score`, as the
    run recorded it for its best agent, which includes a residual agent's chattering), then its
    seed; an entry without a validation summary last."""
    summary = entry.get("validation_summary")
    if not summary:
        return (math.inf, math.inf, entry["seed"])
    recorded = entry.get("validation_score")
    n_term, value = recorded if recorded else score(summary)
    return (n_term, value, entry["seed"])


def select(entries: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The entry ranked first by `selection_key`: the lowest validation score, ties to the lower
    seed."""
    return min(entries, key=selection_key)


def train_seeds(opts: SeedsOptions) -> dict[str, Any]:
    """Train every seed (see the module doc); returns the summary written to OUT/summary.json.

    Raises ValueError before any work for bad options (`check_seeds_options`) and RuntimeError
    after the run when a seed failed (the others are finished and kept).
    """
    plan = check_seeds_options(opts)
    opts = resolve_validation(opts)
    out = Path(opts.out)
    # One run per folder: a second one is refused, a killed one's temporary files removed.
    with contextlib.ExitStack() as stack:
        try:
            stack.enter_context(output_lock(out, "--out"))
            for seed in opts.seeds:  # a separate `auv-gym train --out OUT/seed_<k>` still running
                if seed_dir(out, seed).is_dir():
                    with output_lock(seed_dir(out, seed), "--out"):
                        pass
        except OSError as error:
            raise ValueError(str(error)) from None
        return _train_seeds(opts, plan, out)


def progress_steps(cfg: Any, n_timesteps: int) -> int:
    """Env steps one seed's learning curve will reach: ``n_timesteps``, or for a jump start
    (which runs whole, `benchmarks.training.jump_start`) its dataset's steps and those it flies."""
    jump = cfg.jump_start
    if jump is None:
        return n_timesteps
    steps = sum(jump.round_steps(cfg.n_envs))
    if jump.dataset is not None:
        from benchmarks.training.demonstrations import read_metadata

        steps += sum(int(e["steps"]) for e in read_metadata(jump.dataset)["episodes"])
    return max(1, steps)


def _train_seeds(opts: SeedsOptions, plan: dict[str, Any], out: Path) -> dict[str, Any]:
    write_json(out / PLAN_FILE, plan, indent=2, sort_keys=True)
    n_timesteps = target_timesteps(plan["n_timesteps"], plan["stop_at"])  # this invocation's
    jobs = []
    done_seeds = 0
    for seed in opts.seeds:
        status = seed_status(out, seed, n_timesteps)
        if status == "done":
            done_seeds += 1
            continue
        train_opts = asdict(
            replace(
                opts.train,
                seed=seed,
                out=str(seed_dir(out, seed)),
                n_timesteps=plan["n_timesteps"],
                progress_bar=False,
                export=None,
                resume=False,
            )
        )
        train_opts["eval_seeds"] = tuple(train_opts["eval_seeds"])
        jobs.append((seed, train_opts, status))
    bar = None
    if opts.progress:
        from tqdm.auto import tqdm

        per_seed = plan["progress_steps"]
        bar = tqdm(
            total=per_seed * len(opts.seeds),
            initial=done_seeds * per_seed,
            unit="step",
            desc=f"{plan['algo']} × {len(opts.seeds)} seeds",
        )
    t0 = time.monotonic()
    if opts.backend == "ray":
        failures = run_ray(jobs, opts.address, opts.workers, out, bar, opts.poll_s)
    else:
        failures = run_local(jobs, opts.workers, out, bar, opts.poll_s)
    if bar is not None:
        bar.close()
    if failures:
        raise RuntimeError("; ".join(failures[s] for s in sorted(failures)))
    entries = [seed_entry(seed_dir(out, seed)) for seed in opts.seeds]
    chosen = select(entries)
    summary = {
        "plan": plan,
        "seeds": entries,
        "selected_seed": chosen["seed"],
        "selection": f"lowest validation score ({rule_of(plan).describe()}"
        f"{_chattering_clause(plan)}) on eval_seeds; test episodes are never used "
        "to choose",
        "session_wall_time_s": time.monotonic() - t0,
    }
    write_json(out / SUMMARY_FILE, summary, indent=2, sort_keys=True)
    if opts.results:
        _write_results(Path(opts.results), out, entries, summary)
    if opts.export:
        export_agent(Path(chosen["agent"]), Path(opts.export))
        report = json.loads((Path(chosen["agent"]) / HELD_OUT_FILE).read_text())
        write_json(Path(opts.export) / HELD_OUT_FILE, report, indent=2, sort_keys=True)
    return summary


def _write_results(
    results: Path, out: Path, entries: Sequence[dict[str, Any]], summary: dict[str, Any]
) -> None:
    """Per seed `write_seed_outputs`, and the summary (all atomic). Files an earlier run with
    other seeds wrote there are removed (`replace_outputs`): the suite would take a stale agent
    for a seed of this run."""
    written = [results / SUMMARY_FILE]
    for entry in entries:
        written += write_seed_outputs(results, entry, seed_dir(out, entry["seed"]) / EVAL_FILE)
    write_json(results / SUMMARY_FILE, summary, indent=2, sort_keys=True)
    replace_outputs(results, written)


def write_seed_outputs(results: Path, entry: dict[str, Any], curve: Path) -> list[Path]:
    """One seed's selected agent (``agent_seed_<k>/``, so every seed can be re-evaluated on the
    whole test suite, `benchmarks.runner.evaluate_suite`), its held-out test evaluation and its
    learning curve ``curve``, written atomically into RESULTS; the files written."""
    seed = entry["seed"]
    agent = results / f"{SEED_AGENT_PREFIX}{seed}"
    export_agent(Path(entry["agent"]), agent)
    report = json.loads((Path(entry["agent"]) / HELD_OUT_FILE).read_text())
    return [
        *(f for f in agent.iterdir() if f.is_file()),
        write_json(results / f"seed_{seed}_test_evaluation.json", report, indent=2, sort_keys=True),
        write_text(results / f"seed_{seed}_learning_curve.csv", curve.read_text()),
    ]
