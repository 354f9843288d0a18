"""Seeded rollouts of any policy → recorded episodes (`auv_gym.sim.trajectory.Trajectory`) →
metrics.

A *policy* is anything with SB3's `PolicyPredictor` method

    predict(observation, state=None, episode_start=None, deterministic=True) -> (action, state)

batched over the first axis: the controllers of `controllers`, a stable-baselines3 model, or a
user's object. `rollouts` runs one policy over a list of seeds at once: one row per seed of a
`auv_gym.sim.simulator.Simulator`, each row reset from ``gymnasium.utils.seeding.np_random(seed)`` —
exactly what ``AUVPath3DEnv.reset(seed=seed)`` does — and one batched `predict` call per control
step. Every policy evaluated on a seed therefore meets the same disturbance realisation, and a
row reproduces the single env bit for bit (the tests check it).

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

`evaluate` = `rollouts` + `auv_gym.metrics.compute_metrics` per seed.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, Protocol, runtime_checkable

import numba
import numpy as np
from gymnasium.utils import seeding

from auv_gym.metrics import FIN_RATE_LIMITED, ROLL_ANGLE, SHAFT_POWER, compute_metrics
from auv_gym.sim.config import SimConfig, config_from_kwargs
from auv_gym.sim.observation import GUIDANCE_FIELDS
from auv_gym.sim.plants import ROLL
from auv_gym.sim.simulator import Simulator
from auv_gym.sim.task import REWARD_TERMS
from auv_gym.sim.trajectory import (
    DISTURBANCE_FIELDS,
    INTERVAL_FIELDS,
    SAMPLE_FIELDS,
    TAU_FIELDS,
    Trajectory,
    episode_end,
)
from auv_gym.support.files import environment, json_default
from auv_gym.vehicle.actuators import ACTUATOR_STATE, actuator_record, shaft_powers
from auv_gym.vehicle.dynamics import STATE, STATE_NAMES

__all__ = ["Policy", "evaluate", "policy_name", "rollout", "rollouts"]

DEFAULT_BATCH = 32  # rows per simulator batch; memory ≈ 2 MB per row for a 300-s episode
# Columns of the pre-allocated sample and interval records (layouts of auv_gym.sim.trajectory).
_STATE_SLICE = slice(0, len(STATE_NAMES))
_GUID_SLICE = slice(len(STATE_NAMES), len(STATE_NAMES) + len(GUIDANCE_FIELDS))
_S_COLUMN = SAMPLE_FIELDS.index("s")
_ACTION_SLICE = slice(0, 3)
# τ and the white noise: the first columns of Simulator.record (the ocean's velocity follows).
_RECORD_SLICE = slice(3, 3 + len(TAU_FIELDS) + len(DISTURBANCE_FIELDS))
_REWARD_COLUMN = INTERVAL_FIELDS.index("reward")
_TERMS_SLICE = slice(_REWARD_COLUMN + 1, _REWARD_COLUMN + 1 + len(REWARD_TERMS))
_COST_COLUMN = INTERVAL_FIELDS.index("cost")


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
        batch_size: rows simulated together (bounds memory). The simulator's and the
            classical controllers' (and an ONNX export's) results do not depend on it; a torch
            agent's do, at float rounding (about 1e-6 of a command): torch's matrix products
            sum a row alone and a row in a batch in different orders, so the same seeds in the
            same batches are bit-identical, seed 40 alone and beside seed 41 are not.
        name: policy label for the metadata (default `policy_name`).
        threads: numba threads for the simulator kernel during the call (None: leave numba's
            setting). The default 1 is deliberate: a control step of a few dozen rows is far
            too short to share among threads, and on a loaded machine the threaded kernel's
            barrier makes small batches slower than one thread (README, Performance). Results do
            not depend on it.
        **env_kwargs: `AUVPath3DEnv` keyword arguments (not ``render_mode``), on top of the
            env the policy carries, if it carries one (``policy.env_kwargs``: a saved agent runs
            under the env id and observation it was trained on, `controllers.agent`).

    The policy is called once per control step with the float32 observations of all rows of a
    batch; ``episode_start`` is True at the first step only. Rows that have terminated are fed
    their last observation and their actions are ignored.
    """
    _check_policy(policy)
    carried = getattr(policy, "env_kwargs", None)
    if isinstance(carried, Mapping):
        env_kwargs = {**carried, **env_kwargs}
    seed_list = _check_seeds(seeds)
    if not (isinstance(batch_size, (int, np.integer)) and batch_size >= 1):
        raise ValueError(f"batch_size must be a positive integer, got {batch_size!r}")
    if threads is not None and not (isinstance(threads, (int, np.integer)) and threads >= 1):
        raise ValueError(f"threads must be a positive integer or None, got {threads!r}")
    config = config_from_kwargs(env_kwargs)
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
    propeller = actuator_record(config.actuator_params, config.physics_dt)  # for its power
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
    obs = sim.observations()
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
        intervals[:, k, _RECORD_SLICE] = sim.record[:, : _RECORD_SLICE.stop - _RECORD_SLICE.start]
        intervals[:, k, _REWARD_COLUMN] = sim.reward
        intervals[:, k, _TERMS_SLICE] = sim.terms
        intervals[:, k, _COST_COLUMN] = sim.cost
        if config.actuator == "realistic":  # the plant's, beside the policy's diagnostics
            limited = sim.actuator_state[:, ACTUATOR_STATE.rate_limited]
            u, v, w = (sim.state[:, i] for i in (STATE.u, STATE.v, STATE.w))
            rpm = sim.actuator_state[:, ACTUATOR_STATE.n_rpm]
            power = shaft_powers(rpm, u, v, w, propeller)
            _record_extras(extras, {FIN_RATE_LIMITED: limited, SHAFT_POWER: power}, k, n, max_steps)
        if sim.six_dof:  # the 6-DOF plant's roll, at each interval's end
            _record_extras(extras, {ROLL_ANGLE: sim.roll[:, ROLL.phi]}, k, n, max_steps)
        ended = alive & (sim.code != 0)
        if ended.any():
            steps[ended] = k + 1
            codes[ended] = sim.code[ended]
            alive &= ~ended
            if not alive.any():
                break
        episode_start = np.zeros(n, dtype=bool)
        fresh = sim.observations()
        obs = fresh if alive.all() else np.where(alive[:, None], fresh, obs)
    base_meta = {
        "policy": label,
        "env_kwargs": json.loads(json.dumps(dict(env_kwargs), default=json_default)),
        "physics_dt": config.physics_dt,
        "noise_hold": config.noise.hold,
        "max_time": config.max_time,
        **environment(),
    }
    result = []
    for i, seed in enumerate(seeds):
        length = int(steps[i])
        s = samples[i, : length + 1, _S_COLUMN]
        samples[i, : length + 1, -3:] = sim.paths[i].evaluate(s)[0]
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
                termination_reason=episode_end(int(codes[i])),
                control_dt=config.control_dt,
                u_desired=config.u_desired,
                actuator_limits=config.params.actuator_limits,
                top_speed=config.params.max_surge,
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


def evaluate(
    policy: Any,
    seeds: Sequence[int],
    *,
    transient: float | None = None,
    batch_size: int = DEFAULT_BATCH,
    threads: int | None = 1,
    **env_kwargs: Any,
) -> list[dict[str, Any]]:
    """Metrics (`compute_metrics`) of ``policy`` on each seed, in the order of ``seeds``.

    ``transient`` [s]: the metrics window start; None: the shared rule min(100 s, max_time/2)
    (`auv_gym.metrics.window_start`).

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
