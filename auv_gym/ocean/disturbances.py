"""Disturbances (docs/model.md §2.5): bounded white noise, ocean current, parameter uncertainty.

Randomness inside the simulation is counter-based: every noise value is a pure function of an
episode key (drawn once from the reset seed) and the index of the physics step it belongs to
(SplitMix64, Steele, Lea & Flood, OOPSLA 2014). So the whole disturbance sequence of an episode
depends on the seed only, never on the actions, and a batched simulation reproduces a single one
without sharing generator state.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, fields

import numpy as np
from numba import njit

from auv_gym.support.records import field_indices
from auv_gym.support.validation import ArgumentTypeError, is_real, keys_within, real, vector

__all__ = [
    "KEY",
    "N_CHANNELS",
    "CurrentConfig",
    "NoiseConfig",
    "draw_keys",
    "gauss_markov_coefficients",
    "gauss_markov_step",
    "white_noise",
]

N_CHANNELS = 5  # white-noise channels f_u, f_v, f_w, f_q, f_r
# The two 64-bit keys of an episode (`draw_keys`), one per random stream.
KEY = field_indices("KeyIndex", ("noise", "current"), __name__)

# Documented ranges (AUVPath3DEnv docstring, "Arguments").
MAX_NOISE_AMPLITUDE = 1e4  # [N, N·m] 200× the thrust limit
MAX_NOISE_HOLD = 1e6  # [s]
MAX_CURRENT_SPEED = 10.0  # [m/s] per axis, mean and std; ocean currents stay below 3 m/s
MAX_CURRENT_TIME_CONSTANT = 1e6  # [s]
DEFAULT_CURRENT_TIME_CONSTANT = 60.0  # [s]

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)
_TWO_M53 = 2.0**-53


@njit(cache=True, inline="always")
def uniform01(key, counter):
    """A uniform number in [0, 1) from (key, counter): SplitMix64's output function."""
    z = key + (np.uint64(counter) + np.uint64(1)) * _GOLDEN
    z = (z ^ (z >> _S30)) * _MIX1
    z = (z ^ (z >> _S27)) * _MIX2
    z = z ^ (z >> _S31)
    return float(z >> _S11) * _TWO_M53


@njit(cache=True, inline="always")
def standard_normal(key, counter):
    """A standard normal number from (key, counter) by Box-Muller on two counter draws."""
    u1 = 1.0 - uniform01(key, 2 * counter)  # (0, 1], safe for log
    u2 = uniform01(key, 2 * counter + 1)
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


@njit(cache=True, inline="always")
def _bounded_noise(amplitude, key, counter):
    """A·(2U − 1), U = uniform01(key, counter) [N or N·m]."""
    return amplitude * (2.0 * uniform01(key, counter) - 1.0)


