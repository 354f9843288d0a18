"""A recorded episode (`Trajectory`): its field layout, units, episode ends and .npz file.

Time base. Control step k runs from t_k = k·control_dt to t_{k+1}. A trajectory of K steps holds

* K + 1 **samples** (`SAMPLE_FIELDS`) at t_0 … t_K: the state and guidance after each step,
  starting with the reset state, and the virtual point p(s);
* K **intervals** (`INTERVAL_FIELDS`) belonging to [t_k, t_{k+1}): the action the policy
  returned at t_k, the applied τ and the disturbance averaged over the period, the reward;
* optional **extras** of the same length K from the policy's diagnostics (`auv_gym.rollout`).

Units (SI): positions x, y, z, x_e, y_e, z_e, distance, x_p, y_p, z_p [m]; θ, ψ, ψ_F, θ_F
[rad]; u, v, w, u_p [m/s]; q, r, ψ̇_F, θ̇_F [rad/s]; path parameter s [-], ṡ [1/s]; actions
a_X, a_M, a_N [-] in [−1, 1]; τ = (X [N], M [N·m], N [N·m]); disturbance f_u, f_v, f_w [N],
f_q, f_r [N·m]; reward and its terms, safety cost [-].

Episode ends. The env names the reason of a terminated episode with
`auv_gym.sim.task.TERMINATION_REASONS` ("" = not terminated, the `info["termination_reason"]`
spelling); a recorded episode always ended somehow, so it names an episode that ran to
``max_time`` `TIME_LIMIT`. `FAILURE_REASONS` are the ends that count as failure (every
termination except reaching the end of a finite path, as in the env's termination penalty).
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path as FilePath
from typing import Any

import numpy as np

from auv_gym.sim.config import ACTUATOR_LIMITS
from auv_gym.sim.observation import GUIDANCE_FIELDS
from auv_gym.sim.task import PATH_END, REMUS_TOP_SPEED, REWARD_TERMS, TERMINATION_REASONS
from auv_gym.support.files import json_default, write_atomic
from auv_gym.vehicle.dynamics import STATE_NAMES

__all__ = [
    "EPISODE_ENDS",
    "FAILURE_REASONS",
    "INTERVAL_FIELDS",
    "NOT_TERMINATED",
    "SAMPLE_FIELDS",
    "TIME_LIMIT",
    "Trajectory",
    "env_termination_reason",
    "episode_end",
]

NOT_TERMINATED = TERMINATION_REASONS[0]  # "": the env's reason while an episode goes on
TIME_LIMIT = "time_limit"  # the end of a recorded episode that ran to max_time
EPISODE_ENDS: tuple[str, ...] = (*TERMINATION_REASONS[1:], TIME_LIMIT)
FAILURE_REASONS = frozenset(EPISODE_ENDS) - {TIME_LIMIT, TERMINATION_REASONS[PATH_END]}


def episode_end(code: int) -> str:
    """The `EPISODE_ENDS` name of a simulator termination code (0: `TIME_LIMIT`)."""
    return TERMINATION_REASONS[code] if code else TIME_LIMIT


def env_termination_reason(end: str) -> str:
    """An episode end in the env's spelling: `NOT_TERMINATED` ("") for `TIME_LIMIT`."""
    return NOT_TERMINATED if end == TIME_LIMIT else end


# Samples at t_0 … t_K: simulator state, guidance row, virtual-point position p(s).
POINT_FIELDS = ("x_p", "y_p", "z_p")
SAMPLE_FIELDS: tuple[str, ...] = STATE_NAMES + GUIDANCE_FIELDS + POINT_FIELDS
# Intervals [t_k, t_{k+1}): commanded action (as returned, before saturation), mean applied τ,
# mean white-noise disturbance, reward and its terms, safety cost (`auv_gym.sim.safety_cost`).
ACTION_FIELDS = ("a_X", "a_M", "a_N")
TAU_FIELDS = ("X", "M", "N")
DISTURBANCE_FIELDS = ("f_u", "f_v", "f_w", "f_q", "f_r")
INTERVAL_FIELDS: tuple[str, ...] = (
    ACTION_FIELDS
    + TAU_FIELDS
    + DISTURBANCE_FIELDS
    + ("reward",)
    + tuple(f"reward_{term}" for term in REWARD_TERMS)
    + ("cost",)
)


