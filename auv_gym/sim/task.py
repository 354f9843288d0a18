"""The path-following task on top of the physics: reward terms and episode termination.

Reward per control step (weights are constructor arguments of the envs):

    r = w_progress·min(u_p/u_D, 1)            progress of the virtual point (0 if the vehicle idles)
      + w_tracking·exp(−(d/d_0)²)             dense bonus for being on the path, d_0 = 1 m
      − w_distance·d/d_corridor               distance to the virtual point, normalised
      − w_speed·min(((u − u_D)/u_D)², 1)      surge-speed tracking
      − w_overspeed·min(max(u − u_D, 0)/(u_max − u_D), 1)²   approaching the surge limit u_max
      − w_effort·|a|²/3                       normalised actuator effort
      + w_precision·exp(−(d/d_P)²)            precision bonus, d_P = 0.1 m (0 by default)
      − w_termination·[terminated by failure]  corridor, pitch, non-finite, envelope exit,
                                              broached or grounded (`depth_envelope`)

Because the virtual point waits for a slow vehicle (docs/model.md §3.3), error penalties alone are
maximised by not moving; the progress and speed terms make idling cost about 1.5 per step while
following the path earns about 2 per step.

Surge limit (`TaskLimits.surge_limit` u_max, the env argument `surge_limit`): the speed term is
capped at u = 2u_D, so without a limit an agent may sprint (4.5 m/s seen, a REMUS 100 tops out
near 2.3-2.5 m/s). With a finite u_max the overspeed term grows from 0 at u_D to w_overspeed at
u_max and u > u_max ends the episode as "overspeed", a failure (docs/design.md §3). With
u_max = inf (the `AUVPath3D-v0` default) the term is exactly −0.0 and nothing terminates, so v0
rewards are unchanged bit for bit; `AUVPath3DSpeedLimit-v0` (and `AUVPath3DPreview-v0`) set
``surge_limit="vehicle"`` (`VEHICLE_TOP_SPEED`): u_max is the vehicle record's top speed
`AUVParams.max_surge`, 2.0 m/s for REMUS 100 (`REMUS_TOP_SPEED`).
"""

from __future__ import annotations

import math
from dataclasses import astuple, dataclass

import numpy as np
from numba import njit

from auv_gym.sim.observation import ERROR_BOUND, GUIDE, OBS, OBS_DIM
from auv_gym.sim.safety_cost import SAFETY_FIELDS, SafetyCost, safety_cost, safety_vector
from auv_gym.support.records import field_indices, fixed_tuple, record_type
from auv_gym.support.validation import is_real, real
from auv_gym.vehicle.dynamics import STATE
from auv_gym.vehicle.params import AUVParams

__all__ = [
    "REWARD_TERMS",
    "TASK_FIELDS",
    "TERM",
    "TERMINATION_REASONS",
    "RewardWeights",
    "TaskLimits",
    "task_cost",
    "task_row",
    "task_vector",
]

