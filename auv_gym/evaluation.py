"""Seeded rollouts of any policy → full time series (`Trajectory`) → metrics.

A *policy* is anything with SB3's `PolicyPredictor` method

    predict(observation, state=None, episode_start=None, deterministic=True) -> (action, state)

batched over the first axis: the controllers of `controllers`, a stable-baselines3 model, or a
user's object. `rollouts` runs one policy over a list of seeds at once: one row per seed of a
`auv_gym.simulator.Simulator`, each row reset from ``gymnasium.utils.seeding.np_random(seed)`` —
exactly what ``AUVPath3DEnv.reset(seed=seed)`` does — and one batched `predict` call per control
step. Every policy evaluated on a seed therefore meets the same disturbance realisation, and a
row reproduces the single env bit for bit (the tests check it).

Time base. Control step k runs from t_k = k·control_dt to t_{k+1}. A trajectory of K steps holds

* K + 1 **samples** (`SAMPLE_FIELDS`) at t_0 … t_K: the state and guidance after each step,
  starting with the reset state;
* K **intervals** (`INTERVAL_FIELDS`) belonging to [t_k, t_{k+1}): the action the policy
  returned at t_k, the applied τ and the disturbance averaged over the period, the reward;
* optional **extras** of the same length K from the policy's diagnostics hook (below).

An episode that terminates (corridor, pitch, non-finite state, envelope, path end) stops being
recorded at its terminating step, so its trajectory is shorter; the other rows go on.

Diagnostics hook (optional). A policy may define

    diagnostics(state) -> Mapping[str, np.ndarray]

called with the ``state`` that `predict` just returned; each value has shape (n,) or (n, m) for
the n rows of that call and belongs to the interval that starts at the current sample. The
values are stored as ``extras[name]`` with shape (K,) or (K, m). Names the plots recognise:
``theta_d`` [rad] (desired pitch), ``psi_d_rel`` [rad] (desired heading relative to the path,
ψ_d − ψ_F: the observation holds ψ − ψ_F but not ψ itself) or ``psi_d`` [rad] (absolute), and
any name starting with ``norm_`` (an adaptive-parameter norm, e.g. ``norm_theta_f_surge``; a
(K, m) value is reduced to its row norms). `controllers` document which extras they provide.
The hook must not change the state.

Metrics: see `compute_metrics`; `evaluate` = `rollouts` + `compute_metrics` per seed.
"""

from __future__ import annotations

import inspect
import json
import math
import os
import tempfile
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, is_dataclass
from pathlib import Path as FilePath
from typing import IO, Any, Protocol, runtime_checkable

import numba
import numpy as np
from gymnasium.utils import seeding

from auv_gym.dynamics import STATE_NAMES
from auv_gym.observation import GUIDANCE_FIELDS
from auv_gym.simulator import ACTUATOR_LIMITS, SimConfig, Simulator
from auv_gym.task import REWARD_TERMS, TERMINATION_REASONS

__all__ = [
    "FAILURE_REASONS",
    "INTERVAL_FIELDS",
    "SAMPLE_FIELDS",
    "Policy",
    "Trajectory",
    "compute_metrics",
    "evaluate",
    "policy_name",
    "rollout",
    "rollouts",
    "write_atomic",
]

