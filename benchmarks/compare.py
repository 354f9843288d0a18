"""FBSM vs backstepping vs PPO (and any Policy) on the same seeded scenarios.

    python -m benchmarks.compare --policies fbsm,backstepping,ppo,fbsm_ilos,backstepping_ilos \\
        --scenarios all --seeds 10 --duration 300 --workers 2 --out benchmarks/results/full

Jobs are (policy, scenario, seed) episodes. Each finished episode is written atomically to
``OUT/episodes/<scenario>/<policy>/seed_<k>.json`` (metrics) and ``.npz`` (time series) with a
fingerprint of everything that determines it, so an interrupted run restarted with the same
arguments reuses finished episodes. Results do not depend on the number of workers or the backend:
every episode is a pure function of (policy, scenario, seed, duration).
"""

from __future__ import annotations

import argparse
import csv
import functools
import hashlib
import importlib
import io
import json
import math
import os
import platform
import sys
import time
import tomllib
from collections.abc import Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, field
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import numpy as np

import auv_gym
import controllers
from auv_gym.numba_cache import sources_digest
from controllers import CLASSICAL, REGISTRY

HERE = Path(__file__).resolve().parent
SCENARIOS_FILE = HERE / "scenarios.toml"
DEFAULT_AGENT = HERE / "agents" / "ppo_helix"
# Metrics in the summary table, with the direction that is better.
SUMMARY_METRICS = {
    "rms_distance": "min",
    "rms_y_e": "min",
    "rms_z_e": "min",
    "iae_distance": "min",
    "settling_time_0p5": "min",
    "surge_overshoot": "min",
    "rms_speed_error": "min",
    "control_effort": "min",
    "chattering": "min",
    "saturation_fraction": "min",
    "success": "max",
}


@dataclass(frozen=True)
class Scenario:
    """A named, documented set of env keyword arguments (and controller keyword arguments)."""

    name: str
    description: str
    env: dict[str, Any] = field(default_factory=dict)
    controller: dict[str, Any] = field(default_factory=dict)


def load_scenarios(path: Path = SCENARIOS_FILE) -> dict[str, Scenario]:
    """Scenarios from a TOML file: one table per scenario with description, env, controller."""
    with open(path, "rb") as fh:
        raw = tomllib.load(fh)
    scenarios = {}
    for name, table in raw.items():
        unknown = set(table) - {"description", "env", "controller"}
        if unknown:
            raise ValueError(f"{path}: scenario {name!r} has unknown keys {sorted(unknown)}")
        scenarios[name] = Scenario(
            name,
            table.get("description", ""),
            dict(table.get("env", {})),
            dict(table.get("controller", {})),
        )
    return scenarios


def select(names: str, available: Sequence[str], what: str) -> list[str]:
    """Comma-separated names ("all" for every one), validated against the available ones."""
    chosen = list(available) if names == "all" else [n.strip() for n in names.split(",") if n]
    unknown = [n for n in chosen if n not in available]
    if unknown:
        raise ValueError(f"unknown {what} {unknown}; valid: {list(available)}")
    return chosen


def policy_label(spec: str) -> str:
    """A file-system-safe label of a policy spec ("ppo:runs/x" → "ppo-runs_x")."""
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in spec.replace(":", "-", 1))
    return safe.strip("_") or "policy"


def agent_path(spec: str) -> Path | None:
    """The saved agent a "ppo" or "ppo:PATH" spec names (the shipped one for "ppo"), else None."""
    if spec == "ppo":
        return DEFAULT_AGENT
    return Path(spec[4:]) if spec.startswith("ppo:") else None


def check_policy_spec(spec: str) -> None:
    """Fail early, with a clear message, on an unknown policy or a missing agent file."""
    if spec in CLASSICAL:
        return
    agent = agent_path(spec)
    if agent is not None:
        if not agent.exists():
            raise FileNotFoundError(f"policy {spec!r}: agent {agent} does not exist")
        return
    if ":" in spec:
        from controllers import import_policy

        import_policy(spec, instantiate=False)
        return
    raise ValueError(
        f"unknown policy {spec!r}; valid: {list(REGISTRY)}, 'ppo:PATH' or 'module:attribute'"
    )


