"""`ScaledActions`: the agent's outputs scaled per axis before the env (``action_scale``).

The agent acts in [−1, 1]³ (its action space is unchanged, so PPO's Gaussian and SAC's squash
work as before); the env receives k ⊙ clip(y, −1, 1), the transform a loaded agent applies
(`controllers.action_scale`), so training and evaluation see the same commands.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper

from controllers.action_scale import apply_scale, check_action_scale

__all__ = ["ScaledActions"]


class ScaledActions(VecEnvWrapper):
    """``venv`` whose commands are the agent's outputs times ``scale`` (k_X, k_M, k_N)."""

    def __init__(self, venv: VecEnv, scale: Sequence[float]) -> None:
        self.scale = check_action_scale(scale, "ScaledActions")
        super().__init__(venv)

    def step_async(self, actions: np.ndarray) -> None:
        self.venv.step_async(apply_scale(actions, self.scale))

    def reset(self) -> np.ndarray:
        return self.venv.reset()

    def step_wait(self):  # SB3 VecEnvStepReturn
        return self.venv.step_wait()
