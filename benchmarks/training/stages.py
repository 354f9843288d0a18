"""`StagedActions`: the env's commands pass the agent's stages in training, as they do at
inference (`controllers.stages`: the same `Stage` objects, the same arithmetic).

The wrapper sits under `VecNormalize`, innermost of the action wrappers: the network's action
goes through every stage (the envelope guard, the actuator allocation) to the command the env
receives, and what the network observes is the stages' view of the raw observation (the
allocation feeds back the command the actuator delivered). ``last_obs`` is that view of each
vehicle's last observation (the new episode's first after an autoreset) and ``memories`` the
stages' per-vehicle state; a resumed run restores both (`checkpoints`). A stage that follows
each episode's drawn actuator (`controllers.stages.DrawnAllocationStage`) is told the draw of
every vehicle whose episode starts, read from the env (``get_attr("actuator")``).

An allocation with ``observation_factors`` scales entries of what the network sees on its
actuator; the final observation of an episode that ends (``terminal_observation``, from which
PPO and SAC bootstrap a truncated episode's value) is scaled alike, so the critic values the
states it is trained on. The allocation's fed-back command is not put into final observations
(the recipes trained before the factors bootstrap from the env's own previous action).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper

from controllers.stages import (
    AllocationStage,
    DrawnAllocationStage,
    Stage,
    apply_stages,
    observe_stages,
)

__all__ = ["StagedActions"]


class StagedActions(VecEnvWrapper):
    """``venv`` whose actions pass ``stages`` (in order) and whose observations their view."""

    def __init__(self, venv: VecEnv, stages: Sequence[Stage], obs_dim: int) -> None:
        super().__init__(venv)
        self.stages = list(stages)
        self.memories = [stage.start(venv.num_envs) for stage in self.stages]
        self.last_obs = np.zeros((venv.num_envs, obs_dim), np.float32)
        # the stages told each starting episode's drawn actuator (found once: step is hot)
        self.drawn = [
            k for k, stage in enumerate(self.stages) if isinstance(stage, DrawnAllocationStage)
        ]
        self.factored = [
            k
            for k, stage in enumerate(self.stages)
            if isinstance(stage, AllocationStage) and stage.factors is not None
        ]

    def _seen(self, obs: np.ndarray) -> np.ndarray:
        seen = observe_stages(self.stages, obs, self.memories)
        self.last_obs = np.array(seen, dtype=np.float32)
        return seen

    def _tell_drawn(self, rows: np.ndarray) -> None:
        """Each drawn-actuator stage learns the actuators of the episodes starting at ``rows``."""
        if self.drawn and rows.any():
            actuators = self.venv.get_attr("actuator")
            for k in self.drawn:
                self.stages[k].set_drawn(self.memories[k], rows, actuators)

    def reset(self) -> np.ndarray:
        obs = self.venv.reset()
        self.memories = [stage.start(self.num_envs) for stage in self.stages]
        self._tell_drawn(np.ones(self.num_envs, dtype=bool))
        return self._seen(obs)

    def step_async(self, actions: np.ndarray) -> None:
        self.venv.step_async(apply_stages(self.stages, actions, self.last_obs, self.memories))

    def step_wait(self):  # SB3 VecEnvStepReturn
        obs, rewards, dones, infos = self.venv.step_wait()
        starts = np.asarray(dones, dtype=bool)  # autoreset: these rows begin a new episode
        if self.factored and starts.any():
            self._scale_final(starts, infos)
        for stage, memory in zip(self.stages, self.memories, strict=True):
            stage.restart(memory, starts)
        self._tell_drawn(starts)
        return self._seen(obs), rewards, dones, infos

    def _scale_final(self, ended: np.ndarray, infos: Sequence[dict]) -> None:
        """The observation factors applied to the final observations of the episodes that
        ended (``ended``: bool, (n,)) on the allocated actuator, in ``infos`` in place; before
        the memories restart (a drawn stage's memory still holds the ended episode's draw)."""
        for i in np.flatnonzero(ended):  # once per ended episode, not per step
            final = infos[i].get("terminal_observation")
            if final is None:
                continue
            for k in self.factored:
                stage, memory = self.stages[k], self.memories[k]
                if isinstance(stage, DrawnAllocationStage) and memory[i, 3] <= 0.5:
                    continue  # the ended episode flew the paper's actuator: nothing to scale
                final = stage.factors.apply(np.array(final, dtype=np.float32))
            infos[i]["terminal_observation"] = final