def build_policy(spec: str, controller_kwargs: dict[str, Any], control_dt: float) -> Any:
    """The Policy named by spec, configured for the scenario (see `check_policy_spec`)."""
    if spec in CLASSICAL:
        return controllers.make(spec, control_dt=control_dt, **controller_kwargs)
    agent = agent_path(spec)
    if agent is not None:
        return controllers.make("ppo", path=str(agent))
    return controllers.import_policy(spec, **controller_kwargs)


@dataclass(frozen=True)
class Job:
    """One episode: a policy on a scenario with a seed, for `duration` seconds."""

    policy: str
    scenario: Scenario
    seed: int
    duration: float
    transient: float

    @property
    def env_kwargs(self) -> dict[str, Any]:
        return {**self.scenario.env, "max_time": self.duration}

    def fingerprint(self) -> str:
        """Hash of everything that determines the episode: the job, the agent file if any, and
        the source code of `auv_gym` and `controllers`."""
        payload = {
            "policy": self.policy,
            "scenario": asdict(self.scenario),
            "seed": self.seed,
            "duration": self.duration,
            "transient": self.transient,
            "agent": _agent_digest(self.policy),
            "code": code_digest(),
        }
        return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:16]

    def path(self, out: Path) -> Path:
        return (
            out / "episodes" / self.scenario.name / policy_label(self.policy) / f"seed_{self.seed}"
        )


@functools.cache
def code_digest() -> str:
    """Hash of the simulator and controller sources: a code change invalidates cached episodes."""
    packages = (Path(auv_gym.__file__).parent, Path(controllers.__file__).parent)
    return sources_digest(*packages)[:16]


def _agent_digest(spec: str) -> str:
    agent = agent_path(spec)
    if agent is None:
        return ""
    digest = hashlib.sha256()
    for file in sorted(p for p in agent.rglob("*") if p.is_file()) if agent.is_dir() else [agent]:
        digest.update(file.read_bytes())
    return digest.hexdigest()[:16]


def write_text(path: Path, text: str) -> None:
    """Write UTF-8 text atomically (`auv_gym.evaluation.write_atomic`)."""
    from auv_gym.evaluation import write_atomic

    write_atomic(path, lambda fh: fh.write(text.encode("utf-8")))


def finished(job: Job, out: Path) -> dict[str, Any] | None:
    """The stored record of a finished episode with a matching fingerprint, else None."""
    file = job.path(out).with_suffix(".json")
    if not file.exists() or not job.path(out).with_suffix(".npz").exists():
        return None
    try:
        record = json.loads(file.read_text())
    except json.JSONDecodeError:
        return None
    return record if record.get("fingerprint") == job.fingerprint() else None


def run_job(job: Job, out: Path) -> dict[str, Any]:
    """Run one episode, store its time series and metrics atomically, return the record."""
    from auv_gym import evaluation

    os.environ.setdefault("OMP_NUM_THREADS", "1")
    start = time.perf_counter()
    control_dt = float(job.env_kwargs.get("control_dt", 0.05))
    policy = build_policy(job.policy, job.scenario.controller, control_dt)
    trajectory = evaluation.rollout(policy, job.seed, **job.env_kwargs)
    metrics = evaluation.compute_metrics(trajectory, transient=job.transient)
    record = {
        "policy": job.policy,
        "scenario": job.scenario.name,
        "seed": job.seed,
        "duration": job.duration,
        "transient": job.transient,
        "fingerprint": job.fingerprint(),
        "wall_time_s": time.perf_counter() - start,
        "metrics": _jsonable(metrics),
        "trajectory": str(job.path(out).with_suffix(".npz").relative_to(out)),
    }
    base = job.path(out)
    trajectory.save(base.with_suffix(".npz"))  # atomic
    write_text(base.with_suffix(".json"), json.dumps(record))
    return record


def _jsonable(metrics: dict[str, Any]) -> dict[str, Any]:
    out = {}
    for key, value in metrics.items():
        if isinstance(value, (np.floating, float)):
            value = float(value)
            out[key] = value if math.isfinite(value) else None
        elif isinstance(value, (np.integer, np.bool_)):
            out[key] = value.item()
        else:
            out[key] = value
    return out


