"""`ActionBox`: the agent acts in a sub-box of the env's normalised actions (``action_bounds``).

SB3 squashes a SAC agent's Gaussian into its action space and rescales it to the space's bounds;
giving the agent a narrower space than the env's [−1, 1]³ therefore narrows its exploration and
its commands to that box, and the space is saved in the model, so a loaded agent stays inside it
(`benchmarks.training.config`, key ``action_bounds``; `benchmarks.analysis.action_bounds`
measures boxes).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper

__all__ = ["ActionBox", "parse_action_bounds"]


class ActionBox(VecEnvWrapper):
    """``venv`` with the action space Box(low, high) ⊆ [−1, 1]³; actions pass through unchanged
    (an action outside the box is an error: an agent never produces one)."""

    def __init__(self, venv: VecEnv, low: Sequence[float], high: Sequence[float]) -> None:
        box = spaces.Box(np.asarray(low, np.float32), np.asarray(high, np.float32))
        outer = venv.action_space
        if not (np.all(box.low >= outer.low) and np.all(box.high <= outer.high)):
            raise ValueError(
                f"action box [{box.low}, {box.high}] is not inside the env's "
                f"[{outer.low}, {outer.high}]"
            )
        super().__init__(venv, action_space=box)

    def step_async(self, actions: np.ndarray) -> None:
        low, high = self.action_space.low, self.action_space.high
        outside = np.any((actions < low) | (actions > high), axis=-1)
        if np.any(outside):
            row = int(np.flatnonzero(outside)[0])
            raise ValueError(
                f"action {actions[row]!r} (vehicle {row}) is outside the agent's "
                f"box [{low}, {high}]"
            )
        self.venv.step_async(actions)

    def reset(self) -> np.ndarray:
        return self.venv.reset()

    def step_wait(self):  # SB3 VecEnvStepReturn
        return self.venv.step_wait()


def parse_action_bounds(value: Any, path: Path) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """[[low × 3], [high × 3]] inside [−1, 1] with low < high per axis, or a named error."""
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
