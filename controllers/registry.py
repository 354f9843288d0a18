"""The classical controllers by name: the paper's FBSM and backstepping, the PID + LOS autopilot
and their named variants (`PRESETS`). The learned policies (saved agents, residual and low-pass
policies) are built on top of these by `controllers.make`.
"""

from __future__ import annotations

from typing import Any

from auv_gym.vehicle.record import DerivedAUVParams
from controllers.backstepping import Backstepping
from controllers.command_filtered import CommandFilteredBackstepping
from controllers.fbsm import FBSM
from controllers.guarded import GuardedPolicy, guard_for_actuator
from controllers.lowpass import DEFAULT_ALPHA, LowPassPolicy
from controllers.pid import PIDLOS

__all__ = [
    "CLASSICAL",
    "MODEL_BASED",
    "PRESETS",
    "UNFILTERED",
    "NoFiveDofModelError",
    "make_classical",
    "make_guarded",
    "make_lowpass",
    "reads_ground_velocity",
]

# Named variants of the classical controllers (not in the paper), against ocean currents; see
# `ControllerGains` and README "Results". Integral LOS in the horizontal plane, σ_y = 3. Current-
# observer LOS (`controllers.alos`, docs/model.md §3.7): observer ω_o = 3 rad/s, crab angles over
# ground, speed over ground; backstepping adds the gated ALOS trims (γ = 0.01 rad/(m·s)) that
# remove the bias its fixed nominal model leaves (the FBSM adapts that bias away itself).
_COLOS = {"current_observer": 3.0, "speed_over_ground": True}
# The PID for the vehicle as built (its re-tune below); its climb-speed preset shares it.
_PID_AS_BUILT = {**_COLOS, "k_z": 0.1}
PRESETS: dict[str, tuple[str, dict[str, Any]]] = {
    "fbsm_ilos": ("fbsm", {"ilos_y": 3.0}),
    "backstepping_ilos": ("backstepping", {"ilos_y": 3.0}),
    "fbsm_colos": ("fbsm", _COLOS),
    "backstepping_colos": ("backstepping", {**_COLOS, "alos_y": 0.01, "alos_z": 0.01}),
    # The current-robust FBSM through a first-order low-pass (`controllers.lowpass`, α = 0.5):
    # the classical answer to chattering, which a residual agent must beat (docs/design.md §3.11).
    "fbsm_colos_lowpass": ("lowpass", {"base": "fbsm_colos"}),
    # The textbook baseline (`controllers.pid`, docs/model.md §4.9) with the same guidance options.
    "pid_ilos": ("pid_los", {"ilos_y": 3.0}),
    "pid_colos": ("pid_los", _COLOS),
    # For the vehicle as built (propeller and fins, navigation filter, docs/results.md "The
    # vehicle as built"): command-filtered backstepping (`controllers.command_filtered`,
    # docs/model.md §4.10) keeps the backstepping law inside the fins' magnitude and rate
    # limits, and both it and the PID re-tune soften the vertical LOS (k_z 0.5 → 0.15, 0.1 1/m:
    # the depth loop then stops chasing the noise of the estimate) and, for backstepping,
    # stiffen the yaw error gain k2 0.3 → 1 1/s; chosen on validation seed 100 (4 vehicles ×
    # 3 as-built scenarios), never on the test seeds.
    "command_filtered_colos": (
        "command_filtered",
        {**_COLOS, "alos_y": 0.01, "alos_z": 0.01, "k_z": 0.15, "k2": 1.0},
    ),
    "pid_as_built": ("pid_los", _PID_AS_BUILT),
    # The as-built PID inside the envelope guard the as-built agents carry (`controllers.guarded`):
    # the classical reference under the agents' rule, the 2.0 m/s top speed (docs/results.md
    # "The vehicle as built").
    "pid_as_built_guarded": ("guarded", {"base": "pid_as_built"}),
    # The as-built PID that speeds up when its stern plane runs out of authority (the climb-speed
    # law of `controllers.pid`, docs/model.md §4.9): the 6-DOF hull's climbs need it.
    "pid_as_built_climb": ("pid_los", {**_PID_AS_BUILT, "climb_speed": 1.4}),
    "pid_as_built_climb_guarded": ("guarded", {"base": "pid_as_built_climb"}),
    # The climb-speed PID with a softer pitch loop (ω_n 3 → 2 rad/s, ζ 1 → 1.4): the stiffer loop
    # answers the sea state 3 waves' pitch moments with stern-plane swings that heave the vehicle
    # (docs/model.md §4.9); the best of 16 pitch and heading loops on validation seeds 100-109 of
    # the 3 as-built scenarios (`benchmarks.analysis.tune_pid --base pid_as_built_climb`), never
    # on the test seeds.
    "pid_as_built_climb_soft_pitch": (
        "pid_los",
        {**_PID_AS_BUILT, "climb_speed": 1.4, "pitch_wn": 2.0, "pitch_zeta": 1.4},
    ),
    # The soft-pitch PID with the current read from the DVL (`controllers.alos`, 5) in place of
    # the observer: the velocity over ground the as-built agents see, given to the classical
    # reference too (it flies the agents' observation, `reads_ground_velocity`), and the ALOS
    # trims (γ_h = 0.02, γ_v = 0.01 rad/(m·s)) for the drift of the navigation's heading error,
    # which the observer absorbed and the measured current does not. ω_c, γ_h, γ_v chosen on
    # validation seeds 100-109 of the 3 as-built scenarios on both plants
    # (`benchmarks.analysis.tune_pid`, docs/model.md §4.9), never on the test seeds.
    "pid_as_built_dvl": (
        "pid_los",
        {
            **_PID_AS_BUILT,
            "current_observer": 0.0,
            "dvl_current": 0.3,
            "alos_y": 0.02,
            "alos_z": 0.01,
            "climb_speed": 1.4,
            "pitch_wn": 2.0,
            "pitch_zeta": 1.4,
        },
    ),
}
CLASSICAL = ("fbsm", "backstepping", "pid_los", "command_filtered", *PRESETS)
# The controllers whose laws are built on the vehicle's 5-DOF model (docs/model.md §4).
MODEL_BASED = ("fbsm", "backstepping", "command_filtered")
# The classical controllers a low-pass or a guard may wrap (neither wraps a wrapped one).
UNFILTERED = tuple(n for n in CLASSICAL if PRESETS.get(n, ("",))[0] not in ("lowpass", "guarded"))