# Samples at t_0 … t_K: simulator state, guidance row, virtual-point position p(s).
_POINT_FIELDS = ("x_p", "y_p", "z_p")
SAMPLE_FIELDS: tuple[str, ...] = STATE_NAMES + GUIDANCE_FIELDS + _POINT_FIELDS
# Intervals [t_k, t_{k+1}): commanded action (as returned, before saturation), mean applied τ,
# mean white-noise disturbance, reward and its terms.
_ACTION_FIELDS = ("a_X", "a_M", "a_N")
_TAU_FIELDS = ("X", "M", "N")
_DISTURBANCE_FIELDS = ("f_u", "f_v", "f_w", "f_q", "f_r")
INTERVAL_FIELDS: tuple[str, ...] = (
    _ACTION_FIELDS
    + _TAU_FIELDS
    + _DISTURBANCE_FIELDS
    + ("reward",)
    + tuple(f"reward_{term}" for term in REWARD_TERMS)
)
UNITS: dict[str, str] = {
    "t": "s",
    "x": "m",
    "y": "m",
    "z": "m",
    "theta": "rad",
    "psi": "rad",
    "u": "m/s",
    "v": "m/s",
    "w": "m/s",
    "q": "rad/s",
    "r": "rad/s",
    "s": "-",
    "x_e": "m",
    "y_e": "m",
    "z_e": "m",
    "distance": "m",
    "psi_F": "rad",
    "theta_F": "rad",
    "psi_F_dot": "rad/s",
    "theta_F_dot": "rad/s",
    "u_p": "m/s",
    "s_dot": "1/s",
    "x_p": "m",
    "y_p": "m",
    "z_p": "m",
    "a_X": "-",
    "a_M": "-",
    "a_N": "-",
    "X": "N",
    "M": "N·m",
    "N": "N·m",
    "f_u": "N",
    "f_v": "N",
    "f_w": "N",
    "f_q": "N·m",
    "f_r": "N·m",
    "reward": "-",
    **{f"reward_{term}": "-" for term in REWARD_TERMS},
}
# Termination reasons that count as failure (a finite path's end is not one).
FAILURE_REASONS = frozenset({"corridor", "pitch", "non_finite", "envelope"})
TIME_LIMIT = "time_limit"  # reason recorded when the episode ran to max_time
DEFAULT_TRANSIENT = 100.0  # [s] start of the metrics window
DEFAULT_BATCH = 32  # rows per simulator batch; memory ≈ 2 MB per row for a 300-s episode
_SAT_TOL = 1e-9
_STATE_SLICE = slice(0, len(STATE_NAMES))
_GUID_SLICE = slice(len(STATE_NAMES), len(STATE_NAMES) + len(GUIDANCE_FIELDS))
_S_COLUMN = SAMPLE_FIELDS.index("s")
_ACTION_SLICE = slice(0, 3)
_RECORD_SLICE = slice(3, 3 + len(_TAU_FIELDS) + len(_DISTURBANCE_FIELDS))  # = Simulator.record
_REWARD_COLUMN = INTERVAL_FIELDS.index("reward")
_TERMS_SLICE = slice(_REWARD_COLUMN + 1, _REWARD_COLUMN + 1 + len(REWARD_TERMS))


@runtime_checkable
class Policy(Protocol):
    """SB3's `PolicyPredictor`: batched over the first axis of ``observation``."""

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]: ...


def policy_name(policy: Any) -> str:
    """``policy.name`` if it has one, else its class name."""
    name = getattr(policy, "name", None)
    return name if isinstance(name, str) and name else type(policy).__name__


