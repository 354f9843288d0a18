"""The suite's unit of work: one chunk (policy, run, task set) of batched episodes, its
fingerprint and record (`benchmarks.runner.cache`), the policies and runs of ``--policies``, and
the episodes.csv rows of the records (`benchmarks.runner.evaluate_suite`)."""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from auv_gym import VARIANTS
from auv_gym.rollout import evaluate
from auv_gym.support.files import json_default, write_json
from benchmarks.catalog.policies import (
    PolicySpec,
    agent_run,
    build_policy,
    check_policy_spec,
    policy_env,
    policy_label,
)
from benchmarks.catalog.tasks import TaskSet
from benchmarks.runner.jobs import agent_digest, code_digest, vehicle_digest
from benchmarks.training.checkpoints import SEED_AGENT_PREFIX
from controllers.ensemble import ENSEMBLE_FILE

__all__ = [
    "CHUNKS",
    "COLUMNS",
    "METRICS",
    "Chunk",
    "Run",
    "SuitePolicy",
    "episodes_csv",
    "resolve_policy",
    "run_chunk",
]

CHUNKS = "chunks"  # OUT/chunks/<policy>/run_<k>/<set>.json
AGENT_SEED = re.compile(
    re.escape(SEED_AGENT_PREFIX) + r"(\d+)"
)  # DIR/agent_seed_<k>/ (train_seeds)
# episodes.csv metric column → key of `auv_gym.metrics.compute_metrics` (units: m, m/s, -, 1/s, s).
METRICS = {
    "rms_distance": "rms_distance",
    "rms_x_e": "rms_x_e",
    "rms_y_e": "rms_y_e",
    "rms_z_e": "rms_z_e",
    "max_distance": "max_distance_window",
    "max_surge": "max_surge",
    "overspeed_fraction": "overspeed_fraction",
    "mean_path_speed": "mean_path_speed",  # [m/s] the pace u_p at which the path is flown
    "chattering": "chattering",  # [1/s]
    "saturation_fraction": "saturation_fraction",
    "max_roll": "max_roll",  # [rad] the 6-DOF plant's; NaN on the 5-DOF, which has no roll
    "termination_reason": "termination_reason",
    "window_samples": "window_samples",
    "duration": "duration",
}
COLUMNS = ("policy", "run", "set", "seed", "env_id", *METRICS)


@dataclass(frozen=True)
class Run:
    """One run of a policy: the training seed of an agent (0 for a controller), its env id."""

    run: int
    env_id: str
    spec: str  # what `benchmarks.catalog.policies.build_policy` builds: a name or "agent:<dir>"
    # An agent's own env arguments (its observation) beyond the id's; never part of the hash.
    agent_env: dict[str, Any] = field(default_factory=dict, hash=False, compare=False)


@dataclass(frozen=True)
class SuitePolicy:
    """A policy of the suite with its runs; ``results``: a multi-seed results directory."""

    name: str
    kind: str  # "classical", "agent", "onnx" or "import"
    runs: tuple[Run, ...]
    results: str | None = None


@dataclass(frozen=True)
class Chunk:
    """The episodes of one task set for one run of one policy."""

    policy: str
    run: Run
    task: TaskSet
    duration: float  # [s]
    transient: float  # [s] metrics window start

    @property
    def env_kwargs(self) -> dict[str, Any]:
        return {
            **VARIANTS[self.run.env_id],
            **self.run.agent_env,
            **self.task.env,
            "max_time": self.duration,
        }

    def fingerprint(self) -> str:
        """Hash of everything that determines the chunk's episodes."""
        parsed = PolicySpec.parse(self.run.spec)
        payload = {
            "policy": "agent" if parsed.agent is not None else self.run.spec,
            "agent": agent_digest(parsed.files),
            "env": self.env_kwargs,
            "vehicle": vehicle_digest(self.env_kwargs.get("vehicle")),  # its values, not its path
            "controller": self.task.controller if parsed.agent is None else {},
            "seeds": [self.task.seeds.start, self.task.seeds.stop],
            "transient": self.transient,
            "code": code_digest(),
        }
        text = json.dumps(payload, sort_keys=True, default=json_default)
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def path(self, out: Path) -> Path:
        run = f"run_{self.run.run}"
        return (
            out / CHUNKS / policy_label(self.policy) / run / f"{policy_label(self.task.name)}.json"
        )

    def record_file(self, out: Path) -> Path:
        """The chunk's record (`benchmarks.runner.cache`): its episodes' metrics."""
        return self.path(out)

    def files(self, out: Path) -> tuple[Path]:
        return (self.path(out),)


