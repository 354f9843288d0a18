"""A share of the training vehicles on another plant or actuator: the ``plant_share`` and
``actuator_share`` keys of a hyper-parameter file (`benchmarks.training.config`)::

    AUVPath3DPreview-v0:
      n_envs: 32
      env_kwargs: {observation: preview_integral}   # the 5-DOF plant, env's default
      plant_share: {6dof: 0.25}                     # 8 of the 32 vehicles fly the 6-DOF plant

    AUVPath3DPreview-v0:
      n_envs: 32
      env_kwargs: {actuator: paper}
      actuator_share: {fins: 0.2}                   # 6 of the 32 vehicles fly the fins

A value named there flies round(n_envs × share) of the ``n_envs`` vehicles (Python's `round`,
halves to even); the others fly the section's own (``env_kwargs``' ``plant`` or ``actuator``,
else the env id's default), and every vehicle has the section's other env keyword arguments.
A native vector env simulates one plant and one actuator setting, so the training env is one
per value, concatenated (`benchmarks.training.plant_mix.ConcatVecEnv`): the section's own
vehicles first, then each named value's in the order given; vehicle i keeps the env seed
env_seed + i (`benchmarks.training.envs.make_training_env`). The concatenation reports each
vehicle's actuator, so stages that follow it (the allocation, docs/design.md §3.16) act per
vehicle. A residual section's parts are each a residual env whose base flies that part's
actuator. Evaluation flies the evaluation env as before.

One of the two keys per section: a share of both would need every pair of plant and actuator.
In a schedule (`benchmarks.training.schedule`) a phase may set or change a share like any
other key (it replaces the mapping; ``plant_share: null`` returns to the section's own).

Refused in one line naming the file and the key, with the rest of the file: both keys at once,
an unknown name (`auv_gym.sim.config.PLANTS`; the actuators an episode's draw can take,
`auv_gym.sim.randomization.RANDOM_ACTUATORS`, whose allocation the stages follow per vehicle),
the section's own
named, a section whose actuator is drawn per episode (``actuator: random``) with an actuator
share, a share that is not a finite number in (0, 1), shares summing to 1 or more, a share
that rounds to 0 vehicles or leaves none on the section's own, env keyword arguments the named
value refuses, an env id without the native vector env; and
(`check_native`) ``vec_env="dummy"``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from auv_gym import VARIANTS
from auv_gym.sim.config import PLANTS, SimConfig
from auv_gym.sim.randomization import RANDOM_ACTUATORS

__all__ = ["SHARE_KEYS", "VehicleShare", "check_native", "parse_vehicle_share"]

# The file's key -> the env keyword argument its shares set.
SHARE_KEYS = {"plant_share": "plant", "actuator_share": "actuator"}


def _names(argument: str) -> tuple[str, ...]:
    """The values a share of ``argument`` may name (module-level lookups: tests may patch)."""
    return tuple(PLANTS) if argument == "plant" else tuple(RANDOM_ACTUATORS)


def _empty(value: Any) -> bool:
    """A key left out, null or an empty mapping: every vehicle on the section's own."""
    return value is None or (isinstance(value, Mapping) and not value)


@dataclass(frozen=True)
class VehicleShare:
    """The vehicles of a training env: the section's own value of one env keyword argument
    (``plant`` or ``actuator``) and the shares of the others."""

    base: str  # the section's own value: its env_kwargs' or the env id's default
    shares: tuple[tuple[str, float], ...]  # (value, share of n_envs in (0, 1)), in the file's order
    argument: str = "plant"  # the env keyword argument the shares set

    @property
    def key(self) -> str:
        """The file's key: ``plant_share`` or ``actuator_share``."""
        return f"{self.argument}_share"

    def vehicles(self, n_envs: int, where: str | None = None) -> tuple[tuple[str, int], ...]:
        """(value, vehicles) over ``n_envs`` vehicles: the base first, then each share's
        round(n_envs × share); ValueError naming ``where`` when one of them gets none."""
        where = self.key if where is None else where
        counts = [(value, round(n_envs * share)) for value, share in self.shares]
        for value, count in counts:
            if count < 1:
                share = dict(self.shares)[value]
                raise ValueError(
                    f"{where}: {value} share {share:g} of n_envs {n_envs} rounds to 0 vehicles; "
                    "raise the share or n_envs"
                )
        rest = n_envs - sum(count for _, count in counts)
        if rest < 1:
            raise ValueError(
                f"{where}: the shares take all {n_envs} vehicles ({dict(counts)}) and leave 0 "
                f"on the section's {self.argument} {self.base}; lower them or raise n_envs"
            )
        return ((self.base, rest), *counts)

    def to_dict(self, n_envs: int) -> dict[str, Any]:
        """The record of a run's metadata: the shares and the vehicles each value flies."""
        return {"shares": dict(self.shares), "vehicles": dict(self.vehicles(n_envs))}


