"""The training environments of one run (`benchmarks.training.train`): the SB3 VecEnv (native
batched, one per plant concatenated for a plant share, a residual agent's wrapped env, or SB3's
DummyVecEnv), the thread limit of a run, and the zeroed last layer that makes an untrained
residual agent its base controller."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import Any

from auv_gym import ENV_ID, VARIANTS
from benchmarks.training.evaluation import TRAIN_SEED_BASE
from benchmarks.training.residual import ResidualTraining
from benchmarks.training.vehicle_share import VehicleShare

__all__ = ["describe_env", "make_training_env", "thread_limit", "zero_correction_layer"]


@contextlib.contextmanager
def thread_limit(threads: int) -> Iterator[None]:
    """torch's intra-op, numba's and numpy's BLAS threads set to ``threads`` inside the block,
    restored after.

    One thread is the default: on a machine shared with other jobs, multi-threaded kernels
    stall at their barriers (docs/design.md §4). The BLAS limit matters at resets: a drawn
    spline of up to 128 waypoints takes its coefficients from `numpy.linalg.solve`, whose
    OpenBLAS threads spin on a busy machine (a 161-waypoint spline: 20 ms on one thread, 136 ms
    on two beside five training processes); longer ones from a BLAS-free solve
    (`auv_gym.paths.cubic`).
    """
    import numba
    import torch
    from threadpoolctl import threadpool_limits

    torch_before, numba_before = torch.get_num_threads(), numba.get_num_threads()
    torch.set_num_threads(int(threads))
    numba.set_num_threads(min(int(threads), numba.config.NUMBA_NUM_THREADS))
    try:
        with threadpool_limits(limits=int(threads), user_api="blas"):
            yield
    finally:
        # numba's OpenMP layer may share torch's libgomp: numba first, so that torch's count
        # is the one left (the other order handed torch numba's count).
        numba.set_num_threads(numba_before)
        torch.set_num_threads(torch_before)


def make_training_env(
    n_envs: int,
    seed: int,
    env_kwargs: dict[str, Any],
    kind: str = "auto",
    env_id: str = ENV_ID,
    residual: ResidualTraining | None = None,
    threads: int | None = None,
    vehicle_share: VehicleShare | None = None,
) -> Any:
    """An SB3 VecEnv of `n_envs` training environments.

    "native": `auv_gym.envs.sb3` over the batched `AUVPath3DVectorEnv` (one compiled call per step);
    "dummy": SB3's DummyVecEnv over `gym.make`; "auto": native when available. The native env
    simulates every id of `auv_gym.VARIANTS` (its fixed keyword arguments, then `env_kwargs`).
    With ``residual`` the native env is wrapped in
    `benchmarks.training.residual_env.ResidualVectorEnv` (the residual agent's observation,
    action and chattering charge; native only).
    ``threads``: numba threads of the native env's kernel (1: the serial kernel at every N;
    None: `AUVPath3DVectorEnv`'s default).
    ``vehicle_share`` (native only): one native env per plant or actuator
    (`VehicleShare.vehicles`), the section's own first, concatenated
    (`benchmarks.training.plant_mix.ConcatVecEnv`); vehicle i keeps the env seed of vehicle i.
    With ``residual`` each part is its own `ResidualVectorEnv`, whose base flies that part's
    actuator (a base knows no plant: it flies the 6-DOF hull as it would in evaluation).
    """
    if kind not in ("auto", "native", "dummy"):
        raise ValueError(f"vec_env must be 'auto', 'native' or 'dummy', got {kind!r}")
    env_seed = TRAIN_SEED_BASE + 1000 * int(seed)
    if residual is not None and not (kind in ("auto", "native") and env_id in VARIANTS):
        raise ValueError(
            f"a residual agent trains on the native vector env of "
            f"{sorted(VARIANTS)}, not vec_env={kind!r} / {env_id}"
        )
    if vehicle_share is not None and not (kind in ("auto", "native") and env_id in VARIANTS):
        raise ValueError(
            f"{vehicle_share.key} needs the native vector env of {sorted(VARIANTS)}, not "
            f"vec_env={kind!r} / {env_id}"
        )
    if kind in ("auto", "native") and env_id in VARIANTS:
        from stable_baselines3.common.vec_env import VecMonitor

        from auv_gym.envs.sb3 import make_sb3_vec_env

        kwargs = {**VARIANTS[env_id], **env_kwargs}
        if residual is not None:
            from benchmarks.training.residual_env import make_residual_sb3_env

            def make_part(count: int, **part_kwargs: Any) -> Any:
                return make_residual_sb3_env(count, residual, threads=threads, **part_kwargs)
        else:

            def make_part(count: int, **part_kwargs: Any) -> Any:
                # SB3 and VecMonitor read no other info key: skip the per-vehicle copies.
                return make_sb3_vec_env(count, threads=threads, infos="minimal", **part_kwargs)

        if vehicle_share is not None:
            from benchmarks.training.plant_mix import ConcatVecEnv

            parts = [
                make_part(count, **{**kwargs, vehicle_share.argument: value})
                for value, count in vehicle_share.vehicles(n_envs)
            ]
            venv = ConcatVecEnv(parts)
            venv.seed(env_seed)
            return VecMonitor(venv)
        venv = make_part(n_envs, **kwargs)
        venv.seed(env_seed)
        return VecMonitor(venv)
    if kind == "native":
        raise ValueError(f"the native vector env simulates {sorted(VARIANTS)} only, not {env_id}")
    from stable_baselines3.common.env_util import make_vec_env

    return make_vec_env(env_id, n_envs=n_envs, seed=env_seed, env_kwargs=env_kwargs)


def zero_correction_layer(model: Any) -> None:
    """Zero the last layer of the actor's mean (PPO ``action_net``, SAC ``actor.mu``): the
    untrained residual agent's deterministic correction is exactly 0, so it starts at the base
    controller's performance; exploration comes from the policy's std (``log_std_init``)."""
    policy = model.policy
    layer = getattr(policy, "action_net", None)
    if layer is None:
        layer = getattr(getattr(policy, "actor", None), "mu", None)
    if layer is None or not hasattr(layer, "weight"):
        raise ValueError(f"cannot find the actor's last layer of {type(policy).__name__}")
    import torch

    with torch.no_grad():
        layer.weight.zero_()
        layer.bias.zero_()


def describe_env(venv: Any) -> str:
    """The chain of VecEnv wrappers, outermost first ("VecNormalize<VecMonitor<SB3VecEnv>>"); a
    concatenation lists its parts with their vehicles ("ConcatVecEnv[24×SB3VecEnv<...>, ...]")."""
    from benchmarks.training.plant_mix import ConcatVecEnv

    names = []
    while venv is not None:
        names.append(type(venv).__name__)
        if isinstance(venv, ConcatVecEnv):
            parts = (f"{part.num_envs}×{describe_env(part)}" for part in venv.envs)
            names[-1] += f"[{', '.join(parts)}]"
        venv = getattr(venv, "venv", None)
    return "<".join(names) + ">" * (len(names) - 1)