@dataclass(eq=False)
class Trajectory:
    """One recorded episode (see the module docstring for the time base).

    Attributes:
        t: sample times t_0 … t_K [s], shape (K + 1,).
        samples: `SAMPLE_FIELDS` name → (K + 1,) array (units in `UNITS`).
        intervals: `INTERVAL_FIELDS` name → (K,) array; value for [t_k, t_{k+1}).
        extras: policy diagnostics name → (K,) or (K, m) array.
        termination_reason: a `auv_gym.task.TERMINATION_REASONS` name, or "time_limit".
        control_dt: control period [s].
        u_desired: desired surge speed u_D [m/s].
        actuator_limits: (X, M, N) normalisation of τ in the metrics [N, N·m, N·m].
        metadata: JSON-serialisable facts: seed, policy, env_kwargs, versions.

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
        valid = (*TERMINATION_REASONS[1:], TIME_LIMIT)
        if self.termination_reason not in valid:
            raise ValueError(
                f"termination_reason must be one of {valid}, got {self.termination_reason!r}"
            )
        if not (math.isfinite(self.control_dt) and self.control_dt > 0):
            raise ValueError(f"control_dt must be a positive time in s, got {self.control_dt}")
        limits = tuple(float(v) for v in self.actuator_limits)
        if len(limits) != 3 or not all(math.isfinite(v) and v > 0 for v in limits):
            raise ValueError(f"actuator_limits must be 3 positive numbers, got {limits}")
        self.actuator_limits = limits  # type: ignore[assignment]

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
        return np.column_stack([self.samples[k] for k in _POINT_FIELDS])

    @property
    def tau(self) -> np.ndarray:
        """(K, 3) applied (X, M, N) averaged over each control period [N, N·m, N·m]."""
        return np.column_stack([self.intervals[k] for k in _TAU_FIELDS])

    @property
    def actions(self) -> np.ndarray:
        """(K, 3) actions as the policy returned them (before saturation to [−1, 1])."""
        return np.column_stack([self.intervals[k] for k in _ACTION_FIELDS])

    def save(self, path: str | os.PathLike, compress: bool = True) -> None:
        """Write a .npz atomically (temporary file in the same folder, then `os.replace`).

        Keys: "t", every sample and interval name, "extra.<name>" and "metadata" (a JSON
        string with termination_reason, control_dt, u_desired, actuator_limits and `metadata`).
        """
        target = FilePath(path)
        arrays: dict[str, np.ndarray] = {"t": self.t, **self.samples, **self.intervals}
        arrays.update({f"extra.{k}": v for k, v in self.extras.items()})
        meta = {
            "termination_reason": self.termination_reason,
            "control_dt": self.control_dt,
            "u_desired": self.u_desired,
            "actuator_limits": list(self.actuator_limits),
            "metadata": self.metadata,
        }
        arrays["metadata"] = np.array(json.dumps(meta, default=_json_default))
        saver = np.savez_compressed if compress else np.savez
        # Through a file object, so numpy appends no ".npz" to a name that lacks it.
        write_atomic(target, lambda fh: saver(fh, **arrays))

    @classmethod
    def load(cls, path: str | os.PathLike) -> Trajectory:
        """Read a file written by `save`."""
        with np.load(path, allow_pickle=False) as data:
            if "metadata" not in data.files or "t" not in data.files:
                raise ValueError(f"{path} is not a Trajectory file (no 't' or 'metadata')")
            meta = json.loads(str(data["metadata"]))
            samples = {k: data[k] for k in SAMPLE_FIELDS if k in data.files}
            intervals = {k: data[k] for k in data.files if k in INTERVAL_FIELDS}
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
            )


def write_atomic(path: str | os.PathLike, write: Callable[[IO[bytes]], Any]) -> FilePath:
    """Call ``write(file)`` on a temporary file beside ``path``, then rename it over ``path``.

    Readers see the old file or the complete new one, never a partial write; the temporary
    file is removed if ``write`` fails. Permissions follow the umask, as for `open`.
    """
    target = FilePath(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, target)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return target


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _json_default(obj: Any) -> Any:
    """JSON for env keyword arguments: dataclasses as dicts, arrays as lists, others by repr."""
    if is_dataclass(obj) and not isinstance(obj, type):
        return {"type": type(obj).__name__, **asdict(obj)}
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if hasattr(obj, "data") and hasattr(obj, "kind"):  # an auv_gym.paths.Path
        return {"type": type(obj).__name__, "data": np.asarray(obj.data).tolist()}
    return repr(obj)


_ENV_KWARGS = frozenset(inspect.signature(SimConfig.from_kwargs).parameters)


def _config(env_kwargs: Mapping[str, Any]) -> SimConfig:
    unknown = sorted(set(env_kwargs) - _ENV_KWARGS)
    if unknown:
        raise ValueError(f"unknown env keyword arguments {unknown}; valid: {sorted(_ENV_KWARGS)}")
    return SimConfig.from_kwargs(**env_kwargs)


def _check_policy(policy: Any) -> None:
    if not callable(getattr(policy, "predict", None)):
        raise ValueError(
            f"policy must have predict(observation, state, episode_start, deterministic), "
            f"got {type(policy).__name__}"
        )


def _check_seeds(seeds: Iterable[int]) -> list[int]:
    out = []
    for seed in seeds:
        if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)):
            raise ValueError(f"seeds must be integers, got {seed!r}")
        if seed < 0:
            raise ValueError(f"seeds must be non-negative, got {seed}")
        out.append(int(seed))
    if not out:
        raise ValueError("seeds must not be empty")
    return out


def _policy_actions(action: Any, n: int) -> np.ndarray:
    a = np.asarray(action, dtype=np.float64)
    if a.size != 3 * n or a.shape[-1] != 3:
        raise ValueError(f"policy returned actions of shape {a.shape}, expected ({n}, 3)")
    return a.reshape(n, 3)


def rollouts(
    policy: Any,
    seeds: Sequence[int],
    *,
    batch_size: int = DEFAULT_BATCH,
    name: str | None = None,
    threads: int | None = 1,
    **env_kwargs: Any,
) -> list[Trajectory]:
    """Run ``policy`` on the episodes of ``seeds`` (batched) and record one `Trajectory` each.

    Args:
        policy: an object with SB3's ``predict`` (see `Policy`), optionally ``diagnostics``.
        seeds: reset seeds; seed k reproduces ``AUVPath3DEnv(**env_kwargs).reset(seed=k)``.
        batch_size: rows simulated together (bounds memory; results do not depend on it).
        name: policy label for the metadata (default `policy_name`).
        threads: numba threads for the simulator kernel during the call (None: leave numba's
            setting). The default 1 is deliberate: a control step of a few dozen rows takes
            microseconds, and on a loaded machine the threaded kernel's barrier made batches of
            16–64 rows 10–20× slower than one thread (2-core machine, load ≈ 4). Results do not
            depend on it.
        **env_kwargs: `AUVPath3DEnv` keyword arguments (not ``render_mode``).

    The policy is called once per control step with the float32 observations of all rows of a
    batch; ``episode_start`` is True at the first step only. Rows that have terminated are fed
    their last observation and their actions are ignored.
    """
    _check_policy(policy)
    seed_list = _check_seeds(seeds)
    if not (isinstance(batch_size, (int, np.integer)) and batch_size >= 1):
        raise ValueError(f"batch_size must be a positive integer, got {batch_size!r}")
    if threads is not None and not (isinstance(threads, (int, np.integer)) and threads >= 1):
        raise ValueError(f"threads must be a positive integer or None, got {threads!r}")
    config = _config(env_kwargs)
    label = name if name is not None else policy_name(policy)
    out: list[Trajectory] = []
    previous = numba.get_num_threads()
    if threads is not None:
        numba.set_num_threads(min(int(threads), numba.config.NUMBA_NUM_THREADS))
    try:
        for start in range(0, len(seed_list), batch_size):
            seeds_batch = seed_list[start : start + batch_size]
            out.extend(_run_batch(policy, seeds_batch, config, label, env_kwargs))
    finally:
        numba.set_num_threads(previous)
    return out


def rollout(policy: Any, seed: int, *, name: str | None = None, **env_kwargs: Any) -> Trajectory:
    """One seeded episode of ``policy``; see `rollouts`."""
    return rollouts(policy, [seed], name=name, **env_kwargs)[0]


def _run_batch(
    policy: Any, seeds: list[int], config: SimConfig, label: str, env_kwargs: Mapping[str, Any]
) -> list[Trajectory]:
    n = len(seeds)
    sim = Simulator(config, n)
    for i, seed in enumerate(seeds):
        sim.reset_row(i, seeding.np_random(seed)[0])
    max_steps = config.max_steps
    # Pre-allocated records: samples (state | guidance | p(s), filled after the loop) and
    # intervals (action | τ, f | reward | reward terms).
    samples = np.empty((n, max_steps + 1, len(SAMPLE_FIELDS)))
    intervals = np.empty((n, max_steps, len(INTERVAL_FIELDS)))
    samples[:, 0, _STATE_SLICE] = sim.state
    samples[:, 0, _GUID_SLICE] = sim.guid
    diagnostics = getattr(policy, "diagnostics", None)
    extras: dict[str, np.ndarray] = {}
    steps = np.full(n, max_steps, dtype=np.int64)
    codes = np.zeros(n, dtype=np.int64)  # termination code at each row's terminating step
    alive = np.ones(n, dtype=bool)
    obs = sim.obs.astype(np.float32)
    state = None
    episode_start = np.ones(n, dtype=bool)
    for k in range(max_steps):
        action, state = policy.predict(
            obs, state=state, episode_start=episode_start, deterministic=True
        )
        actions = _policy_actions(action, n)
        intervals[:, k, _ACTION_SLICE] = actions
        if diagnostics is not None:
            _record_extras(extras, diagnostics(state), k, n, max_steps)
        if not alive.all():
            actions = np.where(alive[:, None], actions, 0.0)
        sim.step(actions)
        samples[:, k + 1, _STATE_SLICE] = sim.state
        samples[:, k + 1, _GUID_SLICE] = sim.guid
        intervals[:, k, _RECORD_SLICE] = sim.record
        intervals[:, k, _REWARD_COLUMN] = sim.reward
        intervals[:, k, _TERMS_SLICE] = sim.terms
        ended = alive & (sim.code != 0)
        if ended.any():
            steps[ended] = k + 1
            codes[ended] = sim.code[ended]
            alive &= ~ended
            if not alive.any():
                break
        episode_start = np.zeros(n, dtype=bool)
        fresh = sim.obs.astype(np.float32)
        obs = fresh if alive.all() else np.where(alive[:, None], fresh, obs)
    base_meta = {
        "policy": label,
        "env_kwargs": json.loads(json.dumps(dict(env_kwargs), default=_json_default)),
        "physics_dt": config.physics_dt,
        "noise_hold": config.noise.hold,
        "max_time": config.max_time,
        "versions": _versions(),
    }
    result = []
    for i, seed in enumerate(seeds):
        length = int(steps[i])
        s = samples[i, : length + 1, _S_COLUMN]
        samples[i, : length + 1, -3:] = config.path.evaluate(s)[0]
        code = int(codes[i])
        result.append(
            Trajectory(
                # As the env's info["t"]: physics steps × physics_dt.
                t=(np.arange(length + 1) * config.substeps) * config.physics_dt,
                samples={
                    f: samples[i, : length + 1, j].copy() for j, f in enumerate(SAMPLE_FIELDS)
                },
                intervals={
                    f: intervals[i, :length, j].copy() for j, f in enumerate(INTERVAL_FIELDS)
                },
                extras={f: v[i, :length].copy() for f, v in extras.items()},
                termination_reason=TERMINATION_REASONS[code] if code else TIME_LIMIT,
                control_dt=config.control_dt,
                u_desired=config.u_desired,
                actuator_limits=config.actuator_limits,
                metadata={**base_meta, "seed": seed},
            )
        )
    return result


def _record_extras(
    extras: dict[str, np.ndarray], values: Mapping[str, Any], k: int, n: int, steps: int
) -> None:
    for key, value in values.items():
        arr = np.asarray(value, dtype=np.float64)
        if arr.ndim == 0 or arr.shape[0] != n or arr.ndim > 2:
            raise ValueError(
                f"diagnostics[{key!r}] must have shape ({n},) or ({n}, m), got {arr.shape}"
            )
        if key not in extras:
            extras[key] = np.full((n, steps, *arr.shape[1:]), np.nan)
        extras[key][:, k] = arr


def _versions() -> dict[str, str]:
    import auv_gym

    return {"auv_gym": auv_gym.__version__, "numpy": np.__version__, "numba": numba.__version__}


def _window_rms(t: np.ndarray, values: np.ndarray, start: float) -> float:
    mask = t >= start - 1e-9
    if not mask.any():
        return math.nan
    return float(np.sqrt(np.mean(np.square(values[mask]))))


def _trapezoid(values: np.ndarray, t: np.ndarray) -> float:
    """∫ values dt by the trapezoid rule (0 for a single sample)."""
    return float(0.5 * np.sum((values[1:] + values[:-1]) * np.diff(t)))


def _settling_time(t: np.ndarray, distance: np.ndarray, threshold: float) -> float:
    """First t_k with distance < threshold at every sample from k on; inf if none."""
    outside = ~(distance < threshold)  # NaN counts as outside
    if outside[-1]:
        return math.inf
    if not outside.any():
        return float(t[0])
    return float(t[np.flatnonzero(outside)[-1] + 1])


def compute_metrics(
    trajectory: Trajectory,
    transient: float = DEFAULT_TRANSIENT,
    success_distance: float = 1.0,
    final_window: float = 10.0,
) -> dict[str, Any]:
    """Scalar metrics of one episode. Units: m, s, m/s; τ normalised by `actuator_limits`.

    Windowed metrics use the samples (or intervals) with t ≥ ``transient`` [s] and are NaN when
    the episode is shorter than that. With d the distance to the virtual point, e = (x_e, y_e,
    z_e), τ̄_j = τ_j / τ_max,j and a_j the policy's action:

    Distance and errors [m]:
      rms_distance, rms_x_e, rms_y_e, rms_z_e — √mean(·²) over the window;
      max_distance_window — max d over the window; final_distance — d at the last sample;
      iae_distance — ∫ d dt over the whole episode (trapezoid) [m·s];
      iae_distance_window — the same over the window [m·s];
      settling_time_0p5, settling_time_0p1 — the first t_k with d < 0.5 (0.1) m at every
      later sample [s]; inf if the last sample is not below the threshold (never settled) or
      the episode ended in failure.
    Speed [m/s]:
      surge_overshoot — max_k (u − u_D) over the episode (negative if u never reaches u_D);
      surge_overshoot_percent — 100·surge_overshoot/u_D;
      rms_speed_error — √mean((u − u_D)²) over the window.
    Actuation:
      control_effort — Σ_k Σ_j τ̄_j² Δt over the episode, i.e. ∫ of the squared normalised τ [s];
      chattering — Σ_k Σ_j abs(τ̄_j(t_{k+1}) − τ̄_j(t_k)) / window length, the total variation
      of the normalised τ per second of window [1/s];
      saturation_fraction — fraction of control steps with any abs(a_j) ≥ 1 (saturated
      command); control_effort_X/_M/_N, chattering_X/_M/_N, saturation_fraction_X/_M/_N — per
      channel.
    Outcome:
      success — no failure termination (`FAILURE_REASONS`) and RMS d over the final
      ``final_window`` s ≤ ``success_distance`` (default 1 m, about one REMUS length);
      episode_return — Σ reward; termination_reason — "time_limit" or the env's reason;
      duration [s], steps; transient — the window start used [s].
    """
    if not (math.isfinite(transient) and transient >= 0):
        raise ValueError(f"transient must be a non-negative time in s, got {transient}")
    if not (success_distance > 0 and final_window > 0):
        raise ValueError("success_distance and final_window must be positive")
    tr = trajectory
    t, t_int, dt = tr.t, tr.t_interval, tr.control_dt
    distance = tr["distance"]
    failed = tr.termination_reason in FAILURE_REASONS
    window = t >= transient - 1e-9
    window_int = t_int >= transient - 1e-9
    speed_error = tr["u"] - tr.u_desired
    tau_norm = tr.tau / np.asarray(tr.actuator_limits)
    actions = tr.actions
    metrics: dict[str, Any] = {}
    for name, values in (
        ("distance", distance),
        ("x_e", tr["x_e"]),
        ("y_e", tr["y_e"]),
        ("z_e", tr["z_e"]),
    ):
        metrics[f"rms_{name}"] = _window_rms(t, values, transient)
    metrics["max_distance_window"] = float(distance[window].max()) if window.any() else math.nan
    metrics["iae_distance"] = _trapezoid(distance, t)
    metrics["iae_distance_window"] = (
        _trapezoid(distance[window], t[window]) if window.sum() > 1 else math.nan
    )
    for label, threshold in (("0p5", 0.5), ("0p1", 0.1)):
        settle = _settling_time(t, distance, threshold)
        metrics[f"settling_time_{label}"] = math.inf if failed else settle
    overshoot = float(speed_error.max())
    metrics["surge_overshoot"] = overshoot
    metrics["surge_overshoot_percent"] = 100.0 * overshoot / tr.u_desired
    metrics["rms_speed_error"] = _window_rms(t, speed_error, transient)
    per_channel_effort = (tau_norm**2).sum(axis=0) * dt
    metrics["control_effort"] = float(per_channel_effort.sum())
    # Chattering: total variation inside the window, per second of window.
    tv_window = tau_norm[window_int]
    span = tv_window.shape[0] * dt
    if tv_window.shape[0] > 1:
        variation = np.abs(np.diff(tv_window, axis=0)).sum(axis=0) / span
    else:
        variation = np.full(3, math.nan)
    metrics["chattering"] = float(variation.sum())
    saturated = np.abs(actions) >= 1.0 - _SAT_TOL
    steps = tr.steps
    metrics["saturation_fraction"] = float(saturated.any(axis=1).mean()) if steps else 0.0
    for j, axis in enumerate(_TAU_FIELDS):
        metrics[f"control_effort_{axis}"] = float(per_channel_effort[j])
        metrics[f"chattering_{axis}"] = float(variation[j])
        metrics[f"saturation_fraction_{axis}"] = float(saturated[:, j].mean()) if steps else 0.0
    metrics["final_distance"] = float(distance[-1])
    final = t >= t[-1] - final_window + 1e-9
    final_rms = float(np.sqrt(np.mean(np.square(distance[final]))))
    metrics["success"] = bool(not failed and final_rms <= success_distance)
    metrics["episode_return"] = float(tr["reward"].sum())
    metrics["termination_reason"] = tr.termination_reason
    metrics["duration"] = tr.duration
    metrics["steps"] = steps
    metrics["transient"] = float(transient)
    return metrics


def evaluate(
    policy: Any,
    seeds: Sequence[int],
    *,
    transient: float = DEFAULT_TRANSIENT,
    batch_size: int = DEFAULT_BATCH,
    threads: int | None = 1,
    **env_kwargs: Any,
) -> list[dict[str, Any]]:
    """Metrics (`compute_metrics`) of ``policy`` on each seed, in the order of ``seeds``.

    Each dict also holds "seed" and "policy". The same seed gives every policy the same
    disturbances, parameters and start, so the dicts of two policies compare episode by episode.
    """
    results = []
    for trajectory in rollouts(policy, seeds, batch_size=batch_size, threads=threads, **env_kwargs):
        metrics = compute_metrics(trajectory, transient=transient)
        results.append(
            {
                "seed": trajectory.metadata["seed"],
                "policy": trajectory.metadata["policy"],
                **metrics,
            }
        )
    return results
