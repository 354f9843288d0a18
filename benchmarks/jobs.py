"""Benchmark episodes as jobs: (policy, scenario, seed, duration), fingerprinted, resumable.

An agent's episode runs under the env id its metadata.json records (e.g. AUVPath3DSpeedLimit-v0's
2.0 m/s surge limit, under which a faster agent terminates "overspeed"), everything else under
AUVPath3D-v0; the record says which (``env_id``).

Each finished episode is written atomically to ``OUT/episodes/<scenario>/<policy>/seed_<k>.json``
(metrics) and ``.npz`` (time series) with a fingerprint of everything that determines it, so a
run restarted with the same arguments reuses finished episodes. Results do not depend on the
number of workers or the backend: every episode is a pure function of the job.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import json
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import auv_gym
import controllers
from auv_gym import ENV_ID, VARIANTS
from auv_gym.files import jsonable, remove_temporaries, write_json
from auv_gym.metrics import compute_metrics
from auv_gym.numba_cache import sources_digest
from auv_gym.rollout import rollout
from benchmarks.policies import PolicySpec, build_policy, policy_label
from benchmarks.scenarios import Scenario

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
]

PR_SET_PDEATHSIG = 1  # linux/prctl.h
RAY_PROBE_TIMEOUT_S = 10.0  # [s] deadline of the handshake with a Ray cluster
# One cheap RPC each that only a Ray server answers: the GCS of a cluster (HOST:PORT) returns its
# cluster id; a Ray Client server (ray://HOST:PORT) answers a ping (ClusterInfoType PING = 6).
RAY_GCS_METHOD = "/ray.rpc.NodeInfoGcsService/GetClusterId"
RAY_CLIENT_METHOD = "/ray.rpc.RayletDriver/ClusterInfo"
RAY_CLIENT_PING = b"\x08\x06"


@dataclass(frozen=True)
class Job:
    """One episode: a policy on a scenario with a seed, for `duration` seconds."""

    policy: str
    scenario: Scenario
    seed: int
    duration: float
    transient: float
    env_id: str = ENV_ID  # an agent's training env (`benchmarks.policies.policy_env_id`)

    @property
    def env_kwargs(self) -> dict[str, Any]:
        """The env: the env id's fixed arguments, the scenario's, the duration [s]."""
        return {**VARIANTS[self.env_id], **self.scenario.env, "max_time": self.duration}

    def fingerprint(self) -> str:
        """Hash of everything that determines the episode: the job, the agent file if any, and
        the source code of `auv_gym` and `controllers`."""
        payload = {
            "policy": self.policy,
            "scenario": asdict(self.scenario),
            "seed": self.seed,
            "duration": self.duration,
            "transient": self.transient,
            "agent": agent_digest(PolicySpec.parse(self.policy).agent),
            "code": code_digest(),
        }
        if self.env_id != ENV_ID:  # the default keeps the fingerprints of earlier runs
            payload["env_id"] = self.env_id
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


def agent_digest(agent: Path | None) -> str:
    """Hash of an agent's files (a directory's, sorted by path, or one model zip); "" for None."""
    if agent is None:
        return ""
    digest = hashlib.sha256()
    for file in sorted(p for p in agent.rglob("*") if p.is_file()) if agent.is_dir() else [agent]:
        digest.update(file.read_bytes())
    return digest.hexdigest()[:16]


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
    """Run one episode, store its time series and metrics atomically, return the record.

    Non-finite metrics (a settling time never reached, a window never entered) are stored as
    null.
    """
    start = time.perf_counter()
    control_dt = float(job.env_kwargs.get("control_dt", 0.05))
    policy = build_policy(job.policy, control_dt, job.scenario.controller)
    trajectory = rollout(policy, job.seed, **job.env_kwargs)
    metrics = compute_metrics(trajectory, transient=job.transient)
    record = {
        "policy": job.policy,
        "scenario": job.scenario.name,
        "env_id": job.env_id,
        "seed": job.seed,
        "duration": job.duration,
        "transient": job.transient,
        "fingerprint": job.fingerprint(),
        "wall_time_s": time.perf_counter() - start,
        "metrics": jsonable(metrics),
        "trajectory": str(job.path(out).with_suffix(".npz").relative_to(out)),
    }
    base = job.path(out)
    trajectory.save(base.with_suffix(".npz"))  # atomic
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
    """Run the jobs that are not finished yet; return the records of all jobs, in job order."""
    from tqdm.auto import tqdm

    remove_temporaries(out / "episodes")  # of a run killed mid-write (callers hold the folder)
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
    else:
        yield from parallel_map(run_job, jobs, indices, out, workers)


def parallel_map(
    function: Callable[[Any, Path], Any],
    items: Sequence[Any],
    indices: Sequence[int],
    out: Path,
    workers: int,
) -> Iterable[tuple[int, Any]]:
    """(index, ``function(item, out)``) for every item, in completion order: in this process
    for ``workers`` <= 1, else in that many spawned worker processes that die with this one.
    ``function`` must be a module-level (picklable) function."""
    if workers <= 1:
        for index, item in zip(indices, items, strict=True):
            yield index, function(item, out)
        return
    # spawn: numba's threading layer is not fork-safe once its threads have started.
    with ProcessPoolExecutor(
        max_workers=workers,
        mp_context=get_context("spawn"),
        initializer=die_with_parent,
        initargs=(os.getpid(),),
    ) as pool:
        futures = {
            pool.submit(function, item, out): index
            for index, item in zip(indices, items, strict=True)
        }
        for future in as_completed(futures):
            yield futures[future], future.result()


def die_with_parent(parent_pid: int) -> None:
    """Worker initializer: end this process when the parent ends, even by SIGKILL (which runs
    no clean-up in the parent). Linux: the kernel sends SIGKILL on the parent's death
    (prctl PR_SET_PDEATHSIG); elsewhere a daemon thread polls the parent's pid every 0.5 s."""
    if sys.platform.startswith("linux"):
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) != 0:
            raise OSError(ctypes.get_errno(), "prctl(PR_SET_PDEATHSIG) failed")
    else:

        def watch() -> None:
            while os.getppid() == parent_pid:
                time.sleep(0.5)
            os._exit(1)

        threading.Thread(target=watch, name="parent-watchdog", daemon=True).start()
    if os.getppid() != parent_pid:  # the parent died before the signal was armed
        os._exit(1)


