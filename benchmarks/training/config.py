"""RL-Zoo hyper-parameter files and the SB3 algorithms the harness trains.

A file has one top-level section per env id, in rl_zoo3 2.x format::

    AUVPath3D-v0:
      n_envs: 32
      n_timesteps: !!float 2e7
      policy: MlpPolicy
      normalize: "dict(norm_obs=True, norm_reward=True)"
      learning_rate: lin_3e-4
      ...

The keys an algorithm accepts are listed in its `Algorithm` entry of `ALGORITHMS` (PPO, SAC);
another algorithm is one more entry, read with the same `read_zoo_config`. Off-policy algorithms
(`Algorithm.off_policy`) also save their replay buffer in checkpoints, so a resumed run continues
with the samples it had.

An optional ``residual`` section trains a residual agent (docs/design.md §3.10): the harness
wraps the training env in `controllers.residual_env.ResidualVectorEnv` with these settings
(`controllers.residual.ResidualSettings`)::

      residual:
        base: fbsm_colos            # a classical controller name (controllers.CLASSICAL)
        bound: [0.25, 0.5, 0.5]     # β per X, M, N, normalised actuator units
        tv_weight: 0.25             # chattering charge per unit TV of the applied action
        base_kwargs: {}             # base gains (actuator and control_dt come from the env)

An optional ``action_bounds`` key narrows the box the agent acts in, a sub-box of the env's
[−1, 1]³ given as ``[[low_X, low_M, low_N], [high_X, high_M, high_N]]``: the agent's action
space becomes that box (`benchmarks.training.train.ActionBox`), saved with the model, so a loaded
agent acts inside it too. For off-policy agents, whose squashed-Gaussian exploration covers the
whole box from the first step (`benchmarks.action_bounds` measures what that does).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from auv_gym import ENV_ID
from controllers.residual import ResidualSettings

__all__ = ["ALGORITHMS", "Algorithm", "ZooConfig", "read_zoo_config", "schedule"]

# RL-Zoo keys of the harness itself (not constructor arguments of the algorithm).
ZOO_KEYS = frozenset(
    {
        "n_envs",
        "n_timesteps",
        "policy",
        "normalize",
        "policy_kwargs",
        "env_kwargs",
        "residual",
        "action_bounds",
    }
)


@dataclass(frozen=True)
class Algorithm:
    """An SB3 algorithm: its class in `stable_baselines3` and the constructor arguments a
    hyper-parameter file may set (`schedules`: those that may be "lin_<x>" schedules)."""

    name: str
    class_name: str
    hyperparameters: frozenset[str]
    schedules: tuple[str, ...] = ()
    off_policy: bool = False

    def sb3_class(self) -> Any:
        """The SB3 class (imports stable_baselines3)."""
        import stable_baselines3

        return getattr(stable_baselines3, self.class_name)


ALGORITHMS: dict[str, Algorithm] = {
    "ppo": Algorithm(
        "ppo",
        "PPO",
        frozenset({
            "learning_rate", "n_steps", "batch_size", "n_epochs", "gamma", "gae_lambda",
            "clip_range", "clip_range_vf", "normalize_advantage", "ent_coef", "vf_coef",
            "max_grad_norm", "use_sde", "sde_sample_freq", "target_kl", "stats_window_size",
        }),
        schedules=("learning_rate", "clip_range"),
    ),
    "sac": Algorithm(
        "sac",
        "SAC",
        frozenset({
            "learning_rate", "buffer_size", "learning_starts", "batch_size", "tau", "gamma",
            "train_freq", "gradient_steps", "optimize_memory_usage", "ent_coef",
            "target_update_interval", "target_entropy", "use_sde", "sde_sample_freq",
            "use_sde_at_warmup", "stats_window_size", "n_steps",
        }),
        schedules=("learning_rate",),
        off_policy=True,
    ),
}  # fmt: skip


@dataclass(frozen=True)
class ZooConfig:
    """One env's section of an RL-Zoo hyper-parameter file, validated for one algorithm.

    `normalize` holds the `VecNormalize` keyword arguments; `algo_kwargs` the algorithm's
    constructor arguments, with "lin_<x>" schedules still as strings (`model_kwargs` resolves
    them). `residual` holds the residual settings when the file has a ``residual`` section.
    """

    algo: str
    n_envs: int
    n_timesteps: int
    policy: str
    normalize: dict[str, Any]
    policy_kwargs: dict[str, Any]
    env_kwargs: dict[str, Any]
    algo_kwargs: dict[str, Any]
    raw: dict[str, Any] = field(default_factory=dict)
    residual: ResidualSettings | None = None
    action_bounds: tuple[tuple[float, ...], tuple[float, ...]] | None = None  # (low, high)

    def model_kwargs(self) -> dict[str, Any]:
        """`algo_kwargs` with the algorithm's schedule keys turned into SB3 schedules."""
        schedules = ALGORITHMS[self.algo].schedules
        return {k: schedule(v) if k in schedules else v for k, v in self.algo_kwargs.items()}


