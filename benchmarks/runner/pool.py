"""One process pool for the benchmark runners: local spawned workers or a Ray cluster.

`execute` maps a module-level function over work items, in completion order, in this process
(one worker), in spawned worker processes that die with the parent, or as Ray tasks. Results do
not depend on the backend or the number of workers: callers pass pure functions of the item.
`check_pool_options` is the one check of ``--workers``, ``--backend`` and ``--address``.
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from multiprocessing import get_context
from pathlib import Path
from typing import Any

__all__ = [
    "BACKENDS",
    "MAX_WORKERS",
    "RAY_PROBE_TIMEOUT_S",
    "check_pool_options",
    "check_ray_address",
    "connect_ray",
    "die_with_parent",
    "execute",
    "parallel_map",
]

BACKENDS = ("local", "ray")
MAX_WORKERS = 1024  # local worker processes of one command
PR_SET_PDEATHSIG = 1  # linux/prctl.h
RAY_PROBE_TIMEOUT_S = 10.0  # [s] deadline of the handshake with a Ray cluster
# One cheap RPC each that only a Ray server answers: the GCS of a cluster (HOST:PORT) returns its
# cluster id; a Ray Client server (ray://HOST:PORT) answers a ping (ClusterInfoType PING = 6).
RAY_GCS_METHOD = "/ray.rpc.NodeInfoGcsService/GetClusterId"
RAY_CLIENT_METHOD = "/ray.rpc.RayletDriver/ClusterInfo"
RAY_CLIENT_PING = b"\x08\x06"


def check_pool_options(workers: int, backend: str = "local", address: str | None = None) -> None:
    """ValueError naming the option: ``--workers`` outside [1, `MAX_WORKERS`], an unknown
    ``--backend``, ``--address`` without Ray, Ray not installed, Ray without a cluster to join
    (no ``--address``, no ``RAY_ADDRESS`` and no ``ray.init`` of the caller's: a local cluster
    started here would listen on every interface, docs/usage.md "Ray"), or a Ray address no
    Ray server answers (`check_ray_address`)."""
    if not 1 <= workers <= MAX_WORKERS:
        raise ValueError(f"--workers must be an integer in [1, {MAX_WORKERS}], got {workers}")
    if backend not in BACKENDS:
        raise ValueError(f"--backend must be one of {list(BACKENDS)}, got {backend!r}")
    if address is not None and backend != "ray":
        raise ValueError("--address needs --backend ray")
    if backend == "ray":
        try:
            import ray
        except ImportError:
            raise ValueError("--backend ray needs Ray: pip install 'auv-gym[ray]'") from None
        if ray.is_initialized():  # the caller's own ray.init: its cluster
            return
        if address is None and not os.environ.get("RAY_ADDRESS"):
            raise ValueError(
                "--backend ray needs --address HOST:PORT (or auto) of a Ray cluster you started "
                "(e.g. ray start --head --node-ip-address 127.0.0.1): auv-gym starts no cluster "
                "of its own, whose servers would listen on every network interface; for this "
                "machine's cores use --backend local"
            )
        check_ray_address(address)  # ray.init would retry an unreachable address for ever


def execute(
    function: Callable[[Any, Path], Any],
    items: Sequence[Any],
    indices: Sequence[int],
    out: Path,
    workers: int,
    backend: str = "local",
    address: str | None = None,
) -> Iterable[tuple[int, Any]]:
    """(index, ``function(item, out)``) for every item, in completion order, on ``backend``:
    "local" (`parallel_map`) or "ray" (one task of one CPU per item)."""
    if not items:
        return
    if backend == "ray":
        yield from ray_map(function, items, indices, out, address)
    else:
        yield from parallel_map(function, items, indices, out, workers)


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


def connect_ray(address: str | None, **init_kwargs: Any) -> Any:
    """The ray module, connected: to ``address`` after its handshake (`check_ray_address`;
    ``ray.init`` retries an unreachable address for ever), or as it already is."""
    try:
        import ray
    except ImportError as exc:
        raise ImportError("--backend ray needs Ray: pip install 'auv-gym[ray]'") from exc
    if not ray.is_initialized():
        check_ray_address(address)
        ray.init(address=address, log_to_driver=False, **init_kwargs)
    return ray


def ray_map(
    function: Callable[[Any, Path], Any],
    items: Sequence[Any],
    indices: Sequence[int],
    out: Path,
    address: str | None,
) -> Iterable[tuple[int, Any]]:
    """`parallel_map` as Ray tasks of one CPU each, on the cluster at ``address``."""
    ray = connect_ray(address)
    remote = ray.remote(num_cpus=1)(function)
    pending = {remote.remote(item, out): index for index, item in zip(indices, items, strict=True)}
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
