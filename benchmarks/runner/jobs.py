"""Benchmark episodes as jobs: (policy, scenario, seed, duration), fingerprinted, resumable.

An agent's episode runs under the env id its metadata.json records (e.g. AUVPath3DSpeedLimit-v0's
2.0 m/s surge limit, under which a faster agent terminates "overspeed"), everything else under
AUVPath3D-v0; the record says which (``env_id``).

Each finished episode is written atomically to ``OUT/episodes/<scenario>/<policy>/seed_<k>.json``
(metrics) with a fingerprint of everything that determines it, so a run restarted with the same
arguments reuses finished episodes (the vehicle enters by the values its file holds, not its path,
so an edited vehicle file reruns its episodes: `vehicle_digest`); a job that keeps its time
series (``keep_trajectory``) also writes ``seed_<k>.npz``, 0.7–0.9 MB for 150 s of a helix,
already deflate-compressed (float64 samples of a noisy ocean: LZMA saves 16 %, byte shuffling and
deltas 29 %), so `compare` keeps the series its figures draw, the first seed's, unless asked for
all. Results do not depend on the number of workers or the backend: every episode is a pure
function of the job.
"""

from __future__ import annotations

import functools
import hashlib
import json
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import auv_gym
import controllers
from auv_gym import ENV_ID, VARIANTS
from auv_gym.metrics import compute_metrics
from auv_gym.rollout import rollout
from auv_gym.support.files import jsonable, write_json
from auv_gym.support.numba_cache import sources_digest
from auv_gym.vehicle.record import Vehicle, load_vehicle, vehicle_file, vehicle_from_bytes
from benchmarks.catalog.policies import PolicySpec, build_policy, policy_label
from benchmarks.catalog.scenarios import Scenario
from benchmarks.runner.cache import run_resumable, stored_record

# The pool functions lived here first; they stay importable from this module.
from benchmarks.runner.pool import (
    RAY_PROBE_TIMEOUT_S,
    check_ray_address,
    die_with_parent,
    parallel_map,
)
from controllers.ensemble import ensemble_members

__all__ = [
    "RAY_PROBE_TIMEOUT_S",
    "Job",
    "agent_digest",
    "check_ray_address",
    "code_digest",
    "die_with_parent",
    "finished",
    "parallel_map",
    "run_job",
    "run_jobs",
    "vehicle_digest",
]


@dataclass(frozen=True)
class Job:
    """One episode: a policy on a scenario with a seed, for `duration` seconds."""

    policy: str
    scenario: Scenario
    seed: int
    duration: float
    transient: float
    env_id: str = ENV_ID  # an agent's training env (`benchmarks.catalog.policies.policy_env`)
    # An agent's own env arguments (its observation) beyond the id's; never part of the hash.
    agent_env: dict[str, Any] = field(default_factory=dict, hash=False, compare=False)
    # Whether the episode's time series (.npz) is stored beside its record; not part of the
    # fingerprint (the episode is the same): a record without one is rerun when one is wanted.
    keep_trajectory: bool = field(default=True, compare=False)

    @property
    def env_kwargs(self) -> dict[str, Any]:
        """The env: the env id's fixed arguments, the agent's, the scenario's, the duration [s]."""
        return {
            **VARIANTS[self.env_id],
            **self.agent_env,
            **self.scenario.env,
            "max_time": self.duration,
        }

    def fingerprint(self) -> str:
        """Hash of everything that determines the episode: the job, the agent file if any, the
        values of the vehicle flown (`vehicle_digest`: a shipped file's or a user's, read now;
        not its path) and the source code of `auv_gym` and `controllers`."""
        scenario = asdict(self.scenario)
        if isinstance(scenario["env"].get("vehicle"), (str, Path)):  # a name or a file's path
            del scenario["env"]["vehicle"]  # its values are "vehicle": not where the file lies
        payload = {
            "policy": self.policy,
            "scenario": scenario,
            "vehicle": self.vehicle_digest(),
            "seed": self.seed,
            "duration": self.duration,
            "transient": self.transient,
            "agent": agent_digest(PolicySpec.parse(self.policy).files),
            "code": code_digest(),
        }
        if self.env_id != ENV_ID:  # the default keeps the fingerprints of earlier runs
            payload["env_id"] = self.env_id
        if self.agent_env:
            payload["agent_env"] = self.agent_env
        return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:16]

    def vehicle_digest(self) -> str:
        """Hash of the values of the vehicle the episode flies (`vehicle_digest`)."""
        return vehicle_digest(self.env_kwargs.get("vehicle"))

    def path(self, out: Path) -> Path:
        return (
            out / "episodes" / self.scenario.name / policy_label(self.policy) / f"seed_{self.seed}"
        )

    def record_file(self, out: Path) -> Path:
        """The episode's metrics record (`benchmarks.runner.cache`)."""
        return self.path(out).with_suffix(".json")

    def files(self, out: Path) -> tuple[Path, ...]:
        """Everything the episode writes: its record and, if kept, its time series (.npz)."""
        if not self.keep_trajectory:
            return (self.record_file(out),)
        return self.record_file(out), self.path(out).with_suffix(".npz")


