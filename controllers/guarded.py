"""A classical controller inside the envelope guard the agents carry (`controllers.envelope_guard`).

The as-built agents fly under `AUVPath3DSpeedLimit-v0`, whose episode ends past the vehicle's
top speed, and carry the envelope guard that keeps them below it; the classical controllers fly
without either. `GuardedPolicy` puts a controller under the same protection, so that the two can
be compared under one rule (docs/results.md "The vehicle as built"): per control step the base
controller's action b_k, then

    a_k = guard(b_k; θ, q, u of o_k)

the pitch and surge commands ramped away near the limits, the yaw command untouched. The guard
is stateless, so the policy's state is the base's and inside the soft limits the policy is the
base bit for bit. Its M command is a nose-up moment on the paper's actuator and the fins, the
stern-plane angle (positive nose-down) on the realistic one: ``actuator="realistic"`` sets
``nose_up_command = -1`` unless the guard's settings say otherwise.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from auv_gym.sim.observation import OBS_DIM
from controllers.envelope_guard import check_envelope_guard, check_guard_sign, guard_env_commands

__all__ = ["GuardedPolicy", "guard_for_actuator"]


def guard_for_actuator(settings: Any, actuator: str | None, where: str) -> Any:
    """The `EnvelopeGuard` of ``settings`` (True or None: the defaults; a mapping of its
    fields), its stern-plane sign set for ``actuator`` where the settings leave it; a sign the
    settings give against the actuator's is a ValueError naming ``where``."""
    fields = {} if settings is None or settings is True else settings
    if isinstance(fields, dict) and "nose_up_command" not in fields and actuator == "realistic":
        fields = {**fields, "nose_up_command": -1.0}
    guard = check_envelope_guard(fields, where)
    check_guard_sign(guard, actuator, where)
    return guard


class GuardedPolicy:
    """Base controller followed by the envelope guard (module doc); the Policy protocol.

    Args:
        base: the base controller (any Policy of the env's 15-value observation).
        guard: an `EnvelopeGuard`.

    State: the base's. `diagnostics` forwards the base's.
    """

    def __init__(self, base: Any, guard: Any) -> None:
        if not callable(getattr(base, "predict", None)):
            raise ValueError(f"guarded base must have predict(...), got {type(base).__name__}")
        self.base = base
        # what the base reads and the env it needs (the current from the DVL: `controllers.base`)
        self.observation_width = getattr(base, "observation_width", OBS_DIM)
        self.env_kwargs = getattr(base, "env_kwargs", None)
        self.guard = check_envelope_guard(guard, "guarded")
        self.name = f"{getattr(base, 'name', 'base')}_guarded"

    def init_state(self, n: int) -> Any:
        """A fresh state for ``n`` vehicles: the base's (None if it has no ``init_state``)."""
        hook = getattr(self.base, "init_state", None)
        return hook(n) if hook is not None else None

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """Guarded actions in [−1, 1] for a batch (n, 15) or one (15,) observation."""
        action, state = self.base.predict(
            observation, state=state, episode_start=episode_start, deterministic=deterministic
        )
        return guard_env_commands(action, observation, self.guard), state

    def diagnostics(self, state: Any) -> dict[str, np.ndarray]:
        """The base's diagnostics, if it has any."""
        hook = getattr(self.base, "diagnostics", None)
        return {} if hook is None else dict(hook(state))

    def __repr__(self) -> str:
        return f"GuardedPolicy(base={self.base!r}, guard={self.guard!r})"