class NoFiveDofModelError(ValueError):
    """A controller built on the 5-DOF model (`MODEL_BASED`) asked to fly a vehicle that has
    none: the benchmark reports the pair as not applicable, a direct call is refused."""


def make_classical(name: str, **kwargs: Any) -> Any:
    """The classical controller ``name`` (a name of `CLASSICAL`); keyword arguments override
    its preset's (see `controllers.make`)."""
    if isinstance(kwargs.get("params"), DerivedAUVParams) and _law(name, kwargs) in MODEL_BASED:
        raise NoFiveDofModelError(
            f"{name} is built on the vehicle's 5-DOF model, and this vehicle has none (its "
            "5-DOF record is derived from the 6-DOF hull): fly a PID + LOS controller"
        )
    if name in PRESETS:
        base, preset = PRESETS[name]
        return make_classical(base, **{**preset, **kwargs})
    if name == "fbsm":
        return FBSM(**kwargs)
    if name == "backstepping":
        return Backstepping(**kwargs)
    if name == "pid_los":
        return PIDLOS(**kwargs)
    if name == "command_filtered":
        return CommandFilteredBackstepping(**kwargs)
    if name == "lowpass":  # a preset's low-pass over an unfiltered classical base
        return make_lowpass(**kwargs)
    if name == "guarded":  # a preset's envelope guard over an unwrapped classical base
        return make_guarded(**kwargs)
    raise ValueError(f"unknown classical controller {name!r}; valid: {list(CLASSICAL)}")


# The wrappers a preset may name: their base when none is named (`make_lowpass`,
# `make_guarded`) and the keywords that are theirs, not the base's.
_WRAPPERS = {
    "lowpass": ("fbsm_colos", ("alpha",)),
    "guarded": ("pid_as_built", ("envelope_guard",)),
}


def _resolve(name: str, kwargs: dict[str, Any]) -> tuple[str, dict[str, Any]]:
    """(control law, its keyword arguments) under the classical name ``name``, through presets
    and the low-pass and guard wrappers, as `make_classical` would build it."""
    while name in PRESETS:
        base, preset = PRESETS[name]
        name, kwargs = base, {**preset, **kwargs}
    if name in _WRAPPERS:
        default, own = _WRAPPERS[name]
        rest = {k: v for k, v in kwargs.items() if k != "base" and k not in own}
        return _resolve(kwargs.get("base", default), rest)
    return name, kwargs


def reads_ground_velocity(name: str, **kwargs: Any) -> bool:
    """Whether the classical controller ``name`` (with these keyword arguments) reads the
    velocity over ground, which only the agents' observation carries (``observation=
    "preview"``): its guidance takes the current from the DVL (the gain ``dvl_current``)."""
    _, kwargs = _resolve(name, kwargs)
    gains = kwargs.get("gains")
    return float(kwargs.get("dvl_current", gains.dvl_current if gains is not None else 0.0)) > 0


def _law(name: str, kwargs: dict[str, Any]) -> str:
    """The control law under the classical name ``name`` (`_resolve`)."""
    return _resolve(name, kwargs)[0]


def make_lowpass(
    base: str = "fbsm_colos", alpha: float = DEFAULT_ALPHA, **kwargs: Any
) -> LowPassPolicy:
    """`controllers.lowpass.LowPassPolicy` over the classical controller ``base`` (a name of
    `CLASSICAL` other than a filtered one) built with ``kwargs`` (gains, actuator,
    control_dt, ...)."""
    if base not in UNFILTERED:
        raise ValueError(
            f"lowpass base {base!r} is not an unfiltered classical controller; "
            f"valid: {list(UNFILTERED)}"
        )
    return LowPassPolicy(make_classical(base, **kwargs), alpha)


def make_guarded(
    base: str = "pid_as_built", envelope_guard: Any = None, **kwargs: Any
) -> GuardedPolicy:
    """`controllers.guarded.GuardedPolicy` over the classical controller ``base`` (a name of
    `UNFILTERED`) built with ``kwargs`` (gains, actuator, control_dt, ...); ``envelope_guard``:
    the guard's settings (None or True: the defaults, the stern-plane sign of the actuator)."""
    if base not in UNFILTERED:
        raise ValueError(
            f"guarded base {base!r} is not an unwrapped classical controller; "
            f"valid: {list(UNFILTERED)}"
        )
    guard = guard_for_actuator(envelope_guard, kwargs.get("actuator"), "guarded")
    return GuardedPolicy(make_classical(base, **kwargs), guard)
