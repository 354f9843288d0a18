"""`IncrementalActions`: the agent outputs increments of its command (``action_increment``).

The wrapper sits under `VecNormalize` (it reads the raw observation) and turns the agent's
Δ ∈ [−1, 1]³ into the env's command clip(a_prev + δ·Δ, −1, 1), with a_prev the previous
saturated action from each vehicle's last observation (0 after a reset; the new episode's
first observation after an autoreset): the transform a loaded agent applies
(`controllers.action_increment`), so training and evaluation see the same commands.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from stable_baselines3.common.vec_env import VecEnv

from benchmarks.training.observed_actions import ObservedActions
from controllers.action_increment import apply_increment, check_increment, prev_action_index

__all__ = ["IncrementalActions"]


class IncrementalActions(ObservedActions):
    """``venv`` whose actions are increments δ·Δ of the previous command (δ = `increment`)."""

    def __init__(self, venv: VecEnv, increment: float, obs_names: Sequence[str]) -> None:
        self.increment = check_increment(increment, "IncrementalActions")
        self.index = prev_action_index(obs_names)
        super().__init__(venv, obs_names)

    def step_async(self, actions: np.ndarray) -> None:
        self.venv.step_async(apply_increment(self.last_obs, actions, self.increment, self.index))
