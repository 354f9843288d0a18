"""`CostPenalty`: the env's safety cost charged in the training reward (``cost_penalty`` w).

Each vehicle's reward becomes r − w·c, with c its per-step safety cost ``info["cost"]``
(`auv_gym.safety_cost`, docs/model.md §12: pitch beyond 45°, surge above 2 m/s, intrusion into a
depth margin; 0 inside every soft limit). The episode ends at 60° of pitch and, on the
surge-limited ids, at 2 m/s: the termination penalty says so once, when it is too late to
recover, while the cost grows from the soft limit on, so the policy meets a slope before the
cliff. The wrapper sits under `VecNormalize` (which then normalises the charged reward); it
changes training only: the env's own reward, its metrics and a loaded agent are unchanged.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper

from auv_gym.validation import real

__all__ = ["MAX_COST_PENALTY", "CostPenalty", "check_cost_penalty"]

MAX_COST_PENALTY = 1e6


def check_cost_penalty(value: Any, where: str) -> float:
    """w as a float in [0, 1e6]; an error naming ``where`` and the value otherwise
    (`auv_gym.validation.real`)."""
    return real(
        f"{where}: cost_penalty",
        value,
        0.0,
        MAX_COST_PENALTY,
        unit="(reward per unit of safety cost)",
    )


class CostPenalty(VecEnvWrapper):
    """``venv`` whose rewards are charged ``weight`` per unit of the safety cost."""

    def __init__(self, venv: VecEnv, weight: float) -> None:
        self.weight = check_cost_penalty(weight, "CostPenalty")
        super().__init__(venv)

    def reset(self) -> np.ndarray:
        return self.venv.reset()

    def step_wait(self):  # SB3 VecEnvStepReturn
        obs, rewards, dones, infos = self.venv.step_wait()
        try:  # the native env (`auv_gym.sb3`) keeps it as an array, whatever its info dicts
            cost = np.asarray(self.venv.step_cost, dtype=np.float64)
        except AttributeError:  # SB3's own VecEnvs: the single envs' info dicts
            cost = np.array([info["cost"] for info in infos], dtype=np.float64)
        charged = (rewards - self.weight * cost).astype(rewards.dtype, copy=False)
        return obs, charged, dones, infos
