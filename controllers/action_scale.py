"""Agents whose outputs are scaled per axis (``action_scale`` in an agent's metadata).

The env's normalised surge command spans ±50 N, but a REMUS 100 cruises at 1 m/s on about
1.6 N (3 % of the range) and reaches the 2.0 m/s surge limit near 7.5 N (15 %): a policy acting
on the whole range must resolve its cruise thrust to a few thousandths, and Gaussian exploration
of σ ≈ 0.2 swings the thrust by ±10 N. A scaled agent outputs y ∈ [−1, 1]³ and commands

    a = k ⊙ clip(y, −1, 1),    k ∈ (0, 1]³                                  (docs/design.md §3.14)

so with k_X = 0.15 its full output spans ±7.5 N. The transform is the same in training
(`benchmarks.training.action_scale`) and when loaded (`ScaledPolicy`), and it is part of the
agent (recorded in its metadata), like its observation statistics.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from controllers.actor_wrapper import ActorWrapper

__all__ = ["ScaledPolicy", "apply_scale", "check_action_scale"]


def check_action_scale(value: Any, where: str) -> tuple[float, float, float]:
    """(k_X, k_M, k_N), each a number in (0, 1], or a one-line error naming ``where``."""
    try:
        scale = tuple(value)
        ok = len(scale) == 3 and all(
            isinstance(k, (int, float))
            and not isinstance(k, bool)
            and math.isfinite(k)
            and 0.0 < k <= 1.0
            for k in scale
        )
    except TypeError:
        ok = False
    if not ok:
        raise ValueError(
            f"{where}: action_scale must be three numbers in (0, 1] (the fraction of the env's "
            f"normalised X, M, N range the agent's output spans), got {value!r}"
        )
    return tuple(float(k) for k in scale)  # type: ignore[return-value]


def apply_scale(action: np.ndarray, scale: tuple[float, float, float]) -> np.ndarray:
    """k ⊙ clip(y, −1, 1) as float32, for one action (3,) or a batch (n, 3)."""
    y = np.clip(np.asarray(action, dtype=np.float32), np.float32(-1.0), np.float32(1.0))
    return y * np.asarray(scale, dtype=np.float32)


class ScaledPolicy(ActorWrapper):
    """A Policy whose actor's outputs are scaled per axis: the command k ⊙ clip(y, −1, 1)."""

    def __init__(self, actor: Any, scale: Any) -> None:
        super().__init__(actor)
        self.scale = check_action_scale(scale, "ScaledPolicy")

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """Commands in [−k, k] for observations (d,) or (n, d) of the agent's layout."""
        output, state = self.actor.predict(observation, state, episode_start, deterministic)
        return apply_scale(output, self.scale), state

    def __repr__(self) -> str:
        return f"ScaledPolicy(path={self.path!r}, scale={list(self.scale)})"
