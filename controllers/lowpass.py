r"""A first-order low-pass filter on a controller's action: the classical answer to chattering,
and the baseline a learned residual has to beat (docs/design.md §3.11).

Per control step k, with b_k the base controller's normalised action:

    a_0 = b_0,    a_k = α a_{k−1} + (1 − α) b_k        α ∈ [0, 1)

α = exp(−Δt/T) is a discrete first-order lag of time constant T = −Δt/ln α (α = 0.5 at the
paper's Δt = 0.05 s: T ≈ 0.072 s, a −3 dB corner near 2.2 Hz). |a_k| ≤ 1 whenever |b| ≤ 1, so
the filter never leaves the actuator range. The base gets every observation and flag exactly as
it would alone (its adaptive laws run on its own commands, as they do on a real vehicle whose
controller output passes through a smoothing stage); with α = 0 the policy is the base bit for
bit.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from auv_gym.sim.observation import OBS_DIM

__all__ = ["DEFAULT_ALPHA", "PREVIOUS_KEY", "LowPassPolicy", "check_alpha"]

PREVIOUS_KEY = "lowpass_previous"  # the filter's a_{k−1} in the policy state
DEFAULT_ALPHA = 0.5  # halves FBSM's chattering under the paper's noise (docs/design.md §3.11)


def check_alpha(alpha: Any) -> float:
    """α as a float in [0, 1); ValueError naming the value."""
    if isinstance(alpha, bool) or not isinstance(alpha, (int, float)):
        raise ValueError(f"alpha must be a number in [0, 1), got {alpha!r}")
    if not (math.isfinite(alpha) and 0.0 <= alpha < 1.0):
        raise ValueError(
            f"alpha must be a number in [0, 1) (1 would freeze the action), got {alpha!r}"
        )
    return float(alpha)


class LowPassPolicy:
    """Base controller followed by a first-order low-pass of its action (module doc); the
    Policy protocol (docs/design.md §3.6).

    Args:
        base: the base controller (any Policy).
        alpha: the filter coefficient α ∈ [0, 1) (0: no filtering).

    State: the base's state dict (one row per vehicle in every array) with the previous
    filtered actions added under `PREVIOUS_KEY` ((n, 3) float32), so code that slices a
    controller's state by vehicle rows (the residual training env) slices this one too.
    `diagnostics` forwards the base's.
    """

    def __init__(self, base: Any, alpha: float = DEFAULT_ALPHA) -> None:
        if not callable(getattr(base, "predict", None)):
            raise ValueError(f"lowpass base must have predict(...), got {type(base).__name__}")
        self.base = base
        # what the base reads and the env it needs (the current from the DVL: `controllers.base`)
        self.observation_width = getattr(base, "observation_width", OBS_DIM)
        self.env_kwargs = getattr(base, "env_kwargs", None)
        self.alpha = check_alpha(alpha)
        self.name = f"{getattr(base, 'name', 'base')}_lowpass"

    def init_state(self, n: int) -> dict[str, np.ndarray]:
        """A fresh state for ``n`` vehicles (the base's, if it has ``init_state``)."""
        hook = getattr(self.base, "init_state", None)
        state = dict(hook(n)) if hook is not None else {}
        state[PREVIOUS_KEY] = np.zeros((n, 3), np.float32)
        return state

    def predict(
        self,
        observation: np.ndarray,
        state: dict[str, Any] | None = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Filtered actions in [−1, 1] for a batch (n, 15) or one (15,) observation."""
        obs = np.asarray(observation)
        n = 1 if obs.ndim == 1 else obs.shape[0]
        fresh = state is None
        if fresh:
            base_state, previous = None, np.zeros((n, 3), np.float32)
        else:
            base_state = {k: v for k, v in state.items() if k != PREVIOUS_KEY} or None
            previous = state[PREVIOUS_KEY]
            if previous.shape[0] != n:
                raise ValueError(f"state is for {previous.shape[0]} vehicles, observation for {n}")
        action, base_state = self.base.predict(
            observation,
            state=base_state,
            episode_start=episode_start,
            deterministic=deterministic,
        )
        b = np.asarray(action, np.float32).reshape(n, 3)
        start = np.full(n, fresh)
        if episode_start is not None:
            start |= np.asarray(episode_start, dtype=bool).reshape(-1)
        filtered = (self.alpha * previous + (1.0 - self.alpha) * b).astype(np.float32)
        filtered[start] = b[start]  # no history yet: the filter starts at the base's action
        state = dict(base_state or {})
        state[PREVIOUS_KEY] = filtered
        return (filtered[0] if obs.ndim == 1 else filtered), state

    def diagnostics(self, state: dict[str, Any]) -> dict[str, np.ndarray]:
        """The base's diagnostics, if it has any."""
        hook = getattr(self.base, "diagnostics", None)
        if hook is None:
            return {}
        return dict(hook({k: v for k, v in state.items() if k != PREVIOUS_KEY}))

    def __repr__(self) -> str:
        return f"LowPassPolicy(base={self.base!r}, alpha={self.alpha})"
