"""An envelope guard for agents: pitch and surge commands limited near the vehicle's limits.

An autopilot's envelope protection, as fly-by-wire aircraft and AUV autopilots carry it: the
agent commands what it likes inside the envelope, and near its edge the guard takes away the
command that would push the vehicle further out. With θ_p = θ + T·q the pitch predicted T
seconds ahead (rad), the nose-up moment command a_M is capped by

    a_M ≤ 1 − 2·clip((θ_p − θ_soft)/(θ_hard − θ_soft), 0, 1)

(full authority below θ_soft, full nose-down at θ_hard) and, mirrored, the nose-down command
by the same ramp in −θ_p (for an agent commanding the stern-plane angle δ_s of the realistic
actuator, whose positive deflection pitches the nose down, ``nose_up_command = -1`` mirrors
the two); the surge command a_X is capped by the same ramp in the surge speed
u between u_soft and u_hard (full astern at u_hard). The yaw command is never touched. Inside
the soft limits the guard is the identity, so an agent that stays there acts as trained.

Optionally the guard also protects the low-speed edge, as an aircraft's alpha floor does: the fins'
lift grows with u², so a vehicle that lets its surge fall loses the moments it would need to
turn back, and a learned policy that brakes to turn can stall for good (docs/design.md §3.15).
With ``surge_floor_soft`` > 0 the surge command is floored by the mirrored ramp

    a_X ≥ −1 + 2·clip((u_floor_soft − u)/(u_floor_soft − u_floor_hard), 0, 1)

(no floor above u_floor_soft, full ahead from u_floor_hard down). It is off by default, and an
agent saved without it records nothing new.

The guard reads θ, q and u from the agent's own observation (what the vehicle's attitude and
velocity sensors give; every agent observation names them) and acts on the command the env receives.
It is a stage of an agent (`controllers.stages`: ``{"name": "envelope_guard", ...}``), applied
around the network at inference and around the env in training alike. The defaults keep margins
below the env's limits: the episode ends at 60° of pitch and, on the surge-limited ids, at
2.0 m/s (docs/design.md §3.15).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from auv_gym.sim.observation import OBS_INDEX
from auv_gym.support.validation import real

__all__ = [
    "ENV_GUARD_INDEX",
    "GUARD_INPUTS",
    "EnvelopeGuard",
    "check_envelope_guard",
    "check_guard_sign",
    "guard_commands",
    "guard_env_commands",
]

GUARD_INPUTS = ("theta", "q", "u")  # observation entries the guard reads [rad, rad/s, m/s]
# Their positions in the env's 15-value observation (what classical and residual policies read).
ENV_GUARD_INDEX = tuple(OBS_INDEX[name] for name in GUARD_INPUTS)


@dataclass(frozen=True)
class EnvelopeGuard:
    """The guard's limits: pitch ramp [deg], pitch look-ahead [s], surge ramp [m/s]."""

    pitch_soft_deg: float = 35.0
    pitch_hard_deg: float = 50.0
    lookahead_s: float = 1.0
    surge_soft: float = 1.8
    surge_hard: float = 1.95
    # The low-speed floor [m/s]: off while surge_floor_soft is 0.
    surge_floor_soft: float = 0.0
    surge_floor_hard: float = 0.0
    # +1: a positive a_M pitches the nose up (the paper's M); −1: a_M is the stern-plane angle
    # δ_s of the realistic actuator, whose positive deflection pitches the nose down (§2.6).
    nose_up_command: float = 1.0

    def __post_init__(self) -> None:
        where = "envelope_guard"
        if self.nose_up_command not in (1.0, -1.0) or isinstance(self.nose_up_command, bool):
            raise ValueError(
                f"{where}.nose_up_command must be 1 (a_M nose-up, the paper's M) or -1 (the "
                f"stern-plane angle, positive nose-down), got {self.nose_up_command!r}"
            )
        soft = real(
            f"{where}.pitch_soft_deg", self.pitch_soft_deg, 0.0, 90.0, low_open=True, unit="deg"
        )
        hard = real(
            f"{where}.pitch_hard_deg", self.pitch_hard_deg, 0.0, 90.0, low_open=True, unit="deg"
        )
        real(f"{where}.lookahead_s", self.lookahead_s, 0.0, 10.0, unit="s")
        u_soft = real(f"{where}.surge_soft", self.surge_soft, 0.0, 10.0, low_open=True, unit="m/s")
        u_hard = real(f"{where}.surge_hard", self.surge_hard, 0.0, 10.0, low_open=True, unit="m/s")
        if not (soft < hard and u_soft < u_hard):
            raise ValueError(
                f"{where}: each soft limit must lie below its hard limit, got pitch "
                f"{soft:g}/{hard:g} deg, surge {u_soft:g}/{u_hard:g} m/s"
            )
        floor_soft = real(f"{where}.surge_floor_soft", self.surge_floor_soft, 0.0, 10.0, unit="m/s")
        floor_hard = real(f"{where}.surge_floor_hard", self.surge_floor_hard, 0.0, 10.0, unit="m/s")
        if floor_soft == 0.0 and floor_hard != 0.0:
            raise ValueError(
                f"{where}: surge_floor_hard {floor_hard:g} m/s needs a surge_floor_soft above "
                "it (0 turns the low-speed floor off)"
            )
        if floor_soft > 0.0 and not (floor_hard < floor_soft < u_soft):
            raise ValueError(
                f"{where}: the low-speed floor needs surge_floor_hard < surge_floor_soft < "
                f"surge_soft, got {floor_hard:g} < {floor_soft:g} < {u_soft:g} m/s"
            )

    @property
    def has_floor(self) -> bool:
        """Whether the low-speed floor is on."""
        return self.surge_floor_soft > 0.0

    def to_dict(self) -> dict[str, float]:
        """The settings as metadata.json records them (the floor only when it is on, so an
        agent without it records what it always did)."""
        settings = {k: float(v) for k, v in asdict(self).items()}
        if not self.has_floor:
            del settings["surge_floor_soft"], settings["surge_floor_hard"]
        return settings