@dataclass(eq=False)
class Trajectory:
    """One recorded episode (see the module docstring for the time base and units).

    Attributes:
        t: sample times t_0 … t_K [s], shape (K + 1,).
        samples: `SAMPLE_FIELDS` name → (K + 1,) array.
        intervals: `INTERVAL_FIELDS` name → (K,) array; value for [t_k, t_{k+1}).
        extras: policy diagnostics name → (K,) or (K, m) array.
        termination_reason: how the episode ended, one of `EPISODE_ENDS`.
        control_dt: control period [s].
        u_desired: desired surge speed u_D [m/s].
        actuator_limits: (X, M, N) normalisation of τ in the metrics [N, N·m, N·m].
        metadata: JSON-serialisable facts: seed, policy, env_kwargs, versions.
        top_speed: the vehicle's top speed u_max [m/s] (`AUVParams.max_surge`; REMUS 100's
            2.0 m/s by default), the threshold of the overspeed metric.

    Items are read with ``trajectory["x_e"]`` (samples, intervals or extras).
    """

    t: np.ndarray
    samples: dict[str, np.ndarray]
    intervals: dict[str, np.ndarray]
    extras: dict[str, np.ndarray] = field(default_factory=dict)
    termination_reason: str = TIME_LIMIT
    control_dt: float = 0.05
    u_desired: float = 1.0
    actuator_limits: tuple[float, float, float] = ACTUATOR_LIMITS
    metadata: dict[str, Any] = field(default_factory=dict)
    top_speed: float = REMUS_TOP_SPEED

    def __post_init__(self) -> None:
        self.t = np.asarray(self.t, dtype=np.float64)
        if self.t.ndim != 1 or self.t.size < 1:
            raise ValueError(f"t must be a non-empty 1-D array, got shape {self.t.shape}")
        steps = self.t.size - 1
        for group, names, length in (
            ("samples", SAMPLE_FIELDS, steps + 1),
            ("intervals", INTERVAL_FIELDS, steps),
        ):
            table = getattr(self, group)
            missing = [n for n in names if n not in table]
            if missing:
                raise ValueError(f"Trajectory {group} lack {missing}")
            for name, values in table.items():
                arr = np.asarray(values, dtype=np.float64)
                if arr.shape != (length,):
                    raise ValueError(
                        f"Trajectory {group}[{name!r}] must have shape ({length},), got {arr.shape}"
                    )
                table[name] = arr
        for name, values in self.extras.items():
            arr = np.asarray(values, dtype=np.float64)
            if arr.ndim not in (1, 2) or arr.shape[0] != steps:
                raise ValueError(
                    f"Trajectory extras[{name!r}] must have shape ({steps},) or ({steps}, m), "
                    f"got {arr.shape}"
                )
            self.extras[name] = arr
        if self.termination_reason not in EPISODE_ENDS:
            raise ValueError(
                f"termination_reason must be one of {EPISODE_ENDS}, got {self.termination_reason!r}"
            )
        if not (math.isfinite(self.control_dt) and self.control_dt > 0):
            raise ValueError(f"control_dt must be a positive time in s, got {self.control_dt}")
        limits = tuple(float(v) for v in self.actuator_limits)
        if len(limits) != 3 or not all(math.isfinite(v) and v > 0 for v in limits):
            raise ValueError(f"actuator_limits must be 3 positive numbers, got {limits}")
        self.actuator_limits = limits  # type: ignore[assignment]
        if not (math.isfinite(self.top_speed) and self.top_speed > 0):
            raise ValueError(f"top_speed must be a positive speed in m/s, got {self.top_speed}")

    def __getitem__(self, name: str) -> np.ndarray:
        for table in (self.samples, self.intervals, self.extras):
            if name in table:
                return table[name]
        if name == "t":
            return self.t
        raise KeyError(f"no series {name!r} in this trajectory")

    @property
    def steps(self) -> int:
        """Number of control steps K."""
        return self.t.size - 1

    @property
    def duration(self) -> float:
        """Recorded time t_K − t_0 [s]."""
        return float(self.t[-1] - self.t[0])

    @property
    def t_interval(self) -> np.ndarray:
        """Start times t_0 … t_{K−1} of the intervals [s]."""
        return self.t[:-1]

    @property
    def position(self) -> np.ndarray:
        """(K + 1, 3) NED positions (x, y, z) [m]."""
        return np.column_stack([self.samples[k] for k in ("x", "y", "z")])

    @property
    def point(self) -> np.ndarray:
        """(K + 1, 3) positions of the virtual point p(s) [m]."""
        return np.column_stack([self.samples[k] for k in POINT_FIELDS])

    @property
    def tau(self) -> np.ndarray:
        """(K, 3) applied (X, M, N) averaged over each control period [N, N·m, N·m]."""
        return np.column_stack([self.intervals[k] for k in TAU_FIELDS])

    @property
    def actions(self) -> np.ndarray:
        """(K, 3) actions as the policy returned them (before saturation to [−1, 1])."""
        return np.column_stack([self.intervals[k] for k in ACTION_FIELDS])

    def save(self, path: str | os.PathLike, compress: bool = True) -> None:
        """Write a .npz atomically (`auv_gym.support.files.write_atomic`).

        Keys: "t", every sample and interval name, "extra.<name>" and "metadata" (a JSON
        string with termination_reason, control_dt, u_desired, actuator_limits and `metadata`,
        and top_speed when it is not REMUS 100's, so a REMUS episode's file is as before).
        """
        arrays: dict[str, np.ndarray] = {"t": self.t, **self.samples, **self.intervals}
        arrays.update({f"extra.{k}": v for k, v in self.extras.items()})
        meta = {
            "termination_reason": self.termination_reason,
            "control_dt": self.control_dt,
            "u_desired": self.u_desired,
            "actuator_limits": list(self.actuator_limits),
            "metadata": self.metadata,
        }
        if self.top_speed != REMUS_TOP_SPEED:
            meta["top_speed"] = self.top_speed
        arrays["metadata"] = np.array(json.dumps(meta, default=json_default))
        saver = np.savez_compressed if compress else np.savez
        # Through a file object, so numpy appends no ".npz" to a name that lacks it.
        write_atomic(FilePath(path), lambda fh: saver(fh, **arrays))

    @classmethod
    def load(cls, path: str | os.PathLike) -> Trajectory:
        """Read a file written by `save`."""
        with np.load(path, allow_pickle=False) as data:
            if "metadata" not in data.files or "t" not in data.files:
                raise ValueError(f"{path} is not a Trajectory file (no 't' or 'metadata')")
            meta = json.loads(str(data["metadata"]))
            samples = {k: data[k] for k in SAMPLE_FIELDS if k in data.files}
            intervals = {k: data[k] for k in data.files if k in INTERVAL_FIELDS}
            if "cost" not in intervals and "reward" in intervals:  # written before the cost
                intervals["cost"] = np.full(data["reward"].shape, np.nan)
            extras = {k[6:]: data[k] for k in data.files if k.startswith("extra.")}
            return cls(
                t=data["t"],
                samples=samples,
                intervals=intervals,
                extras=extras,
                termination_reason=meta["termination_reason"],
                control_dt=float(meta["control_dt"]),
                u_desired=float(meta["u_desired"]),
                actuator_limits=tuple(meta["actuator_limits"]),
                metadata=meta["metadata"],
                top_speed=float(meta.get("top_speed", REMUS_TOP_SPEED)),
            )
