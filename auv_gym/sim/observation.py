"""The one definition of the observation (names, units, bounds, builder) and the guidance row.

| index | name          | unit  | meaning                                                      |
|-------|---------------|-------|--------------------------------------------------------------|
| 0     | x_e           | m     | along-track error, body frame (vehicle − virtual point)      |
| 1     | y_e           | m     | cross-track error, body frame                                |
| 2     | z_e           | m     | vertical-track error, body frame                             |
| 3     | psi_error     | rad   | ψ − ψ_F wrapped to (−π, π]                                   |
| 4     | theta         | rad   | pitch θ (nose up positive)                                   |
| 5     | theta_F       | rad   | path pitch θ_F at the virtual point                          |
| 6–8   | u, v, w       | m/s   | body velocity through the water                              |
| 9–10  | q, r          | rad/s | pitch and yaw rates                                          |
| 11    | u_D           | m/s   | desired surge speed                                          |
| 12    | u_p           | m/s   | virtual-point speed u_D(1 + tanh(x_e/σ))                     |
| 13    | psi_F_dot     | rad/s | ψ̇_F = ψ_F'(s)·ṡ                                              |
| 14    | theta_F_dot   | rad/s | θ̇_F = θ_F'(s)·ṡ                                              |

The agent observation (``observation="preview"``, `ObservationConfig`; docs/design.md §3.12)
appends what a real AUV's navigation system and mission planner give, after these 15:

| index     | name                   | unit | meaning                                           |
|-----------|------------------------|------|---------------------------------------------------|
| 15–17     | u_ground, v_ground,    | m/s  | velocity over ground, body frame, ν + R_Bᵀv_c     |
|           | w_ground               |      | (what a DVL with bottom lock measures)            |
| 18–20     | a_X_prev, a_M_prev,    | –    | the previous saturated action (0 after a reset)   |
|           | a_N_prev               |      |                                                   |
| j..j+2    | preview{k}_x, _y, _z   | m    | path point k·Δs of arc ahead of the virtual point |
|           |                        |      | minus the vehicle, body frame                     |
| j+3       | preview{k}_curvature   | 1/m  | κ = ‖p′×p″‖/‖p′‖³ there, saturated at 1/m         |
| j+4       | preview{k}_torsion     | 1/m  | τ = (p′×p″)·p‴/‖p′×p″‖² (0 where κ = 0), ±1/m     |

for k = 1 … K, j = 21 + 5(k − 1). Past the end of a finite path the preview continues along its
last tangent (a straight line, κ = τ = 0). With an integral time T > 0 (``integral_time``) two
entries follow: y_e_integral, z_e_integral [m·s], leaky integrals
I ← e^(−Δt/T)·I + T(1 − e^(−Δt/T))·e of the cross- and vertical-track errors at each control
step (0 after a reset): the memory a controller's integral term keeps, here for the agent.
With ``integral_errors="xyz"`` three: x_e_integral (the along-track error's) comes first. With
``integral_limit`` L > 0 each integral is clipped to [−L, L] after every update (anti-windup: the
metres of an approach cannot charge it beyond what the path needs).

With ``history_steps`` H > 0 the errors' past follows, last: x_e_past{k}, y_e_past{k},
z_e_past{k} [m] for k = 1 … H, the observed tracking errors k·``history_interval`` seconds ago
(a whole number of control steps; the oldest known value, the one at the reset, stands in
before the episode is that old): a short memory of how the error moved, for a static policy to
tell a steady push (a current) from a passing one (waves).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numba import njit

from auv_gym.paths.guidance import body_errors, path_angles, virtual_point_speed, wrap_angle
from auv_gym.paths.shapes import path_eval
from auv_gym.support.records import field_indices
from auv_gym.support.validation import (
    ArgumentTypeError,
    choice,
    integer,
    keys_within,
    real,
    whole_steps,
)
from auv_gym.vehicle.dynamics import STATE

__all__ = [
    "GUIDANCE_DIM",
    "GUIDANCE_FIELDS",
    "GUIDE",
    "OBS",
    "OBSERVATION_KINDS",
    "OBSERVATION_PRESETS",
    "OBS_HIGH",
    "OBS_INDEX",
    "OBS_LOW",
    "OBS_NAMES",
    "OBS_UNITS",
    "ObservationConfig",
    "build_observation",
    "guidance_row",
    "mirror_signs",
]

ERROR_BOUND = 500.0  # [m] far beyond any corridor; a vehicle outside it is terminated
# [m/s] the speed entries' bound for REMUS 100 (5× its 2.0 m/s top speed), and the range of the
# speed arguments (u_desired, surge_limit); a faster vehicle's is `vehicle_speed_bound`.
SPEED_BOUND = 10.0
OBS_SPEED_MARGIN = 5.0  # speed bound / the vehicle's top speed `AUVParams.max_surge`
RATE_BOUND = 2.0 * math.pi  # [rad/s]
PATH_RATE_BOUND = 10.0  # [rad/s]


def _table(speed: float) -> tuple[tuple[str, str, float, float], ...]:
    """(name, unit, low, high) of the paper's entries, with ``speed`` [m/s] the speed bound."""
    return (
        ("x_e", "m", -ERROR_BOUND, ERROR_BOUND),
        ("y_e", "m", -ERROR_BOUND, ERROR_BOUND),
        ("z_e", "m", -ERROR_BOUND, ERROR_BOUND),
        ("psi_error", "rad", -math.pi, math.pi),
        ("theta", "rad", -math.pi / 2, math.pi / 2),
        ("theta_F", "rad", -math.pi / 2, math.pi / 2),
        ("u", "m/s", -speed, speed),
        ("v", "m/s", -speed, speed),
        ("w", "m/s", -speed, speed),
        ("q", "rad/s", -RATE_BOUND, RATE_BOUND),
        ("r", "rad/s", -RATE_BOUND, RATE_BOUND),
        ("u_D", "m/s", 0.0, speed),
        ("u_p", "m/s", 0.0, 2.0 * speed),
        ("psi_F_dot", "rad/s", -PATH_RATE_BOUND, PATH_RATE_BOUND),
        ("theta_F_dot", "rad/s", -PATH_RATE_BOUND, PATH_RATE_BOUND),
    )


