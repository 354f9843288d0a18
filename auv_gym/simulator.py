"""Configuration and batched state of the path-following simulation, shared by both envs.

`SimConfig` turns the environments' keyword arguments into validated settings; `Simulator` holds
the state of n vehicles as arrays and advances them all with one compiled call. The single env is
a `Simulator` with n = 1, the vector env one with n = num_envs, so the two cannot diverge.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numba import njit, prange

from auv_gym.disturbances import (
    KEY,
    CurrentConfig,
    NoiseConfig,
    draw_keys,
    gauss_markov_coefficients,
)
from auv_gym.dynamics import STATE, STATE_DIM
from auv_gym.integrator import (
    ACTUATORS,
    CONFIG_FIELDS,
    RECORD_DIM,
    advance_vehicle,
    config_record,
)
from auv_gym.observation import (
    GUIDANCE_DIM,
    OBS_DIM,
    OBS_HIGH,
    OBS_LOW,
    build_observation,
    guidance_row,
)
from auv_gym.paths import Path, make_path
from auv_gym.task import REWARD_TERMS, RewardWeights, TaskLimits, task_row, task_vector
from auv_gym.vehicle import N_PARAMS, AUVParams, remus100

__all__ = ["ACTUATOR_LIMITS", "DISTURBANCE_PRESETS", "SimConfig", "Simulator"]

# "paper" mode limits (docs/model.md §2.3): |X| <= 50 N, |M|, |N| <= 10 N·m.
ACTUATOR_LIMITS = (50.0, 10.0, 10.0)
DISTURBANCE_PRESETS = {"paper": 35.0, "none": 0.0}
VIRTUAL_POINT_LAWS = {"corrected": 1.0, "printed": -1.0}
_SUBSTEP_TOL = 1e-9


@dataclass(frozen=True)
class SimConfig:
    """Validated simulation settings (units: s, m, m/s, N, N·m)."""

    path: Path = field(default_factory=lambda: make_path("helix"))
    params: AUVParams = field(default_factory=remus100)
    noise: NoiseConfig = field(default_factory=NoiseConfig)
    current: CurrentConfig = field(default_factory=CurrentConfig)
    param_uncertainty: float = 0.0  # ε: coefficients scaled by 1 + U[−ε, ε] per episode
    actuator: str = "paper"
    actuator_limits: tuple[float, float, float] = ACTUATOR_LIMITS  # [N, N·m, N·m]
    control_dt: float = 0.05  # [s]
    physics_dt: float = 0.01  # [s]
    max_time: float = 300.0  # [s]
    u_desired: float = 1.0  # [m/s] u_D
    sigma: float = 0.5  # [m] virtual-point law width σ
    # "corrected": u_p = u_D(1 + tanh(x_e/σ)) (docs/model.md §3.3); "printed": the paper's misprint
    # u_D(1 − tanh(x_e/σ)), unstable, kept only for the sign-regression tests (docs/model.md §8.9).
    virtual_point_law: str = "corrected"
    randomize_start: bool = False
    start_position: tuple[float, float, float] | None = None  # [m]; None: the path's default
    start_heading: float | None = None  # [rad]
    reward: RewardWeights = field(default_factory=RewardWeights)
    limits: TaskLimits = field(default_factory=TaskLimits)

    @classmethod
    def from_kwargs(
        cls,
        path: str | Path = "helix",
        disturbance: str | float | NoiseConfig = "paper",
        current: CurrentConfig | Sequence[float] | dict | None = None,
        param_uncertainty: float = 0.0,
        actuator: str = "paper",
        control_dt: float = 0.05,
        physics_dt: float = 0.01,
        noise_hold: float = 0.01,
        max_time: float = 300.0,
        randomize_start: bool = False,
        u_desired: float = 1.0,
        sigma: float = 0.5,
        virtual_point_law: str = "corrected",
        corridor: float = 30.0,
        max_pitch: float = math.radians(60.0),
        params: AUVParams | None = None,
        start_position: Sequence[float] | None = None,
        start_heading: float | None = None,
        reward_weights: RewardWeights | dict | None = None,
    ) -> SimConfig:
        """Build from the environments' keyword arguments; see `AUVPath3DEnv` for their meaning."""
        the_path = make_path(path)
        if isinstance(disturbance, NoiseConfig):
            noise = NoiseConfig(disturbance.amplitude, noise_hold)
        elif isinstance(disturbance, str):
            if disturbance not in DISTURBANCE_PRESETS:
                raise ValueError(
                    f"unknown disturbance {disturbance!r}; valid: {sorted(DISTURBANCE_PRESETS)}, "
                    "a NoiseConfig or an amplitude in N / N·m"
                )
            noise = NoiseConfig((DISTURBANCE_PRESETS[disturbance],) * 5, noise_hold)
        else:
            noise = NoiseConfig((float(disturbance),) * 5, noise_hold)
        if isinstance(reward_weights, dict):
            reward_weights = RewardWeights(**reward_weights)
        return cls(
            path=the_path,
            params=params if params is not None else remus100(),
            noise=noise,
            current=CurrentConfig.from_spec(current),
            param_uncertainty=float(param_uncertainty),
            actuator=actuator,
            control_dt=float(control_dt),
            physics_dt=float(physics_dt),
            max_time=float(max_time),
            u_desired=float(u_desired),
            sigma=float(sigma),
            virtual_point_law=virtual_point_law,
            randomize_start=bool(randomize_start),
            start_position=None if start_position is None else tuple(map(float, start_position)),
            start_heading=start_heading,
            reward=reward_weights if reward_weights is not None else RewardWeights(),
            limits=TaskLimits(corridor=corridor, max_pitch=max_pitch, s_end=the_path.s_end),
        )

    def __post_init__(self) -> None:
        if not isinstance(self.params, AUVParams):
            raise ValueError(f"params must be an AUVParams, got {type(self.params).__name__}")
        if self.virtual_point_law not in VIRTUAL_POINT_LAWS:
            raise ValueError(
                f"unknown virtual_point_law {self.virtual_point_law!r}; "
                f"valid: {sorted(VIRTUAL_POINT_LAWS)}"
            )
        if self.actuator not in ACTUATORS:
            raise ValueError(f"unknown actuator {self.actuator!r}; valid: {sorted(ACTUATORS)}")
        for name in ("control_dt", "physics_dt", "max_time", "u_desired", "sigma"):
            value = getattr(self, name)
            if not (isinstance(value, float) and math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive finite number, got {value!r}")
        if not (0.0 <= self.param_uncertainty < 1.0):
            raise ValueError(f"param_uncertainty must be in [0, 1), got {self.param_uncertainty}")
        if not all(math.isfinite(v) and v > 0 for v in self.actuator_limits):
            raise ValueError(f"actuator_limits must be positive, got {self.actuator_limits}")
        for name, value in (("control_dt", self.control_dt), ("noise_hold", self.noise.hold)):
            ratio = value / self.physics_dt
            if abs(ratio - round(ratio)) > _SUBSTEP_TOL * ratio or round(ratio) < 1:
                raise ValueError(
                    f"{name} = {value} s must be a whole multiple of physics_dt = "
                    f"{self.physics_dt} s"
                )
        if self.start_position is not None and (
            len(self.start_position) != 3 or not all(map(math.isfinite, self.start_position))
        ):
            raise ValueError(f"start_position must be a finite 3-vector, got {self.start_position}")

    @property
    def kernel_sigma(self) -> float:
        """σ as the kernels use it: u_D(1 + tanh(x_e/σ)) with σ < 0 gives the printed law."""
        return VIRTUAL_POINT_LAWS[self.virtual_point_law] * self.sigma

    @property
    def substeps(self) -> int:
        """Physics steps per control step."""
        return round(self.control_dt / self.physics_dt)

    @property
    def max_steps(self) -> int:
        """Control steps until truncation at `max_time`."""
        return math.ceil(self.max_time / self.control_dt - _SUBSTEP_TOL)

    def packed(self) -> np.ndarray:
        """The float64 row `integrator.advance_vehicle` reads (layout `CONFIG_FIELDS`)."""
        gm_a, gm_b = gauss_markov_coefficients(self.current, self.physics_dt)
        values = {
            "n_sub": self.substeps,
            "physics_dt": self.physics_dt,
            "hold_steps": round(self.noise.hold / self.physics_dt),
            "u_d": self.u_desired,
            "sigma": self.kernel_sigma,
            "actuator": ACTUATORS[self.actuator],
            "gm_a": gm_a,
        }
        for c, name in enumerate(("f_u", "f_v", "f_w", "f_q", "f_r")):
            values[f"noise_{name}"] = self.noise.amplitude[c]
        for c, axis in enumerate("XMN"):
            values[f"limit_{axis}"] = self.actuator_limits[c]
        for c, axis in enumerate("xyz"):
            values[f"current_{axis}"] = self.current.mean[c]
            values[f"gm_b_{axis}"] = gm_b[c]
        return np.array([float(values[name]) for name in CONFIG_FIELDS])


@njit(cache=True, inline="always")
def _step_row(i, state, current, actions, params, keys, step_index, kind, pdata, cfg, task,
              obs_low, obs_high, guid, obs, record, terms, reward, code):  # fmt: skip
    """Advance vehicle i one control step with its saturated action, then score it."""
    a = actions[i]
    for j in range(3):  # documented actuator saturation: |a_j| <= 1
        a[j] = min(max(a[j], -1.0), 1.0)
    advance_vehicle(state[i], current[i], a, params[i], keys[i, KEY.noise], keys[i, KEY.current],
                    step_index[i], kind, pdata, cfg, guid[i], obs[i], record[i])  # fmt: skip
    step_index[i] += int(config_record(cfg).n_sub)
    reward[i], code[i] = task_row(state[i], guid[i], obs[i], a, obs_low, obs_high, task, terms[i])


@njit(cache=True, inline="always")
def _first_non_finite_row(actions):
    for i in range(actions.shape[0]):
        for j in range(actions.shape[1]):
            if not math.isfinite(actions[i, j]):
                return i
    return -1


# Two entry points with the same arguments: numba keys its on-disk cache by function, so the
# serial and the threaded kernels must be distinct functions. Each returns the first row with a
# non-finite action (nothing is advanced then), or −1. The serial kernel allocates nothing, so it
# runs without numba's reference counting (`_nrt=False`): the row views of its loop otherwise
# cost two atomic updates each, a quarter of its time (the threaded kernel's loop has none).
@njit(cache=True, _nrt=False)
def _step_one(state, current, actions, params, keys, step_index, kind, pdata, cfg, task,
              obs_low, obs_high, guid, obs, record, terms, reward, code):  # fmt: skip
    bad = _first_non_finite_row(actions)
    if bad < 0:
        for i in range(state.shape[0]):
            _step_row(i, state, current, actions, params, keys, step_index, kind, pdata, cfg,
                      task, obs_low, obs_high, guid, obs, record, terms, reward, code)  # fmt: skip
    return bad


@njit(cache=True, parallel=True)
def _step_all(state, current, actions, params, keys, step_index, kind, pdata, cfg, task,
              obs_low, obs_high, guid, obs, record, terms, reward, code):  # fmt: skip
    bad = _first_non_finite_row(actions)
    if bad < 0:
        for i in prange(state.shape[0]):
            _step_row(i, state, current, actions, params, keys, step_index, kind, pdata, cfg,
                      task, obs_low, obs_high, guid, obs, record, terms, reward, code)  # fmt: skip
    return bad


@njit(cache=True)
def _observe_rows(rows, state, kind, pdata, u_d, sigma, guid, obs):
    for i in rows:
        guidance_row(state[i], kind, pdata, u_d, sigma, guid[i])
        build_observation(state[i], guid[i], u_d, obs[i])


class Simulator:
    """n vehicles of one `SimConfig`, as arrays; rows reset independently.

    ``parallel`` picks the threaded kernel (default: when n > 1) or the serial one; both give
    identical results. The serial kernel never starts numba's OpenMP pool, whose spinning
    threads slowed torch in the same process 25× on a loaded 2-core machine.
    """

    def __init__(self, config: SimConfig, n: int = 1, parallel: bool | None = None) -> None:
        if not (isinstance(n, (int, np.integer)) and n >= 1):
            raise ValueError(f"number of vehicles must be an integer >= 1, got {n!r}")
        self.config = config
        self.n = int(n)
        self._cfg = config.packed()
        self._task = task_vector(config.reward, config.limits)
        self._pdata = np.ascontiguousarray(config.path.data, dtype=np.float64)
        self._kind = int(config.path.kind)
        self._nominal = config.params.to_vector()
        self._kernel = _step_all if (n > 1 if parallel is None else parallel) else _step_one
        self.state = np.zeros((n, STATE_DIM))
        self.current = np.zeros((n, 3))
        self.params = np.tile(self._nominal, (n, 1))
        self.keys = np.zeros((n, 2), dtype=np.uint64)
        self.step_index = np.zeros(n, dtype=np.int64)
        self.guid = np.zeros((n, GUIDANCE_DIM))
        self.obs = np.zeros((n, OBS_DIM))
        self.record = np.zeros((n, RECORD_DIM))
        self.terms = np.zeros((n, len(REWARD_TERMS)))
        self.reward = np.zeros(n)
        self.code = np.zeros(n, dtype=np.int64)
        self._actions = np.zeros((n, 3))
        assert self.params.shape[1] == N_PARAMS

    @property
    def steps(self) -> np.ndarray:
        """Control steps of each vehicle since its reset."""
        return self.step_index // self.config.substeps

    @property
    def time(self) -> np.ndarray:
        """Simulated time of each vehicle since its reset [s]."""
        return self.step_index * self.config.physics_dt

    def reset_row(self, i: int, rng: np.random.Generator) -> None:
        """Draw vehicle i's episode (keys, parameters, start, current) from rng, in fixed order."""
        self.reset_rows([i], [rng])

    def reset_rows(self, rows: Sequence[int], rngs: Sequence[np.random.Generator]) -> None:
        """`reset_row` for each row with its own generator; the observations in one kernel call."""
        for i, rng in zip(rows, rngs, strict=True):
            self._draw_episode(int(i), rng)
        cfg = self.config
        _observe_rows(np.asarray(rows, dtype=np.int64), self.state, self._kind, self._pdata,
                      cfg.u_desired, cfg.kernel_sigma, self.guid, self.obs)  # fmt: skip

    def _draw_episode(self, i: int, rng: np.random.Generator) -> None:
        cfg = self.config
        self.keys[i] = draw_keys(rng)
        if cfg.param_uncertainty > 0.0:
            self.params[i] = cfg.params.perturbed(rng, cfg.param_uncertainty).to_vector()
        else:
            self.params[i] = self._nominal
        position, heading, s0, u0 = self._start(rng)
        self.state[i] = 0.0
        self.state[i, [STATE.x, STATE.y, STATE.z]] = position
        self.state[i, STATE.psi] = heading
        self.state[i, STATE.u] = u0
        self.state[i, STATE.s] = s0
        # Start the Gauss–Markov deviation in its stationary distribution.
        self.current[i] = rng.standard_normal(3) * np.asarray(cfg.current.std)
        self.step_index[i] = 0
        self.record[i] = 0.0
        self.terms[i] = 0.0
        self.reward[i] = 0.0
        self.code[i] = 0

    def _start(self, rng: np.random.Generator) -> tuple[np.ndarray, float, float, float]:
        cfg = self.config
        position, heading = cfg.path.default_start()
        if cfg.start_position is not None:
            position = np.asarray(cfg.start_position)
        if cfg.start_heading is not None:
            heading = float(cfg.start_heading)
        if not cfg.randomize_start:
            return position, heading, 0.0, 0.0
        # Training distribution: half the episodes near the paper's start, half anywhere on the
        # first turn of the path, with a random heading error and speed.
        draws = rng.uniform(-1.0, 1.0, size=7)
        if draws[0] < 0.0:
            return position + 2.0 * draws[1:4], heading + 0.2 * draws[4], 0.0, 0.0
        s_span = min(40.0, cfg.path.s_end) if math.isfinite(cfg.path.s_end) else 40.0
        s0 = 0.5 * (draws[1] + 1.0) * 0.9 * s_span
        p, dp, _ = cfg.path.evaluate(s0)
        offset = 8.0 * rng.uniform(-1.0, 1.0, size=3)
        path_heading = math.atan2(dp[1], dp[0])
        return p + offset, path_heading + (math.pi / 3) * draws[5], s0, 0.75 * (draws[6] + 1.0)

    def step(self, actions: np.ndarray) -> None:
        """Advance all vehicles one control step with actions in [−1, 1], shape (n, 3).

        Actions beyond ±1 saturate; a non-finite action raises ValueError before any row moves.
        """
        np.copyto(self._actions, actions)
        bad_row = self._kernel(self.state, self.current, self._actions, self.params, self.keys,
                     self.step_index, self._kind, self._pdata, self._cfg, self._task,
                     OBS_LOW, OBS_HIGH, self.guid, self.obs, self.record, self.terms,
                     self.reward, self.code)  # fmt: skip
        if bad_row >= 0:
            raise ValueError(f"action must be finite, got {actions[bad_row]!r} (row {bad_row})")
