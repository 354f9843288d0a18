"""`GuardedActions`: the env's commands pass the agent's envelope guard (``envelope_guard``).

The wrapper sits under `VecNormalize` (it reads θ, q and u from the raw observation each vehicle
last returned: the new episode's first one after an autoreset) and limits the commands as a
loaded guarded agent does (`controllers.envelope_guard`), so training and evaluation see the
same commands. It is the innermost action wrapper: the guard acts on the command the env
receives.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from stable_baselines3.common.vec_env import VecEnv

from benchmarks.training.observed_actions import ObservedActions
from controllers.envelope_guard import GUARD_INPUTS, EnvelopeGuard, guard_commands

__all__ = ["GuardedActions"]


class GuardedActions(ObservedActions):
    """``venv`` whose commands are limited by ``guard`` near the pitch and surge limits."""

    def __init__(self, venv: VecEnv, guard: EnvelopeGuard, obs_names: Sequence[str]) -> None:
        missing = [name for name in GUARD_INPUTS if name not in obs_names]
        if missing:
            raise ValueError(
                f"envelope_guard reads {list(GUARD_INPUTS)} from the observation, "
                f"which lacks {missing}"
            )
        self.guard = guard
        self.index = tuple(list(obs_names).index(name) for name in GUARD_INPUTS)
        super().__init__(venv, obs_names)

    def step_async(self, actions: np.ndarray) -> None:
        self.venv.step_async(guard_commands(actions, self.last_obs, self.index, self.guard))
