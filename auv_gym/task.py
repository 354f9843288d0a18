"""The path-following task on top of the physics: reward terms and episode termination.

Reward per control step (weights are constructor arguments of the envs):

    r = w_progress·min(u_p/u_D, 1)            progress of the virtual point (0 if the vehicle idles)
      + w_tracking·exp(−(d/d_0)²)             dense bonus for being on the path, d_0 = 1 m
      − w_distance·d/d_corridor               distance to the virtual point, normalised
      − w_speed·min(((u − u_D)/u_D)², 1)      surge-speed tracking
      − w_effort·|a|²/3                       normalised actuator effort
      − w_termination·[terminated by failure]  corridor, pitch, non-finite or envelope exit

Because the virtual point waits for a slow vehicle (MODEL.md §3.3), error penalties alone are
maximised by not moving; the progress and speed terms make idling cost about 1.5 per step while
following the path earns about 2 per step.
"""

from __future__ import annotations

import math
from dataclasses import astuple, dataclass

import numpy as np
from numba import njit

from auv_gym.observation import OBS_DIM

__all__ = ["REWARD_TERMS", "TERMINATION_REASONS", "RewardWeights", "TaskLimits", "task_row"]

REWARD_TERMS = ("progress", "tracking", "distance", "speed", "effort", "termination")
# Codes returned by `task_row`; 0 means "running".
TERMINATION_REASONS = ("", "corridor", "pitch", "non_finite", "envelope", "path_end")
CORRIDOR, PITCH, NON_FINITE, ENVELOPE, PATH_END = 1, 2, 3, 4, 5
TRACKING_SCALE = 1.0  # [m] d_0 of the tracking bonus


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the reward terms above (dimensionless)."""

    progress: float = 1.0
    tracking: float = 1.0
    distance: float = 1.0
    speed: float = 0.5
    effort: float = 0.05
    termination: float = 100.0

    def __post_init__(self) -> None:
        for name, value in zip(REWARD_TERMS, astuple(self), strict=True):
            if not math.isfinite(value):
                raise ValueError(f"reward weight {name} must be finite, got {value}")


@dataclass(frozen=True)
class TaskLimits:
    """Episode-end limits: the corridor [m] around the virtual point and the safe pitch [rad]."""

    corridor: float = 30.0  # [m] initial distance is 17.7 m in the paper scenario
    max_pitch: float = math.radians(60.0)  # [rad]
    s_end: float = math.inf  # path parameter at which the path ends

    def __post_init__(self) -> None:
        if not (math.isfinite(self.corridor) and self.corridor > 0):
            raise ValueError(f"corridor must be a positive distance in m, got {self.corridor}")
        if not (0 < self.max_pitch < math.pi / 2):
            raise ValueError(f"max_pitch must be in (0, π/2) rad, got {self.max_pitch}")


def task_vector(weights: RewardWeights, limits: TaskLimits) -> np.ndarray:
    """Pack weights and limits for `task_row`."""
    return np.array([*astuple(weights), limits.corridor, limits.max_pitch, limits.s_end])


@njit(cache=True, inline="always")
def task_row(state, guid, obs, action, obs_low, obs_high, task, out_terms):
    """Reward terms (into out_terms, layout `REWARD_TERMS`), total reward and termination code."""
    distance = guid[3]
    code = 0
    finite = True
    for j in range(state.shape[0]):
        if not math.isfinite(state[j]):
            finite = False
    if not finite:
        code = NON_FINITE
    elif distance > task[6]:
        code = CORRIDOR
    elif abs(state[3]) > task[7]:
        code = PITCH
    else:
        for j in range(OBS_DIM):
            if obs[j] < obs_low[j] or obs[j] > obs_high[j]:
                code = ENVELOPE
        if code == 0 and state[10] >= task[8]:
            code = PATH_END
    u_d = obs[11]
    if not finite:
        for j in range(5):
            out_terms[j] = 0.0
    else:
        out_terms[0] = task[0] * min(obs[12] / u_d, 1.0) if u_d > 0 else 0.0
        out_terms[1] = task[1] * math.exp(-((distance / TRACKING_SCALE) ** 2))
        out_terms[2] = -task[2] * distance / task[6]
        speed_err = (obs[6] - u_d) / u_d if u_d > 0 else obs[6]
        out_terms[3] = -task[3] * min(speed_err * speed_err, 1.0)
        out_terms[4] = -task[4] * (action[0] ** 2 + action[1] ** 2 + action[2] ** 2) / 3.0
    out_terms[5] = -task[5] if (code != 0 and code != PATH_END) else 0.0
    total = 0.0
    for j in range(6):
        total += out_terms[j]
    return total, code