REWARD_TERMS = (
    "progress",
    "tracking",
    "distance",
    "speed",
    "overspeed",
    "effort",
    "precision",
    "termination",
)
N_TERMS = len(REWARD_TERMS)
TERM = field_indices("RewardTermIndex", REWARD_TERMS, __name__)
# Layout of `task_vector`: the weights w_<term>, then the episode limits [m, rad, -, m/s], then
# the depth envelope and the safety cost (`safety_cost.SAFETY_FIELDS`).
TASK_FIELDS = (
    *(f"w_{name}" for name in REWARD_TERMS),
    "corridor",
    "max_pitch",
    "s_end",
    "surge_limit",
    *SAFETY_FIELDS,
)
TASK_DIM = len(TASK_FIELDS)
TaskRecord = record_type("TaskRecord", TASK_FIELDS, __name__)
# Codes returned by `task_row`; 0 means "running".
TERMINATION_REASONS = (
    "",
    "corridor",
    "pitch",
    "non_finite",
    "envelope",
    "path_end",
    "overspeed",
    "broached",
    "grounded",
)
CORRIDOR, PITCH, NON_FINITE, ENVELOPE, PATH_END, OVERSPEED = 1, 2, 3, 4, 5, 6
BROACHED, GROUNDED = 7, 8  # above the sea surface, below the seabed (`depth_envelope`)
TRACKING_SCALE = 1.0  # [m] d_0 of the tracking bonus
# [m] d_P of the precision bonus: the tracking bonus's slope at d = 5 cm is only 0.1 w_tracking
# per metre; this one's is 3.9 w_precision per metre (docs/design.md §3.12)
PRECISION_SCALE = 0.1
# The `surge_limit` argument that means "the vehicle's top speed" (`AUVParams.max_surge`).
VEHICLE_TOP_SPEED = "vehicle"
# [m/s] u_max of AUVPath3DSpeedLimit-v0 with REMUS 100, the default vehicle
REMUS_TOP_SPEED = AUVParams().max_surge
# Documented ranges. Bounded weights and a corridor of at least 1 cm keep every reward finite
# (the observation is bounded by the float32 range or the episode ends as "non_finite"); a
# corridor inside the observation's ±ERROR_BOUND keeps a running vehicle's errors in bounds.
MAX_REWARD_WEIGHT = 1e6
MIN_CORRIDOR = 0.01  # [m]
FLOAT32_MAX = float(np.finfo(np.float32).max)  # observations are returned as float32


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the reward terms above (dimensionless)."""

    progress: float = 1.0
    tracking: float = 1.0
    distance: float = 1.0
    speed: float = 0.5
    overspeed: float = 1.0  # acts only with a finite surge_limit (AUVPath3DSpeedLimit-v0)
    effort: float = 0.05
    precision: float = 0.0  # off by default: v0's rewards are unchanged (+0.0)
    termination: float = 100.0

    def __post_init__(self) -> None:
        for name in REWARD_TERMS:  # the formula gives each term its sign; weights are magnitudes
            value = real(f"reward weight {name}", getattr(self, name), 0.0, MAX_REWARD_WEIGHT)
            object.__setattr__(self, name, value)


@dataclass(frozen=True)
class TaskLimits:
    """Episode-end limits: the corridor [m] around the virtual point, the safe pitch [rad] and
    the surge limit u_max [m/s] (inf: none)."""

    corridor: float = 30.0  # [m] initial distance is 17.7 m in the paper scenario
    max_pitch: float = math.radians(60.0)  # [rad]
    s_end: float = math.inf  # path parameter at which the path ends
    surge_limit: float = math.inf  # [m/s] u_max; inf: no limit (AUVPath3D-v0)

    def __post_init__(self) -> None:
        corridor = real("corridor", self.corridor, MIN_CORRIDOR, ERROR_BOUND, unit="m")
        max_pitch = real(
            "max_pitch", self.max_pitch, 0.0, math.pi / 2, low_open=True, high_open=True, unit="rad"
        )
        if not (is_real(self.s_end) and self.s_end > 0):  # math.inf: an endless path
            raise ValueError(f"s_end must be a positive path parameter or inf, got {self.s_end!r}")
        object.__setattr__(self, "corridor", corridor)
        object.__setattr__(self, "max_pitch", max_pitch)
        object.__setattr__(self, "s_end", float(self.s_end))
        if not (is_real(self.surge_limit) and self.surge_limit > 0):
            raise ValueError(
                f"surge_limit must be a positive speed in m/s or inf, got {self.surge_limit!r:.80}"
            )
        object.__setattr__(self, "surge_limit", float(self.surge_limit))


def task_vector(
    weights: RewardWeights, limits: TaskLimits, safety: np.ndarray | None = None
) -> np.ndarray:
    """Pack weights, limits and the `safety_cost.safety_vector` (default: no depth envelope,
    the default cost) into the row `task_row` reads (layout `TASK_FIELDS`)."""
    if safety is None:
        safety = safety_vector(None, SafetyCost())
    return np.array(
        [
            *astuple(weights),
            limits.corridor,
            limits.max_pitch,
            limits.s_end,
            limits.surge_limit,
            *safety,
        ]
    )


@njit(cache=True, inline="always")
def task_record(task):
    """The packed task row as a `TaskRecord` held in registers."""
    return TaskRecord(*fixed_tuple(task, TASK_DIM))


@njit(cache=True, inline="always")
def task_row(st, guid, obs, action, obs_low, obs_high, task, out_terms):
    """Reward terms (into ``out_terms``, layout `TERM`), total reward and termination code.

    ``st`` is the simulator state (layout `dynamics.STATE`), ``guid`` its guidance row and
    ``obs`` its observation (`observation.GUIDE`, `observation.OBS`), ``action`` the saturated
    action, ``task`` the row of `task_vector`.
    """
    t = task_record(task)
    distance = guid[GUIDE.distance]
    code = 0
    finite = True
    for j in range(st.shape[0]):
        if not math.isfinite(st[j]):
            finite = False
    for j in range(OBS_DIM):  # NaN, inf or beyond float32: the env could not return it finite
        if not abs(obs[j]) <= FLOAT32_MAX:
            finite = False
    if not finite:
        code = NON_FINITE
    elif st[STATE.z] < t.surface_z:  # −inf without a depth envelope: never
        code = BROACHED
    elif st[STATE.z] > t.seabed_z:
        code = GROUNDED
    elif distance > t.corridor:
        code = CORRIDOR
    elif abs(st[STATE.theta]) > t.max_pitch:
        code = PITCH
    else:
        for j in range(OBS_DIM):
            if obs[j] < obs_low[j] or obs[j] > obs_high[j]:
                code = ENVELOPE
        if code == 0 and st[STATE.s] >= t.s_end:
            code = PATH_END
    u_d, u = obs[OBS.u_D], obs[OBS.u]
    if code == 0 and u > t.surge_limit:
        code = OVERSPEED
    if not finite:
        out_terms[TERM.progress] = out_terms[TERM.tracking] = out_terms[TERM.distance] = 0.0
        out_terms[TERM.speed] = out_terms[TERM.overspeed] = out_terms[TERM.effort] = 0.0
        out_terms[TERM.precision] = 0.0
    else:
        out_terms[TERM.progress] = t.w_progress * min(obs[OBS.u_p] / u_d, 1.0) if u_d > 0 else 0.0
        out_terms[TERM.tracking] = t.w_tracking * math.exp(-((distance / TRACKING_SCALE) ** 2))
        out_terms[TERM.distance] = -t.w_distance * distance / t.corridor
        speed_err = (u - u_d) / u_d if u_d > 0 else u
        out_terms[TERM.speed] = -t.w_speed * min(speed_err * speed_err, 1.0)
        # (u − u_D)/inf = 0 without a limit: the term is −0.0 and the total is unchanged
        excess = min(max(u - u_d, 0.0) / (t.surge_limit - u_d), 1.0)
        out_terms[TERM.overspeed] = -t.w_overspeed * excess * excess
        effort = action[0] ** 2 + action[1] ** 2 + action[2] ** 2
        out_terms[TERM.effort] = -t.w_effort * effort / 3.0
        out_terms[TERM.precision] = t.w_precision * math.exp(-((distance / PRECISION_SCALE) ** 2))
    failed = code != 0 and code != PATH_END
    out_terms[TERM.termination] = -t.w_termination if failed else 0.0
    total = 0.0
    for j in range(N_TERMS):
        total += out_terms[j]
    return total, code


@njit(cache=True, inline="always")
def task_cost(st, task):
    """The safety cost of the state ``st`` after a step (`safety_cost.safety_cost`) [-]."""
    t = task_record(task)
    return safety_cost(
        st[STATE.z],
        st[STATE.u],
        st[STATE.theta],
        t.surface_z,
        t.seabed_z,
        t.depth_margin,
        t.cost_w_depth,
        t.cost_w_speed,
        t.cost_w_pitch,
        t.cost_speed_limit,
        t.cost_pitch_limit,
    )
