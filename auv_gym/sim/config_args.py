"""The environments' arguments that become one `SimConfig` setting each: the white noise from
`disturbance` and `noise_hold`, the reward weights and the path (a fixed `Path` or a
`PathDistribution`); each bad value a one-line error naming it (docs/design.md §3).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from auv_gym.ocean.disturbances import MAX_NOISE_AMPLITUDE, MAX_NOISE_HOLD, NoiseConfig
from auv_gym.paths.shapes import PATHS, Path, make_path
from auv_gym.sim.path_generator import PathDistribution
from auv_gym.sim.task import REWARD_TERMS, RewardWeights
from auv_gym.support.validation import ArgumentTypeError, is_real, keys_within, real, vector

__all__ = [
    "DEFAULT_NOISE_HOLD",
    "DISTURBANCE_PRESETS",
    "noise_from",
    "path_from",
    "path_is_random",
    "reward_from",
    "start_rotation_from",
]

DISTURBANCE_PRESETS = {"paper": 35.0, "none": 0.0}
DEFAULT_NOISE_HOLD = 0.01  # [s]


def noise_from(disturbance: str | float | NoiseConfig, noise_hold: float | None) -> NoiseConfig:
    """The white noise of the `disturbance` and `noise_hold` arguments; a conflict is an error."""
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
    if isinstance(disturbance, str) and disturbance in DISTURBANCE_PRESETS:
        return NoiseConfig((DISTURBANCE_PRESETS[disturbance],) * 5, hold)
    if is_real(disturbance):
        amplitude = real(
            "disturbance (noise amplitude)", disturbance, 0.0, MAX_NOISE_AMPLITUDE, unit="N or N·m"
        )
        return NoiseConfig((amplitude,) * 5, hold)
    error = ValueError if isinstance(disturbance, str) else ArgumentTypeError
    names = sorted([*DISTURBANCE_PRESETS, "ocean"])
    raise error(
        f"unknown disturbance {disturbance!r:.80}; valid: {names}, "
        f"a NoiseConfig or an amplitude in [0, {MAX_NOISE_AMPLITUDE:g}] N / N·m"
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
