"""What a hyper-parameter file changes about the agent's interface to the env, applied in one
place: the action box (``action_bounds``, `action_box`), incremental commands
(``action_increment``, `action_increment`), fixed observation scales (``obs_scales``,
`normalization`) and the exploration-noise schedule (``action_std_schedule``,
`noise_schedule`). Each is opt-in; a file without these keys trains as before."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from benchmarks.training.config import ZooConfig

__all__ = ["interface_callbacks", "pin_scales", "wrap_actions"]


def wrap_actions(venv: Any, cfg: ZooConfig, obs_names: Sequence[str]
                 ) -> tuple[Any, tuple[float, Sequence[str]] | None]:  # fmt: skip
    """``venv`` under the file's action box or incremental commands, and (δ, names) of the
    latter (None without)."""
    if cfg.action_bounds is not None:
        from benchmarks.training.action_box import ActionBox

        venv = ActionBox(venv, *cfg.action_bounds)
    if cfg.action_increment is None:
        return venv, None
    from benchmarks.training.action_increment import IncrementalActions

    increment = (cfg.action_increment, tuple(obs_names))
    return IncrementalActions(venv, *increment), increment


def pin_scales(vec_normalize: Any, cfg: ZooConfig, obs_names: Sequence[str]) -> None:
    """The file's fixed observation scales, on a fresh `VecNormalize`."""
    if cfg.obs_scales is not None:
        from benchmarks.training.normalization import pin_observation_scales

        pin_observation_scales(vec_normalize, obs_names, cfg.obs_scales)


def interface_callbacks(cfg: ZooConfig, n_timesteps: int) -> list[Any]:
    """The callbacks the file asks for: the σ schedule."""
    if cfg.action_std_schedule is None:
        return []
    from benchmarks.training.noise_schedule import AnnealActionStd

    initial = math.exp(cfg.policy_kwargs.get("log_std_init", 0.0))
    return [AnnealActionStd(cfg.action_std_schedule, n_timesteps, initial)]