def parse_vehicle_share(
    section: Mapping[str, Any],
    n_envs: int,
    env_id: str,
    env_kwargs: Mapping[str, Any],
    where: str,
) -> VehicleShare | None:
    """A `VehicleShare` from a section's ``plant_share`` or ``actuator_share`` mapping (None:
    neither, or null or empty: every vehicle on the section's own); one-line ValueError naming
    ``where`` and the key for anything the module doc refuses. ``env_kwargs`` are the
    section's, already checked."""
    given = [key for key in SHARE_KEYS if not _empty(section.get(key))]
    if len(given) > 1:
        raise ValueError(
            f"{where}: give plant_share or actuator_share, not both (a share of both would "
            "need every pair of plant and actuator)"
        )
    if not given:
        return None
    key = given[0]
    argument, value = SHARE_KEYS[key], section[key]
    at = f"{where}: {key}"
    if not isinstance(value, Mapping):
        example = "{6dof: 0.25}" if argument == "plant" else "{fins: 0.2}"
        raise ValueError(
            f"{at} must be a mapping of {argument} name to share of n_envs, e.g. {example}, "
            f"got {value!r:.60}"
        )
    if env_id not in VARIANTS:
        raise ValueError(
            f"{at} needs the native vector env, which simulates {sorted(VARIANTS)}, not {env_id}"
        )
    kwargs = {**VARIANTS[env_id], **env_kwargs}
    base = getattr(SimConfig.from_kwargs(**kwargs), argument)
    if base == "random":
        raise ValueError(
            f"{at}: the section's actuator is drawn per episode (actuator: random); give it "
            "one actuator and the others shares"
        )
    names = _names(argument)
    shares = []
    for name, share in value.items():
        if name not in names:
            raise ValueError(f"{at}: unknown {argument} {name!r}; valid: {list(names)}")
        if name == base:
            raise ValueError(
                f"{at}: {name} is the section's own {argument} (env_kwargs), which flies the "
                f"vehicles the shares leave; name another {argument}"
            )
        number = isinstance(share, (int, float)) and not isinstance(share, bool)
        if not (number and math.isfinite(share) and 0.0 < share < 1.0):
            raise ValueError(f"{at}: {name} share must be a number in (0, 1), got {share!r}")
        shares.append((name, float(share)))
    total = math.fsum(share for _, share in shares)
    if total >= 1.0:
        raise ValueError(
            f"{at}: the shares sum to {total:g} >= 1; the section's {argument} {base} flies "
            "the rest"
        )
    for name, _ in shares:
        try:
            SimConfig.from_kwargs(**{**kwargs, argument: name})
        except (TypeError, ValueError) as error:
            raise ValueError(f"{at}: {name}: env_kwargs: {error}") from None
    checked = VehicleShare(base, tuple(shares), argument)
    checked.vehicles(n_envs, at)
    return checked


def check_native(share: VehicleShare | None, vec_env: str, where: str) -> None:
    """A vehicle share trains on the native vector env (`make_training_env` concatenates one
    per value): ValueError naming ``where`` for ``vec_env="dummy"``."""
    if share is not None and vec_env not in ("auto", "native"):
        raise ValueError(
            f"{where}: {share.key} needs the native vector env (vec_env auto or native), "
            f"not vec_env={vec_env!r}"
        )
