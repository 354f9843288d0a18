"""A share of the training vehicles on another plant: the ``plant_share`` key of a
hyper-parameter file (`benchmarks.training.config`)::

    AUVPath3DPreview-v0:
      n_envs: 32
      env_kwargs: {observation: preview_integral}   # the 5-DOF plant, env's default
      plant_share: {6dof: 0.25}                     # 8 of the 32 vehicles fly the 6-DOF plant

A plant named there flies round(n_envs × share) of the ``n_envs`` vehicles (Python's `round`,
halves to even); the others fly the section's own plant (``env_kwargs``' ``plant``, else the env
id's default), and every vehicle has the section's other env keyword arguments. A native vector
env simulates one plant, so the training env is one per plant, concatenated
(`benchmarks.training.plant_mix.ConcatVecEnv`): the section's own plant's vehicles first, then
each named plant's in the order given; vehicle i keeps the env seed env_seed + i
(`benchmarks.training.envs.make_training_env`). Evaluation flies the evaluation env as before.

In a schedule (`benchmarks.training.schedule`) a phase may set or change ``plant_share`` like
any other key (it replaces the mapping; ``plant_share: null`` returns to the section's plant
alone).

Refused in one line naming the file and the key, with the rest of the file: an unknown plant
name (`auv_gym.sim.config.PLANTS`), the section's own plant named, a share that is not a finite
number in (0, 1), shares summing to 1 or more, a share that rounds to 0 vehicles or leaves none
on the section's plant, env keyword arguments the named plant refuses, a residual section, an
env id without the native vector env; and (`check_native`) ``vec_env="dummy"``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from auv_gym import VARIANTS
from auv_gym.sim.config import PLANTS, SimConfig

__all__ = ["PLANT_SHARE_KEY", "PlantShare", "check_native", "parse_plant_share"]

PLANT_SHARE_KEY = "plant_share"


@dataclass(frozen=True)
class PlantShare:
    """The plants of a training env: the section's own and the shares of the others."""

    base: str  # the section's own plant: its env_kwargs' or the env id's default
    shares: tuple[tuple[str, float], ...]  # (plant, share of n_envs in (0, 1)), in the file's order

    def vehicles(self, n_envs: int, where: str = PLANT_SHARE_KEY) -> tuple[tuple[str, int], ...]:
        """(plant, vehicles) over ``n_envs`` vehicles: the base plant first, then each share's
        round(n_envs × share); ValueError naming ``where`` when one of them gets none."""
        counts = [(plant, round(n_envs * share)) for plant, share in self.shares]
        for plant, count in counts:
            if count < 1:
                share = dict(self.shares)[plant]
                raise ValueError(
                    f"{where}: {plant} share {share:g} of n_envs {n_envs} rounds to 0 vehicles; "
                    "raise the share or n_envs"
                )
        rest = n_envs - sum(count for _, count in counts)
        if rest < 1:
            raise ValueError(
                f"{where}: the shares take all {n_envs} vehicles ({dict(counts)}) and leave 0 "
                f"on the section's plant {self.base}; lower them or raise n_envs"
            )
        return ((self.base, rest), *counts)

    def to_dict(self, n_envs: int) -> dict[str, Any]:
        """The record of a run's metadata: the shares and the vehicles each plant flies."""
        return {"shares": dict(self.shares), "vehicles": dict(self.vehicles(n_envs))}


def parse_plant_share(
    value: Any,
    n_envs: int,
    env_id: str,
    env_kwargs: Mapping[str, Any],
    where: str,
    residual: bool = False,
) -> PlantShare | None:
    """A `PlantShare` from a section's ``plant_share`` mapping (None: null or empty, every
    vehicle on the section's plant); one-line ValueError naming ``where`` and the key for
    anything the module doc refuses. ``env_kwargs`` are the section's, already checked."""
    at = f"{where}: {PLANT_SHARE_KEY}"
    if value is None or (isinstance(value, Mapping) and not value):
        return None
    if not isinstance(value, Mapping):
        raise ValueError(
            f"{at} must be a mapping of plant name to share of n_envs, e.g. {{6dof: 0.25}}, "
            f"got {value!r:.60}"
        )
    if residual:
        raise ValueError(f"{at} is not supported with a residual section (one plant per run)")
    if env_id not in VARIANTS:
        raise ValueError(
            f"{at} needs the native vector env, which simulates {sorted(VARIANTS)}, not {env_id}"
        )
    kwargs = {**VARIANTS[env_id], **env_kwargs}
    base = SimConfig.from_kwargs(**kwargs).plant
    shares = []
    for plant, share in value.items():
        if plant not in PLANTS:
            raise ValueError(f"{at}: unknown plant {plant!r}; valid: {list(PLANTS)}")
        if plant == base:
            raise ValueError(
                f"{at}: {plant} is the section's own plant (env_kwargs), which flies the "
                "vehicles the shares leave; name another plant"
            )
        number = isinstance(share, (int, float)) and not isinstance(share, bool)
        if not (number and math.isfinite(share) and 0.0 < share < 1.0):
            raise ValueError(f"{at}: {plant} share must be a number in (0, 1), got {share!r}")
        shares.append((plant, float(share)))
    total = math.fsum(share for _, share in shares)
    if total >= 1.0:
        raise ValueError(
            f"{at}: the shares sum to {total:g} >= 1; the section's plant {base} flies the rest"
        )
    for plant, _ in shares:
        try:
            SimConfig.from_kwargs(**{**kwargs, "plant": plant})
        except (TypeError, ValueError) as error:
            raise ValueError(f"{at}: {plant}: env_kwargs: {error}") from None
    checked = PlantShare(base, tuple(shares))
    checked.vehicles(n_envs, at)
    return checked


def check_native(plant_share: PlantShare | None, vec_env: str, where: str) -> None:
    """A plant share trains on the native vector env (`make_training_env` concatenates one per
    plant): ValueError naming ``where`` for ``vec_env="dummy"``."""
    if plant_share is not None and vec_env not in ("auto", "native"):
        raise ValueError(
            f"{where}: {PLANT_SHARE_KEY} needs the native vector env (vec_env auto or native), "
            f"not vec_env={vec_env!r}"
        )
