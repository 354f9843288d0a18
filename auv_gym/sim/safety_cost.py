"""The per-step safety cost ``info["cost"]`` (Safety-Gymnasium's convention): `SafetyCost`.

A non-negative float per control step, apart from the reward, for constrained RL (a cost budget
per episode instead of reward shaping). With δ the vehicle's intrusion into the depth envelope's
safety margin m (`auv_gym.ocean.depth_envelope`; 0 without an envelope), u the surge speed through
the water and θ the pitch, after the step (docs/model.md §12):

    c = w_depth·min(δ/m, 1) + w_speed·min(max(u − u_c, 0)/u_c, 1)
        + w_pitch·min(max(|θ| − θ_c, 0)/θ_c, 1),
    δ = max(m − z, z − (z_seabed − m), 0)        [m], z down, surface at z = 0

Each term lies in [0, its weight]: 0 inside the soft limit, the weight at the boundary (depth),
at twice the soft limit (speed, pitch) and beyond. Soft limits: u_c = 2.0 m/s (REMUS 100 tops
out near 2.3-2.5 m/s), θ_c = 45° (the classical controllers peak at 41-44° on the paper's helix,
the episode ends at `max_pitch` = 60°). A non-finite state costs the sum of the weights. The
kernel evaluates it with the reward (`task.task_cost`); the rows below are part of the task row.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields

import numpy as np
from numba import njit

from auv_gym.ocean.depth_envelope import SURFACE_Z, DepthEnvelope
from auv_gym.support.validation import ArgumentTypeError, keys_within, real

__all__ = ["SAFETY_FIELDS", "SafetyCost", "safety_cost", "safety_vector"]

MAX_COST_WEIGHT = 1e6
MAX_SPEED_LIMIT = 10.0  # [m/s] the observation's speed bound
# Task-row fields of the envelope and the cost (`task.TASK_FIELDS` ends with them).
SAFETY_FIELDS = (
    "surface_z",
    "seabed_z",
    "depth_margin",
    "cost_w_depth",
    "cost_w_speed",
    "cost_w_pitch",
    "cost_speed_limit",
    "cost_pitch_limit",
)


@dataclass(frozen=True)
class SafetyCost:
    """Weights (dimensionless) and soft limits of the safety cost (module docstring)."""

    depth: float = 1.0  # w_depth: intrusion into the depth envelope's margin
    speed: float = 1.0  # w_speed: surge speed above speed_limit
    pitch: float = 1.0  # w_pitch: |pitch| above pitch_limit
    speed_limit: float = 2.0  # [m/s] u_c
    pitch_limit: float = math.radians(45.0)  # [rad] θ_c

    def __post_init__(self) -> None:
        for name in ("depth", "speed", "pitch"):
            value = real(f"safety_cost {name}", getattr(self, name), 0.0, MAX_COST_WEIGHT)
            object.__setattr__(self, name, value)
        object.__setattr__(
            self,
            "speed_limit",
            real(
                "safety_cost speed_limit",
                self.speed_limit,
                0.0,
                MAX_SPEED_LIMIT,
                low_open=True,
                unit="m/s",
            ),
        )
        object.__setattr__(
            self,
            "pitch_limit",
            real(
                "safety_cost pitch_limit",
                self.pitch_limit,
                0.0,
                math.pi / 2,
                low_open=True,
                high_open=True,
                unit="rad",
            ),
        )

    @classmethod
    def from_spec(cls, spec: SafetyCost | Mapping | None) -> SafetyCost:
        """None: the defaults; a dict of fields or itself."""
        if spec is None:
            return cls()
        if isinstance(spec, SafetyCost):
            return spec
        if isinstance(spec, Mapping):
            return cls(**keys_within("safety_cost", spec, [f.name for f in fields(cls)]))
        raise ArgumentTypeError(
            f"safety_cost must be None, a dict with keys among "
            f"{sorted(f.name for f in fields(cls))} or a SafetyCost, got {spec!r:.80}"
        )


def safety_vector(envelope: DepthEnvelope | None, cost: SafetyCost) -> np.ndarray:
    """The `SAFETY_FIELDS` part of the task row. Without an envelope the surface and seabed lie
    at ∓inf: nothing ends an episode by depth and δ = 0 exactly."""
    if envelope is None:
        surface, seabed, margin = -math.inf, math.inf, 1.0
    else:
        surface, seabed, margin = SURFACE_Z, envelope.seabed_z, envelope.margin
    return np.array(
        [
            surface,
            seabed,
            margin,
            cost.depth,
            cost.speed,
            cost.pitch,
            cost.speed_limit,
            cost.pitch_limit,
        ]
    )


@njit(cache=True, inline="always")
def safety_cost(z, u, theta, surface_z, seabed_z, margin, w_depth, w_speed, w_pitch, u_c, theta_c):
    """The cost c of the module docstring [-] for depth z [m], surge u [m/s], pitch θ [rad]."""
    if not (math.isfinite(z) and math.isfinite(u) and math.isfinite(theta)):
        return w_depth + w_speed + w_pitch
    intrusion = max(max(surface_z + margin - z, z - (seabed_z - margin)), 0.0)
    cost = w_depth * min(intrusion / margin, 1.0)
    cost += w_speed * min(max(u - u_c, 0.0) / u_c, 1.0)
    cost += w_pitch * min(max(abs(theta) - theta_c, 0.0) / theta_c, 1.0)
    return cost
