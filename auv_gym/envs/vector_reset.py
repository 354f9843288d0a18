"""The vector env's reset arguments: the autoreset mode, the seeds (one per vehicle) and the
reset mask of a partial reset, each parsed into its value or a named error."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode

from auv_gym.support.validation import ArgumentTypeError, integer

__all__ = ["parse_autoreset_mode", "reset_mask", "seed_list"]


def parse_autoreset_mode(mode: AutoresetMode | str) -> AutoresetMode:
    """An `AutoresetMode` from the enum, its value ("NextStep") or its name ("next_step")."""
    if isinstance(mode, AutoresetMode):
        return mode
    if isinstance(mode, str):
        for candidate in AutoresetMode:
            if mode in (candidate.value, candidate.name) or mode.upper() == candidate.name:
                return candidate
    valid = [m.value for m in AutoresetMode]
    raise ValueError(f"unknown autoreset_mode {mode!r}; valid: {valid} or an AutoresetMode")


def seed_list(seed: int | Sequence[int | None] | None, n: int) -> list[int | None]:
    """One seed per vehicle (None: keep or create its generator): an integer k gives k + i, a list
    gives its entries; anything else raises a named error."""
    if seed is None:
        return [None] * n
    if isinstance(seed, (int, np.integer)) and not isinstance(seed, (bool, np.bool_)):
        first = integer("seed", seed, 0)
        return [first + i for i in range(n)]
    if isinstance(seed, (str, bytes, Mapping)) or not isinstance(seed, Sequence | np.ndarray):
        raise ArgumentTypeError(
            f"seed must be None, an integer >= 0 or a list of num_envs = {n} integers or "
            f"None, got {seed!r:.80}"
        )
    seeds = list(seed)
    if len(seeds) != n:
        raise ValueError(f"a list of seeds must have num_envs = {n} entries, got {len(seeds)}")
    return [None if s is None else integer(f"seed[{i}]", s, 0) for i, s in enumerate(seeds)]


def reset_mask(options: dict[str, Any] | None, n: int) -> np.ndarray:
    """The vehicles a reset resets: all, or a copy of ``options["reset_mask"]`` (a numpy bool
    array of shape (n,) selecting at least one); anything else raises a named error."""
    if options is not None and not isinstance(options, Mapping):
        raise ArgumentTypeError(f"options must be None or a dict, got {options!r:.80}")
    unknown = sorted(map(str, set(options or ()) - {"reset_mask"}))
    if unknown:
        raise ValueError(f"unknown reset option(s) {unknown}; valid: ['reset_mask']")
    if not options or "reset_mask" not in options:
        return np.ones(n, dtype=bool)
    mask = options["reset_mask"]
    if not isinstance(mask, np.ndarray) or mask.dtype != np.bool_:
        raise ValueError(f"options['reset_mask'] must be a numpy bool array, got {mask!r}")
    if mask.shape != (n,):
        raise ValueError(f"options['reset_mask'] must have shape ({n},), got {mask.shape}")
    if not mask.any():
        raise ValueError("options['reset_mask'] must select at least one vehicle")
    return mask.copy()
