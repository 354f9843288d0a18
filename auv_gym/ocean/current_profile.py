r"""A horizontal current that varies with depth and turns slowly (docs/model.md §13.5).

Added to the uniform current of `auv_gym.ocean.disturbances` (constant mean + Gauss–Markov), which
is unchanged. With d the depth below the surface z = 0 (NED z) clamped to [0, h]:

    U(d) = U_h + (U_0 − U_h) (1 − d/h)^p          speed [m/s]
    χ(t) = χ₀ + A sin(2π t / T + φ)                direction of flow, from x toward y [rad]
    v_p  = U(d) (cos χ, sin χ, 0)                  NED [m/s]

U_0 is the surface speed, U_h the speed at and below the reference depth h (the seabed, or the
bottom of a shear layer). p = 1 is a linear shear layer; p = 1/7 with U_h = 0 is the classic
seventh-power law of a tidal current over the bed (Soulsby 1997, section 3.3; h the water
depth).
The phase φ of the heading drift is drawn per episode from the episode's seed.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields

from numba import njit

from auv_gym.ocean.disturbances import MAX_CURRENT_SPEED
from auv_gym.support.validation import ArgumentTypeError, keys_within, real

__all__ = ["CurrentProfile", "profile_velocity"]

MAX_REFERENCE_DEPTH = 11_000.0  # [m] the deepest ocean
MAX_DRIFT_PERIOD = 1e6  # [s]
# [s] The kernels evaluate the profile once per physics step (`forcing.ocean_forcing`), at most
# 0.1 s apart (`config.PHYSICS_DT_RANGE`): a drift period of 1 s or more is sampled at least 10
# times per period at every physics step the env accepts; a shorter one would alias.
MIN_DRIFT_PERIOD = 1.0
DEFAULT_DRIFT_PERIOD = 3600.0  # [s]


@dataclass(frozen=True)
class CurrentProfile:
    """Depth profile and heading drift of a horizontal current (module docstring)."""

    surface_speed: float  # [m/s] U_0 at d = 0
    reference_depth: float  # [m] h, where U reaches U_h
    reference_speed: float = 0.0  # [m/s] U_h at and below h
    exponent: float = 1.0 / 7.0  # p: 1 linear shear, 1/7 power law
    direction: float = 0.0  # [rad] χ₀, direction the water flows toward
    drift_amplitude: float = 0.0  # [rad] A
    drift_period: float = DEFAULT_DRIFT_PERIOD  # [s] T

    def __post_init__(self) -> None:
        def put(name: str, low: float, high: float, unit: str = "", **kw: bool) -> None:
            value = real(f"current_profile {name}", getattr(self, name), low, high, unit=unit, **kw)
            object.__setattr__(self, name, value)

        put("surface_speed", 0.0, MAX_CURRENT_SPEED, "m/s")
        put("reference_depth", 0.0, MAX_REFERENCE_DEPTH, "m", low_open=True)
        put("reference_speed", 0.0, MAX_CURRENT_SPEED, "m/s")
        put("exponent", 0.0, 10.0, "", low_open=True)
        put("direction", -2 * math.pi, 2 * math.pi, "rad")
        put("drift_amplitude", 0.0, math.pi, "rad")
        put("drift_period", 0.0, MAX_DRIFT_PERIOD, "s", low_open=True)
        if self.drift_period < MIN_DRIFT_PERIOD:
            raise ValueError(
                f"current_profile drift_period = {self.drift_period!r} s is below "
                f"{MIN_DRIFT_PERIOD:g} s: the kernels sample the drift once per physics step "
                "(up to 0.1 s), too seldom for a faster turn"
            )
        if self.drift_amplitude == 0.0 and self.drift_period != DEFAULT_DRIFT_PERIOD:
            _period_without_drift(self.drift_period)

    @property
    def max_speed(self) -> float:
        """Largest speed of the profile [m/s]: the larger end of a monotonic profile."""
        return max(self.surface_speed, self.reference_speed)

    @classmethod
    def from_spec(cls, spec: CurrentProfile | Mapping | None) -> CurrentProfile | None:
        """None (no profile), a dict of fields, or itself. A dict's drift_period is refused
        without a drift_amplitude > 0, where it does nothing, even at its default."""
        if spec is None or isinstance(spec, CurrentProfile):
            return spec
        if isinstance(spec, Mapping):
            given = keys_within("current_profile", spec, [f.name for f in fields(cls)])
            for name in ("surface_speed", "reference_depth"):
                if name not in given:
                    raise ValueError(f"current_profile needs {name}, got keys {sorted(given)}")
            profile = cls(**given)
            if "drift_period" in given and profile.drift_amplitude == 0.0:
                _period_without_drift(given["drift_period"])
            return profile
        raise ArgumentTypeError(
            f"current_profile must be None, a dict of CurrentProfile "
            f"fields or a CurrentProfile, got {spec!r:.80}"
        )


def _period_without_drift(period: object) -> None:
    raise ValueError(
        f"current_profile drift_period = {period!r} s does nothing without a heading drift "
        "(drift_amplitude = 0): give a drift_amplitude > 0 or leave drift_period out"
    )


@njit(cache=True, inline="always")
def profile_velocity(
    u_surface,
    u_reference,
    depth_ref,
    exponent,
    direction,
    drift_amplitude,
    drift_omega,
    drift_phase,
    depth,
    t,
):
    """v_p = U(d) (cos χ(t), sin χ(t), 0) [m/s] of the module docstring at ``depth`` [m] and
    time t [s]; ``drift_omega`` = 2π/T [rad/s]."""
    d = min(max(depth, 0.0), depth_ref)
    speed = u_reference + (u_surface - u_reference) * (1.0 - d / depth_ref) ** exponent
    chi = direction + drift_amplitude * math.sin(drift_omega * t + drift_phase)
    return speed * math.cos(chi), speed * math.sin(chi), 0.0
