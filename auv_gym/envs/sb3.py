"""The native vector env as a stable-baselines3 `VecEnv` (needs the ``rl`` extra).

`import auv_gym` never imports stable-baselines3; importing this module does, and fails with an
ImportError naming the extra when it is missing.

    from auv_gym.envs.sb3 import make_sb3_vec_env
    venv = make_sb3_vec_env(64, randomize_start=True)      # an SB3 VecEnv of 64 vehicles
    model = PPO("MlpPolicy", VecMonitor(venv)).learn(100_000)
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode

try:
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv
except ImportError as error:  # pragma: no cover - exercised in a subprocess by the tests
    raise ImportError(
        "auv_gym.envs.sb3 needs stable-baselines3, which is not installed; "
        "install the RL extra: pip install 'auv-gym[rl]'"
    ) from error

from auv_gym.envs.vector_env import AUVPath3DVectorEnv

__all__ = ["INFO_MODES", "SB3VecEnv", "make_sb3_vec_env"]

# `SB3VecEnv(infos=...)`: "full" per-vehicle info dicts, or "minimal" ones with only the keys SB3
# itself reads ("TimeLimit.truncated"; "terminal_observation" when the episode ended).
INFO_MODES = ("full", "minimal")

# Attributes that differ between vehicles; every other attribute is shared by all of them.
_PER_VEHICLE = ("state", "np_random", "actuator", "observation_space", "action_space")


class SB3VecEnv(VecEnv):
    """SB3's `VecEnv` interface over an `AUVPath3DVectorEnv` in SAME_STEP autoreset mode.

    Semantics are those of SB3's `DummyVecEnv` over n single envs, bit for bit: `step_wait`
    returns float32 rewards, bool dones and one info dict per vehicle (the single env's info plus
    ``"TimeLimit.truncated"``, and ``"terminal_observation"`` when the episode ended, the
    observation then being the next episode's first); `reset_infos` holds the reset infos;
    `seed(k)` makes the next `reset` seed vehicle i with k + i.

    The vehicles are rows of one simulator, so attributes are shared: `get_attr` returns the vector
    env's attribute for each requested index, except the per-vehicle ``state`` (11-vector),
    ``np_random`` (the vehicle's generator), ``actuator`` (the actuator model of the vehicle's
    current episode: the configured one or, with ``actuator="random"``, the one its episode
    drew) and the single ``observation_space`` /
    ``action_space``; `set_attr` changes the shared attribute and therefore needs all indices;
    `env_method` calls the vector env's method once and returns its result for each index;
    `env_is_wrapped` is False (no gymnasium wrappers; wrap the whole VecEnv with `VecMonitor`,
    `VecNormalize`, ...). `render` draws the vector env's `render_vehicle`.

    ``infos="minimal"`` (opt-in; default "full") skips the per-vehicle copies of the vector env's
    info: each dict then holds only what SB3 reads, ``"TimeLimit.truncated"`` and, when the
    episode ended, ``"terminal_observation"`` (same values as "full"), and `reset_infos` are
    empty dicts. Observations, rewards and dones are unchanged; at 512 vehicles the full dicts
    cost about as much as the physics.

    ``venv`` may also be a gymnasium `VectorWrapper` around an `AUVPath3DVectorEnv` (e.g. the
    residual training wrapper, `benchmarks.training.residual_env.ResidualVectorEnv`): steps,
    resets and spaces are the wrapper's;
    the per-vehicle attributes and the autoreset mode are the vector env's (``unwrapped``), and
    other attributes are looked up on the wrapper first.
    """

    def __init__(self, venv: Any, infos: str = "full") -> None:  # venv: or a VectorWrapper
        if infos not in INFO_MODES:
            raise ValueError(f"infos must be one of {list(INFO_MODES)}, got {infos!r}")
        if not isinstance(getattr(venv, "unwrapped", None), AUVPath3DVectorEnv):
            raise ValueError(f"SB3VecEnv wraps an AUVPath3DVectorEnv, got {type(venv).__name__}")
        core = venv.unwrapped
        if core.autoreset_mode is not AutoresetMode.SAME_STEP:
            raise ValueError(
                "SB3VecEnv needs the vector env's autoreset_mode=AutoresetMode.SAME_STEP "
                f"(SB3 semantics), got {core.autoreset_mode}"
            )
        self.venv = venv
        self.core: AUVPath3DVectorEnv = core
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)
        self.metadata = {**self.metadata, "render_fps": venv.metadata["render_fps"]}
        self._actions: np.ndarray | None = None
        self.info_mode = infos

    # ------------------------------------------------------------------------------- stepping
    def reset(self) -> np.ndarray:
        seeds = self._seeds if any(s is not None for s in self._seeds) else None
        obs, info = self.venv.reset(seed=seeds)
        self.reset_infos = self._dicts(info)
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        if self._actions is None:
            raise RuntimeError("step_wait() without a pending step_async()")
        actions, self._actions = self._actions, None
        obs, reward, terminated, truncated, info = self.venv.step(actions)
        dones = terminated | truncated
        time_limit = (truncated & ~terminated).tolist()
        infos = self._dicts(info)
        if dones.any():
            # Ended vehicles report their last step's info; the reset info goes to reset_infos.
            final = self._dicts(info["final_info"])
            for i in np.flatnonzero(dones).tolist():
                self.reset_infos[i] = infos[i]
                infos[i] = final[i]
                infos[i]["terminal_observation"] = info["final_obs"][i]
        for row, flag in zip(infos, time_limit, strict=True):
            row["TimeLimit.truncated"] = flag
        return obs, reward.astype(np.float32), dones, infos

    def _dicts(self, info: dict[str, Any]) -> list[dict[str, Any]]:
        """One info dict per vehicle: the vector env's (``infos="full"``) or empty ones."""
        if self.info_mode == "full":
            return _info_dicts(info, self.num_envs)
        return [{} for _ in range(self.num_envs)]

    def close(self) -> None:
        self.venv.close()

    # ------------------------------------------------------------------------ snapshots
    def snapshot(self) -> dict[str, Any]:
        """A copy of the state stepping reads: the vector env's (`AUVPath3DVectorEnv.snapshot`),
        every attribute of a wrapper in between (e.g. the residual agent's base-controller
        states and previous actions), and the seeds and options of the next `reset`."""
        wrapper = None
        if self.venv is not self.core:
            wrapper = copy.deepcopy(
                {k: v for k, v in vars(self.venv).items() if k not in ("env", "core")}
            )
        return {
            "core": self.core.snapshot(),
            "wrapper": wrapper,
            "seeds": list(self._seeds),
            "options": copy.deepcopy(self._options),
        }

    def restore(self, snapshot: dict[str, Any]) -> None:
        """Continue from a `snapshot` of an SB3VecEnv built with the same arguments."""
        if (snapshot["wrapper"] is None) != (self.venv is self.core):
            raise ValueError("snapshot and env differ in their wrapper of the vector env")
        self.core.restore(snapshot["core"])
        for key, value in copy.deepcopy(snapshot["wrapper"] or {}).items():
            setattr(self.venv, key, value)
        self._seeds = list(snapshot["seeds"])
        self._options = copy.deepcopy(snapshot["options"])

    # --------------------------------------------------------------------- attribute access
    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        rows = self._rows(indices)
        if attr_name in _PER_VEHICLE:
            if attr_name == "state":
                return [self.core.sim.state[i].copy() for i in rows]
            if attr_name == "np_random":
                return [self.core.vehicle_np_random[i] for i in rows]
            if attr_name == "actuator":
                actuators = self.core.sim.actuators
                return [str(actuators[i]) for i in rows]
            return [getattr(self.venv, f"single_{attr_name}")] * len(rows)
        value = getattr(self._holder(attr_name), attr_name)
        return [value] * len(rows)

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        if len(set(self._rows(indices))) != self.num_envs:
            raise ValueError(
                f"attribute {attr_name!r} is shared by all vehicles of the vector env; "
                "set_attr needs every index (indices=None)"
            )
        setattr(self._holder(attr_name), attr_name, value)

    def env_method(
        self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any
    ) -> list[Any]:
        rows = self._rows(indices)
        result = getattr(self._holder(method_name), method_name)(*method_args, **method_kwargs)
        return [result] * len(rows)

    def _holder(self, name: str) -> Any:
        """The wrapper if it has the attribute, else the vector env it wraps."""
        return self.venv if hasattr(self.venv, name) else self.core

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [False] * len(self._rows(indices))

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [self.venv.render()]

    def _rows(self, indices: Any) -> list[int]:
        rows = list(self._get_indices(indices))
        for i in rows:
            if not 0 <= i < self.num_envs:
                raise ValueError(f"env index {i} out of range [0, {self.num_envs})")
        return rows


def _info_dicts(info: dict[str, Any], n: int) -> list[dict[str, Any]]:
    """Gymnasium's dict of arrays (with ``_key`` masks) → one dict per vehicle, as single envs.

    Each vehicle's dict holds the keys its masks mark, in the vector env's key order; values are
    Python scalars for 1-D numeric columns and rows (views) of the others. Built column-wise (one
    `tolist` per key, one `dict(zip(...))` per vehicle): its cost is the dicts themselves.
    """
    keys = [k for k in info if not k.startswith("_") and k not in ("final_obs", "final_info")]
    columns = [info[k].tolist() if info[k].ndim == 1 else list(info[k]) for k in keys]
    rows = zip(*columns, strict=True) if keys else ((),) * n
    masks = [info[f"_{k}"] for k in keys]
    if all(mask.all() for mask in masks):
        return [dict(zip(keys, row, strict=True)) for row in rows]
    present = np.stack(masks, axis=1).tolist()
    return [
        {k: v for k, v, here in zip(keys, row, marks, strict=True) if here}
        for row, marks in zip(rows, present, strict=True)
    ]


def make_sb3_vec_env(
    num_envs: int,
    *,
    seed: int | None = None,
    max_episode_steps: int | None = None,
    render_mode: str | None = None,
    render_vehicle: int = 0,
    threads: int | None = None,
    infos: str = "full",
    **env_kwargs: Any,
) -> SB3VecEnv:
    """An `SB3VecEnv` of ``num_envs`` vehicles; keyword arguments as `AUVPath3DEnv`.

    ``seed`` seeds the first reset (vehicle i gets seed + i). ``max_episode_steps`` defaults to
    none: the env truncates at its ``max_time`` like ``AUVPath3DEnv`` itself. ``threads``: numba
    threads of the kernel (None: one below 256 vehicles, else all; see `AUVPath3DVectorEnv`).
    ``infos``: "full" or "minimal" per-vehicle info dicts (`SB3VecEnv`).
    """
    venv = AUVPath3DVectorEnv(
        num_envs,
        max_episode_steps=max_episode_steps,
        autoreset_mode=AutoresetMode.SAME_STEP,
        render_mode=render_mode,
        render_vehicle=render_vehicle,
        threads=threads,
        **env_kwargs,
    )
    env = SB3VecEnv(venv, infos=infos)
    if seed is not None:
        env.seed(seed)
    return env