def _execute_ray(
    jobs: list[Job], indices: list[int], out: Path, address: str | None
) -> Iterable[tuple[int, dict[str, Any]]]:
    try:
        import ray
    except ImportError as exc:
        raise ImportError("--backend ray needs Ray: pip install 'auv-gym[ray]'") from exc
    if not ray.is_initialized():
        check_ray_address(address)  # ray.init retries an unreachable address for ever
        ray.init(address=address, log_to_driver=False)
    remote = ray.remote(num_cpus=1)(run_job)
    pending = {remote.remote(job, out): index for index, job in zip(indices, jobs, strict=True)}
    while pending:
        done, _ = ray.wait(list(pending), num_returns=1)
        for ref in done:
            yield pending.pop(ref), ray.get(ref)


def _ray_target(address: str | None) -> str | None:
    """The address ``ray.init(address=address)`` would connect to (None: it starts a local
    instance): ``RAY_ADDRESS`` and, for None and "auto", the cluster ``ray start`` recorded."""
    if address == "local":
        return None
    if address is None or address == "auto":
        try:
            from ray._private.services import get_ray_address_from_environment
        except ImportError:  # Ray moved it: the environment variable is the documented way
            return os.environ.get("RAY_ADDRESS") or (None if address is None else "auto")
        try:
            return get_ray_address_from_environment(address, None)
        except ConnectionError as error:  # "auto" and no running cluster
            raise ValueError(f"--address {address!r}: {error}") from None
    return address


def _ray_token() -> tuple[tuple[str, str], ...]:
    """The token header Ray itself sends to a cluster with token authentication (none when
    this machine has no token, or this Ray has no token authentication)."""
    try:
        from ray._raylet import AuthenticationTokenLoader

        loader = AuthenticationTokenLoader.instance()
        if not loader.has_token(ignore_auth_mode=True):
            return ()
        return tuple(loader.get_token_for_http_header().items())
    except (ImportError, AttributeError, RuntimeError, TypeError):
        return ()


def check_ray_address(address: str | None, timeout_s: float | None = None) -> None:
    """Refuse a Ray address that no Ray server answers within ``timeout_s`` [s] (None:
    `RAY_PROBE_TIMEOUT_S`).

    ``ray.init`` retries an unreachable cluster for ever, and a TCP connection proves only that
    something listens; so this makes one Ray RPC over gRPC with a deadline: the cluster id from
    the GCS of ``HOST:PORT``, a ping to the Ray Client server of ``ray://HOST:PORT``. None,
    "auto" and "local" are resolved as Ray resolves them (``RAY_ADDRESS``, the cluster of
    ``ray start``); a new local instance needs no probe. ValueError naming the address, one
    line, otherwise.
    """
    target = _ray_target(address)
    if target is None:
        return
    timeout_s = RAY_PROBE_TIMEOUT_S if timeout_s is None else timeout_s
    name = f"--address {address!r}" if target == address else f"--address {address!r} ({target})"
    client = target.startswith("ray://")
    host_port = target.split("://", 1)[1] if "://" in target else target
    host, _, port = host_port.rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"{name} is not HOST:PORT or ray://HOST:PORT")
    import grpc  # a dependency of Ray

    channel = grpc.insecure_channel(host_port, options=[("grpc.enable_http_proxy", 0)])
    try:
        rpc = channel.unary_unary(RAY_CLIENT_METHOD if client else RAY_GCS_METHOD)
        rpc(RAY_CLIENT_PING if client else b"", timeout=timeout_s, metadata=_ray_token())
    except grpc.RpcError as error:
        code = error.code()
        if code == grpc.StatusCode.DEADLINE_EXCEEDED:
            reason = f"no answer within {timeout_s:g} s"
        elif code == grpc.StatusCode.UNAUTHENTICATED:
            reason = "Ray refused this machine's token: set RAY_AUTH_TOKEN to the cluster's"
        elif code == grpc.StatusCode.UNIMPLEMENTED:
            reason = "the server there is not a Ray " + ("client server" if client else "GCS")
        else:
            details = (error.details() or "").splitlines()
            reason = f"{code.name.lower()}: {details[0] if details else 'no details'}"
        what = "Ray client server" if client else "Ray cluster (GCS)"
        raise ValueError(f"{name}: no {what} answered the handshake ({reason})") from None
    finally:
        channel.close()