_TABLE = _table(SPEED_BOUND)

OBS_NAMES: tuple[str, ...] = tuple(row[0] for row in _TABLE)
OBS_UNITS: dict[str, str] = {row[0]: row[1] for row in _TABLE}
OBS_INDEX: dict[str, int] = {name: i for i, name in enumerate(OBS_NAMES)}
OBS_LOW = np.array([row[2] for row in _TABLE], dtype=np.float32)
OBS_HIGH = np.array([row[3] for row in _TABLE], dtype=np.float32)
OBS_DIM = len(OBS_NAMES)


def vehicle_speed_bound(max_surge: float) -> float:
    """The speed entries' bound [m/s] (|u|, |v|, |w|, u_D; 2× for u_p) for a vehicle of top speed
    ``max_surge`` [m/s] (`AUVParams.max_surge`): `OBS_SPEED_MARGIN` times it, and never below
    `SPEED_BOUND`, so that every u_desired and surge_limit the env accepts stays observable.
    REMUS 100 (2.0 m/s): `SPEED_BOUND`, the paper's bounds `OBS_LOW`, `OBS_HIGH`."""
    return max(SPEED_BOUND, OBS_SPEED_MARGIN * max_surge)


def paper_bounds(speed_bound: float = SPEED_BOUND) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) float32 of the paper's entries for the speed bound ``speed_bound`` [m/s]
    (`vehicle_speed_bound`); `OBS_LOW`, `OBS_HIGH` for `SPEED_BOUND`."""
    rows = _table(speed_bound)
    return (
        np.array([row[2] for row in rows], dtype=np.float32),
        np.array([row[3] for row in rows], dtype=np.float32),
    )


# Guidance quantities computed by the simulator kernel, one row per vehicle [m, rad, rad/s, m/s].
GUIDANCE_FIELDS = (
    "x_e",
    "y_e",
    "z_e",
    "distance",
    "psi_F",
    "theta_F",
    "psi_F_dot",
    "theta_F_dot",
    "u_p",
    "s_dot",
)
GUIDANCE_DIM = len(GUIDANCE_FIELDS)
GUIDE = field_indices("GuidanceIndex", GUIDANCE_FIELDS, __name__)
OBS = field_indices("ObservationIndex", OBS_NAMES, __name__)


@njit(cache=True)
def guidance_row(st, kind, pdata, u_d, sigma, out):
    """Fill one guidance row ``out`` (layout `GUIDE`) from the simulator state ``st`` (layout
    `dynamics.STATE`): errors, distance, path angles and their rates, u_p and ṡ
    (docs/model.md §3)."""
    px, py, pz, dpx, dpy, dpz, ddx, ddy, ddz = path_eval(kind, pdata, st[STATE.s])
    x_e, y_e, z_e = body_errors(
        st[STATE.x], st[STATE.y], st[STATE.z], st[STATE.theta], st[STATE.psi], px, py, pz
    )
    psi_f, theta_f, dpsi_ds, dtheta_ds, speed = path_angles(dpx, dpy, dpz, ddx, ddy, ddz)
    u_p = virtual_point_speed(x_e, u_d, sigma)
    s_dot = u_p / speed
    out[GUIDE.x_e], out[GUIDE.y_e], out[GUIDE.z_e] = x_e, y_e, z_e
    out[GUIDE.distance] = math.sqrt(x_e * x_e + y_e * y_e + z_e * z_e)
    out[GUIDE.psi_F], out[GUIDE.theta_F] = psi_f, theta_f
    out[GUIDE.psi_F_dot], out[GUIDE.theta_F_dot] = dpsi_ds * s_dot, dtheta_ds * s_dot
    out[GUIDE.u_p], out[GUIDE.s_dot] = u_p, s_dot


@njit(cache=True, inline="always")
def build_observation(st, guid, u_d, out):
    """Write one observation ``out`` (layout `OBS`) from the simulator state ``st`` and its
    guidance row ``guid``."""
    out[OBS.x_e] = guid[GUIDE.x_e]
    out[OBS.y_e] = guid[GUIDE.y_e]
    out[OBS.z_e] = guid[GUIDE.z_e]
    out[OBS.psi_error] = wrap_angle(st[STATE.psi] - guid[GUIDE.psi_F])
    out[OBS.theta] = st[STATE.theta]
    out[OBS.theta_F] = guid[GUIDE.theta_F]
    out[OBS.u] = st[STATE.u]
    out[OBS.v] = st[STATE.v]
    out[OBS.w] = st[STATE.w]
    out[OBS.q] = st[STATE.q]
    out[OBS.r] = st[STATE.r]
    out[OBS.u_D] = u_d
    out[OBS.u_p] = guid[GUIDE.u_p]
    out[OBS.psi_F_dot] = guid[GUIDE.psi_F_dot]
    out[OBS.theta_F_dot] = guid[GUIDE.theta_F_dot]


# The agent observation (module docstring): kinds, defaults and the bounds of its extra entries.
OBSERVATION_KINDS = ("paper", "preview")
# Named observations beyond the kinds: the agent observation with integral action for a static
# policy — integrals of x_e, y_e, z_e (time constant 10 s), each clipped to ±1 m·s (anti-windup;
# docs/model.md, the agent observation). What the reference generalist observes.
OBSERVATION_PRESETS: dict[str, dict] = {
    "preview_integral": {
        "kind": "preview",
        "integral_time": 10.0,
        "integral_errors": "xyz",
        "integral_limit": 1.0,
    },
}
DEFAULT_PREVIEW_POINTS = 5  # K
DEFAULT_PREVIEW_SPACING = 2.0  # [m] Δs: K·Δs = 10 m, 10 s of travel at u_D = 1 m/s
MAX_PREVIEW_POINTS = 64
MAX_PREVIEW_LENGTH = ERROR_BOUND  # [m] K·Δs
CURVATURE_BOUND = 1.0  # [1/m] κ and |τ| saturate here: 8× sharper than the vehicle can turn
# |ν + R_Bᵀ v_c| per axis: the speed bound plus a 10 m/s current, ×1.5 (30 m/s for REMUS 100).
# A configuration whose current can exceed 10 m/s (`SimConfig.current_speed_bound`: the mean,
# a random current and 8 stationary standard deviations of the Gauss–Markov part) widens the
# ground-speed bound to 1.5·(speed bound + that speed).
_GROUND_MARGIN = 1.5
_GROUND_CURRENT = 10.0  # [m/s]
GROUND_SPEED_BOUND = _GROUND_MARGIN * (SPEED_BOUND + _GROUND_CURRENT)  # [m/s]
# Vehicle to a preview point: at most the distance to the virtual point (bounded per axis by
# ERROR_BOUND, so √3·ERROR_BOUND in all) plus K chords of at most 1.5 Δs each: the margin
# covers the midpoint march's arc-length error on splines, and the march halves any step whose
# chord exceeds it (`preview.extend_rows`).
PREVIEW_MARGIN = 1.5
PREVIEW_FEATURES = ("x", "y", "z", "curvature", "torsion")
EXTRA_HEAD = ("u_ground", "v_ground", "w_ground", "a_X_prev", "a_M_prev", "a_N_prev")
INTEGRAL_NAMES = ("x_e_integral", "y_e_integral", "z_e_integral")
INTEGRAL_ERRORS = ("yz", "xyz")  # which tracking errors are integrated
MAX_INTEGRAL_TIME = 1e4  # [s]
HISTORY_ERRORS = ("x_e", "y_e", "z_e")  # the errors whose past the history holds, per sample
MAX_HISTORY_STEPS = 64  # H
MAX_HISTORY_INTERVAL = 100.0  # [s]
OBSERVATION_FIELDS = (  # the keys of an observation dict (`ObservationConfig.from_spec`)
    "kind",
    "points",
    "spacing",
    "integral_time",
    "integral_errors",
    "integral_limit",
    "history_steps",
    "history_interval",
)


# The port-starboard reflection y → −y (body and earth frames; docs/design.md §3.19). A
# laterally symmetric hull in a mirrored ocean flies the mirrored path: the entries below change
# sign (lateral offsets and velocities, heading errors, yaw rates, the yaw command, torsion: a
# pseudo-scalar), every other entry keeps it (along-track and vertical quantities, pitch, surge,
# speeds, curvature ≥ 0).
MIRROR_ODD = frozenset(
    {"y_e", "psi_error", "v", "r", "psi_F_dot", "v_ground", "a_N_prev", "y_e_integral"}
)
MIRROR_EVEN = frozenset(
    {
        "x_e",
        "z_e",
        "theta",
        "theta_F",
        "u",
        "w",
        "q",
        "u_D",
        "u_p",
        "theta_F_dot",
        "u_ground",
        "w_ground",
        "a_X_prev",
        "a_M_prev",
        "x_e_integral",
        "z_e_integral",
    }
)
MIRROR_PREVIEW = {"x": 1.0, "y": -1.0, "z": 1.0, "curvature": 1.0, "torsion": -1.0}


def mirror_signs(names: Sequence[str]) -> np.ndarray:
    """The sign (float32, ±1) each named observation entry takes under the port-starboard
    reflection (`MIRROR_ODD`, `MIRROR_EVEN`, the preview points' `MIRROR_PREVIEW`). ValueError
    naming an entry whose reflection is not defined (e.g. a residual agent's base command)."""
    signs = np.ones(len(names), dtype=np.float32)
    unknown = []
    for i, name in enumerate(names):
        head, _, feature = name.partition("_")
        if name in MIRROR_ODD:
            signs[i] = -1.0
        elif name in MIRROR_EVEN:
            continue
        elif head.startswith("preview") and head[7:].isdigit() and feature in MIRROR_PREVIEW:
            signs[i] = MIRROR_PREVIEW[feature]
        elif (error := _history_error(name)) is not None:
            signs[i] = -1.0 if error in MIRROR_ODD else 1.0
        else:
            unknown.append(name)
    if unknown:
        raise ValueError(f"observation entries {unknown} have no defined port-starboard mirror")
    return signs


def _history_error(name: str) -> str | None:
    """The error a history entry's name holds ("y_e" for "y_e_past3"), else None."""
    error, _, past = name.rpartition("_past")
    return error if error in HISTORY_ERRORS and past.isdigit() else None


@dataclass(frozen=True)
class ObservationConfig:
    """Which observation the envs return: "paper" (the 15 entries above, the default of every
    registered id but `AUVPath3DPreview-v0`) or "preview" (those 15, then velocity over ground,
    the previous action and K path points Δs [m] of arc apart ahead of the virtual point)."""

    kind: str = "paper"
    points: int = DEFAULT_PREVIEW_POINTS  # K
    spacing: float = DEFAULT_PREVIEW_SPACING  # [m] Δs
    integral_time: float = 0.0  # [s] T of the error integrals; 0: none
    integral_errors: str = "yz"  # "yz": y_e, z_e; "xyz": x_e too
    integral_limit: float = 0.0  # [m·s] anti-windup clip of each integral; 0: none
    history_steps: int = 0  # H past samples of (x_e, y_e, z_e); 0: none
    history_interval: float = 1.0  # [s] between the samples (whole control steps)

    def __post_init__(self) -> None:
        def put(name: str, value) -> None:  # a frozen dataclass: fields are set once, checked
            object.__setattr__(self, name, value)

        put("kind", choice("observation kind", self.kind, OBSERVATION_KINDS))
        points = integer("observation points (preview K)", self.points, 1, MAX_PREVIEW_POINTS)
        put("points", points)
        put(
            "spacing",
            real(
                "observation spacing (preview Δs)",
                self.spacing,
                0.0,
                MAX_PREVIEW_LENGTH / points,
                low_open=True,
                unit=f"m (K·Δs <= {MAX_PREVIEW_LENGTH:g} m)",
            ),
        )
        put(
            "integral_time",
            real(
                "observation integral_time",
                self.integral_time,
                0.0,
                MAX_INTEGRAL_TIME,
                unit="s (0: no error integrals)",
            ),
        )
        put(
            "integral_errors",
            choice("observation integral_errors", self.integral_errors, INTEGRAL_ERRORS),
        )
        put(
            "integral_limit",
            real(
                "observation integral_limit",
                self.integral_limit,
                0.0,
                ERROR_BOUND * MAX_INTEGRAL_TIME,
                unit="m·s (0: no clip)",
            ),
        )
        put(
            "history_steps",
            integer("observation history_steps", self.history_steps, 0, MAX_HISTORY_STEPS),
        )
        interval = real(
            "observation history_interval",
            self.history_interval,
            0.0,
            MAX_HISTORY_INTERVAL,
            low_open=True,
            unit="s",
        )
        put("history_interval", interval)
        # A field that differs from its default is one the caller set: refused where it does
        # nothing (`from_spec` refuses a dict's keys so even at their default values).
        values = {f.name: (getattr(self, f.name), f.default) for f in dataclasses.fields(self)}
        self._check_effective({name: v for name, (v, default) in values.items() if v != default})

    def _check_effective(self, given: Mapping[str, object]) -> None:
        """ValueError naming the first of the ``given`` fields (name: value as given) that this
        observation ignores: any but the kind on the paper's 15 entries, the integrals' error
        set and limit without an integral time, the history's interval without a history."""
        if self.kind == "paper":
            for name in OBSERVATION_FIELDS[1:]:
                if name in given:
                    raise ValueError(
                        f"observation {name} = {given[name]!r} needs the agent observation "
                        "(kind 'preview'); the paper's 15 entries have no preview, error "
                        "integrals or history"
                    )
        if self.integral_time == 0.0:
            for name in ("integral_errors", "integral_limit"):
                if name in given:
                    raise ValueError(
                        f"observation {name} = {given[name]!r} does nothing without error "
                        "integrals (integral_time = 0): give an integral_time > 0 or leave "
                        f"{name} out"
                    )
        if self.history_steps == 0 and "history_interval" in given:
            raise ValueError(
                f"observation history_interval = {given['history_interval']!r} does nothing "
                "without a history (history_steps = 0): give history_steps > 0 or leave "
                "history_interval out"
            )

    @classmethod
    def from_spec(cls, spec: str | Mapping | ObservationConfig | None) -> ObservationConfig:
        """From None or "paper", "preview" (default K and Δs), a name of `OBSERVATION_PRESETS`
        ("preview_integral"), a dict {"kind", "points", "spacing", "integral_time",
        "integral_errors", "integral_limit", "history_steps", "history_interval"} or an
        `ObservationConfig`. A dict key the observation would ignore is refused, even at its
        default value: any but "kind" with kind "paper", "integral_errors" and
        "integral_limit" without an integral_time, "history_interval" without history_steps."""
        if spec is None:
            return cls()
        if isinstance(spec, ObservationConfig):
            return spec
        if isinstance(spec, str) and spec in OBSERVATION_PRESETS:
            return cls(**OBSERVATION_PRESETS[spec])
        if isinstance(spec, str):  # a kind, or neither: every valid name listed
            return cls(kind=choice("observation", spec, [*OBSERVATION_KINDS, *OBSERVATION_PRESETS]))
        if isinstance(spec, Mapping):
            given = keys_within("observation", spec, OBSERVATION_FIELDS)
            config = cls(**{"kind": "preview", **given})
            config._check_effective(given)  # a key given at its default value does nothing too
            return config
        raise ArgumentTypeError(
            f"observation must be one of {[*OBSERVATION_KINDS, *OBSERVATION_PRESETS]}, a dict "
            f"with keys {', '.join(OBSERVATION_FIELDS)} or an ObservationConfig, got {spec!r:.80}"
        )

    def to_dict(self) -> dict:
        """The fields as a JSON-ready dict (agent metadata); "paper" holds its kind only."""
        if self.kind == "paper":
            return {"kind": "paper"}
        fields = {"kind": self.kind, "points": self.points, "spacing": self.spacing}
        if self.integral_time > 0.0:
            fields["integral_time"] = self.integral_time
            if self.integral_errors != "yz":  # defaults stay out: older metadata matches
                fields["integral_errors"] = self.integral_errors
            if self.integral_limit > 0.0:
                fields["integral_limit"] = self.integral_limit
        if self.history_steps:  # none stays out: older metadata matches
            fields["history_steps"] = self.history_steps
            fields["history_interval"] = self.history_interval
        return fields

    @property
    def integrals(self) -> int:
        """Number of error-integral entries: one per integrated error with an integral time,
        else 0."""
        if self.kind == "paper" or self.integral_time <= 0.0:
            return 0
        return len(self.integral_errors)

    @property
    def integrated_columns(self) -> slice:
        """The integrated errors' columns in (x_e, y_e, z_e)."""
        return slice(3 - len(self.integral_errors), 3)

    @property
    def history(self) -> int:
        """Number of history entries: 3 per past sample (x_e, y_e, z_e)."""
        return len(HISTORY_ERRORS) * self.history_steps

    def history_stride(self, control_dt: float) -> int:
        """Control steps between two history samples; ValueError unless ``history_interval``
        is a whole number of steps of ``control_dt`` [s] (`SimConfig` checks it when built)."""
        interval = self.history_interval
        return whole_steps("observation history_interval", interval, control_dt, "control_dt")

    @property
    def extra_dim(self) -> int:
        """Entries after the paper's 15 (0 for "paper")."""
        if self.kind == "paper":
            return 0
        preview = len(PREVIEW_FEATURES) * self.points
        return len(EXTRA_HEAD) + preview + self.integrals + self.history

    @property
    def names(self) -> tuple[str, ...]:
        """Every entry's name, in order."""
        if self.kind == "paper":
            return OBS_NAMES
        preview = tuple(
            f"preview{k}_{feature}"
            for k in range(1, self.points + 1)
            for feature in PREVIEW_FEATURES
        )
        integrals = INTEGRAL_NAMES[self.integrated_columns] if self.integrals else ()
        history = tuple(
            f"{error}_past{k}" for k in range(1, self.history_steps + 1) for error in HISTORY_ERRORS
        )
        return (*OBS_NAMES, *EXTRA_HEAD, *preview, *integrals, *history)

    @property
    def units(self) -> dict[str, str]:
        """Unit of every entry, by name."""
        extra = {
            "u_ground": "m/s",
            "v_ground": "m/s",
            "w_ground": "m/s",
            "a_X_prev": "-",
            "a_M_prev": "-",
            "a_N_prev": "-",
        }
        units = {"x": "m", "y": "m", "z": "m", "curvature": "1/m", "torsion": "1/m"}
        for name in self.names[OBS_DIM + len(EXTRA_HEAD) :]:
            if name in INTEGRAL_NAMES:
                extra[name] = "m·s"
            elif _history_error(name) is not None:
                extra[name] = "m"
            else:
                extra[name] = units[name.split("_", 1)[1]]
        return {**OBS_UNITS, **(extra if self.kind != "paper" else {})}

    def bounds(
        self, current_speed: float = 0.0, speed_bound: float = SPEED_BOUND
    ) -> tuple[np.ndarray, np.ndarray]:
        """(low, high) float32 arrays of the observation space; ``current_speed`` [m/s] is the
        largest current the configuration can draw (`SimConfig.current_speed_bound`),
        ``speed_bound`` [m/s] the vehicle's (`vehicle_speed_bound`)."""
        low, high = paper_bounds(speed_bound)
        if self.kind == "paper":
            return low, high
        ground = _GROUND_MARGIN * (speed_bound + max(_GROUND_CURRENT, current_speed))
        reach = math.sqrt(3.0) * ERROR_BOUND + PREVIEW_MARGIN * self.points * self.spacing
        point = (reach, reach, reach, CURVATURE_BOUND, CURVATURE_BOUND)
        largest = ERROR_BOUND * self.integral_time  # |e| ≤ 500 m: |I| ≤ 500 T
        if self.integral_limit > 0.0:
            largest = min(largest, self.integral_limit)
        integral = (largest,) * self.integrals
        history = (ERROR_BOUND,) * self.history  # past values of bounded entries
        extra = np.array([*(ground,) * 3, 1.0, 1.0, 1.0, *point * self.points, *integral, *history])
        return (
            np.concatenate([low, -extra.astype(np.float32)]),
            np.concatenate([high, extra.astype(np.float32)]),
        )