@njit(cache=True, inline="always")
def white_noise(amplitude, key, step, hold_steps):
    """The five channels f = A ⊙ (2U − 1) at physics step ``step`` [N, N, N, N·m, N·m].

    Channel c draws U = uniform01(key, 5·(step // hold_steps) + c): each value is held for
    ``hold_steps`` physics steps and depends on the key and the time only.
    """
    block = (step // hold_steps) * N_CHANNELS
    return (
        _bounded_noise(amplitude[0], key, block),
        _bounded_noise(amplitude[1], key, block + 1),
        _bounded_noise(amplitude[2], key, block + 2),
        _bounded_noise(amplitude[3], key, block + 3),
        _bounded_noise(amplitude[4], key, block + 4),
    )


@njit(cache=True, inline="always")
def _gauss_markov_axis(deviation, a, b, key, counter):
    if b == 0.0:  # no random current: skip the ~25 ns normal draw
        return a * deviation
    return a * deviation + b * standard_normal(key, counter)


@njit(cache=True, inline="always")
def gauss_markov_step(deviation, a, b, key, step):
    """One exact step δ ← a·δ + b ⊙ N(0, 1) of the current deviation (x, y, z) [m/s].

    ``a``, ``b`` from `gauss_markov_coefficients`; axis j at physics step n draws its normal
    number at counter 3n + j of ``key``.
    """
    counter = 3 * step
    return (
        _gauss_markov_axis(deviation[0], a, b[0], key, counter),
        _gauss_markov_axis(deviation[1], a, b[1], key, counter + 1),
        _gauss_markov_axis(deviation[2], a, b[2], key, counter + 2),
    )


@dataclass(frozen=True)
class NoiseConfig:
    """Bounded white noise f_i = A_i·U(−1, 1) on (f_u, f_v, f_w, f_q, f_r), held `hold` seconds.

    Amplitudes in [N, N, N, N·m, N·m]; the paper uses 35 on every channel. The equivalent
    spectral density is A²·hold/3, so the hold time is part of the model
    (docs/model.md §2.5, §10.1).
    """

    amplitude: tuple[float, float, float, float, float] = (35.0,) * 5
    hold: float = 0.01  # [s]

    def __post_init__(self) -> None:
        # One amplitude stands for all five channels.
        amplitude = (self.amplitude,) * 5 if is_real(self.amplitude) else self.amplitude
        amp = vector("NoiseConfig.amplitude", amplitude, 5, 0.0, MAX_NOISE_AMPLITUDE, "N or N·m")
        hold = real("NoiseConfig.hold", self.hold, 0.0, MAX_NOISE_HOLD, low_open=True, unit="s")
        object.__setattr__(self, "amplitude", amp)
        object.__setattr__(self, "hold", hold)


@dataclass(frozen=True)
class CurrentConfig:
    """Ocean current: constant earth-frame mean plus optional first-order Gauss–Markov part.

    v_c(t) = mean + δ(t),  δ̇ = −δ/τ + w, with stationary standard deviation `std` per axis
    (Fossen 2011, §8.3), discretised exactly at the physics step. The current enters through the
    relative velocity: the vehicle's state is its velocity through the water and its kinematics
    add v_c, which is exact for a current that is constant in the earth frame.
    """

    mean: tuple[float, float, float] = (0.0, 0.0, 0.0)  # [m/s] NED
    std: tuple[float, float, float] = (0.0, 0.0, 0.0)  # [m/s] stationary std of δ per axis
    time_constant: float = DEFAULT_CURRENT_TIME_CONSTANT  # [s] τ of the Gauss–Markov process

    def __post_init__(self) -> None:
        limit = MAX_CURRENT_SPEED
        object.__setattr__(self, "mean", vector("current mean", self.mean, 3, -limit, limit, "m/s"))
        object.__setattr__(self, "std", vector("current std", self.std, 3, 0.0, limit, "m/s"))
        tau = real(
            "current time_constant",
            self.time_constant,
            0.0,
            MAX_CURRENT_TIME_CONSTANT,
            low_open=True,
            unit="s",
        )
        object.__setattr__(self, "time_constant", tau)

    @classmethod
    def from_spec(cls, spec: CurrentConfig | Sequence[float] | dict | None) -> CurrentConfig:
        """Build from None (no current), a 3-vector mean [m/s], a dict of fields, or itself.
        A dict's time_constant other than the default 60 s is refused without a Gauss–Markov
        part (std 0 on every axis), where it does nothing."""
        if spec is None:
            return cls()
        if isinstance(spec, CurrentConfig):
            return spec
        if isinstance(spec, Mapping):
            given = keys_within("current", spec, [f.name for f in fields(cls)])
            config = cls(**given)
            default = DEFAULT_CURRENT_TIME_CONSTANT
            if not any(config.std) and config.time_constant != default:
                raise ValueError(
                    f"current time_constant = {given['time_constant']!r} s does nothing without "
                    "a Gauss–Markov current (std = 0 on every axis): give a std > 0 or leave "
                    "time_constant out"
                )
            return config
        if isinstance(spec, (str, bytes)) or not isinstance(spec, Iterable):
            raise ArgumentTypeError(
                f"current must be None, a 3-vector mean [m/s], a dict of CurrentConfig fields or "
                f"a CurrentConfig, got {spec!r:.80}"
            )
        return cls(mean=spec)


def gauss_markov_coefficients(config: CurrentConfig, dt: float) -> tuple[float, np.ndarray]:
    """Exact discretisation δ_{k+1} = a δ_k + b ⊙ n_k of the Gauss–Markov current over dt [s]."""
    a = math.exp(-dt / config.time_constant)
    b = np.asarray(config.std) * math.sqrt(1.0 - a * a)
    return a, b


def draw_keys(rng: np.random.Generator) -> tuple[np.uint64, np.uint64]:
    """Two independent 64-bit episode keys (white noise, current) from the episode generator."""
    keys = rng.integers(0, 2**63, size=2, dtype=np.int64).astype(np.uint64)
    return keys[0], keys[1]
