"""The Policy protocol shared by every controller and agent, and the batched-controller base.

A policy is exactly stable-baselines3's `PolicyPredictor`:

    predict(observation, state=None, episode_start=None, deterministic=True) -> (action, state)

batched over the first axis (a single 1-D observation works too and gives a 1-D action). Memory
(adaptive weights, command filters) travels in ``state`` and is re-initialised for the rows where
``episode_start`` is true, as SB3's recurrent policies do. Actions are in [−1, 1].
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from auv_gym.rollout import Policy  # the one definition, shared with the rollouts
from auv_gym.sim.integrator import ACTUATORS
from auv_gym.sim.observation import OBS_DIM, OBS_INDEX
from auv_gym.vehicle import AUVParams, remus100
from auv_gym.vehicle.actuators import ActuatorParams, actuator_params_from_spec
from controllers.allocation import allocate, fin_authority, fin_gain
from controllers.gains import ControllerGains
from controllers.los import observation_width

__all__ = ["BatchedController", "Policy", "actuator_vector"]

_U, _V, _W = (OBS_INDEX[k] for k in ("u", "v", "w"))


def actuator_vector(
    actuator: str, params: AUVParams, actuator_params: ActuatorParams | None = None
) -> tuple[float, float, float, float, float]:
    """(fins flag, fin gain K·δ_max [kg], X_max [N], M_max [N·m], N_max [N·m]) of an actuator model.

    "paper": the vehicle's constant limits ``params.actuator_limits`` (REMUS 100: 50 N, 10 N·m,
    10 N·m); "fins": M, N limited by K·δ_max·u|u|
    (docs/model.md §2.3), evaluated by the controller at the observed surge speed;
    "realistic": the same law with the fins' K·δ_max of ``actuator_params``, its τ then
    allocated to shaft speed and fin angles (`controllers.allocation`, docs/model.md §2.7).
    """
    if actuator not in ACTUATORS:
        raise ValueError(f"unknown actuator {actuator!r}; valid: {sorted(ACTUATORS)}")
    if actuator == "realistic":
        return (1.0, fin_gain(actuator_params or ActuatorParams()), *params.actuator_limits)
    fins = 1.0 if actuator == "fins" else 0.0
    return (fins, params.fin_moment_coeff * params.fin_max, *params.actuator_limits)


# What every classical controller takes beside its gains (`BatchedController`, `controllers.make`).
CONTROLLER_KEYWORDS = ("gains", "params", "control_dt", "actuator", "actuator_params", "threads")


def unknown_keywords(name: str, unknown: Any, gains: Any, more: tuple[str, ...] = ()) -> str:
    """The one-line error for keywords ``unknown`` that controller ``name`` does not take:
    what it takes, its keywords (``more`` first) and its gains by name (a typo in a scenario's
    ``controller`` table is found in the list, not guessed)."""
    return (
        f"unknown {name} keyword arguments {sorted(unknown)}; valid: "
        f"{[*more, *CONTROLLER_KEYWORDS]} and its gains {sorted(gains)}"
    )


class BatchedController:
    """Base of the classical controllers: observation checks, state handling, `predict`.

    Subclasses provide `init_state(n)` (a dict of arrays with a leading vehicle axis) and
    `_control(obs, state, actions)` (fills actions (n, 3) in place, updates state in place).
    """

    name = "controller"

    def __init__(
        self,
        gains: ControllerGains | None,
        params: AUVParams | None,
        control_dt: float,
        actuator: str,
        gain_overrides: dict[str, Any],
        threads: str = "auto",
    ) -> None:
        if not (isinstance(control_dt, (int, float)) and math.isfinite(control_dt)):
            raise ValueError(f"control_dt must be a positive time in s, got {control_dt!r}")
        if control_dt <= 0:
            raise ValueError(f"control_dt must be a positive time in s, got {control_dt!r}")
        self.params = params if params is not None else remus100()
        if not isinstance(self.params, AUVParams):
            raise ValueError(f"params must be an AUVParams, got {type(self.params).__name__}")
        if threads not in ("auto", "serial"):
            raise ValueError(f"threads must be 'auto' or 'serial', got {threads!r}")
        self.threads = threads
        self.control_dt = float(control_dt)
        self.actuator = actuator
        # The realistic actuators' numbers (`ActuatorParams`), a keyword beside the gains.
        gain_overrides = dict(gain_overrides)
        spec = gain_overrides.pop("actuator_params", None)
        self.actuator_params = actuator_params_from_spec(spec)
        self._actuator = actuator_vector(actuator, self.params, self.actuator_params)
        base = gains if gains is not None else ControllerGains()
        unknown = set(gain_overrides) - {f.name for f in dataclasses.fields(base)}
        if unknown:
            raise ValueError(
                unknown_keywords(self.name, unknown, [f.name for f in dataclasses.fields(base)])
            )
        self.gains = dataclasses.replace(base, **gain_overrides) if gain_overrides else base
        # the paper's 15 entries, or with the DVL's current the agents' layout up to w_ground
        self.observation_width = observation_width(self.gains)
        # the env it needs beyond the default, which `auv_gym.rollout` merges under the caller's
        self.env_kwargs = {"observation": "preview"} if self.observation_width > OBS_DIM else None

    def init_state(self, n: int) -> dict[str, np.ndarray]:
        raise NotImplementedError

    def _control(self, obs: np.ndarray, state: dict[str, np.ndarray], actions: np.ndarray) -> None:
        raise NotImplementedError

    def _allocate(self, obs: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """The law's normalised τ → its τ_d at the observed u → shaft speed and fin angles."""
        u = obs[:, _U]
        authority = fin_authority(self._actuator[1], u)
        tau = actions * np.stack([np.full_like(u, self._actuator[2]), authority, authority], 1)
        return allocate(tau, obs[:, [_U, _V, _W]], self.actuator_params)

    def predict(
        self,
        observation: np.ndarray,
        state: dict[str, np.ndarray] | None = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """Actions in [−1, 1] for a batch (n, d) or one (d,) observation, d ≥ 15; see module doc.

        The law reads the paper's 15 entries (`auv_gym.OBS_NAMES`); the agent observation's
        further entries (``observation="preview"``) follow them and are ignored, except the
        velocity over ground with the gain ``dvl_current`` (then d ≥ 18). The returned
        ``state`` is the one passed in, updated in place (copying the FBSM's 150 kB of adaptive
        weights per vehicle every step would cost more than the control law); ``state=None``
        starts fresh memory for every row.
        """
        obs = np.asarray(observation, dtype=np.float64)
        single = obs.ndim == 1
        obs = obs[None] if single else obs
        if obs.ndim != 2 or obs.shape[1] < OBS_DIM:
            raise ValueError(
                f"observation must have shape (n, d) or (d,) with d >= {OBS_DIM} "
                f"(layout auv_gym.OBS_NAMES first), got {np.shape(observation)}"
            )
        if obs.shape[1] < self.observation_width:
            raise ValueError(
                f"{self.name} with dvl_current reads the velocity over ground: the observation "
                f"must have d >= {self.observation_width} (the env's observation='preview'), "
                f"got {np.shape(observation)}"
            )
        obs = np.ascontiguousarray(obs[:, : self.observation_width])
        if not np.isfinite(obs).all():
            raise ValueError("observation must be finite")
        n = obs.shape[0]
        if state is None:
            state = self.init_state(n)
        elif state["started"].shape[0] != n:
            raise ValueError(
                f"state is for {state['started'].shape[0]} vehicles, observation for {n}"
            )
        if episode_start is not None:
            reset = np.asarray(episode_start, dtype=bool).reshape(-1)
            if reset.shape[0] != n:
                raise ValueError(f"episode_start must have {n} entries, got {reset.shape[0]}")
            if reset.any():
                fresh = self.init_state(int(reset.sum()))
                for key, value in state.items():
                    value[reset] = fresh[key]
        actions = np.empty((n, 3))
        self._control(obs, state, actions)
        if self.actuator == "realistic":
            actions = self._allocate(obs, actions)
        out = actions.astype(np.float32)
        return (out[0] if single else out), state