def run_jobs(
    jobs: list[Job],
    out: Path,
    workers: int,
    backend: str,
    address: str | None,
    progress: bool = True,
) -> list[dict[str, Any]]:
    """Run the jobs that are not finished yet; return the records of all jobs, in job order."""
    from tqdm.auto import tqdm

    for stale in (out / "episodes").rglob(".*.tmp") if (out / "episodes").exists() else ():
        stale.unlink(missing_ok=True)  # temporary files of a run killed mid-write
    records: dict[int, dict[str, Any]] = {}
    todo = []
    for index, job in enumerate(jobs):
        done = finished(job, out)
        if done is not None:
            records[index] = done
        else:
            todo.append(index)
    bar = tqdm(
        total=len(jobs), initial=len(records), desc="episodes", disable=not progress, unit="ep"
    )
    for index, record in _execute([jobs[i] for i in todo], todo, out, workers, backend, address):
        records[index] = record
        bar.update(1)
    bar.close()
    return [records[i] for i in range(len(jobs))]


def _execute(
    jobs: list[Job], indices: list[int], out: Path, workers: int, backend: str, address: str | None
) -> Iterable[tuple[int, dict[str, Any]]]:
    if not jobs:
        return
    if backend == "ray":
        yield from _execute_ray(jobs, indices, out, address)
    elif workers <= 1:
        for index, job in zip(indices, jobs, strict=True):
            yield index, run_job(job, out)
    else:
        # spawn: numba's threading layer is not fork-safe once its threads have started.
        with ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn")) as pool:
            futures = {
                pool.submit(run_job, job, out): index
                for index, job in zip(indices, jobs, strict=True)
            }
            for future in as_completed(futures):
                yield futures[future], future.result()


def _execute_ray(
    jobs: list[Job], indices: list[int], out: Path, address: str | None
) -> Iterable[tuple[int, dict[str, Any]]]:
    try:
        import ray
    except ImportError as exc:
        raise ImportError("--backend ray needs Ray: pip install 'auv-gym[ray]'") from exc
    if not ray.is_initialized():
        ray.init(address=address, log_to_driver=False)
    remote = ray.remote(num_cpus=1)(run_job)
    pending = {remote.remote(job, out): index for index, job in zip(indices, jobs, strict=True)}
    while pending:
        done, _ = ray.wait(list(pending), num_returns=1)
        for ref in done:
            yield pending.pop(ref), ray.get(ref)


def versions() -> dict[str, str]:
    """Versions of Python and the packages that determine the results."""
    found = {"python": platform.python_version()}
    for name in ("auv_gym", "numpy", "numba", "gymnasium", "stable_baselines3", "torch"):
        try:
            found[name] = str(importlib.import_module(name).__version__)
        except ImportError:
            continue
    return found


def write_tables(records: list[dict[str, Any]], out: Path, config: dict[str, Any]) -> str:
    """episodes.csv, episodes.json and summary.md; returns the markdown summary."""
    metric_names = sorted({k for r in records for k in r["metrics"]})
    header = ["scenario", "policy", "seed", *metric_names]

    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(header)
    for r in records:
        writer.writerow(
            [r["scenario"], r["policy"], r["seed"], *(r["metrics"].get(m) for m in metric_names)]
        )
    write_text(out / "episodes.csv", buffer.getvalue())
    payload = {"config": config, "versions": versions(), "episodes": records}
    write_text(out / "episodes.json", json.dumps(payload, indent=1))
    summary = summarise(records, config)
    write_text(out / "summary.md", summary)
    return summary


def aggregate(records: list[dict[str, Any]]) -> dict[tuple[str, str], dict[str, np.ndarray]]:
    """(scenario, policy) → metric → per-seed values (NaN where undefined)."""
    table: dict[tuple[str, str], dict[str, list[float]]] = {}
    for r in records:
        cell = table.setdefault((r["scenario"], r["policy"]), {})
        for metric in SUMMARY_METRICS:
            value = r["metrics"].get(metric)
            cell.setdefault(metric, []).append(np.nan if value is None else float(value))
    return {key: {m: np.asarray(v) for m, v in cell.items()} for key, cell in table.items()}


