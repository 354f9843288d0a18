"""Sensor and navigation settings (docs/model.md §14): what the observation is measured with.

`SensorConfig` holds the error model of each sensor of a REMUS-class navigation suite: a Doppler
velocity log (DVL: white noise, a turn-on bias and scale-factor error per episode, dropout), an
attitude and heading reference (AHRS: pitch, heading and the rates q, r, each with white noise
and a turn-on bias), a pressure depth sensor (noise, bias), the horizontal position from dead
reckoning on the DVL and AHRS reset by a position fix (USBL, or GPS at the surface) every
`fix_interval` seconds, and a delay of whole control steps. The kernels that apply it live in
`auv_gym.sim.navigation`; the reward, termination and metrics keep reading the true state.

The horizontal position is dead reckoning reset by each fix (``navigation="dead_reckoning"``),
or a Kalman filter over the same measurements (``navigation="kalman"``, docs/model.md §14.8)
that blends each fix into the dead-reckoned track and estimates the track's velocity error.

The virtual point (the path point the errors are measured from) moves with the true along-track
error by default, as part of the plant (``virtual_point="true"``); ``virtual_point="estimate"``
advances it as a vehicle's guidance computer would, from the estimated one (docs/model.md §14.9).

Presets (`SENSOR_PRESETS`): "ideal" (no sensor model: the observation is the exact state, the
default), "typical" (values and their sources in docs/model.md §14.3) and "typical_kalman"
(the same suite with the navigation filter). A dict of fields, or {"preset": name,
**overrides}, sets them one by one.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields, replace

import numpy as np

from auv_gym.support.validation import (
    ArgumentTypeError,
    choice,
    integer,
    keys_within,
    real,
    whole_steps,
)

__all__ = [
    "SENSOR_FIELDS",
    "SENSOR_PRESETS",
    "VIRTUAL_POINT_SOURCES",
    "SensorConfig",
    "sensor_key",
]

# Documented ranges: far beyond any real sensor, so only nonsense is refused.
MAX_SPEED_ERROR = 1.0  # [m/s] DVL noise and bias σ
MAX_SCALE_ERROR = 0.5  # [-] DVL scale-factor σ
MAX_ANGLE_ERROR = 0.5  # [rad] pitch and heading noise and bias σ (29°)
MAX_RATE_ERROR = 0.5  # [rad/s] q, r noise and bias σ
MAX_DEPTH_ERROR = 10.0  # [m] depth noise and bias σ
MAX_FIX_NOISE = 100.0  # [m] position-fix σ per horizontal axis
MAX_FIX_INTERVAL = 1e6  # [s]
MAX_DELAY = 1000  # [control steps]
MAX_DROPOUT = 0.99  # [-] probability that a DVL sample is lost
PRESET_NAMES = ("ideal", "typical", "typical_kalman")
NAVIGATION_MODES = ("dead_reckoning", "kalman")
# What moves the virtual point (docs/model.md §14.9): the plant's law at the true along-track
# error, or a guidance computer's at the estimated one, held over each control period.
VIRTUAL_POINT_SOURCES = ("true", "estimate")
MAX_FILTER_NOISE = 10.0  # [m/s, 1/√s, -, rad] the filter's assumed errors
# The smallest filter setting and, with the filter, position-fix σ [m/s, 1/√s, -, rad, m]: the
# filter's covariance holds their squares and the fix update divides by a product of two, so
# they must stay far from float64's underflow (all five at 1e-100: 1e-400 rounds to 0, and the
# first fix divided by zero; docs/model.md §14.8). 1e-6 is far below any real sensor.
MIN_FILTER_NOISE = 1e-6
# The filter's bias model when not given (docs/model.md §14.8): the scale and heading errors
# are constant in the sensor model; a random walk of 3e-4 /√s (1° over an hour) keeps the
# filter from locking onto its first estimate, and floors of 0.1 % and 0.1° keep P₀ positive
# definite for sensors without those biases.
DEFAULT_BIAS_NOISE = 3e-4  # [1/√s]
MIN_INITIAL_SCALE = 0.001  # [-]
MIN_INITIAL_HEADING = 0.1 * math.pi / 180.0  # [rad]


@dataclass(frozen=True)
class SensorConfig:
    """Error model of the navigation suite; every σ is a standard deviation, every bias the σ of
    a constant drawn per episode (a turn-on bias), all 0 by default (exact sensors).

    Measurements at each control step t (docs/model.md §14.1), n ~ N(0, 1) drawn per sample:
    DVL ν̂ = (1 + k)ν + b + σ n per axis (k, b drawn per episode); AHRS θ̂ = θ + b + σ n,
    ψ̂ = ψ + b + σ n, q̂, r̂ likewise; depth ẑ = z + b + σ n; horizontal position from a fix
    p̂ = p + σ_fix n every `fix_interval` [s] (0: every control step), else dead reckoning.
    """

    dvl_noise: float = 0.0  # [m/s] σ of each velocity sample, per axis
    dvl_bias: float = 0.0  # [m/s] σ of the per-episode velocity offset, per axis
    dvl_scale: float = 0.0  # [-] σ of the per-episode scale-factor error, per axis
    dvl_dropout: float = 0.0  # [-] probability a sample is lost (the last valid one is held)
    pitch_noise: float = 0.0  # [rad]
    pitch_bias: float = 0.0  # [rad]
    heading_noise: float = 0.0  # [rad]
    heading_bias: float = 0.0  # [rad]
    rate_noise: float = 0.0  # [rad/s] σ of q̂ and r̂ samples
    rate_bias: float = 0.0  # [rad/s]
    depth_noise: float = 0.0  # [m]
    depth_bias: float = 0.0  # [m]
    fix_noise: float = 0.0  # [m] σ of a position fix, per horizontal axis
    fix_interval: float | None = 0.0  # [s] between fixes; 0: every step; None: start fix only
    delay: int = 0  # [control steps] k: the observation uses the measurements of step t − k
    navigation: str = "dead_reckoning"  # or "kalman": the position filter of §14.8
    virtual_point: str = "true"  # or "estimate": advanced from the estimated x_e (§14.9)
    # The filter's model (None: derived from the errors above, docs/model.md §14.8): σ of the
    # measured horizontal velocity per sample [m/s], the random-walk density of the scale and
    # heading errors it estimates [1/√s, rad/√s] and their initial σ [-], [rad].
    filter_velocity_noise: float | None = None
    filter_bias_noise: float | None = None
    filter_initial_scale: float | None = None
    filter_initial_heading: float | None = None
    preset: str = "custom"  # the name it was built from ("ideal" bypasses the sensor model)

    def __post_init__(self) -> None:
        ranges = {
            "dvl_noise": (MAX_SPEED_ERROR, "m/s"),
            "dvl_bias": (MAX_SPEED_ERROR, "m/s"),
            "dvl_scale": (MAX_SCALE_ERROR, ""),
            "dvl_dropout": (MAX_DROPOUT, ""),
            "pitch_noise": (MAX_ANGLE_ERROR, "rad"),
            "pitch_bias": (MAX_ANGLE_ERROR, "rad"),
            "heading_noise": (MAX_ANGLE_ERROR, "rad"),
            "heading_bias": (MAX_ANGLE_ERROR, "rad"),
            "rate_noise": (MAX_RATE_ERROR, "rad/s"),
            "rate_bias": (MAX_RATE_ERROR, "rad/s"),
            "depth_noise": (MAX_DEPTH_ERROR, "m"),
            "depth_bias": (MAX_DEPTH_ERROR, "m"),
            "fix_noise": (MAX_FIX_NOISE, "m"),
        }
        for name, (high, unit) in ranges.items():
            value = real(f"sensors {name}", getattr(self, name), 0.0, high, unit=unit)
            object.__setattr__(self, name, value)
        if self.fix_interval is not None:
            unit = "s (0: a fix every control step; None: dead reckoning)"
            interval = real(
                "sensors fix_interval", self.fix_interval, 0.0, MAX_FIX_INTERVAL, unit=unit
            )
            object.__setattr__(self, "fix_interval", interval)
        object.__setattr__(self, "delay", integer("sensors delay", self.delay, 0, MAX_DELAY))
        choice("sensors preset", self.preset, [*PRESET_NAMES, "custom"])
        choice("sensors navigation", self.navigation, NAVIGATION_MODES)
        choice("sensors virtual_point", self.virtual_point, VIRTUAL_POINT_SOURCES)
        for name, unit in (
            ("filter_velocity_noise", "m/s"),
            ("filter_bias_noise", "1/√s"),
            ("filter_initial_scale", ""),
            ("filter_initial_heading", "rad"),
        ):
            value = getattr(self, name)
            if value is None:
                continue
            if self.navigation != "kalman":
                raise ValueError(
                    f"sensors {name} sets the model of the navigation filter; with navigation="
                    f"{self.navigation!r} there is no filter and it would do nothing: drop it "
                    "or give navigation='kalman'"
                )
            if not isinstance(value, bool) and isinstance(value, int | float) and value <= 0.0:
                raise ValueError(
                    f"sensors {name} = {value!r} {unit} makes the navigation filter's "
                    "covariance not positive definite: give a value > 0 (or None to derive it)"
                )
            checked = real(f"sensors {name}", value, MIN_FILTER_NOISE, MAX_FILTER_NOISE, unit=unit)
            object.__setattr__(self, name, checked)
        if self.navigation == "kalman" and not (self.fix_noise > 0.0 and self.fix_interval):
            raise ValueError(
                "sensors navigation = 'kalman' blends position fixes into dead reckoning: it "
                "needs a sensor model with fix_noise > 0 and a fix_interval > 0 (the preset "
                "'typical_kalman' has them)"
            )
        if self.navigation == "kalman" and self.fix_noise < MIN_FILTER_NOISE:
            raise ValueError(
                f"sensors fix_noise = {self.fix_noise!r} m is below {MIN_FILTER_NOISE:g} m, "
                "the smallest fix error the navigation filter can divide by (its square and "
                "their product would underflow): give fix_noise >= "
                f"{MIN_FILTER_NOISE:g} m with navigation='kalman'"
            )
        if self.preset == "ideal" and replace(self, preset="custom") != SensorConfig():
            raise ValueError(
                "sensors preset 'ideal' means exact sensors: give its errors with "
                "preset='custom' (or a dict {'preset': 'ideal', ...})"
            )

    @property
    def ideal(self) -> bool:
        """True for the "ideal" preset: the observation is the exact state (no sensor kernel)."""
        return self.preset == "ideal"

    @property
    def guidance_from_estimate(self) -> bool:
        """Whether a guidance computer advances the virtual point from the estimated x_e."""
        return self.virtual_point == "estimate"

    @classmethod
    def from_spec(cls, spec: str | Mapping | SensorConfig | None) -> SensorConfig:
        """From None or a preset name, a dict of fields (optionally with "preset": the name
        whose values the others override) or a `SensorConfig`."""
        if spec is None:
            return SENSOR_PRESETS["ideal"]
        if isinstance(spec, SensorConfig):
            return spec
        if isinstance(spec, str):
            return SENSOR_PRESETS[choice("sensors preset", spec, SENSOR_PRESETS)]
        if isinstance(spec, Mapping):
            names = [f.name for f in fields(cls)]
            given = keys_within("sensors", spec, names)
            base = SENSOR_PRESETS[
                choice("sensors preset", given.pop("preset", "ideal"), SENSOR_PRESETS)
            ]
            return replace(base, **given, preset="custom") if given else base
        raise ArgumentTypeError(
            f"sensors must be None, one of {sorted(SENSOR_PRESETS)}, a dict of SensorConfig "
            f"fields or a SensorConfig, got {spec!r:.80}"
        )

    def to_dict(self) -> dict:
        """The fields as a JSON-ready dict."""
        return asdict(self)

    def fix_steps(self, control_dt: float) -> int:
        """Control steps between position fixes: 1 for `fix_interval` = 0, 0 for none; a
        ValueError unless the interval is a whole multiple of control_dt."""
        if self.fix_interval is None:
            return 0
        if self.fix_interval == 0.0:
            return 1
        return whole_steps("sensors fix_interval", self.fix_interval, control_dt, "control_dt")

    def filter_model(self, speed: float) -> tuple[float, float, float, float]:
        """The navigation filter's (velocity noise σ_v [m/s], bias noise q [1/√s], initial
        scale error σ_k0 [-], initial heading error σ_β0 [rad]) at the cruising ``speed``
        [m/s]: the given values, else σ_v from the DVL and heading noise, σ_k0 and σ_β0 from
        the DVL scale factor and the AHRS heading bias (docs/model.md §14.8)."""
        velocity = self.filter_velocity_noise
        if velocity is None:
            velocity = math.hypot(self.dvl_noise, self.heading_noise * speed)
        bias = DEFAULT_BIAS_NOISE if self.filter_bias_noise is None else self.filter_bias_noise
        scale = self.filter_initial_scale
        if scale is None:
            scale = max(math.hypot(self.dvl_scale, self.dvl_bias / speed), MIN_INITIAL_SCALE)
        heading = self.filter_initial_heading
        if heading is None:
            heading = max(math.hypot(self.heading_bias, self.dvl_bias / speed), MIN_INITIAL_HEADING)
        return velocity, bias, scale, heading

    def packed(self, control_dt: float, speed: float = 1.0) -> np.ndarray:
        """The float64 row `navigation.sense_rows` reads (layout `SENSOR_FIELDS`); ``speed``
        [m/s] sizes the filter's model (`filter_model`)."""
        values = {f.name: getattr(self, f.name) for f in fields(self) if f.name in SENSOR_FIELDS}
        values["fix_steps"] = self.fix_steps(control_dt)
        values["delay"] = self.delay
        values["control_dt"] = control_dt
        velocity, bias, scale, heading = self.filter_model(speed)
        values["kalman"] = 1.0 if self.navigation == "kalman" else 0.0
        values["guidance_estimate"] = 1.0 if self.guidance_from_estimate else 0.0
        values["q_position"] = (velocity * control_dt) ** 2  # [m²] per control step
        values["q_bias"] = bias * bias * control_dt  # [-, rad²] per control step
        values["p0_scale"] = scale * scale
        values["p0_heading"] = heading * heading
        return np.array([float(values[name]) for name in SENSOR_FIELDS])


