"""The checks both environments make at their boundary: an action batch of real numbers of the
right shape (`validate_actions`), and reset observations inside the observation space
(`check_reset_observations`). Also importable from `auv_gym.envs.env`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from auv_gym.sim.observation import SPEED_BOUND, ObservationConfig
from auv_gym.support.validation import ArgumentTypeError

__all__ = ["check_reset_observations", "validate_actions"]


def validate_actions(action: Any, shape: tuple[int, ...]) -> np.ndarray:
    """float64 array of real numbers of the given shape, or a named error.

    Strings, booleans, complex numbers and objects raise `ArgumentTypeError` (a TypeError), a
    wrong shape ValueError; non-finite values are rejected by `Simulator.step`, inside the
    compiled kernel, before any vehicle moves.
    """
    try:
        a = np.asarray(action)
    except (TypeError, ValueError):  # ragged nesting
        a = np.asarray(None)
    if a.dtype.kind not in "iuf":
        raise ArgumentTypeError(
            f"action must be an array of real numbers, got dtype {a.dtype}: {action!r:.80}"
        )
    if a.shape != shape:
        raise ValueError(f"action must have shape {shape}, got {a.shape}")
    return a.astype(np.float64, copy=False)


def check_reset_observations(
    obs: np.ndarray,
    rows: Sequence[int] | np.ndarray,
    layout: ObservationConfig | None = None,
    current_speed: float = 0.0,
    speed_bound: float = SPEED_BOUND,
) -> None:
    """Raise ValueError, naming the component, if a reset observation (float32, one row per
    vehicle, ``layout`` default: the paper's; ``current_speed``, ``speed_bound``: see
    `ObservationConfig.bounds`) lies outside the observation space; the
    configuration checks make this unreachable for the built-in paths, so it guards what they
    cannot see (a spline between its samples)."""
    layout = layout or ObservationConfig()
    low, high = layout.bounds(current_speed, speed_bound)
    outside = ~((obs >= low) & (obs <= high))  # NaN counts as outside
    if outside.any():
        i, j = np.argwhere(outside)[0]
        name = layout.names[j]
        raise ValueError(
            f"reset gave {name} = {obs[i, j]:.6g} {layout.units[name]} (vehicle {rows[i]}), "
            f"outside the observation space [{low[j]:.6g}, {high[j]:.6g}]: the start "
            "(start_position, start_heading, randomize_start) or the path (its turn rate at "
            "u_p <= 2 u_desired) does not fit the observation bounds"
        )
