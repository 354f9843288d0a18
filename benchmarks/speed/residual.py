"""Residual-RL speed: the base controller's batched cost, the wrapped env, and PPO training.

    python -m benchmarks.speed.residual [--steps 2000] [--train-steps 100000]

Prints, on the training distribution of benchmarks/hyperparams/ppo_residual.yml (n_envs
vehicles, ``actuator="random"``, one thread):

1. the base controller's `predict` per control step for the batch (µs per vehicle-step), once
   per actuator model: `ResidualVectorEnv` runs one batched call per model in use;
2. env steps/s of `ResidualVectorEnv` (base + physics + chattering charge) with zero actions,
   against the bare vector env;
3. PPO training env steps/s through `benchmarks.training.train` (rollouts and updates, no
   evaluation), which sets the YAML's n_timesteps budget: 25 min of one core per seed.
"""

from __future__ import annotations

import json
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from gymnasium.vector import AutoresetMode

from auv_gym import VARIANTS
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from benchmarks.arguments import parse_options, program_name
from benchmarks.options import option
from benchmarks.training.config import read_zoo_config
from benchmarks.training.residual_env import ResidualVectorEnv

CONFIG = Path(__file__).resolve().parents[1] / "hyperparams" / "ppo_residual.yml"
ENV_ID = "AUVPath3DSpeedLimit-v0"
BUDGET_S = 25 * 60  # [s] per seed, one core


def _env_kwargs() -> tuple[int, dict]:
    cfg = read_zoo_config(CONFIG, ENV_ID)
    return cfg.n_envs, {**VARIANTS[ENV_ID], **cfg.env_kwargs}


def base_cost(steps: int) -> dict[str, float]:
    """µs per vehicle-step of each actuator model's base controller inside the wrapper."""
    n, kwargs = _env_kwargs()
    env = ResidualVectorEnv(
        AUVPath3DVectorEnv(n, autoreset_mode=AutoresetMode.SAME_STEP, threads=1, **kwargs),
        read_zoo_config(CONFIG, ENV_ID).residual,
    )
    obs, _ = env.reset(seed=0)
    start = np.zeros(n, dtype=bool)
    states = {name: None for name in env.controllers}
    elapsed = dict.fromkeys(env.controllers, 0.0)
    zeros = np.zeros((n, 3))
    for _ in range(steps):
        for name, controller in env.controllers.items():
            tic = time.perf_counter()
            _, states[name] = controller.predict(obs[:, :15], states[name], start)
            elapsed[name] += time.perf_counter() - tic
        obs, *_ = env.step(zeros)
    return {name: 1e6 * t / (n * steps) for name, t in elapsed.items()}


def env_rate(steps: int) -> tuple[float, float]:
    """(wrapped, bare) env steps/s with zero actions (one env step = one vehicle-step)."""
    n, kwargs = _env_kwargs()
    residual = read_zoo_config(CONFIG, ENV_ID).residual
    rates = []
    for wrap in (True, False):
        core = AUVPath3DVectorEnv(n, autoreset_mode=AutoresetMode.SAME_STEP, threads=1, **kwargs)
        env = ResidualVectorEnv(core, residual) if wrap else core
        env.reset(seed=0)
        zeros = np.zeros((n, 3))
        env.step(zeros)
        tic = time.perf_counter()
        for _ in range(steps):
            env.step(zeros)
        rates.append(n * steps / (time.perf_counter() - tic))
    return rates[0], rates[1]


def training_rate(n_timesteps: int) -> float:
    """PPO env steps/s of `benchmarks.training.train` on the YAML (no evaluation)."""
    from benchmarks.training.train import TrainOptions, train

    with tempfile.TemporaryDirectory() as tmp:
        opts = TrainOptions(
            config=str(CONFIG),
            env_id=ENV_ID,
            out=str(Path(tmp) / "run"),
            n_timesteps=n_timesteps,
            eval_freq=0,
            checkpoint_freq=10**9,
            progress_bar=True,
        )
        tic = time.perf_counter()
        train(opts, argv=["benchmarks.speed.residual"])
        elapsed = time.perf_counter() - tic
        metadata = json.loads((Path(tmp) / "run" / "metadata.json").read_text())
        steps = int(metadata["num_timesteps"])
    return steps / elapsed


@dataclass
class Options:
    """The command line of `python -m benchmarks.speed.residual`."""

    steps: int = option(2000, "control steps of parts 1-2")
    train_steps: int = option(100_000, "PPO env steps")


def main(argv: list[str] | None = None) -> dict[str, float]:
    args, parser = parse_options(Options, argv, program_name("benchmarks.speed.residual"), __doc__)
    if args.steps < 1 or args.train_steps < 1:
        parser.error("--steps and --train-steps must be positive")
    n, _ = _env_kwargs()
    out: dict[str, float] = {}
    env_rate(10)  # compile the kernels outside the timers
    for name, us in base_cost(args.steps).items():
        out[f"base_{name}_us"] = us
        print(
            f"base controller ({name:5s}), batch of {n}: {us:8.2f} µs per vehicle-step "
            f"({us * n / 1e3:.3f} ms per batched call)"
        )
    wrapped, bare = env_rate(args.steps)
    out.update(env_wrapped=wrapped, env_bare=bare)
    print(
        f"env steps/s, zero actions: ResidualVectorEnv {wrapped:,.0f}, bare vector env {bare:,.0f}"
    )
    rate = training_rate(args.train_steps)
    out["train"] = rate
    print(
        f"PPO training: {rate:,.0f} env steps/s → {rate * BUDGET_S / 1e6:.1f} M env steps in "
        f"{BUDGET_S // 60} min of one core"
    )
    return out


if __name__ == "__main__":
    main()
