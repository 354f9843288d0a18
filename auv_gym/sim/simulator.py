"""Batched state of the path-following simulation, shared by both envs.

`Simulator` holds the state of n vehicles as arrays and advances them all with one compiled call;
its settings are a `auv_gym.sim.config.SimConfig`. The single env is a `Simulator` with n = 1, the
vector env one with n = num_envs, so the two cannot diverge.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numba import njit, prange, types
from numba.extending import overload

from auv_gym.ocean.disturbances import draw_keys
from auv_gym.ocean.forcing import ocean_row, ocean_width
from auv_gym.paths.shapes import Path
from auv_gym.sim.config import SIX_DOF_PLANT, SimConfig
from auv_gym.sim.episode_start import draw_start
from auv_gym.sim.fleet import EpisodeTable, Fleet, StepOutputs
from auv_gym.sim.integrator import ACTUATORS, CONFIG_FIELDS, RECORD_DIM, config_record
from auv_gym.sim.navigation import Navigation
from auv_gym.sim.observation import (
    GUIDANCE_DIM,
    GUIDE,
    OBS_DIM,
    build_observation,
    guidance_row,
    vehicle_speed_bound,
)
from auv_gym.sim.path_depths import episode_surface_z
from auv_gym.sim.period import advance_period, period_body
from auv_gym.sim.plants import ROLL_DIM
from auv_gym.sim.preview import extend_rows
from auv_gym.sim.randomization import EpisodeTask, draw_task
from auv_gym.sim.safety_cost import safety_vector
from auv_gym.sim.task import (
    ENVELOPE,
    REWARD_TERMS,
    TASK_FIELDS,
    TERM,
    task_cost,
    task_row,
    task_vector,
)
from auv_gym.vehicle.actuators import ACTUATOR_STATE_DIM, check_commands
from auv_gym.vehicle.dynamics import STATE, STATE_DIM
from auv_gym.vehicle.params import N_PARAMS
from auv_gym.vehicle.variation import HullDraw, varied_hull_row, varied_params

__all__ = ["PARALLEL_MIN_VEHICLES", "Simulator"]

# Below this many vehicles the kernel runs on one thread unless told otherwise: a step costs
# < 1 ms there, and on a loaded 2-core machine the threads' barrier made it 5-50x slower (and
# the serial kernel is the one the set-up compiles; the threaded one compiles on first use).
PARALLEL_MIN_VEHICLES = 256


def _no_cost(cost, i, st, task):
    return None


def _score_cost(cost, i, st, task):
    cost[i] = task_cost(st, task)


def score_cost(cost, i, st, task):
    """Vehicle i's safety cost after a step into ``cost[i]``; nothing when ``cost`` is None (the
    configuration has no safety cost: it stays 0)."""
    (_no_cost if cost is None else _score_cost)(cost, i, st, task)


@overload(score_cost, inline="always")
def _score_cost_kernel(cost, i, st, task):
    return _no_cost if isinstance(cost, types.NoneType) else _score_cost


@njit(cache=True, inline="always")
def _saturated_action(actions, i):
    """Vehicle i's action, saturated in place: the documented |a_j| <= 1."""
    a = actions[i]
    for j in range(3):
        a[j] = min(max(a[j], -1.0), 1.0)
    return a


@njit(cache=True, inline="always")
def _score_row(i, fleet, a, table, out, r, cfg):
    """After vehicle i's period: its step count, reward, end code and safety cost."""
    fleet.step_index[i] += int(config_record(cfg).n_sub)
    st, task = fleet.state[i], table.tasks[r]
    out.reward[i], out.code[i] = task_row(
        st, out.guid[i], out.obs[i], a, table.obs_low, table.obs_high, task, out.terms[i]
    )
    score_cost(out.cost, i, st, task)


