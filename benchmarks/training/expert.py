"""A classical controller as the expert of an agent: its commands in the agent's action space.

A jump start (`benchmarks.training.jump_start`) and the demonstrations of ``auv-gym demos``
(`benchmarks.training.demonstrations`) imitate a classical policy (`controllers.CLASSICAL`:
FBSM + CO-LOS on the paper's actuator, the as-built PID on propeller and fins, ...). The agent
does not command what the controller commands: its network's action passes its training stages
(`controllers.stages`) and its action box (``action_bounds``) before the env receives it. The
label of a state is therefore the controller's command expressed in the agent's action space,
the action the agent must output for the env to receive what the controller commanded:

- no stage, or the envelope guard: the env's command itself (the guard acts on whatever the
  agent outputs, in training and at inference alike, and is the identity inside its soft
  limits);
- the actuator allocation on the fin-limited actuator (the agent commands the paper's
  normalised τ, the env fins): the controller's normalised fin command a'_M times the fin
  authority K·δ_max·u|u| over M_max (and N alike), which the allocation maps back to a'_M;
- the action box: the command clipped to the box, then to the agent's action space [−1, 1]³.

The allocation onto the propeller and fins (``actuator="realistic"``) is not inverted: an agent
trained inside it is refused (its label would need the controller's τ before the controller's
own allocation). An agent that commands the propeller and fins itself (the as-built agent) needs
no inversion: its actions are the env's.

The expert keeps its own memory (integrators, adaptive fuzzy weights, command filters), so it
flies alongside the episode: every step it is given the observation of every vehicle, and its
memory restarts where an episode starts. It reads the paper's 15 observation entries, which
every agent observation begins with; the stages rewrite only the previous-action entries.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from controllers.stages import AllocationStage, build_stages

__all__ = ["ExpertLabels", "check_expert_name"]


def check_expert_name(name: Any, where: str) -> str:
    """``name`` if it names a classical controller (`controllers.CLASSICAL`), else a one-line
    ValueError naming ``where`` and the valid names."""
    from controllers import CLASSICAL

    if not isinstance(name, str) or name not in CLASSICAL:
        raise ValueError(
            f"{where}: expert {name!r} is not a classical controller; valid: {list(CLASSICAL)}"
        )
    return name


class ExpertLabels:
    """The classical controller ``name`` configured for the env of ``env_kwargs`` (the id's
    fixed arguments and the file's), labelling states in the action space of an agent observing
    ``obs_names`` with training ``stage_specs`` (checked specs) and ``action_bounds`` ((low,
    high) or None). Errors name ``where``."""

    def __init__(
        self,
        name: str,
        env_kwargs: Mapping[str, Any],
        obs_names: Sequence[str],
        stage_specs: Sequence[Mapping[str, Any]] = (),
        action_bounds: tuple[Sequence[float], Sequence[float]] | None = None,
        where: str = "expert",
    ) -> None:
        import controllers
        from controllers.env_settings import draws_actuator, policy_settings

        self.name = check_expert_name(name, where)
        settings = policy_settings(dict(env_kwargs))
        if draws_actuator(dict(env_kwargs)) and any(
            spec["name"] == "actuator_allocation" for spec in stage_specs
        ):
            raise ValueError(
                f"{where}: the agent trains inside the actuator allocation on actuators drawn "
                "per episode (actuator='random'), where the expert's labels would need each "
                "episode's draw; jump-start on one actuator and add a phase on 'random' after it"
            )
        self.policy = controllers.make(name, env=dict(env_kwargs))
        self.stages = build_stages(stage_specs, obs_names, settings, f"{where}: stages")
        self.allocation = None
        self.factors = None  # the allocation's observation factors: undone for the expert
        for stage in self.stages:
            if isinstance(stage, AllocationStage):
                if stage.allocation.actuator != "fins":
                    raise ValueError(
                        f"{where}: the agent trains inside the actuator allocation onto the "
                        f"{stage.allocation.actuator!r} actuator, whose commands the expert's "
                        "labels cannot be mapped back to (only 'fins' is inverted); train the "
                        "agent on that actuator's own commands (no allocation stage) instead"
                    )
                self.allocation = stage.allocation
                self.factors = stage.factors
        low, high = (-1.0, 1.0) if action_bounds is None else action_bounds
        self.low = np.broadcast_to(np.asarray(low, dtype=np.float32), (3,)).copy()
        self.high = np.broadcast_to(np.asarray(high, dtype=np.float32), (3,)).copy()
        self.state: Any = None
        self.rows = -1

    def label(self, observation: np.ndarray, episode_start: np.ndarray) -> np.ndarray:
        """The agent's actions (float32, (n, 3)) for the raw observations (n, d) the agent sees;
        ``episode_start`` (bool, (n,)) restarts the expert's memory of those rows. The expert's
        memory advances by one control step."""
        obs = np.atleast_2d(np.asarray(observation))
        starts = np.asarray(episode_start, dtype=bool).reshape(obs.shape[0])
        if obs.shape[0] != self.rows:  # another batch of vehicles: fresh memory
            self.state, self.rows = None, obs.shape[0]
        # the expert reads the errors the vehicle has, unscaled
        flown = obs if self.factors is None else self.factors.removed(obs)
        command, self.state = self.policy.predict(flown, self.state, starts, True)
        return self.to_agent(np.atleast_2d(command), obs)

    def to_agent(self, command: np.ndarray, observation: np.ndarray) -> np.ndarray:
        """The env's commands (n, 3) as the agent's actions at the observations (n, d)."""
        action = np.array(command, dtype=np.float64)
        if self.allocation is not None:  # fins: a'·K·δ_max·u|u| / τ_max in the paper's units
            from controllers.allocation import fin_authority

            u = np.atleast_2d(observation)[:, self.allocation.velocity_index[0]]
            authority = fin_authority(self.allocation.fin_gain, u.astype(np.float64))
            action[:, 1:] *= authority[:, None] / self.allocation.limits[1:]
        action = np.clip(action, -1.0, 1.0)
        return np.clip(action, self.low, self.high).astype(np.float32)