@functools.cache
def code_digest() -> str:
    """Hash of the simulator and controller sources: a code change invalidates cached episodes."""
    packages = (Path(auv_gym.__file__).parent, Path(controllers.__file__).parent)
    return sources_digest(*packages)[:16]


def agent_digest(agent: Path | None) -> str:
    """Hash of an agent's files (a directory's, sorted by path, one model zip, an exported
    .onnx file with its contract, or an ensemble's list and its members' files); "" for
    None."""
    if agent is None:
        return ""
    digest = hashlib.sha256()
    members = ensemble_members(agent) if agent.is_dir() else None
    for member in members or ():
        digest.update(agent_digest(member).encode())
    if agent.is_dir():
        files = sorted(p for p in agent.rglob("*") if p.is_file())
    elif agent.suffix == ".onnx":
        files = [agent, agent.with_suffix(".json")]
    else:
        files = [agent]
    for file in files:
        digest.update(file.read_bytes())
    return digest.hexdigest()[:16]


# What a `Vehicle` says about itself but the simulator never reads: the file it came from, its
# description and literature. Every other field (name, limits, models, fins, sensors) enters.
_VEHICLE_PROSE = ("source", "description", "sources")


def vehicle_digest(vehicle: Any) -> str:
    """Hash of the values of the vehicle an env's ``vehicle`` argument names (None: the REMUS 100;
    a shipped vehicle's name, a ``.toml`` file, a mapping or a `Vehicle`) as `load_vehicle`
    builds it from the file's content now: an edited value changes it, the file's path, comments,
    description and layout do not. The shipped files are data, not the sources `code_digest`
    hashes, so an edit of ``auv_gym/vehicle/data/torpedo.toml`` shows here. Raises as
    `load_vehicle` does for a file that cannot be read or describes no vehicle."""
    file = vehicle_file(vehicle)
    try:
        text = None if file is None else file.read_bytes()
    except OSError:
        text = None
    if text is None:  # a mapping, a `Vehicle`, or a name or file `load_vehicle` refuses (raises)
        return _values_digest(load_vehicle(vehicle))
    return _file_digest(text, str(file))


@functools.lru_cache(maxsize=32)
def _file_digest(text: bytes, where: str) -> str:
    """`vehicle_digest` of a vehicle file's content (read and checked once per process)."""
    return _values_digest(vehicle_from_bytes(text, where))


def _values_digest(vehicle: Vehicle) -> str:
    values = {k: v for k, v in asdict(vehicle).items() if k not in _VEHICLE_PROSE}
    text = json.dumps(jsonable(values, non_finite="text"), sort_keys=True, default=_array)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _array(value: Any) -> Any:
    if hasattr(value, "tolist"):  # a numpy array of a record
        return value.tolist()
    raise TypeError(f"a vehicle's field of type {type(value).__name__} cannot be hashed")


def finished(job: Job, out: Path) -> dict[str, Any] | None:
    """The stored record of a finished episode with a matching fingerprint, else None."""
    return stored_record(job, out)


def run_job(job: Job, out: Path) -> dict[str, Any]:
    """Run one episode, store its metrics (and its time series if the job keeps it) atomically,
    return the record ("trajectory": the .npz relative to ``out``, or None).

    Non-finite metrics (a settling time never reached, a window never entered) are stored as
    null.
    """
    start = time.perf_counter()
    # Before the episode reads its vehicle file: an edit while it runs leaves a stale fingerprint.
    fingerprint, vehicle = job.fingerprint(), job.vehicle_digest()
    policy = build_policy(job.policy, job.env_kwargs, job.scenario.controller)
    trajectory = rollout(policy, job.seed, **job.env_kwargs)
    metrics = compute_metrics(trajectory, transient=job.transient)
    record = {
        "policy": job.policy,
        "scenario": job.scenario.name,
        "env_id": job.env_id,
        "seed": job.seed,
        "duration": job.duration,
        "transient": job.transient,
        "fingerprint": fingerprint,
        "vehicle_digest": vehicle,  # the values of the vehicle flown (not its path)
        "wall_time_s": time.perf_counter() - start,
        "metrics": jsonable(metrics),
        "trajectory": (
            str(job.path(out).with_suffix(".npz").relative_to(out)) if job.keep_trajectory else None
        ),
    }
    base = job.path(out)
    if job.keep_trajectory:
        trajectory.save(base.with_suffix(".npz"))  # atomic
    else:  # a series of an earlier run of other code would sit beside this record unowned
        base.with_suffix(".npz").unlink(missing_ok=True)
    write_json(base.with_suffix(".json"), record, indent=None)
    return record


def run_jobs(
    jobs: list[Job],
    out: Path,
    workers: int,
    backend: str,
    address: str | None,
    progress: bool = True,
) -> list[dict[str, Any]]:
    """Run the jobs that are not finished yet; return the records of all jobs, in job order
    (`benchmarks.runner.cache.run_resumable` on the pool of `benchmarks.runner.pool`)."""
    return run_resumable(
        jobs,
        out,
        out / "episodes",
        run_job,
        workers=workers,
        backend=backend,
        address=address,
        progress=progress,
        desc="episodes",
    )
