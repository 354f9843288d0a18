"""`ObservedActions`: the base of action wrappers that act on each vehicle's last raw observation
(the envelope guard). It sits under `VecNormalize` and keeps ``last_obs``: the observation each
vehicle last returned (the new episode's first one after an autoreset), which a resumed run restores
(`checkpoints`)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper

__all__ = ["ObservedActions"]


class ObservedActions(VecEnvWrapper):
    """``venv`` that records its last raw observations; subclasses define `step_async`."""

    def __init__(self, venv: VecEnv, obs_names: Sequence[str]) -> None:
        super().__init__(venv)
        self.last_obs = np.zeros((venv.num_envs, len(obs_names)), np.float32)

    def reset(self) -> np.ndarray:
        obs = self.venv.reset()
        self.last_obs = np.array(obs, dtype=np.float32)
        return obs

    def step_wait(self):  # SB3 VecEnvStepReturn
        obs, rewards, dones, infos = self.venv.step_wait()
        self.last_obs = np.array(obs, dtype=np.float32)
        return obs, rewards, dones, infos