def resolve_policy(spec: str) -> SuitePolicy:
    """The policy of one ``--policies`` entry, its agents checked (`controllers.agent.check_agent`);
    ValueError / FileNotFoundError naming the entry otherwise."""
    if "=" not in spec:
        parsed = check_policy_spec(spec)
        if parsed.onnx is not None:  # an export runs in the env its contract records
            env_id, env_kwargs = policy_env(spec)
            return SuitePolicy(spec, "onnx", (Run(0, env_id, spec, env_kwargs),))
        if parsed.agent is None:
            env_id, env_kwargs = policy_env(spec)
            return SuitePolicy(spec, parsed.kind, (Run(0, env_id, spec, env_kwargs),))
        seed, env_id, agent_env = agent_run(f"policy {spec!r}", parsed.agent)
        run = Run(seed, env_id, f"agent:{parsed.agent}", agent_env)
        return SuitePolicy(spec, "agent", (run,))
    name, _, folder = spec.partition("=")
    where = f"--policies {spec!r}"
    if not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.-]*", name):
        raise ValueError(f"{where}: NAME {name!r} must be letters, digits, '_', '.', '-'")
    directory = Path(folder)
    if not folder or not directory.is_dir():
        raise FileNotFoundError(f"{where}: agent directory {folder!r} does not exist")
    if (directory / "model.zip").is_file() or (directory / ENSEMBLE_FILE).is_file():
        seed, env_id, agent_env = agent_run(where, directory)
        return SuitePolicy(name, "agent", (Run(seed, env_id, f"agent:{directory}", agent_env),))
    seeds = sorted(int(m[1]) for p in directory.iterdir() if (m := AGENT_SEED.fullmatch(p.name)))
    if not seeds:
        raise ValueError(
            f"{where}: {folder} holds neither an agent (model.zip) nor agent_seed_<k>/ "
            "folders of a multi-seed results directory"
        )
    runs = []
    for seed in seeds:
        agent = directory / f"{SEED_AGENT_PREFIX}{seed}"
        _, env_id, agent_env = agent_run(where, agent)
        runs.append(Run(seed, env_id, f"agent:{agent}", agent_env))
    return SuitePolicy(name, "agent", tuple(runs), str(directory))


def run_chunk(chunk: Chunk, out: Path) -> dict[str, Any]:
    """Evaluate one chunk (batched, `auv_gym.rollout.evaluate`), store it atomically, return it."""
    start = time.perf_counter()
    env_kwargs = chunk.env_kwargs
    policy = build_policy(chunk.run.spec, env_kwargs, chunk.task.controller)
    results = evaluate(policy, list(chunk.task.seeds), transient=chunk.transient, **env_kwargs)
    record = {
        "policy": chunk.policy,
        "run": chunk.run.run,
        "set": chunk.task.name,
        "env_id": chunk.run.env_id,
        "fingerprint": chunk.fingerprint(),
        "wall_time_s": time.perf_counter() - start,
        "episodes": [
            {"seed": int(r["seed"]), **{col: r.get(key, math.nan) for col, key in METRICS.items()}}
            for r in results
        ],
    }
    write_json(chunk.path(out), record, indent=None)  # atomic: NaN stays NaN
    return record


def episodes_csv(records: list[dict[str, Any]]) -> str:
    """episodes.csv of chunk records: floats as Python's repr (full precision, 'nan')."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(COLUMNS)
    for r in records:
        for e in r["episodes"]:
            writer.writerow(
                [
                    r["policy"],
                    r["run"],
                    r["set"],
                    e["seed"],
                    r["env_id"],
                    # a chunk stored before a metric existed (a resumed suite) has none: NaN
                    *(e.get(m, math.nan) for m in METRICS),
                ]
            )
    return buffer.getvalue()