# Layout of `SensorConfig.packed`.
SENSOR_FIELDS = (
    "dvl_noise",
    "dvl_bias",
    "dvl_scale",
    "dvl_dropout",
    "pitch_noise",
    "pitch_bias",
    "heading_noise",
    "heading_bias",
    "rate_noise",
    "rate_bias",
    "depth_noise",
    "depth_bias",
    "fix_noise",
    "fix_steps",
    "delay",
    "control_dt",
    "kalman",
    "q_position",
    "q_bias",
    "p0_scale",
    "p0_heading",
    "guidance_estimate",
)

_DEG = math.pi / 180.0
SENSOR_PRESETS: dict[str, SensorConfig] = {
    "ideal": SensorConfig(preset="ideal"),
    # A REMUS-class suite; each value's source is in docs/model.md §14.3.
    "typical": SensorConfig(
        dvl_noise=0.01,  # [m/s] single-ping σ, 1200 kHz bottom track at ~1 m/s
        dvl_bias=0.002,  # [m/s] "±0.2 % ± 2 mm/s": the offset part
        dvl_scale=0.003,  # [-] the proportional part (0.2-0.3 % of v)
        dvl_dropout=0.02,  # [-] lost bottom lock on 2 % of the pings
        pitch_noise=0.05 * _DEG,
        pitch_bias=0.3 * _DEG,  # AHRS roll/pitch accuracy 0.2-0.3° (dynamic)
        heading_noise=0.1 * _DEG,
        heading_bias=1.0 * _DEG,  # AHRS magnetic heading accuracy 1°
        rate_noise=0.03 * _DEG,  # [rad/s] 0.01 °/s/√Hz over a 10 Hz band
        rate_bias=10.0 / 3600.0 * _DEG,  # [rad/s] in-run bias stability 10 °/h
        depth_noise=0.01,  # [m]
        depth_bias=0.05,  # [m] 0.05 % of a 100 m full scale
        fix_noise=0.5,  # [m] USBL, ~0.5 % of a 100 m slant range
        fix_interval=10.0,  # [s] one USBL fix every 10 s
        delay=0,
        preset="typical",
    ),
}
SENSOR_PRESETS["typical_kalman"] = replace(
    SENSOR_PRESETS["typical"], navigation="kalman", preset="typical_kalman"
)

_SALT = np.uint64(0x5E4507A7105E4507)  # separates the sensor streams from the disturbance ones
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)


def sensor_key(noise_key: np.uint64 | np.ndarray, stream: int) -> np.ndarray:
    """The episode's sensor key number ``stream`` (0: per-sample errors, 1: per-episode
    biases), derived from its white-noise key by SplitMix64 mixing: a new key per episode that
    draws nothing from the episode generator, so every existing configuration's draws stay the
    same, and that depends on the seed only, never on the actions."""
    with np.errstate(over="ignore"):
        z = np.asarray(noise_key, dtype=np.uint64) ^ _SALT
        z = z + (np.uint64(stream) + np.uint64(1)) * _GOLDEN
        z = (z ^ (z >> np.uint64(30))) * _MIX1
        z = (z ^ (z >> np.uint64(27))) * _MIX2
        return z ^ (z >> np.uint64(31))