def read_zoo_config(path: str | os.PathLike, env_id: str = ENV_ID, algo: str = "ppo") -> ZooConfig:
    """Parse the `env_id` section of an RL-Zoo YAML file for `algo` (rl_zoo3 2.x semantics).

    `normalize` may be a bool, a dict or a string evaluating to a dict, as in RL Zoo; the
    discount `gamma` is copied into it like RL Zoo does. `policy_kwargs` may be a dict or a
    string such as "dict(net_arch=[64, 64])" (evaluated with only `dict` and `torch.nn`).
    """
    import yaml

    if algo not in ALGORITHMS:
        raise ValueError(f"unknown algorithm {algo!r}; valid: {sorted(ALGORITHMS)}")
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"hyper-parameter file {path} does not exist")
    with path.open() as f:
        data = yaml.safe_load(f)
    if not isinstance(data, dict) or env_id not in data:
        raise ValueError(f"{path}: no top-level key {env_id!r}")
    section = dict(data[env_id])
    accepted = ALGORITHMS[algo].hyperparameters
    unknown = set(section) - ZOO_KEYS - accepted
    if unknown:
        raise ValueError(f"{path}: unsupported keys for {env_id}: {sorted(unknown)}")
    for key in ("n_timesteps", "policy"):
        if key not in section:
            raise ValueError(f"{path}: {env_id} needs {key!r}")
    n_envs = int(section.get("n_envs", 1))
    n_timesteps = int(float(section["n_timesteps"]))
    if n_envs < 1 or n_timesteps < 1:
        raise ValueError(f"{path}: n_envs and n_timesteps must be positive")
    algo_kwargs = {k: section[k] for k in accepted if k in section}
    normalize = section.get("normalize", False)
    if isinstance(normalize, str):
        normalize = _eval_kwargs(normalize, path, "normalize")
    if normalize is True:
        normalize = {}
    elif normalize is False:
        raise ValueError(f"{path}: normalize must be enabled (VecNormalize, docs/design.md §3)")
    elif not isinstance(normalize, dict):
        raise ValueError(f"{path}: normalize must be a bool, a dict or a dict expression")
    normalize = {"norm_obs": True, "norm_reward": True, **normalize}
    if "gamma" in algo_kwargs:
        normalize["gamma"] = float(algo_kwargs["gamma"])
    if not normalize["norm_obs"]:
        raise ValueError(f"{path}: this project requires observation normalisation")
    policy_kwargs = section.get("policy_kwargs", {})
    if isinstance(policy_kwargs, str):
        policy_kwargs = _eval_kwargs(policy_kwargs, path, "policy_kwargs")
    env_kwargs = dict(section.get("env_kwargs") or {})
    residual = None
    if "residual" in section:
        residual = ResidualSettings.from_dict(section["residual"], f"{path}: residual")
    action_bounds = None
    if "action_bounds" in section:
        if residual is not None:
            raise ValueError(f"{path}: action_bounds and residual exclude each other")
        action_bounds = _action_bounds(section["action_bounds"], path)
    return ZooConfig(
        algo=algo, n_envs=n_envs, n_timesteps=n_timesteps, policy=str(section["policy"]),
        normalize=normalize, policy_kwargs=dict(policy_kwargs), env_kwargs=env_kwargs,
        algo_kwargs=algo_kwargs, raw=section, residual=residual, action_bounds=action_bounds,
    )  # fmt: skip


def _action_bounds(value: Any, path: Path) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """[[low × 3], [high × 3]] inside [−1, 1] with low < high per axis, or a named error."""
    import math

    try:
        low, high = (tuple(float(v) for v in side) for side in value)
        ok = len(low) == len(high) == 3 and all(
            math.isfinite(a) and math.isfinite(b) and -1.0 <= a < b <= 1.0
            for a, b in zip(low, high, strict=True)
        )
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ValueError(
            f"{path}: action_bounds must be [[low_X, low_M, low_N], [high_X, high_M, high_N]] "
            f"with -1 <= low < high <= 1 per axis, got {value!r}"
        )
    return low, high


def _eval_kwargs(text: str, path: Path, key: str) -> dict[str, Any]:
    import torch

    try:
        value = eval(text, {"__builtins__": {}}, {"dict": dict, "nn": torch.nn})
    except Exception as exc:
        raise ValueError(f"{path}: cannot evaluate {key} {text!r}: {exc}") from exc
    if not isinstance(value, dict):
        raise ValueError(f"{path}: {key} must evaluate to a dict, got {type(value).__name__}")
    return value


def schedule(value: Any) -> Any:
    """RL-Zoo schedules: "lin_<x>" decays linearly from x to 0; numbers stay constant."""
    if isinstance(value, str):
        match = re.fullmatch(r"lin_([0-9.eE+-]+)", value)
        if not match:
            raise ValueError(f"schedule {value!r} is not a number or 'lin_<x>'")
        from stable_baselines3.common.utils import LinearSchedule

        return LinearSchedule(float(match.group(1)), 0.0, 1.0)
    return float(value)
