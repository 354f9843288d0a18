"""Agents that command the change of their action (``action_increment`` in an agent's metadata).

A static policy a = π(o) holds the path where its output balances the plant; when the trim the
vehicle needs differs from the one it learned (another vehicle, a current, a climbing path), it
keeps a steady error (the 256-256 generalist: z_e = −0.22 m on the noise-free helix,
docs/results.md). An incremental agent outputs Δ ∈ [−1, 1]³ and the command becomes

    a_k = clip(a_{k−1} + δ·Δ_k, −1, 1)                                       (docs/design.md §3.14)

with a_{k−1} the previous saturated action, which the agent observation holds (a_X_prev,
a_M_prev, a_N_prev); δ [1 per control step] is the largest change per step. The command is an
integral of the agent's output, so a steady state needs Δ = 0 — at whatever command the plant
needs — and the policy stays stateless: it reads a_{k−1} from its observation, in training
(`benchmarks.training.action_increment`) and when loaded (`IncrementPolicy`) alike.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from controllers.actor_wrapper import ActorWrapper

__all__ = [
    "PREV_ACTION_NAMES",
    "IncrementPolicy",
    "apply_increment",
    "check_increment",
    "prev_action_index",
]

PREV_ACTION_NAMES = ("a_X_prev", "a_M_prev", "a_N_prev")


def check_increment(value: Any, where: str) -> float:
    """δ in (0, 2] [1 per control step] (2: any command is one step from any other)."""
    number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if not (number and math.isfinite(value) and 0.0 < value <= 2.0):
        raise ValueError(
            f"{where}: action_increment must be a number in (0, 2] (the largest change of a "
            f"normalised command per control step), got {value!r}"
        )
    return float(value)


def prev_action_index(obs_names: Sequence[str]) -> np.ndarray:
    """Positions of the previous action in an observation layout, or an error naming them."""
    names = list(obs_names)
    missing = [n for n in PREV_ACTION_NAMES if n not in names]
    if missing:
        raise ValueError(
            f"action_increment needs the previous action in the observation "
            f"({list(PREV_ACTION_NAMES)}; the agent observation, "
            f"observation='preview'), missing {missing}"
        )
    return np.array([names.index(n) for n in PREV_ACTION_NAMES], dtype=np.intp)


def apply_increment(
    observation: np.ndarray, delta: np.ndarray, increment: float, index: np.ndarray
) -> np.ndarray:
    """clip(a_prev + δ·Δ, −1, 1) as float32, for one observation (d,) or a batch (n, d)."""
    prev = np.asarray(observation, dtype=np.float32)[..., index]
    step = np.float32(increment) * np.asarray(delta, dtype=np.float32)
    return np.clip(prev + step, np.float32(-1.0), np.float32(1.0))


class IncrementPolicy(ActorWrapper):
    """A Policy whose actor outputs increments: the command a_prev + δ·Δ, saturated."""

    def __init__(self, actor: Any, increment: float, obs_names: Sequence[str]) -> None:
        super().__init__(actor)
        self.increment = check_increment(increment, "IncrementPolicy")
        self.index = prev_action_index(obs_names)

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """Commands in [−1, 1]³ for observations (d,) or (n, d) of the agent's layout."""
        delta, state = self.actor.predict(observation, state, episode_start, deterministic)
        return apply_increment(observation, delta, self.increment, self.index), state

    def __repr__(self) -> str:
        return f"IncrementPolicy(path={self.path!r}, increment={self.increment})"
