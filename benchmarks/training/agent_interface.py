"""What a hyper-parameter file changes about the agent's interface to the env, read and applied
in one place: the action box (``action_bounds``, `action_box`), incremental commands
(``action_increment``, `action_increment`), scaled commands (``action_scale``, `action_scale`),
fixed observation scales (``obs_scales``,
`normalization`), the exploration-noise schedule (``action_std_schedule``, `noise_schedule`)
the safety cost charged in the reward (``cost_penalty``, `cost_penalty`) and the envelope guard
of the commands (``envelope_guard``, `envelope_guard`). Each is opt-in; a file without these
keys trains as before."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from controllers.action_increment import check_increment
from controllers.action_scale import check_action_scale
from controllers.envelope_guard import check_envelope_guard

if TYPE_CHECKING:
    from benchmarks.training.config import ZooConfig

__all__ = ["interface_callbacks", "parse_interface", "pin_scales", "wrap_actions", "wrap_rewards"]


def parse_interface(
    section: dict[str, Any], path: Any, env_id: str, residual: Any, action_bounds: Any
) -> dict[str, Any]:
    """The `ZooConfig` fields of a file's interface keys (``action_bounds`` is read before:
    incremental and scaled commands exclude it, a residual agent and each other); errors name
    ``path`` and ``env_id``."""
    where = f"{path}: {env_id}"
    fields: dict[str, Any] = {}
    if "obs_scales" in section:
        from benchmarks.training.normalization import parse_obs_scales

        fields["obs_scales"] = parse_obs_scales(section["obs_scales"], where)
    if "action_increment" in section:
        if residual is not None or action_bounds is not None:
            raise ValueError(f"{path}: action_increment excludes residual and action_bounds")
        fields["action_increment"] = check_increment(section["action_increment"], where)
    if "action_scale" in section:
        if residual is not None or action_bounds is not None or "action_increment" in section:
            raise ValueError(
                f"{path}: action_scale excludes residual, action_bounds and action_increment"
            )
        fields["action_scale"] = check_action_scale(section["action_scale"], where)
    if "action_std_schedule" in section:
        from benchmarks.training.noise_schedule import parse_std_schedule

        fields["action_std_schedule"] = parse_std_schedule(section["action_std_schedule"], where)
    if "cost_penalty" in section:
        from benchmarks.training.cost_penalty import check_cost_penalty

        fields["cost_penalty"] = check_cost_penalty(section["cost_penalty"], where)
    if "envelope_guard" in section:
        if residual is not None:
            raise ValueError(f"{path}: envelope_guard excludes residual")
        fields["envelope_guard"] = check_envelope_guard(section["envelope_guard"], where)
    return fields


def wrap_actions(
    venv: Any, cfg: ZooConfig, obs_names: Sequence[str]
) -> tuple[Any, tuple[float, Sequence[str]] | None]:
    """``venv`` under the file's envelope guard (innermost: it limits the env's command), action
    box, scaled or incremental commands, and (δ, names) of the latter (None without)."""
    if cfg.envelope_guard is not None:
        from benchmarks.training.envelope_guard import GuardedActions

        venv = GuardedActions(venv, cfg.envelope_guard, obs_names)
    if cfg.action_bounds is not None:
        from benchmarks.training.action_box import ActionBox

        venv = ActionBox(venv, *cfg.action_bounds)
    if cfg.action_scale is not None:
        from benchmarks.training.action_scale import ScaledActions

        venv = ScaledActions(venv, cfg.action_scale)
    if cfg.action_increment is None:
        return venv, None
    from benchmarks.training.action_increment import IncrementalActions

    increment = (cfg.action_increment, tuple(obs_names))
    return IncrementalActions(venv, *increment), increment


def wrap_rewards(venv: Any, cfg: ZooConfig) -> Any:
    """``venv`` with the file's safety-cost charge in its rewards (unchanged without one)."""
    if not cfg.cost_penalty:
        return venv
    from benchmarks.training.cost_penalty import CostPenalty

    return CostPenalty(venv, cfg.cost_penalty)


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
