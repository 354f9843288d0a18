"""The environments' arguments that become one `SimConfig` setting each: the white noise from
`disturbance` and `noise_hold` (a preset name, an amplitude, a `NoiseConfig` or a dict of its
fields over a preset), the reward weights and the path (a fixed `Path` or a
`PathDistribution`); each bad value a one-line error naming it (docs/design.md §3).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import fields, replace

from auv_gym.ocean.disturbances import MAX_NOISE_AMPLITUDE, MAX_NOISE_HOLD, NoiseConfig
from auv_gym.ocean.preset import OCEAN_PRESET, OCEAN_PRESET_NAME
from auv_gym.paths.shapes import PATHS, Path, make_path
from auv_gym.sim.path_generator import PathDistribution
from auv_gym.sim.task import REWARD_TERMS, RewardWeights
from auv_gym.support.validation import (
    ArgumentTypeError,
    choice,
    is_real,
    keys_within,
    real,
    vector,
)

__all__ = [
    "DEFAULT_NOISE_HOLD",
    "DISTURBANCE_PRESETS",
    "NOISE_FIELDS",
    "NOISE_PRESETS",
    "disturbance_preset",
    "noise_from",
    "path_from",
    "path_is_random",
    "reward_from",
    "start_rotation_from",
]

DISTURBANCE_PRESETS = {"paper": 35.0, "none": 0.0}
DEFAULT_NOISE_HOLD = 0.01  # [s]
# The white noise of each named disturbance: "ocean"'s is that of the ocean preset, which
# `SimConfig.from_kwargs` also fills the ocean's other arguments from.
NOISE_PRESETS = {
    **{
        name: NoiseConfig((amplitude,) * 5, DEFAULT_NOISE_HOLD)
        for name, amplitude in DISTURBANCE_PRESETS.items()
    },
    OCEAN_PRESET_NAME: OCEAN_PRESET.noise,
}
NOISE_FIELDS = tuple(f.name for f in fields(NoiseConfig))  # a disturbance dict's other keys


def disturbance_preset(disturbance: object) -> str | None:
    """The preset a `disturbance` argument names: itself if a string, a dict's "preset"
    ("paper" when absent); None for an amplitude or a `NoiseConfig`."""
    if isinstance(disturbance, str):
        return disturbance
    if isinstance(disturbance, Mapping):
        preset = disturbance.get("preset", "paper")
        return preset if isinstance(preset, str) else None
    return None


def noise_from(
    disturbance: str | float | NoiseConfig | Mapping, noise_hold: float | None
) -> NoiseConfig:
    """The white noise of the `disturbance` and `noise_hold` arguments; a conflict is an error.

    ``disturbance`` is a preset name (`NOISE_PRESETS`), an amplitude, a `NoiseConfig` or a dict
    of its fields with an optional "preset" (default "paper") whose noise they replace;
    ``noise_hold`` replaces the hold of a name's, an amplitude's or a dict's noise."""
    hold = DEFAULT_NOISE_HOLD
    if noise_hold is not None:
        hold = real("noise_hold", noise_hold, 0.0, MAX_NOISE_HOLD, low_open=True, unit="s")
    if isinstance(disturbance, NoiseConfig):
        if noise_hold is not None and hold != disturbance.hold:
            raise ValueError(
                f"noise_hold = {noise_hold!r} s conflicts with disturbance = {disturbance!r}: "
                "give the hold once (NoiseConfig.hold or noise_hold)"
            )
        return disturbance
    if isinstance(disturbance, Mapping):
        given = keys_within("disturbance", disturbance, ["preset", *NOISE_FIELDS])
        name = choice("disturbance preset", given.pop("preset", "paper"), NOISE_PRESETS)
        try:  # validated as a NoiseConfig
            noise = replace(NOISE_PRESETS[name], **given)
        except (TypeError, ValueError) as error:
            raise type(error)(f"disturbance: {error}") from None
        if noise_hold is not None and "hold" in given and hold != noise.hold:
            raise ValueError(
                f"noise_hold = {noise_hold!r} s conflicts with disturbance = "
                f"{dict(disturbance)!r:.120}: give the hold once (its 'hold' or noise_hold)"
            )
        return noise if noise_hold is None else replace(noise, hold=hold)
    if isinstance(disturbance, str) and disturbance in NOISE_PRESETS:
        noise = NOISE_PRESETS[disturbance]
        return noise if noise_hold is None else replace(noise, hold=hold)
    if is_real(disturbance):
        amplitude = real(
            "disturbance (noise amplitude)", disturbance, 0.0, MAX_NOISE_AMPLITUDE, unit="N or N·m"
        )
        return NoiseConfig((amplitude,) * 5, hold)
    error = ValueError if isinstance(disturbance, str) else ArgumentTypeError
    raise error(
        f"unknown disturbance {disturbance!r:.80}; valid: {sorted(NOISE_PRESETS)}, "
        f"a NoiseConfig, a dict of its fields {list(NOISE_FIELDS)} with an optional 'preset', "
        f"or an amplitude in [0, {MAX_NOISE_AMPLITUDE:g}] N / N·m"
    )


def reward_from(reward_weights: RewardWeights | dict | None) -> RewardWeights:
    if reward_weights is None:
        return RewardWeights()
    if isinstance(reward_weights, RewardWeights):
        return reward_weights
    if not isinstance(reward_weights, Mapping):
        raise ArgumentTypeError(
            f"reward_weights must be None, a RewardWeights or a dict with keys among "
            f"{list(REWARD_TERMS)}, got {reward_weights!r:.80}"
        )
    return RewardWeights(**keys_within("reward_weights", reward_weights, REWARD_TERMS))


def path_is_random(path: object) -> bool:
    """True for the name "random"."""
    return isinstance(path, str) and path == "random"


def path_from(path: object) -> Path | PathDistribution:
    """The `path` argument: a name, "random", a `Path`, a `PathDistribution`, a dict of its
    fields, a dict {"kind": name, **arguments} of one fixed path, or a list of (x, y, z)
    waypoints."""
    fixed = isinstance(path, Mapping) and "kind" in path
    if not fixed and (isinstance(path, (PathDistribution, Mapping)) or path_is_random(path)):
        return PathDistribution.from_spec(path)  # type: ignore[arg-type]
    try:
        return make_path(path)  # type: ignore[arg-type]
    except ValueError as error:
        if isinstance(path, str):  # the env also takes "random": list it with the others
            names, with_random = str(sorted(PATHS)), str(sorted([*PATHS, "random"]))
            raise ValueError(str(error).replace(names, with_random, 1)) from None
        raise


def start_rotation_from(value: object) -> float | tuple[float, float]:
    """`start_rotation` [rad] as a float in [−π, π], or a (low, high) range in it with
    low ≤ high (drawn per episode); else a one-line error naming it."""
    if is_real(value):
        return real("start_rotation", value, -math.pi, math.pi, unit="rad")
    low, high = vector("start_rotation", value, 2, -math.pi, math.pi, "rad")
    if low > high:
        raise ValueError(
            f"start_rotation must be a number or (low, high) with low <= high "
            f"[rad], got {(low, high)}"
        )
    return (low, high)
