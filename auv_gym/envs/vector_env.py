"""`AUVPath3DVectorEnv`: n vehicles of `AUVPath3D-v0` advanced natively by one compiled kernel.

The vector env is the single env's glue applied to a `simulator.Simulator` of n rows: the physics,
guidance, reward and termination are the same compiled functions, called for every vehicle in one
parallel loop. Vehicle i keeps its own random generator, seeded like a single env reset with
seed k + i, so it reproduces `AUVPath3DEnv` step for step, autoresets included.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Sequence
from typing import Any, ClassVar

import numba
import numpy as np
from gymnasium import spaces
from gymnasium.envs.registration import EnvSpec
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from auv_gym.envs.checks import check_reset_observations, validate_actions
from auv_gym.envs.info import add_vector_infos, track_point
from auv_gym.envs.rendering import EpisodeRenderer
from auv_gym.envs.vector_reset import parse_autoreset_mode, reset_mask, seed_list
from auv_gym.sim.config import ENV_KEYWORDS, SimConfig
from auv_gym.sim.simulator import PARALLEL_MIN_VEHICLES, Simulator
from auv_gym.sim.task import NON_FINITE
from auv_gym.support.validation import integer

__all__ = ["PARALLEL_MIN_VEHICLES", "AUVPath3DVectorEnv", "parse_autoreset_mode"]

MAX_VEHICLES = 2**24  # about 60 GB of state: a bound that names the argument before numpy fails


class AUVPath3DVectorEnv(VectorEnv):
    r"""`num_envs` independent vehicles of `AUVPath3D-v0`, stepped by one batched kernel.

    Every keyword argument of `AUVPath3DEnv` is accepted with the same meaning and default
    (table in its docstring); the spaces are the single env's, batched with `batch_space`.
    `gym.make_vec("AUVPath3D-v0", num_envs=n, **kwargs)` builds this class.

    ## Arguments (in addition to the single env's)
    | argument | default | meaning |
    |---|---|---|
    | `num_envs` | 1 | number of vehicles, 1 ≤ n ≤ 2^24 |
    | `max_episode_steps` | None | `TimeLimit`-like step limit, an integer >= 1 |
    | `autoreset_mode` | NEXT_STEP | `AutoresetMode` or its value: NEXT_STEP, SAME_STEP, DISABLED |
    | `render_vehicle` | 0 | index of the vehicle `render()` draws |
    | `threads` | None | numba threads of the kernel; None: 1 below 256 vehicles, else all |

    Truncation happens where the single env truncates: from the first control step at which
    t ≥ `max_time`, and at `max_episode_steps` control steps if given, whether or not the step
    also terminates. `gym.make_vec` passes no `max_episode_steps` (the registration has none);
    `spec.max_episode_steps` is the smaller of the two limits.

    Results are identical for any thread count. On a machine whose cores are busy with other
    processes, the threads' barrier can make a step several times slower than `threads=1`
    (README, Performance; `auv-gym speed vector` measures it); pass `threads=1` there.

    ## Seeding and parity
    `reset(seed=k)` seeds vehicle i with k + i (a list gives one seed per vehicle, None entries
    keep that vehicle's generator). Vehicle i then reproduces ``AUVPath3DEnv(**kwargs)`` reset with
    seed k + i bit for bit: observation, reward, terminated, truncated and info. An autoreset
    draws the new episode from the vehicle's own generator, exactly like ``env.reset()`` without a
    seed, so a vehicle's sequence of episodes is that of one single env.

    ## Autoreset
    - NEXT_STEP (default, `metadata["autoreset_mode"]`): the step after a vehicle's episode ended
      resets it and returns its first observation with reward 0, terminated = truncated = False
      and the reset info; its action is ignored.
    - SAME_STEP: a finished vehicle is reset in the step that ended it; the returned observation
      and info are the new episode's, the last ones are in ``info["final_obs"]`` (object array)
      and ``info["final_info"]`` (dict of arrays), masked by ``info["_final_obs"]``.
    - DISABLED: nothing resets by itself; call ``reset(options={"reset_mask": mask})``.

    ``reset(options={"reset_mask": mask})`` (bool array of shape (n,)) resets only the masked
    vehicles, in every mode; the returned infos describe those vehicles.

    ## Snapshots
    `snapshot()` copies everything stepping reads (vehicle states, task draws, generators, step
    counters, last observations); `restore(snapshot)` on a vector env built with the same
    arguments continues bit for bit (a paused training run resumes with it).

    ## Info
    Gymnasium's vector convention, identical to `SyncVectorEnv` over the single env: for every key
    of the single env's info an array over vehicles (``tau`` (n, 3), ``disturbance`` (n, 5),
    ``termination_reason`` an object array with None where no episode terminated) and a boolean
    mask ``"_" + key`` marking the vehicles that report it.

    ## Bad input
    A wrong action batch shape, a NaN or inf in any row (no vehicle moves then) and
    ``num_envs < 1`` raise ValueError; non-numeric actions, seeds and options of the wrong type
    raise `ArgumentTypeError` (a TypeError and a ValueError). A vehicle whose state or
    observation stops being finite terminates alone with ``termination_reason == "non_finite"``
    and returns its last observation again; rows never share state.
    """

    metadata: ClassVar[dict[str, Any]] = {
        "render_modes": ["rgb_array"],
        "render_fps": 20,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def __init__(
        self,
        num_envs: int = 1,
        *,
        max_episode_steps: int | None = None,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        render_mode: str | None = None,
        render_vehicle: int = 0,
        threads: int | None = None,
        **env_kwargs: Any,
    ) -> None:
        num_envs = integer("num_envs", num_envs, 1, MAX_VEHICLES)
        unknown = sorted(set(env_kwargs) - set(ENV_KEYWORDS))
        if unknown:
            raise TypeError(
                f"unexpected keyword argument(s) {unknown}; valid: {sorted(ENV_KEYWORDS)}, "
                "num_envs, max_episode_steps, autoreset_mode, render_mode, render_vehicle, threads"
            )
        if max_episode_steps is not None:
            max_episode_steps = integer("max_episode_steps", max_episode_steps, 1)
        if threads is not None:
            threads = integer("threads", threads, 1)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be None or one of {self.metadata['render_modes']}, "
                f"got {render_mode!r}"
            )
        self.config = SimConfig.from_kwargs(**env_kwargs)
        self.num_envs = int(num_envs)
        self.autoreset_mode = parse_autoreset_mode(autoreset_mode)
        self.metadata = {
            **self.metadata,
            "autoreset_mode": self.autoreset_mode,
            "render_fps": max(1, round(1.0 / self.config.control_dt)),
        }
        self.render_mode = render_mode
        self.max_episode_steps = None if max_episode_steps is None else int(max_episode_steps)
        if threads is None and self.num_envs < PARALLEL_MIN_VEHICLES:
            threads = 1
        # numba refuses more threads than it started with; None: numba's current setting
        self.threads = (
            None if threads is None else min(int(threads), numba.config.NUMBA_NUM_THREADS)
        )

        # One thread: the serial kernel, which leaves numba's thread pool alone.
        self.sim = Simulator(self.config, self.num_envs, parallel=self.threads != 1)
        self.single_observation_space = spaces.Box(
            self.sim.obs_low, self.sim.obs_high, dtype=np.float32
        )
        self.single_action_space = spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)

        # Both limits truncate whatever else happened (as `TimeLimit`); a physics-step index.
        self._episode_steps = min(self.config.max_steps, self.max_episode_steps or np.inf)
        self._limit = int(self._episode_steps) * self.config.substeps
        self._last_obs = np.zeros(self.single_observation_space.shape, np.float32)[None].repeat(
            self.num_envs, axis=0
        )  # the last observation returned per vehicle
        self._rngs: list[np.random.Generator | None] = [None] * self.num_envs
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._ever_reset = False
        self._all = np.ones(self.num_envs, dtype=bool)
        self._render_vehicle = 0
        self._renderer = (
            EpisodeRenderer(
                self.config.path, self.config.max_time, envelope=self.config.depth_envelope
            )
            if render_mode
            else None
        )  # draws vehicle `render_vehicle` since its reset
        self.render_vehicle = render_vehicle

    @property
    def spec(self) -> EnvSpec | None:
        """The spec `gym.make_vec` set, with ``max_episode_steps`` = the episode length."""
        if self._spec is None:
            return None
        return dataclasses.replace(self._spec, max_episode_steps=int(self._episode_steps))

    @spec.setter
    def spec(self, value: EnvSpec | None) -> None:
        self._spec = value

    _spec: EnvSpec | None = None

    # ----------------------------------------------------------------------------------- reset
    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset all vehicles, or those of ``options["reset_mask"]``; see the class docstring."""
        n = self.num_envs
        seeds = seed_list(seed, n)
        mask = reset_mask(options, n)
        if not (self._ever_reset or mask.all()):
            raise ValueError("the first reset must reset every vehicle (no reset_mask)")
        super().reset(seed=seed if isinstance(seed, int) else None)
        rows = np.flatnonzero(mask)
        for i in rows:
            if seeds[i] is not None or self._rngs[i] is None:
                self._rngs[i], _ = seeding.np_random(seeds[i])
        self._reset_rows(rows)
        self._autoreset[rows] = False
        self._ever_reset = True
        infos: dict[str, Any] = {}
        self._add_infos(infos, mask, np.zeros(n, dtype=bool), fill=True)
        return self._observations(), infos

    def _reset_rows(self, rows: np.ndarray) -> None:
        """New episodes for `rows`, each drawn from its vehicle's generator (single-env order)."""
        self.sim.reset_rows(rows, [self._rngs[i] for i in rows])
        first = self.sim.observations(rows)
        check_reset_observations(
            first,
            rows,
            self.config.observation,
            self.config.current_speed_bound,
            self.sim.speed_bound,
        )
        self._last_obs[rows] = first
        if self._render_vehicle in rows:
            self._restart_rendering()

    # ------------------------------------------------------------------------------------ step
    def step(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Advance every vehicle one control period with actions of shape (num_envs, 3)."""
        if not self._ever_reset:
            raise RuntimeError("call reset() before step()")
        sim = self.sim
        actions = validate_actions(actions, (self.num_envs, 3))
        if self.threads is None or self.threads == 1:
            sim.step(actions)
        else:
            previous = numba.get_num_threads()
            numba.set_num_threads(self.threads)
            try:
                sim.step(actions)
            finally:
                numba.set_num_threads(previous)
        code = sim.code
        terminated = code != 0
        truncated = sim.step_index >= self._limit
        if self._renderer is not None:
            v = self._render_vehicle
            t = int(sim.step_index[v]) * self.config.physics_dt
            self._renderer.append(*track_point(sim, v), t)

        mode = self.autoreset_mode
        infos: dict[str, Any] = {}
        if mode is AutoresetMode.NEXT_STEP and self._autoreset.any():
            stepped = ~self._autoreset
            self._reset_rows(np.flatnonzero(self._autoreset))
            terminated &= stepped
            truncated &= stepped
            self._add_infos(infos, self._all, stepped)
        elif mode is AutoresetMode.SAME_STEP and (terminated.any() or truncated.any()):
            done = terminated | truncated
            final_obs = self._observations()
            final_rows = np.flatnonzero(done)
            final_info: dict[str, Any] = {}
            self._add_infos(final_info, done, done, fill=True)
            rewards = sim.reward.copy()
            self._reset_rows(final_rows)
            self._add_infos(infos, self._all, ~done)
            boxed = np.full(self.num_envs, None, dtype=object)
            for i in final_rows:
                boxed[i] = final_obs[i]
            infos["final_obs"], infos["_final_obs"] = boxed, done.copy()
            infos["final_info"], infos["_final_info"] = final_info, done.copy()
            return self._observations(), rewards, terminated, truncated, infos
        else:
            self._add_infos(infos, self._all, self._all)
        rewards = sim.reward.copy()  # 0 for the vehicles just reset
        if mode is AutoresetMode.NEXT_STEP:
            self._autoreset = terminated | truncated
        return self._observations(), rewards, terminated, truncated, infos

    def _observations(self) -> np.ndarray:
        """float32 observations; a "non_finite" vehicle repeats the last one it returned."""
        broken = self.sim.code == NON_FINITE
        if broken.any():  # their rows may not even fit float32
            obs = self._last_obs.copy()
            obs[~broken] = self.sim.observations(np.flatnonzero(~broken))
        else:
            obs = self.sim.observations()
        self._last_obs[:] = obs
        return obs

    def _add_infos(
        self, infos: dict[str, Any], base: np.ndarray, stepped: np.ndarray, fill: bool = False
    ) -> None:
        add_vector_infos(infos, self.sim, self.config.physics_dt, base, stepped, fill)

    # ------------------------------------------------------------------------ snapshots
    def snapshot(self) -> dict[str, Any]:
        """A copy of everything stepping and autoresets read: the simulator's arrays (vehicle
        states, ocean currents, parameter and task draws, noise keys, step counters), each
        vehicle's path and random generator, the last observations and the autoreset flags.

        `restore` of it on a vector env built with the same arguments continues bit for bit as
        this one would (what a paused training run needs); the renderer's track is not included.
        """
        return {
            "num_envs": self.num_envs,
            "sim": self.sim.snapshot(),
            "rngs": copy.deepcopy(self._rngs),
            "np_random": copy.deepcopy((self._np_random, self._np_random_seed)),
            "last_obs": self._last_obs.copy(),
            "autoreset": self._autoreset.copy(),
            "ever_reset": self._ever_reset,
        }

    def restore(self, snapshot: dict[str, Any]) -> None:
        """Continue from a `snapshot` of a vector env built with the same arguments; ValueError
        if its number of vehicles or array shapes differ."""
        if snapshot.get("num_envs") != self.num_envs:
            raise ValueError(
                f"snapshot of {snapshot.get('num_envs')} vehicles, this vector env "
                f"has {self.num_envs}"
            )
        self.sim.restore(snapshot["sim"])
        self._rngs = copy.deepcopy(snapshot["rngs"])
        self._np_random, self._np_random_seed = copy.deepcopy(snapshot["np_random"])
        self._last_obs[:] = snapshot["last_obs"]
        self._autoreset[:] = snapshot["autoreset"]
        self._ever_reset = bool(snapshot["ever_reset"])
        self._restart_rendering()

    # ---------------------------------------------------------------------------- properties
    @property
    def state(self) -> np.ndarray:
        """States (n, 11): x, y, z, θ, ψ, u, v, w, q, r, s [m, rad, m/s, rad/s, -]."""
        return self.sim.state.copy()

    @property
    def vehicle_np_random(self) -> list[np.random.Generator | None]:
        """Each vehicle's generator (None before its first reset)."""
        return list(self._rngs)

    @property
    def render_vehicle(self) -> int:
        """Index of the vehicle `render` draws; setting it restarts the drawn track."""
        return self._render_vehicle

    @render_vehicle.setter
    def render_vehicle(self, index: int) -> None:
        if isinstance(index, bool) or not isinstance(index, (int, np.integer)):
            raise ValueError(f"render_vehicle must be an integer, got {index!r}")
        if not 0 <= index < self.num_envs:
            raise ValueError(f"render_vehicle must be in [0, {self.num_envs}), got {index}")
        self._render_vehicle = int(index)
        self._restart_rendering()

    def _restart_rendering(self) -> None:
        if self._renderer is not None:
            v, sim = self._render_vehicle, self.sim
            t = int(sim.step_index[v]) * self.config.physics_dt
            self._renderer.reset(*track_point(sim, v), t, path=sim.paths[v])

    def render(self) -> np.ndarray | None:
        """RGB image (H, W, 3) of vehicle `render_vehicle`'s track since its last reset."""
        if self._renderer is None:
            return None
        return self._renderer.frame()

    def __repr__(self) -> str:
        return (
            f"AUVPath3DVectorEnv(num_envs={self.num_envs}, "
            f"autoreset_mode={self.autoreset_mode.name})"
        )
