r"""Training side of the residual policy: the native vector env with the base controller inside
(docs/design.md §3.10).

`ResidualVectorEnv` wraps an `auv_gym.envs.vector_env.AUVPath3DVectorEnv` (any autoreset mode). It
runs the base controller of all vehicles in one batched `predict` per control step, exactly as
`controllers.residual.ResidualPolicy` and the evaluation run it, and exposes to the agent

    observation  [o_k, b_k, a_{k−1}]  (float32, `residual_observation_names` of the env's
                 observation: 21 values on the paper's, more with a preview of the path)
    action       c_k ∈ [−1, 1]³, applied as a_k = clip(b_k + β ⊙ clip(c_k, −1, 1), −1, 1);
                 with ``filter_max`` > 0, (c_k, g_k) ∈ [−1, 1]⁶ and the learned low-pass of
                 `controllers.residual` (α_k = 0 at an episode's first step); with an
                 ``envelope_guard``, a_k through it (θ, q, u of o_k), as at inference
    reward       r_k − w_TV · Σ_j |a_{k,j} − a_{k−1,j}|     (no charge at an episode's first step)
                 + w_P · exp(−(d_{k+1}/d_P)²)               (precision bonus, d [m] after the step)

(d: the distance to the virtual point, or with ``precision_axes="yz"`` its part across the path,
√(y_e² + z_e²), from the true state the env reports in ``info``)

The chattering charge w_TV (``tv_weight``, default 0.25) is the total variation of the applied
normalised action per step, the quantity the benchmark's ``chattering`` metric sums per second
(`auv_gym.metrics`); it is reported per step as ``info["reward_chattering"]`` beside the env's
reward terms. The precision bonus (``precision_weight`` w_P, default 0, scale
``precision_scale`` d_P = 0.1 m) is the env's tracking bonus at the scale where a classical
base already holds the path, so that accuracy lost to smoothing costs reward; it is reported as
``info["reward_residual_precision"]`` (present when w_P > 0; the env's own "precision" term,
`auv_gym.sim.task`, has a fixed d_P).
With ``actuator="random"`` each vehicle's base controller uses the actuator its
episode drew (`auv_gym.sim.simulator.Simulator.actuators`), as a scenario would configure it: one
controller per actuator model, each called for the whole batch while any vehicle uses it.

`make_residual_sb3_env` gives the same env as a stable-baselines3 VecEnv (`auv_gym.envs.sb3`).
Deterministic: the base controllers are deterministic functions of the observations, so the same
seed and actions give bit-identical trajectories.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorWrapper
from gymnasium.vector.utils import batch_space

from auv_gym.envs.env import validate_actions
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from benchmarks.training.residual import (
    PRIVILEGED_INFO_KEYS,
    ResidualTraining,
    privileged_extension,
)
from controllers.envelope_guard import guard_env_commands
from controllers.residual import (
    agent_observation,
    base_kwargs_for_env,
    residual_action,
    residual_observation_bounds,
    residual_observation_names,
)

__all__ = ["CHATTERING_KEY", "PRECISION_KEY", "ResidualVectorEnv", "make_residual_sb3_env"]

CHATTERING_KEY = "reward_chattering"  # info key of −w_TV·TV_k, beside the env's reward terms
PRECISION_KEY = "reward_residual_precision"  # info key of w_P·exp(−(d/d_P)²)


class ResidualVectorEnv(VectorWrapper):
    """The residual agent's view of an `AUVPath3DVectorEnv` (module doc).

    Args:
        env: the vector env (its ``unwrapped`` must be an `AUVPath3DVectorEnv`).
        settings: `ResidualTraining` (base controller, β, w_TV, w_P); default: their defaults.

    Info: the env's, plus ``reward_chattering`` and, with w_P > 0, ``reward_residual_precision``
    (each with its ``_`` mask; in ``final_info`` for the vehicles whose episode ended in
    SAME_STEP mode), ``base_action`` (n, 3), the base action of the returned observation.
    """

    def __init__(self, env: Any, settings: ResidualTraining | None = None) -> None:
        core = getattr(env, "unwrapped", None)
        if not isinstance(core, AUVPath3DVectorEnv):
            raise ValueError(
                f"ResidualVectorEnv wraps an AUVPath3DVectorEnv, got {type(env).__name__}"
            )
        super().__init__(env)
        self.core = core
        self.settings = settings if settings is not None else ResidualTraining()
        self.bound = np.asarray(self.settings.bound)
        dim = self.settings.action_dim  # 3 corrections, or 6 with the learned filter
        self.single_action_space = spaces.Box(-1.0, 1.0, (dim,), dtype=np.float32)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        config = core.config
        # the base of a classical controller on this env (its vehicle record, actuator model),
        # as validation and the benchmark build it; with "random", one per actuator drawn
        settings = base_kwargs_for_env(config)
        names = ("paper", "fins") if config.actuator == "random" else (config.actuator,)
        self.controllers = {
            name: self.settings.make_base(**{**settings, "actuator": name}) for name in names
        }
        self._states: dict[str, Any] = dict.fromkeys(names)
        # The env's bounds for its vehicle, observation kind and currents, then ±1 for b, a_{k−1}.
        low, high = residual_observation_bounds(
            config.params.max_surge, config.observation, config.current_speed_bound
        )
        self._privileged = self.settings.privileged_critic
        if self._privileged:  # the critic's true errors, within the observed errors' bounds
            names = residual_observation_names(config.observation)
            low, high = privileged_extension(low, names), privileged_extension(high, names)
        self.single_observation_space = spaces.Box(low, high, dtype=np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        n = self.num_envs
        self._base = np.zeros((n, 3), np.float32)  # b_k of the last returned observation
        self._obs = np.zeros((n, self.env.single_observation_space.shape[0]), np.float32)  # o_k
        self._previous = np.zeros((n, 3), np.float32)  # a_{k−1} (0 at an episode's start)
        self._started = np.zeros(n, dtype=bool)  # a_{k−1} exists (not the first step)
        self._actuators = core.sim.actuators  # each vehicle's actuator when b_k was computed
        self._pending = np.zeros(n, dtype=bool)  # NEXT_STEP: reset by the coming step
        self._ever_reset = False

    # ------------------------------------------------------------------------ base controller
    def _base_predict(self, obs: np.ndarray, episode_start: np.ndarray) -> np.ndarray:
        """b for every vehicle: one batched call per actuator model in use (all rows)."""
        actuators = self.core.sim.actuators
        out = np.empty((self.num_envs, 3), np.float32)
        for name, controller in self.controllers.items():
            rows = actuators == name
            if rows.any():
                action, self._states[name] = controller.predict(
                    obs,
                    state=self._states[name],
                    episode_start=episode_start,
                    deterministic=True,
                )
                out[rows] = np.asarray(action, np.float32).reshape(-1, 3)[rows]
        self._actuators = actuators
        return out

    def _precision_error(self, info: dict[str, Any]) -> np.ndarray:
        """d [m] of the precision bonus per vehicle, from an info dict's true errors: the
        distance, or with ``precision_axes`` "yz" its part across the path."""
        if self.settings.precision_axes == "yz":
            return np.hypot(
                np.asarray(info["y_e"], np.float64), np.asarray(info["z_e"], np.float64)
            )
        return np.asarray(info["distance"], np.float64)

    def _base_predict_rows(
        self,
        obs: np.ndarray,
        rows: np.ndarray,
        episode_start: bool,
        actuators: np.ndarray,
        keep: bool,
    ) -> np.ndarray:
        """b for ``rows`` only, on copies of their controller states (written back if
        ``keep``): partial resets, and the final observations of ended episodes (not kept)."""
        out = np.empty((rows.size, 3), np.float32)
        for name, controller in self.controllers.items():
            pick = actuators[rows] == name
            if not pick.any():
                continue
            chosen = rows[pick]
            full = self._states[name]
            sub = None if full is None else {k: v[chosen] for k, v in full.items()}
            start = np.full(chosen.size, episode_start)
            action, sub = controller.predict(
                obs[chosen], state=sub, episode_start=start, deterministic=True
            )
            out[pick] = np.asarray(action, np.float32).reshape(-1, 3)
            if keep:
                if full is None:  # first use: a fresh state for every vehicle, then these rows
                    full = self._states[name] = controller.init_state(self.num_envs)
                for key, value in sub.items():
                    full[key][chosen] = value
        return out

    # --------------------------------------------------------------------------------- API
    def reset(
        self, *, seed: Any = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset as the vector env does; the base controllers restart for the reset vehicles."""
        obs, info = self.env.reset(seed=seed, options=options)
        mask = (options or {}).get("reset_mask")
        mask = np.ones(self.num_envs, dtype=bool) if mask is None else np.asarray(mask, bool)
        if mask.all() or not self._ever_reset:
            self._base = self._base_predict(obs, mask)
        else:
            rows = np.flatnonzero(mask)
            actuators = self.core.sim.actuators
            self._base[rows] = self._base_predict_rows(obs, rows, True, actuators, keep=True)
            self._actuators = actuators
        self._ever_reset = True
        self._obs = np.array(obs, dtype=np.float32)
        self._previous[mask] = 0.0
        self._started[mask] = False
        self._pending[mask] = False
        info["base_action"], info["_base_action"] = self._base.copy(), mask.copy()
        return self._features(obs, self._base, self._previous, info), info

    def _features(
        self, obs: np.ndarray, base: np.ndarray, previous: np.ndarray, info: dict[str, Any]
    ) -> np.ndarray:
        """The agent's observation, followed with a privileged critic by the true errors of
        ``info`` (`benchmarks.training.privileged`)."""
        features = agent_observation(obs, base, previous)
        if not self._privileged:
            return features
        truth = np.stack([np.asarray(info[key], np.float32) for key in PRIVILEGED_INFO_KEYS], 1)
        return np.concatenate([features, truth], axis=1)

    def step(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Apply base + bounded correction, charge chattering, run the base on the new
        observation. A NaN or inf correction raises ValueError before any vehicle moves."""
        if not self._ever_reset:
            raise RuntimeError("call reset() before step()")
        correction = validate_actions(actions, (self.num_envs, self.settings.action_dim))
        applied = residual_action(
            self._base,
            correction,
            self.bound,
            self.settings.filter_max,
            self._previous,
            self._started,
            self.settings.bound_below,
            brake_fin_margin=self.settings.brake_fin_margin,
        )
        applied = guard_env_commands(applied, self._obs, self.settings.envelope_guard)
        obs, reward, terminated, truncated, info = self.env.step(applied)
        stepped = ~self._pending  # NEXT_STEP: vehicles reset by this step did not move
        variation = np.abs(applied.astype(np.float64) - self._previous).sum(axis=1)
        charge = np.where(stepped & self._started, -self.settings.tv_weight * variation, 0.0)
        reward = reward + charge
        done = terminated | truncated
        mode = self.core.autoreset_mode
        bonus = None
        if self.settings.precision_weight > 0.0:
            distance = self._precision_error(info)
            if mode is AutoresetMode.SAME_STEP and done.any():  # info holds the new episodes'
                distance = np.where(done, self._precision_error(info["final_info"]), distance)
            scaled = distance / self.settings.precision_scale
            bonus = np.where(
                stepped, self.settings.precision_weight * np.exp(-scaled * scaled), 0.0
            )
            reward = reward + bonus
        fresh = self._pending.copy() if mode is AutoresetMode.NEXT_STEP else np.zeros_like(done)
        if mode is AutoresetMode.SAME_STEP and done.any():
            fresh = done.copy()
            rows = np.flatnonzero(done)
            final_obs = np.stack([info["final_obs"][i] for i in rows])
            final = np.zeros((self.num_envs, final_obs.shape[1]), np.float32)
            final[rows] = final_obs
            # b at the last observation, from copies of the ended episodes' controller states
            final_base = self._base_predict_rows(final, rows, False, self._actuators, keep=False)
            boxed = info["final_obs"].copy()
            final_info = info["final_info"]
            for j, i in enumerate(rows):
                ended = {key: final_info[key][i : i + 1] for key in PRIVILEGED_INFO_KEYS}
                boxed[i] = self._features(
                    final_obs[j : j + 1], final_base[j : j + 1], applied[i : i + 1], ended
                )[0]
            info["final_obs"] = boxed
            final_info[CHATTERING_KEY] = np.where(done, charge, 0.0)
            final_info[f"_{CHATTERING_KEY}"] = done.copy()
            info[CHATTERING_KEY] = np.where(done, 0.0, charge)
            info[f"_{CHATTERING_KEY}"] = ~done
            if bonus is not None:
                final_info[PRECISION_KEY] = np.where(done, bonus, 0.0)
                final_info[f"_{PRECISION_KEY}"] = done.copy()
                info[PRECISION_KEY] = np.where(done, 0.0, bonus)
                info[f"_{PRECISION_KEY}"] = ~done
        else:
            info[CHATTERING_KEY] = charge
            info[f"_{CHATTERING_KEY}"] = stepped.copy()
            if bonus is not None:
                info[PRECISION_KEY] = bonus
                info[f"_{PRECISION_KEY}"] = stepped.copy()
        self._previous[stepped] = applied[stepped]
        self._started[stepped] = True
        self._previous[fresh] = 0.0
        self._started[fresh] = False
        self._base = self._base_predict(obs, fresh)
        self._obs = np.array(obs, dtype=np.float32)
        self._pending = done if mode is AutoresetMode.NEXT_STEP else np.zeros_like(done)
        info["base_action"] = self._base.copy()
        info["_base_action"] = np.ones(self.num_envs, dtype=bool)
        features = self._features(obs, self._base, self._previous, info)
        return features, reward, terminated, truncated, info

    def __repr__(self) -> str:
        s = self.settings
        return f"ResidualVectorEnv({self.env!r}, base={s.base!r}, bound={s.bound})"


def make_residual_sb3_env(
    num_envs: int,
    settings: ResidualTraining | None = None,
    *,
    seed: int | None = None,
    max_episode_steps: int | None = None,
    threads: int | None = None,
    **env_kwargs: Any,
) -> Any:
    """`ResidualVectorEnv` over ``num_envs`` vehicles as an SB3 VecEnv (`auv_gym.envs.sb3`);
    keyword arguments as `auv_gym.envs.sb3.make_sb3_vec_env`."""
    from auv_gym.envs.sb3 import SB3VecEnv

    core = AUVPath3DVectorEnv(
        num_envs,
        max_episode_steps=max_episode_steps,
        autoreset_mode=AutoresetMode.SAME_STEP,
        threads=threads,
        **env_kwargs,
    )
    venv = SB3VecEnv(ResidualVectorEnv(core, settings))
    if seed is not None:
        venv.seed(seed)
    return venv