def check_envelope_guard(value: Any, where: str) -> EnvelopeGuard:
    """An `EnvelopeGuard` from a mapping of its fields (missing ones: the defaults), True (the
    defaults) or a guard; a one-line error naming ``where`` otherwise."""
    if isinstance(value, EnvelopeGuard):
        return value
    if value is True:
        return EnvelopeGuard()
    fields = sorted(EnvelopeGuard.__dataclass_fields__)
    if not isinstance(value, Mapping):
        raise ValueError(
            f"{where}: envelope_guard must be true or a mapping of {fields}, got {value!r}"
        )
    unknown = sorted(set(value) - set(fields))
    if unknown:
        raise ValueError(f"{where}: envelope_guard has unknown keys {unknown}; valid: {fields}")
    try:
        return EnvelopeGuard(**value)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{where}: {error}") from None


def check_guard_sign(guard: EnvelopeGuard, actuator: str | None, where: str) -> None:
    """A one-line ValueError naming ``where`` unless ``guard``'s pitch sign is that of the
    actuator's M command: the stern-plane angle (positive nose-down) on "realistic", a nose-up
    command on the others (None: the paper's). A wrong sign would push the pitch further out."""
    expected = -1.0 if actuator == "realistic" else 1.0
    if guard.nose_up_command != expected:
        meaning = (
            "the stern-plane angle (positive nose-down)" if expected < 0 else "a nose-up command"
        )
        raise ValueError(
            f"{where}: on the {actuator or 'paper'} actuator the M command is {meaning}: the "
            f"envelope guard needs nose_up_command {expected:g}, got {guard.nose_up_command:g}"
        )


def _authority(x: np.ndarray, soft: float, hard: float) -> np.ndarray:
    """1 below ``soft``, −1 from ``hard`` on, linear between."""
    return 1.0 - 2.0 * np.clip((x - soft) / (hard - soft), 0.0, 1.0)


def guard_commands(
    commands: np.ndarray, observation: np.ndarray, index: Sequence[int], guard: EnvelopeGuard
) -> np.ndarray:
    """The guarded commands (float32, the shape of ``commands``: (3,) or (n, 3)) for raw
    observations of the same batch shape; ``index``: the positions of θ, q, u in them."""
    obs = np.atleast_2d(np.asarray(observation, dtype=np.float64))
    out = np.array(commands, dtype=np.float32, copy=True)
    rows = out.reshape(-1, 3)
    theta, q, u = (obs[:, i] for i in index)
    predicted = theta + guard.lookahead_s * q  # [rad]
    soft, hard = math.radians(guard.pitch_soft_deg), math.radians(guard.pitch_hard_deg)
    nose_up = _authority(predicted, soft, hard)
    nose_down = _authority(-predicted, soft, hard)
    if guard.nose_up_command > 0.0:
        rows[:, 1] = np.clip(rows[:, 1], -nose_down, nose_up)
    else:  # the stern plane: a positive command pitches the nose down
        rows[:, 1] = np.clip(rows[:, 1], -nose_up, nose_down)
    if guard.has_floor:  # the mirrored ramp in −u: −1 above the soft floor, +1 below the hard
        floor = -_authority(-u, -guard.surge_floor_soft, -guard.surge_floor_hard)
        rows[:, 0] = np.maximum(rows[:, 0], floor)
    rows[:, 0] = np.minimum(rows[:, 0], _authority(u, guard.surge_soft, guard.surge_hard))
    return out


def guard_env_commands(
    commands: np.ndarray, observation: np.ndarray, guard: EnvelopeGuard | None
) -> np.ndarray:
    """``guard_commands`` on commands answering the env's 15-value observations (θ, q, u at
    `ENV_GUARD_INDEX`); ``guard`` None leaves them unchanged."""
    if guard is None:
        return commands
    return guard_commands(commands, observation, ENV_GUARD_INDEX, guard)