# Called, not inlined: inlined into a prange loop, its writes into arrays that are members of
# the records were lost (numba 0.68 parfors; tests/test_simulation_core.py checks the threaded
# kernel against the serial one).
@njit(cache=True)
def _step_row(i, fleet, actions, table, out):
    """Advance vehicle i one control step with its saturated action, then score it. Its path,
    config and task are row ``table.row[i]`` of the episode table (`Simulator`)."""
    a = _saturated_action(actions, i)
    r = table.row[i]
    cfg = table.cfgs[r]
    advance_period(fleet, i, a[0], a[1], a[2], table.kinds[r], table.pdata[r], cfg, out)
    _score_row(i, fleet, a, table, out, r, cfg)


@njit(cache=True, inline="always")
def _first_non_finite_row(actions):
    for i in range(actions.shape[0]):
        for j in range(actions.shape[1]):
            if not math.isfinite(actions[i, j]):
                return i
    return -1


# Two entry points with the same arguments: numba keys its on-disk cache by function, so the
# serial and the threaded kernels must be distinct functions. Each takes the `fleet.Fleet`, the
# (n, 3) actions, the `fleet.EpisodeTable` and the `fleet.StepOutputs`, and returns the first
# row with a non-finite action (nothing is advanced then), or −1. The serial kernel allocates
# nothing, so it runs without numba's reference counting (`_nrt=False`): the row views of its
# loop otherwise cost two atomic updates each, a quarter of its time (the threaded kernel's
# loop has none).
@njit(cache=True, _nrt=False)
def _step_one(fleet, actions, table, out):
    bad = _first_non_finite_row(actions)
    if bad < 0:
        for i in range(actions.shape[0]):  # `_step_row`, inlined
            a = _saturated_action(actions, i)
            r = table.row[i]
            cfg = table.cfgs[r]
            period_body(fleet, i, a[0], a[1], a[2], table.kinds[r], table.pdata[r], cfg, out)
            _score_row(i, fleet, a, table, out, r, cfg)
    return bad


@njit(cache=True, parallel=True)
def _step_all(fleet, actions, table, out):
    bad = _first_non_finite_row(actions)
    if bad < 0:
        for i in prange(actions.shape[0]):
            _step_row(i, fleet, actions, table, out)
    return bad


@njit(cache=True)
def _observe_rows(rows, state, row, kinds, pdata, cfgs, guid, obs):
    for i in rows:
        cfg = config_record(cfgs[row[i]])
        guidance_row(state[i], kinds[row[i]], pdata[row[i]], cfg.u_d, cfg.sigma, guid[i])
        build_observation(state[i], guid[i], cfg.u_d, obs[i])


_S_END = TASK_FIELDS.index("s_end")
_W_TERMINATION = TASK_FIELDS.index("w_termination")
_CONFIG_INDEX = {name: j for j, name in enumerate(CONFIG_FIELDS)}
_NOISE_COLUMNS = [_CONFIG_INDEX[f"noise_f_{c}"] for c in "uvwqr"]
_CURRENT_COLUMNS = [_CONFIG_INDEX[f"current_{c}"] for c in "xyz"]
_HULL_STREAM = 6  # the 6-DOF hull's draws: a stream of the episode's keys of its own
_VARIATION_STREAM = 7  # the hull variation's draw (`auv_gym.vehicle.variation`), both plants'
_ERRORS = slice(GUIDE.x_e, GUIDE.z_e + 1)  # the tracking errors in a guidance row (the history)
_ACTUATOR_NAMES = np.array(sorted(ACTUATORS, key=ACTUATORS.__getitem__))  # code → name


# The arrays of a `Simulator` that change while stepping or at a reset (`Simulator.snapshot`);
# the others are fixed at construction. `error_integral` is a view into `extra` and follows it.
SNAPSHOT_ARRAYS = (
    "state",
    "current",
    "params",
    "keys",
    "step_index",
    "guid",
    "obs",
    "record",
    "terms",
    "reward",
    "code",
    "cost",
    "_actions",
    "extra",
    "last_action",
    "_cfg",
    "_task",
    "_pdata",
    "_kind",
    "ocean",
    "actuator_state",
    "roll",
    "hull",
    "error_history",
    "history_index",
)