def summarise(records: list[dict[str, Any]], config: dict[str, Any]) -> str:
    """Markdown: mean ± std of each metric per policy per scenario; the best value in bold."""
    cells = aggregate(records)
    policies = list(dict.fromkeys(r["policy"] for r in records))
    scenarios = list(dict.fromkeys(r["scenario"] for r in records))
    lines = [
        "# Benchmark summary",
        "",
        f"Seeds per cell: {config['seeds']}; duration {config['duration']} s; metrics over "
        f"t ≥ {config['transient']} s where windowed. Mean ± std over seeds (n = finite "
        "values); **bold** marks the best policy per row. Settling times are `inf` when the "
        "distance never stays below the threshold.",
    ]
    for scenario in scenarios:
        lines += [
            "",
            f"## {scenario}",
            "",
            "| metric | " + " | ".join(policies) + " |",
            "|---|" + "---|" * len(policies),
        ]
        for metric, better in SUMMARY_METRICS.items():
            means = []
            texts = []
            for policy in policies:
                values = cells.get((scenario, policy), {}).get(metric, np.array([]))
                finite = values[np.isfinite(values)]
                if values.size and finite.size == 0:
                    means.append(np.inf if better == "min" else -np.inf)
                    texts.append("inf")
                elif finite.size:
                    mean = float(finite.mean())
                    means.append(mean)
                    std = float(finite.std())
                    suffix = f" (n={finite.size})" if finite.size < values.size else ""
                    texts.append(f"{mean:.4g} ± {std:.2g}{suffix}")
                else:
                    means.append(np.nan)
                    texts.append("–")
            finite_means = [m for m in means if not np.isnan(m)]
            if finite_means:
                best = min(finite_means) if better == "min" else max(finite_means)
                texts = [
                    f"**{t}**" if m == best and np.isfinite(m) else t
                    for t, m in zip(texts, means, strict=True)
                ]
            lines.append(f"| {metric} | " + " | ".join(texts) + " |")
    return "\n".join(lines) + "\n"


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0],
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument(
        "--policies",
        default="fbsm,backstepping,ppo",
        help=f"comma-separated: {', '.join(REGISTRY)}, ppo:PATH, module:attribute",
    )
    parser.add_argument("--scenarios", default="all", help="comma-separated names or 'all'")
    parser.add_argument("--scenario-file", type=Path, default=SCENARIOS_FILE,
                        help="TOML file of named scenarios (env keyword arguments)")  # fmt: skip
    parser.add_argument("--seeds", type=int, default=10, help="seeds 0..N-1 per scenario")
    parser.add_argument("--duration", type=float, default=300.0, help="episode length [s]")
    parser.add_argument(
        "--transient",
        type=float,
        default=None,
        help="metrics window start [s]; None: min(100, duration/2)",
    )
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                        help="local worker processes (results do not depend on it)")  # fmt: skip
    parser.add_argument("--backend", choices=("local", "ray"), default="local",
                        help="run the episodes in local processes or on a Ray cluster")  # fmt: skip
    parser.add_argument("--address", default=None, help="Ray cluster address to join")
    parser.add_argument("--out", type=Path, default=Path("out/compare"),
                        help="output folder; a rerun with the same arguments resumes")  # fmt: skip
    parser.add_argument("--no-figures", action="store_true", help="tables only")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    return parser.parse_args(argv)


def main(argv: Sequence[str] | None = None) -> list[dict[str, Any]]:
    args = parse_args(argv)
    scenarios = load_scenarios(args.scenario_file)
    scenario_names = select(args.scenarios, list(scenarios), "scenario")
    policies = [p.strip() for p in args.policies.split(",") if p.strip()]
    for spec in policies:
        check_policy_spec(spec)
    if args.seeds < 1 or not (math.isfinite(args.duration) and args.duration > 0):
        raise ValueError("--seeds must be >= 1 and --duration a positive number of seconds")
    transient = args.transient if args.transient is not None else min(100.0, args.duration / 2)
    jobs = [
        Job(policy, scenarios[name], seed, args.duration, transient)
        for name in scenario_names
        for policy in policies
        for seed in range(args.seeds)
    ]
    config = {
        "policies": policies,
        "scenarios": {n: asdict(scenarios[n]) for n in scenario_names},
        "seeds": args.seeds,
        "duration": args.duration,
        "transient": transient,
        "command": " ".join(
            [
                Path(sys.executable).name,
                "-m",
                "benchmarks.compare",
                *(argv if argv is not None else sys.argv[1:]),
            ]
        ),
    }
    records = run_jobs(
        jobs, args.out, args.workers, args.backend, args.address, progress=not args.quiet
    )
    summary = write_tables(records, args.out, config)
    if not args.no_figures:
        from auv_gym.benchmark_plots import comparison_figures

        comparison_figures(records, args.out, scenarios={n: scenarios[n] for n in scenario_names})
    print(summary)
    return records


if __name__ == "__main__":
    try:
        main()
    except (ValueError, FileNotFoundError) as error:
        raise SystemExit(f"error: {error}") from None
