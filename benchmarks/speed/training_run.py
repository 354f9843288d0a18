"""`measure`: one timed PPO run of `benchmarks.speed.training`, in the tree on ``PYTHONPATH``.

The benchmark runs this file with `runpy.run_path` in a fresh interpreter per tree, the
current one and a baseline commit's, so it imports nothing of the project at module level:
only what every version of the harness has, inside `measure`.
"""

from __future__ import annotations

import importlib
import inspect
import os
import time
from pathlib import Path
from typing import Any

CONFIG = Path(__file__).resolve().parent / "training_workload.yml"  # this tree's, for both
ENV_ID = "AUVPath3DSpeedLimit-v0"
LEGACY_ENV_ID = "AUVPath3D-v1"  # the same env's id in trees before the rename


def measure(spec: dict[str, Any]) -> dict[str, Any]:
    """Time PPO on the importable tree's trainer (run in a subprocess per tree).

    ``spec``: n_envs, n_steps, batch_size, n_epochs, rollouts, warmup, update_threads,
    update_dtype, net_arch (empty: the configuration's networks), seed. Uses only what every
    version of the harness has (`read_zoo_config`, `make_training_env`, `thread_limit`), so
    the same function times old and new code; the bfloat16 update (``update_dtype``:
    `PPO.train` under `torch.autocast`) is applied here, so it times either tree's learner in
    that precision.
    """
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    import auv_gym
    from benchmarks.training.config import read_zoo_config

    trainer = importlib.import_module("benchmarks.training.train")  # the package hides the name
    env_id = ENV_ID if ENV_ID in auv_gym.VARIANTS else LEGACY_ENV_ID  # the tree's name for it
    cfg = read_zoo_config(CONFIG, env_id, "ppo")
    n_envs, n_steps = int(spec["n_envs"]), int(spec["n_steps"])
    bfloat16 = spec.get("update_dtype", "float32") == "bfloat16"
    phases: list[tuple[float, float, float]] = []  # (start, collected, updated) per rollout

    class TimedPPO(PPO):
        """PPO that stamps the start of each rollout, its end and the end of its update."""

        def collect_rollouts(self, *args: Any, **kwargs: Any) -> bool:
            start = time.perf_counter()
            more = super().collect_rollouts(*args, **kwargs)
            phases.append((start, time.perf_counter(), float("nan")))
            return more

        def train(self) -> None:
            threads = torch.get_num_threads()
            torch.set_num_threads(int(spec["update_threads"]))
            try:
                with torch.autocast("cpu", dtype=torch.bfloat16, enabled=bfloat16):
                    super().train()
            finally:
                torch.set_num_threads(threads)
            start, collected, _ = phases[-1]
            phases[-1] = (start, collected, time.perf_counter())

    with trainer.thread_limit(1):
        # As `train._train` with threads=1 builds it: the trees that can pass the kernel's
        # thread count to the env pass 1 (the serial kernel at every N).
        serial = "threads" in inspect.signature(trainer.make_training_env).parameters
        venv = trainer.make_training_env(
            n_envs,
            int(spec["seed"]),
            cfg.env_kwargs,
            "auto",
            env_id,
            **({"threads": 1} if serial else {}),
        )
        venv = VecNormalize(venv, **cfg.normalize)
        kwargs = {
            **cfg.model_kwargs(),
            "n_steps": n_steps,
            "batch_size": int(spec["batch_size"]),
            **({"n_epochs": int(spec["n_epochs"])} if "n_epochs" in spec else {}),
        }
        policy_kwargs = dict(cfg.policy_kwargs)
        if spec.get("net_arch"):
            policy_kwargs["net_arch"] = [int(width) for width in spec["net_arch"]]
        model = TimedPPO(
            cfg.policy,
            venv,
            policy_kwargs=policy_kwargs,
            seed=int(spec["seed"]),
            verbose=0,
            device="cpu",
            **kwargs,
        )
        rollouts = int(spec["warmup"]) + int(spec["rollouts"])
        model.learn(rollouts * n_envs * n_steps)
    timed = phases[int(spec["warmup"]) :]
    steps = len(timed) * n_envs * n_steps
    collect = sum(c - s for s, c, _ in timed)
    update = sum(u - c for _, c, u in timed)
    floor = bare_update_seconds(model, n_envs * n_steps, int(spec["update_threads"]), bfloat16)
    return {
        **spec,
        "steps": steps,
        "collect_s": collect,
        "update_s": update,
        "collect_per_s": steps / collect,
        "update_per_s": steps / update,
        "total_per_s": steps / (collect + update),
        **({"floor_update_per_s": n_envs * n_steps / floor} if floor else {}),
        "epochs_run": int(model._n_updates),  # SB3 counts epochs: rollouts × n_epochs
        "load_average": os.getloadavg()[0],
    }


def bare_update_seconds(model: Any, rollout: int, threads: int, bfloat16: bool) -> float:
    """Wall time [s] of the arithmetic one rollout's update cannot avoid: as many minibatch
    steps as `PPO.train` takes (n_epochs × rollout / batch_size), each the policy's forward
    (`evaluate_actions`), a loss of its outputs, backward, gradient clipping and an Adam step,
    on random tensors of the minibatch's shape; none of SB3's buffer, statistics or logging.
    Median of three rollouts' worth; the update rate's ceiling at this width and batch."""
    import numpy as np
    import torch

    policy, batch = model.policy, int(model.batch_size)
    steps = int(model.n_epochs) * max(1, rollout // batch)
    obs = torch.randn(batch, *model.observation_space.shape)
    actions = torch.randn(batch, *model.action_space.shape)
    threads_before = torch.get_num_threads()
    torch.set_num_threads(threads)
    times = []
    try:
        for _ in range(3):
            start = time.perf_counter()
            for _ in range(steps):
                with torch.autocast("cpu", dtype=torch.bfloat16, enabled=bfloat16):
                    values, log_prob, entropy = policy.evaluate_actions(obs, actions)
                    loss = values.float().mean() + log_prob.float().mean()
                    if entropy is not None:
                        loss = loss + entropy.float().mean()
                policy.optimizer.zero_grad()
                loss.backward()
                torch.nn.utils.clip_grad_norm_(policy.parameters(), model.max_grad_norm)
                policy.optimizer.step()
            times.append(time.perf_counter() - start)
    finally:
        torch.set_num_threads(threads_before)
    return float(np.median(times))