class Simulator:
    """n vehicles of one `SimConfig`, as arrays; rows reset independently.

    The kernels read each vehicle's path, packed config and task row from an episode table
    indexed by ``row``: one shared row for a fixed configuration, one row per vehicle when
    episodes draw their own path, current, noise amplitude or actuator
    (`SimConfig.randomized`, `randomization.draw_task`). The path table is padded to the
    longest path vector; `paths` holds each vehicle's current `Path`.

    ``parallel`` picks the threaded kernel (default: from `PARALLEL_MIN_VEHICLES` vehicles) or
    the serial one; both give
    identical results. The serial kernel never starts numba's OpenMP pool, whose spinning
    threads compete with torch in the same process (README, Performance).
    """

    def __init__(self, config: SimConfig, n: int = 1, parallel: bool | None = None) -> None:
        if not (isinstance(n, (int, np.integer)) and n >= 1):
            raise ValueError(f"number of vehicles must be an integer >= 1, got {n!r}")
        self.config = config
        self.n = int(n)
        self._per_vehicle = config.randomized
        m = self.n if self._per_vehicle else 1
        self._row = np.arange(n, dtype=np.int64) if self._per_vehicle else np.zeros(n, np.int64)
        self._cfg = np.tile(config.packed(), (m, 1))
        safety = safety_vector(config.depth_envelope, config.safety_cost)
        self._task = np.tile(task_vector(config.reward, config.limits, safety), (m, 1))
        fixed = isinstance(config.path, Path)
        width = config.path.data.size if fixed else config.path.max_data_size
        self._pdata = np.zeros((m, width))
        self._kind = np.zeros(m, dtype=np.int64)
        self.paths: list[Path | None] = [config.path if fixed else None] * self.n
        if fixed:
            self._pdata[:] = config.path.data
            self._kind[:] = config.path.kind
        self._nominal = config.params.to_vector()
        threaded = n >= PARALLEL_MIN_VEHICLES if parallel is None else parallel
        self._kernel = _step_all if threaded else _step_one
        self.state = np.zeros((n, STATE_DIM))
        self.current = np.zeros((n, 3))
        # Realistic actuators' shaft speed, fin angles and rate-limited fraction (zero otherwise).
        self.actuator_state = np.zeros((n, ACTUATOR_STATE_DIM))
        self._command_box = config.actuator == "realistic"
        self.params = np.tile(self._nominal, (n, 1))
        self.keys = np.zeros((n, 2), dtype=np.uint64)
        self.step_index = np.zeros(n, dtype=np.int64)
        self.guid = np.zeros((n, GUIDANCE_DIM))
        self.obs = np.zeros((n, OBS_DIM))
        self.record = np.zeros((n, RECORD_DIM))
        self.terms = np.zeros((n, len(REWARD_TERMS)))
        self.reward = np.zeros(n)
        self.code = np.zeros(n, dtype=np.int64)
        self.cost = np.zeros(n)  # safety cost of the last step (`auv_gym.sim.safety_cost`)
        self._actions = np.zeros((n, 3))
        # The 6-DOF plant: each vehicle's roll (φ [rad], p [rad/s]) and hull row
        # (`SixDofVehicle.kernel_vector`, drawn per episode with parameter uncertainty); no
        # columns on the 5-DOF plant.
        self.roll = np.zeros((n, ROLL_DIM))
        self.six_dof = config.plant == SIX_DOF_PLANT
        self._nominal_hull = config.plant_params.kernel_vector() if self.six_dof else np.zeros(0)
        self.hull = np.tile(self._nominal_hull, (n, 1))
        # Waves and profiled current per vehicle (`ocean.ocean_row`); all zero without them.
        self.ocean = np.zeros((n, ocean_width(config.waves)))
        # The agent observation's extra entries (`preview.extend_rows`); none for "paper".
        self.layout = config.observation
        self.speed_bound = vehicle_speed_bound(config.params.max_surge)  # [m/s]
        self.obs_low, self.obs_high = self.layout.bounds(
            config.current_speed_bound, self.speed_bound
        )
        # The paper entries' bounds, which the step kernel's termination check reads.
        self._paper_bounds = (self.obs_low[:OBS_DIM].copy(), self.obs_high[:OBS_DIM].copy())
        self.extra = np.zeros((n, self.layout.extra_dim))
        self.last_action = np.zeros((n, 3))  # saturated, 0 after a reset
        # Leaky error integrals (y_e, z_e; x_e too with "xyz") [m·s] (`ObservationConfig`
        # integral_time, integral_limit), then the errors' history [m]: the last columns of
        # `extra`, which `extend_rows` leaves alone, updated in place.
        self._bind_error_views()
        if self.layout.integrals:
            decay = math.exp(-config.control_dt / self.layout.integral_time)
            self._integral_gain = (decay, self.layout.integral_time * (1.0 - decay))
        # The observed errors (x_e, y_e, z_e) [m] of the last H·stride + 1 control steps, a ring
        # written at `history_index` (all rows step together); H past samples read from it.
        steps = self.layout.history_steps
        stride = self.layout.history_stride(config.control_dt) if steps else 1
        self.error_history = np.zeros((n, steps * stride + 1 if steps else 0, 3))
        self.history_index = np.zeros(1, dtype=np.int64)
        self._history_lags = stride * np.arange(1, steps + 1, dtype=np.int64)
        self._every_row = np.arange(n, dtype=np.int64)
        assert self.params.shape[1] == N_PARAMS
        # The sensor model (`auv_gym.sim.navigation`): None for ideal sensors, the exact state.
        self.navigation = (
            None
            if config.sensors.ideal
            else Navigation(config.sensors, config.control_dt, self.n, config.u_desired)
        )
        # The kernels' records (`fleet`). A kernel is compiled per combination of None and array
        # in them. The plant is chosen that way (each kernel has one plant's code), and a safety
        # cost with zero weights; the actuator state and the ocean rows are always passed and
        # their flags decide at run time: compiling them out bought 1-3 % of the paper
        # configuration's speed and cost a minute of compiling per combination on 2 cores
        # (docs/performance.md).
        self.fleet = Fleet(
            state=self.state,
            current=self.current,
            params=self.params,
            keys=self.keys,
            step_index=self.step_index,
            roll=self.roll if self.six_dof else None,
            hull=self.hull if self.six_dof else None,
            actuators=self.actuator_state,
            ocean=self.ocean,
            guidance=None if self.navigation is None else self.navigation.guidance,
        )
        self.episodes = EpisodeTable(
            self._row, self._kind, self._pdata, self._cfg, self._task, *self._paper_bounds
        )
        weights = config.safety_cost
        costly = (weights.depth, weights.speed, weights.pitch) != (0.0, 0.0, 0.0)
        self.outputs = StepOutputs(
            guid=self.guid,
            obs=self.obs,
            record=self.record,
            terms=self.terms,
            reward=self.reward,
            code=self.code,
            cost=self.cost if costly else None,
        )

    @property
    def steps(self) -> np.ndarray:
        """Control steps of each vehicle since its reset."""
        return self.step_index // self.config.substeps

    @property
    def time(self) -> np.ndarray:
        """Simulated time of each vehicle since its reset [s]."""
        return self.step_index * self.config.physics_dt

    @property
    def actuators(self) -> np.ndarray:
        """Each vehicle's actuator model in its current episode, "paper", "fins" or "realistic"
        (n,): the configured one, or the one its episode drew (``actuator="random"``)."""
        codes = self._cfg[self._row, _CONFIG_INDEX["actuator"]].astype(np.int64)
        return _ACTUATOR_NAMES[codes]

    def _snapshot_arrays(self) -> dict[str, np.ndarray]:
        """`SNAPSHOT_ARRAYS` by name, then the sensor model's (`Navigation.arrays`) if any."""
        arrays = {name: getattr(self, name) for name in SNAPSHOT_ARRAYS}
        if self.navigation is not None:
            for name in self.navigation.arrays:
                arrays[f"navigation.{name}"] = getattr(self.navigation, name)
        return arrays

    def _bind_error_views(self) -> None:
        """`error_integral` and `error_past`: views of `extra`'s last columns, written in place."""
        history_start = self.extra.shape[1] - self.layout.history
        self.error_integral = self.extra[:, history_start - self.layout.integrals : history_start]
        self.error_past = self.extra[:, history_start:]

    def __setstate__(self, state: dict[str, Any]) -> None:
        """Unpickled or deep-copied: pickle stores a view as an array of its own, which the
        steps would then update while the observation reads `extra`; the views are rebuilt."""
        self.__dict__.update(state)
        self._bind_error_views()

    def snapshot(self) -> dict[str, Any]:
        """Copies of the arrays that change while stepping or at a reset (`SNAPSHOT_ARRAYS`)
        and each vehicle's path: with `restore`, a simulator built with the same arguments
        continues bit for bit (the vector env's snapshots, a paused training run)."""
        arrays = {name: array.copy() for name, array in self._snapshot_arrays().items()}
        return {"arrays": arrays, "paths": list(self.paths)}  # paths are immutable, shared

    def restore(self, snapshot: Mapping[str, Any]) -> None:
        """Continue from a `snapshot` of a simulator built with the same arguments; ValueError
        naming the first array whose shape differs (then nothing is changed)."""
        # A snapshot from before these arrays existed (a paused training run) had a flat sea,
        # the instantaneous actuators and no safety cost.
        arrays = {
            "ocean": np.zeros((self.n, ocean_width(None))),
            "actuator_state": np.zeros_like(self.actuator_state),
            "cost": np.zeros(self.n),
            "roll": np.zeros_like(self.roll),
            "hull": self.hull.copy(),
            "error_history": np.zeros((self.n, 0, 3)),
            "history_index": np.zeros(1, dtype=np.int64),
            **snapshot["arrays"],
        }
        targets = self._snapshot_arrays()
        for name, target in targets.items():
            value = arrays.get(name)
            if value is None or target.shape != value.shape:
                shape = None if value is None else value.shape
                raise ValueError(
                    f"snapshot array {name} has shape {shape}, this vector "
                    f"env's {target.shape}: built with other arguments"
                )
        for name, target in targets.items():  # in place: views such as `error_integral` stay
            np.copyto(target, arrays[name])
        self.paths[:] = snapshot["paths"]

    def reset_row(self, i: int, rng: np.random.Generator) -> None:
        """Draw vehicle i's episode (keys, parameters, start, current) from rng, in fixed order."""
        self.reset_rows([i], [rng])

    def reset_rows(self, rows: Sequence[int], rngs: Sequence[np.random.Generator]) -> None:
        """`reset_row` for each row with its own generator; the observations in one kernel call."""
        for i, rng in zip(rows, rngs, strict=True):
            self._draw_episode(int(i), rng)
        rows = np.asarray(rows, dtype=np.int64)
        _observe_rows(
            rows, self.state, self._row, self._kind, self._pdata, self._cfg, self.guid, self.obs
        )
        if self.navigation is not None:
            self.navigation.sense(self, rows, reset=True)
        if self.extra.shape[1]:
            self.last_action[rows] = 0.0
            self.error_integral[rows] = 0.0
            if self.layout.history_steps:  # no past yet: the reset's errors stand in for it
                errors = self._observed_guid[rows, _ERRORS]
                self.error_history[rows] = errors[:, None, :]
                self.error_past[rows] = np.tile(errors, self.layout.history_steps)
            self._extend(rows)

    def observations(self, rows: np.ndarray | None = None) -> np.ndarray:
        """float32 observations of ``rows`` (default all): the paper's 15 entries, then the
        agent observation's extra ones when configured (`auv_gym.sim.observation`)."""
        base = self.obs if rows is None else self.obs[rows]
        if not self.extra.shape[1]:
            return base.astype(np.float32)
        extra = self.extra if rows is None else self.extra[rows]
        return np.concatenate([base, extra], axis=1, dtype=np.float32)

    @property
    def _observed_state(self) -> np.ndarray:
        """The state the observation is computed from: the navigation estimate or the truth."""
        return self.state if self.navigation is None else self.navigation.estimate

    @property
    def _observed_guid(self) -> np.ndarray:
        """The guidance row of `_observed_state` (the true one stays in `guid`)."""
        return self.guid if self.navigation is None else self.navigation.guid

    def _extend(self, rows: np.ndarray) -> None:
        layout = self.layout
        extend_rows(
            rows,
            self._observed_state,
            self.current,
            self.last_action,
            self._row,
            self._kind,
            self._pdata,
            self._cfg,
            self._task,
            _S_END,
            layout.points,
            layout.spacing,
            self.extra,
        )
        if self.navigation is not None:  # over ground as the DVL measured it, not the truth
            self.extra[rows, :3] = self.navigation.ground_velocity(rows)

    def _set_task(self, i: int, task: EpisodeTask) -> None:
        """Write vehicle i's drawn task into its row of the episode table."""
        path = task.path
        if path.data.size > self._pdata.shape[1]:  # a user's distribution cannot exceed it
            raise RuntimeError(f"drawn path of {path.data.size} values exceeds the table width")
        if not isinstance(self.config.path, Path):  # drawn: its depths are known only now
            self.config.check_depths(path, drawn=True)
        self.paths[i] = path
        self._kind[i] = path.kind
        self._pdata[i] = 0.0
        self._pdata[i, : path.data.size] = path.data
        cfg = self.config.packed()
        cfg[_CONFIG_INDEX["actuator"]] = ACTUATORS[task.actuator]
        cfg[_NOISE_COLUMNS] *= task.noise_scale
        cfg[_CURRENT_COLUMNS] += task.current
        self._cfg[i] = cfg
        self._task[i, _S_END] = path.s_end

    def _draw_episode(self, i: int, rng: np.random.Generator) -> None:
        cfg = self.config
        if self._per_vehicle:  # the task first, from its own seeds (`draw_task`)
            self._set_task(i, draw_task(cfg, rng))
        self.keys[i] = draw_keys(rng)
        # One hull variation per episode, read by both plants' parameters.
        variation = self._hull_draw(i) if cfg.hull_variation.active else None
        params = cfg.params
        if cfg.param_uncertainty > 0.0:
            params = params.perturbed(rng, cfg.param_uncertainty)
        if variation is not None:
            params = varied_params(params, variation)
        self.params[i] = self._nominal if params is cfg.params else params.to_vector()
        position, heading, s0, u0 = draw_start(cfg, rng, self.paths[i])
        self.state[i] = 0.0
        self.state[i, [STATE.x, STATE.y, STATE.z]] = position
        self.state[i, STATE.psi] = heading
        self.state[i, STATE.u] = u0
        self.state[i, STATE.s] = s0
        # Start the Gauss–Markov deviation in its stationary distribution.
        self.current[i] = rng.standard_normal(3) * np.asarray(cfg.current.std)
        self.actuator_state[i] = 0.0  # propeller stopped, fins centred
        self.roll[i] = 0.0
        if self.six_dof:
            self.hull[i] = self._hull_row(i, variation)
        if cfg.waves is not None or cfg.current_profile is not None:
            surface_z = episode_surface_z(cfg, self.paths[i], float(position[2]))
            self.ocean[i] = ocean_row(
                cfg.waves, cfg.current_profile, self.keys[i], cfg.physics_dt, surface_z
            )
        self.step_index[i] = 0
        self.record[i] = 0.0
        self.terms[i] = 0.0
        self.reward[i] = 0.0
        self.code[i] = 0
        self.cost[i] = 0.0

    def _hull_row(self, i: int, variation: HullDraw | None) -> np.ndarray:
        """Vehicle i's 6-DOF hull row for its episode: the nominal one, or with parameter
        uncertainty one drawn from the episode's keys (so the episode's other draws, and hence
        its start and disturbances, are those of the same seed on the 5-DOF plant), with the
        episode's hull ``variation`` applied (None: none)."""
        fraction = self.config.param_uncertainty
        hull = self.config.plant_params
        if fraction > 0.0:
            rng = np.random.Generator(np.random.PCG64([*self.keys[i].tolist(), _HULL_STREAM]))
            hull = hull.perturbed(rng, fraction)
        if variation is not None:
            return varied_hull_row(hull, variation)
        return self._nominal_hull if fraction == 0.0 else hull.kernel_vector()

    def _hull_draw(self, i: int) -> HullDraw:
        """Vehicle i's hull variation for its episode, from a stream of the episode's keys of its
        own: both plants read the same draw, and the episode's other draws are unchanged."""
        rng = np.random.Generator(np.random.PCG64([*self.keys[i].tolist(), _VARIATION_STREAM]))
        return self.config.hull_variation.draw(rng)

    def step(self, actions: np.ndarray) -> None:
        """Advance all vehicles one control step with actions in [−1, 1], shape (n, 3).

        Actions beyond ±1 saturate, except the realistic actuators' commands (n, δ_s, δ_r), which
        must lie in the box; a non-finite action or such a command raises ValueError before any
        row moves.
        """
        np.copyto(self._actions, actions)
        if self._command_box:
            check_commands(self._actions)
        bad_row = self._kernel(self.fleet, self._actions, self.episodes, self.outputs)
        if bad_row >= 0:
            raise ValueError(f"action must be finite, got {actions[bad_row]!r} (row {bad_row})")
        if self.navigation is not None:  # after scoring: the reward reads the true state
            self.navigation.sense(self, self._every_row, reset=False)
        if self.extra.shape[1]:
            self.last_action[:] = self._actions  # saturated in place by the kernel
            if self.layout.integrals:  # exact for an error held over the control period
                decay, gain = self._integral_gain
                self.error_integral *= decay
                self.error_integral += gain * self._observed_guid[:, self.layout.integrated_columns]
                if self.layout.integral_limit > 0.0:  # anti-windup: the approach cannot charge it
                    limit = self.layout.integral_limit
                    np.clip(self.error_integral, -limit, limit, out=self.error_integral)
            if self.layout.history_steps:
                self._remember_errors()
            self._extend(self._every_row)
            self._end_outside_extra_bounds()

    def _remember_errors(self) -> None:
        """Write this step's observed errors into the ring and read the H past samples, the
        k-th `history_interval`·k seconds ago, into the history columns."""
        length = self.error_history.shape[1]
        index = (int(self.history_index[0]) + 1) % length
        self.history_index[0] = index
        self.error_history[:, index] = self._observed_guid[:, _ERRORS]
        past = self.error_history[:, (index - self._history_lags) % length]
        self.error_past[:] = past.reshape(self.n, -1)

    def _end_outside_extra_bounds(self) -> None:
        """A running vehicle whose extra entries left their bounds ends as "envelope", with the
        termination charge, as `task.task_row` ends one whose paper entries did."""
        low, high = self.obs_low[OBS_DIM:], self.obs_high[OBS_DIM:]
        outside = ~((self.extra >= low) & (self.extra <= high)).all(axis=1) & (self.code == 0)
        for i in np.flatnonzero(outside):  # practically never: the bounds hold by construction
            charge = -self._task[self._row[i], _W_TERMINATION]
            self.code[i] = ENVELOPE
            self.terms[i, TERM.termination] = charge
            self.reward[i] += charge
