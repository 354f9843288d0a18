"""What a hyper-parameter file changes about the agent's interface to the env, read and applied
in one place: the action box (``action_bounds``, `action_box`), fixed observation scales
(``obs_scales``, `normalization`) and the agent's stages (``stages``, `controllers.stages`:
trained inside them, exported with them). Each is opt-in; a file without these keys trains as
before."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from auv_gym.sim.randomization import RANDOM_ACTUATORS
from controllers.actuator_allocation import ALLOCATED_ACTUATORS
from controllers.env_settings import draws_actuator, env_config, policy_settings
from controllers.mirror import MIRROR_STAGE
from controllers.residual import NO_STAGES
from controllers.stages import build_stages, check_stage_specs

if TYPE_CHECKING:
    from benchmarks.training.config import ZooConfig

__all__ = ["parse_interface", "pin_scales", "wrap_actions"]


def parse_interface(
    section: dict[str, Any], path: Any, env_id: str, residual: Any
) -> dict[str, Any]:
    """The `ZooConfig` fields of a file's interface keys (``action_bounds`` is read before);
    errors name ``path`` and ``env_id``."""
    where = f"{path}: {env_id}"
    fields: dict[str, Any] = {}
    if "obs_scales" in section:
        from benchmarks.training.normalization import parse_obs_scales

        fields["obs_scales"] = parse_obs_scales(section["obs_scales"], where)
    if "envelope_guard" in section:
        place = (
            "a residual setting: residual: {envelope_guard: ...}"
            if residual is not None
            else "a stage: stages: [{name: envelope_guard, ...}]"
        )
        raise ValueError(f"{where}: envelope_guard is now {place}")
    if "stages" in section:
        if residual is not None:
            raise ValueError(f"{where}: {NO_STAGES}")
        fields["stages"] = check_stage_specs(section["stages"], where)
        if any(spec["name"] == MIRROR_STAGE for spec in fields["stages"]):
            raise ValueError(
                f"{where}: stage {MIRROR_STAGE} averages the trained network with its mirror "
                "image, and SB3 samples its training actions from the bare network: list it in "
                "the schedule's stages (added to the exports), not among those trained inside"
            )
    return fields


def wrap_actions(
    venv: Any, cfg: ZooConfig, obs_names: Sequence[str], env_kwargs: dict[str, Any]
) -> Any:
    """``venv`` inside the file's stages (innermost: they give the env's command), built for
    the training env's plant (``env_kwargs``: the id's and the file's), and its action box.

    On an env that draws each episode's actuator (``actuator="random"``: the paper's or the
    fins), or whose vehicles fly both (``actuator_share``), the allocation flies the vehicles
    on the fins and passes the others (`controllers.stages.DrawnAllocationStage`), as the
    exported agent will on each actuator."""
    share = cfg.vehicle_share
    if share is not None and share.argument == "actuator":
        env_kwargs = {**env_kwargs, "actuator": "random"}  # per vehicle, as a draw per episode
    settings = policy_settings(env_kwargs)
    drawn = None
    if draws_actuator(env_kwargs):
        settings = {**settings, "actuator_params": env_config(env_kwargs).actuator_params}
        (drawn,) = [a for a in RANDOM_ACTUATORS if a in ALLOCATED_ACTUATORS]
    stages = build_stages(cfg.stages, obs_names, settings, "stages", drawn)
    if stages:
        from benchmarks.training.stages import StagedActions

        venv = StagedActions(venv, stages, len(obs_names))
    if cfg.action_bounds is not None:
        from benchmarks.training.action_box import ActionBox

        venv = ActionBox(venv, *cfg.action_bounds)
    return venv


def pin_scales(vec_normalize: Any, cfg: ZooConfig, obs_names: Sequence[str]) -> None:
    """The file's fixed observation scales, on a fresh `VecNormalize`."""
    if cfg.obs_scales is not None:
        from benchmarks.training.normalization import pin_observation_scales

        pin_observation_scales(vec_normalize, obs_names, cfg.obs_scales)
