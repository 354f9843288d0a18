"""Actuator allocation for agents: an agent's moment commands flown on fins or propeller and fins.

An agent trained on the paper's actuator commands generalised forces: a = τ/τ_max with
τ_max = (X_max, M_max, N_max) the vehicle's limits (REMUS 100: 50 N, 10 N·m, 10 N·m). On
another actuator the same numbers mean something else: with the fin-limited moments ("fins",
docs/model.md §2.3) a_M is a fin deflection whose moment is K·δ_max·u|u|·a_M (3.2 N·m at
1 m/s), with the realistic propeller and fins ("realistic", §2.6) a shaft speed and two fin
angles. A classical controller is told its vehicle's actuator and allocates its τ_d to it
(`controllers.base.BatchedController._allocate`); `Allocation` does the same for an agent:

    τ_d = a·τ_max                                            (the agent's command, N and N·m)
    fins:      a'_M = clip(M_d / (K·δ_max·u|u|), −1, 1), a'_N alike; the sign at u ≤ 0
    realistic: (n, δ_s, δ_r) = `controllers.allocation.allocate` of τ_d with M_d, N_d clipped
               to ±K·δ_max·u|u|, at the observed (u, v, w)

and feeds the agent, in its previous-action entries (a_X_prev, a_M_prev, a_N_prev), the command
it gave as far as the actuator could deliver it, a_prev = (a_X, clip(a_M, ±K·δ_max·u|u|/M_max),
clip(a_N, ±K·δ_max·u|u|/N_max)), instead of the fin or shaft commands it has never seen: the
agent then meets the vehicle it was trained on with less moment authority. On the paper's
actuator the allocation is the identity and the loader does not add it.

It is a stage of an agent (`controllers.stages`: ``{"name": "actuator_allocation", "commands":
"paper"}``, the actuator whose normalised τ it commands), built for the scenario's actuator. An
env that draws the actuator per episode (``actuator="random"``) tells no actuator, and the agent
runs unallocated there; in training on one, the allocation follows each episode's draw
(`controllers.stages.DrawnAllocationStage`; docs/design.md §3.16).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from auv_gym.vehicle import AUVParams, remus100
from auv_gym.vehicle.actuators import ActuatorParams, actuator_params_from_spec
from controllers.allocation import allocate, fin_angle, fin_authority
from controllers.base import actuator_vector

__all__ = [
    "ALLOCATED_ACTUATORS",
    "COMMANDED_ACTUATOR",
    "Allocation",
    "check_actuator_allocation",
]

COMMANDED_ACTUATOR = "paper"  # the one actuator whose normalised τ an agent may command
ALLOCATED_ACTUATORS = ("fins", "realistic")  # the actuators `Allocation` flies
VELOCITY_INPUTS = ("u", "v", "w")  # [m/s] the observation entries the allocation reads
PREV_ACTION_NAMES = ("a_X_prev", "a_M_prev", "a_N_prev")  # where it feeds the delivered command


def check_actuator_allocation(value: Any, where: str) -> str:
    """The commanded actuator of an agent's ``actuator_allocation`` ("paper"), or a one-line
    error naming ``where``."""
    if value != COMMANDED_ACTUATOR:
        raise ValueError(
            f"{where}: actuator_allocation must be {COMMANDED_ACTUATOR!r} (the "
            f"actuator whose normalised τ the agent commands), "
            f"got {value!r}"
        )
    return value


def prev_action_index(obs_names: Sequence[str]) -> np.ndarray:
    """Positions of the previous action in an observation layout, or an error naming them."""
    names = list(obs_names)
    missing = [n for n in PREV_ACTION_NAMES if n not in names]
    if missing:
        raise ValueError(
            f"actuator_allocation needs the previous action in the observation "
            f"({list(PREV_ACTION_NAMES)}; the agent observation, "
            f"observation='preview'), missing {missing}"
        )
    return np.array([names.index(n) for n in PREV_ACTION_NAMES], dtype=np.intp)


class Allocation:
    """The allocation of an agent's commands (the paper actuator's normalised τ) to
    ``actuator`` ("fins" or "realistic"; module docstring), for an agent observing
    ``obs_names``; errors name ``where``."""

    def __init__(
        self,
        obs_names: Sequence[str],
        actuator: str,
        params: AUVParams | None = None,
        actuator_params: ActuatorParams | dict | None = None,
        where: str = "actuator_allocation",
    ) -> None:
        if actuator not in ALLOCATED_ACTUATORS:
            raise ValueError(
                f"{where}: the allocation flies {list(ALLOCATED_ACTUATORS)}, got "
                f"actuator {actuator!r}"
            )
        names = list(obs_names)
        missing = [name for name in VELOCITY_INPUTS if name not in names]
        if missing:
            raise ValueError(
                f"{where}: actuator_allocation reads {list(VELOCITY_INPUTS)} from the "
                f"agent's observation, which lacks {missing}"
            )
        self.velocity_index = np.array([names.index(n) for n in VELOCITY_INPUTS])
        try:
            self.previous_index = prev_action_index(names)
        except ValueError as error:
            raise ValueError(f"{where}: {error}") from None
        self.actuator = actuator
        self.actuator_params = actuator_params_from_spec(actuator_params)
        vehicle = params if params is not None else remus100()
        _, self.fin_gain, *limits = actuator_vector(actuator, vehicle, self.actuator_params)
        self.limits = np.array(limits, dtype=np.float64)  # (X_max [N], M_max, N_max [N·m])

    def allocate(
        self, commands: np.ndarray, observation: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """(the actuator's commands, the delivered command in the agent's units), both float32
        (n, 3), for the agent's commands (n, 3) at the observations (n, d) it saw."""
        a = np.clip(np.atleast_2d(np.asarray(commands, dtype=np.float64)), -1.0, 1.0)
        velocity = np.atleast_2d(observation)[:, self.velocity_index].astype(np.float64)
        authority = fin_authority(self.fin_gain, velocity[:, 0])  # [N·m]
        moments = a[:, 1:] * self.limits[1:]  # [N·m] M_d, N_d
        delivered = np.clip(moments, -authority[:, None], authority[:, None])
        previous = np.column_stack([a[:, 0], delivered / self.limits[1:]]).astype(np.float32)
        if self.actuator == "fins":  # a normalised deflection; the sign where there is no flow
            out = np.column_stack([a[:, 0], fin_angle(moments, authority[:, None], 1.0, 1.0)])
        else:
            tau = np.column_stack([a[:, 0] * self.limits[0], delivered])
            out = allocate(tau, velocity, self.actuator_params)
        return out.astype(np.float32), previous
