"""One stable-baselines3 `VecEnv` over several, their vehicles in order: `ConcatVecEnv`.

A native vector env (`auv_gym.envs.sb3.SB3VecEnv`) simulates one plant and one actuator setting;
a training env with a share of its vehicles on another plant or actuator (``plant_share``,
``actuator_share``, `benchmarks.training.vehicle_share`) is one such env per value,
concatenated.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

__all__ = ["ConcatVecEnv"]


class ConcatVecEnv(VecEnv):
    """SB3's `VecEnv` interface over sub-VecEnvs, their vehicles concatenated in order.

    Semantics are those of one VecEnv over all the vehicles: `step_async` hands each sub-env its
    rows of the actions; `reset` and `step_wait` concatenate the observations, rewards, dones and
    info dicts (``terminal_observation`` included); `reset_infos` joins the sub-envs'; `seed(k)`
    seeds sub-env j with k + (vehicles before it), so vehicle i gets k + i as in one
    `SB3VecEnv`; `set_options` hands each sub-env its vehicles' options.

    `get_attr`, `set_attr`, `env_method` and `env_is_wrapped` send each requested index to its
    sub-env (as that sub-env's index) and return the results in the order requested; each
    sub-env keeps its own rules. An `SB3VecEnv`'s vehicles share their attributes, so `set_attr`
    needs every index of each sub-env it touches, and `env_method` calls the method once per
    sub-env touched. `snapshot` / `restore` hold the sub-envs' (exact resume,
    `benchmarks.training.checkpoints`); `close` closes them all.

    The sub-envs must have equal observation and action spaces (ValueError naming the space and
    the sub-env otherwise); observations are arrays.
    """

    def __init__(self, envs: Sequence[VecEnv]) -> None:
        envs = list(envs)
        if not envs:
            raise ValueError("ConcatVecEnv needs at least one VecEnv")
        for name in ("observation_space", "action_space"):
            first = getattr(envs[0], name)
            for j, env in enumerate(envs[1:], start=1):
                if getattr(env, name) != first:
                    raise ValueError(
                        f"ConcatVecEnv: the {name} of sub-env {j} ({getattr(env, name)}) "
                        f"differs from sub-env 0's ({first})"
                    )
        self.envs = envs
        # Sub-env j holds the vehicles starts[j] to starts[j + 1] - 1.
        self.starts = np.cumsum([0, *(env.num_envs for env in envs)])
        super().__init__(int(self.starts[-1]), envs[0].observation_space, envs[0].action_space)
        if "render_fps" in envs[0].metadata:
            self.metadata = {**self.metadata, "render_fps": envs[0].metadata["render_fps"]}

    # ------------------------------------------------------------------------------- stepping
    def reset(self) -> np.ndarray:
        obs = np.concatenate([env.reset() for env in self.envs])
        self._join_reset_infos()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        actions = np.asarray(actions)
        if actions.shape[:1] != (self.num_envs,):
            raise ValueError(
                f"actions must have one row per vehicle ({self.num_envs}), got shape "
                f"{actions.shape}"
            )
        for env, start, stop in zip(self.envs, self.starts[:-1], self.starts[1:], strict=True):
            env.step_async(actions[start:stop])

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        obs, rewards, dones, infos = zip(*(env.step_wait() for env in self.envs), strict=True)
        self._join_reset_infos()
        return (
            np.concatenate(obs),
            np.concatenate(rewards),
            np.concatenate(dones),
            list(itertools.chain.from_iterable(infos)),
        )

    def _join_reset_infos(self) -> None:
        self.reset_infos = list(itertools.chain.from_iterable(e.reset_infos for e in self.envs))

    def seed(self, seed: int | None = None) -> Sequence[int | None]:
        if seed is None:  # one draw for all, as SB3's `VecEnv.seed`
            seed = int(np.random.randint(0, np.iinfo(np.uint32).max, dtype=np.uint32))  # noqa: NPY002
        offsets = self.starts[:-1].tolist()
        return list(
            itertools.chain.from_iterable(
                env.seed(seed + offset) for env, offset in zip(self.envs, offsets, strict=True)
            )
        )

    def set_options(self, options: list[dict] | dict | None = None) -> None:
        for env, start, stop in zip(self.envs, self.starts[:-1], self.starts[1:], strict=True):
            env.set_options(options if not isinstance(options, list) else options[start:stop])

    def close(self) -> None:
        for env in self.envs:
            env.close()

    # ------------------------------------------------------------------------ snapshots
    def snapshot(self) -> dict[str, Any]:
        """The sub-envs' snapshots (`SB3VecEnv.snapshot`), in order."""
        return {"envs": [env.snapshot() for env in self.envs]}

    def restore(self, snapshot: dict[str, Any]) -> None:
        """Continue from a `snapshot` of a ConcatVecEnv of the same sub-envs."""
        if len(snapshot["envs"]) != len(self.envs):
            raise ValueError(
                f"snapshot holds {len(snapshot['envs'])} sub-envs, this env {len(self.envs)}"
            )
        for env, part in zip(self.envs, snapshot["envs"], strict=True):
            env.restore(part)

    # --------------------------------------------------------------------- attribute access
    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        return self._gather(indices, lambda env, rows: env.get_attr(attr_name, rows))

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        for j, _, rows in self._route(indices):
            self.envs[j].set_attr(attr_name, value, rows)

    def env_method(
        self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any
    ) -> list[Any]:
        return self._gather(
            indices,
            lambda env, rows: env.env_method(
                method_name, *method_args, indices=rows, **method_kwargs
            ),
        )

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return self._gather(indices, lambda env, rows: env.env_is_wrapped(wrapper_class, rows))

    def get_images(self) -> Sequence[np.ndarray | None]:
        return list(itertools.chain.from_iterable(env.get_images() for env in self.envs))

    def _route(self, indices: Any) -> list[tuple[int, list[int], list[int]]]:
        """(sub-env, positions in the request, its own indices) of each sub-env requested."""
        requested = np.asarray(list(self._get_indices(indices)), dtype=np.int64).reshape(-1)
        outside = requested[(requested < 0) | (requested >= self.num_envs)]
        if outside.size:
            raise ValueError(f"env index {outside[0]} out of range [0, {self.num_envs})")
        owner = np.searchsorted(self.starts, requested, side="right") - 1
        return [
            (
                int(j),
                np.flatnonzero(owner == j).tolist(),
                (requested[owner == j] - self.starts[j]).tolist(),
            )
            for j in np.unique(owner)
        ]

    def _gather(self, indices: Any, call: Callable[[VecEnv, list[int]], list[Any]]) -> list[Any]:
        """``call(sub-env, its indices)`` for each sub-env requested, placed in request order."""
        routes = self._route(indices)
        results: list[Any] = [None] * sum(len(positions) for _, positions, _ in routes)
        for j, positions, rows in routes:
            for position, value in zip(positions, call(self.envs[j], rows), strict=True):
                results[position] = value
        return results
