r"""Ocean waves: a seeded linear (Airy) deep-water wave field (docs/model.md §13).

The sea surface is the plane z = 0 of the NED frame; depth below it is d = z [m], positive down.
A field of N regular components i (amplitude a_i, frequency ω_i, direction of travel β_i,
phase φ_i) with the deep-water dispersion relation ω² = g k gives at (x, y, d) and time t

    ζ   = Σ a_i cos θ_i,                 θ_i = k_i (x cos β_i + y sin β_i) − ω_i t + φ_i
    v_h = Σ a_i ω_i e^{−k_i d} cos θ_i   (horizontal, along β_i)
    v_z = −Σ a_i ω_i e^{−k_i d} sin θ_i  (NED: positive down)

and the local accelerations ∂v/∂t (Faltinsen 1990, Table 2.1; DNV-RP-C205, section 3.2). The
components are drawn per episode (`draw_components`) from a JONSWAP or Pierson–Moskowitz
spectrum in H_s and T_p with cos-2s directional spreading; `wave_kinematics` evaluates the
field in the compiled kernels.
"""

from __future__ import annotations

import functools
import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass, fields

import numpy as np
from numba import njit

from auv_gym.support.records import field_indices
from auv_gym.support.validation import ArgumentTypeError, choice, integer, keys_within, real

__all__ = [
    "COMPONENT",
    "COMPONENT_DIM",
    "GRAVITY",
    "SEA_STATES",
    "SPECTRA",
    "WaveConfig",
    "draw_components",
    "spectral_density",
    "surface_elevation",
    "wave_kinematics",
]

GRAVITY = 9.81  # [m/s²]
SPECTRA = ("jonswap", "pierson_moskowitz")
# WMO sea-state code → (H_s [m], T_p [s]): the mean significant height and most probable modal
# period of the open North Atlantic for codes 3-5 (Bales, Lee & Voelker 1981, NATO standardized
# wave and wind environments; docs/model.md §13.2); each H_s lies inside the WMO code's band
# (3: 0.5-1.25 m, 4: 1.25-2.5 m, 5: 2.5-4 m).
SEA_STATES = {3: (0.88, 7.5), 4: (1.88, 8.8), 5: (3.25, 9.7)}
DEFAULT_COMPONENTS = 32  # docs/model.md §13.2: Hs, Tp within 5 %, ≥ 50 % of the no-wave speed
MAX_COMPONENTS = 1024
DEFAULT_GAMMA = 3.3  # JONSWAP's peak enhancement; Pierson–Moskowitz has none
MAX_HEIGHT = 30.0  # [m] beyond any recorded sea
# Miche's limit for a deep-water wave, H/L ≤ 1/7, held by the significant height at the peak
# wavelength: steeper seas break (docs/model.md §13); every sea state of `SEA_STATES` is far below.
MAX_STEEPNESS = 1.0 / 7.0


def peak_wavelength(peak_period: float) -> float:
    """Deep-water wavelength L = g·T²/(2π) [m] of waves of period ``peak_period`` [s]."""
    return GRAVITY * peak_period**2 / (2.0 * math.pi)


PERIOD_RANGE = (1.0, 30.0)  # [s] wind sea and swell
MAX_SPREADING = 1000.0  # s of cos-2s; 1000 is long-crested within ±3°
# The discretised band [0.5, 3] ω_p holds all but ~1.5 % of the PM energy (renormalised).
BAND = (0.5, 3.0)

# Columns of one component in a vehicle's ocean row: wavenumber vector, |k|, ω, phase, the
# velocity amplitude a·ω and the direction cosines.
COMPONENT_FIELDS = ("kx", "ky", "k", "omega", "phase", "a_omega", "cos_beta", "sin_beta")
COMPONENT_DIM = len(COMPONENT_FIELDS)
COMPONENT = field_indices("ComponentIndex", COMPONENT_FIELDS, __name__)


def spectral_density(
    omega: np.ndarray, height: float, period: float, spectrum: str, gamma: float = 3.3
) -> np.ndarray:
    """One-sided wave spectrum S(ω) [m²·s/rad] (DNV-RP-C205, section 3.5.5):

    Pierson–Moskowitz  S_PM(ω) = 5/16 H_s² ω_p⁴ ω⁻⁵ exp(−5/4 (ω_p/ω)⁴),  ω_p = 2π/T_p
    JONSWAP            S_J(ω) = (1 − 0.287 ln γ) S_PM(ω) γ^exp(−(ω − ω_p)²/(2 σ² ω_p²)),
                       σ = 0.07 for ω ≤ ω_p, 0.09 above.
    """
    omega = np.asarray(omega, dtype=float)
    wp = 2.0 * math.pi / period
    pm = 5.0 / 16.0 * height**2 * wp**4 * omega**-5.0 * np.exp(-1.25 * (wp / omega) ** 4)
    if spectrum == "pierson_moskowitz":
        return pm
    sigma = np.where(omega <= wp, 0.07, 0.09)
    peak = gamma ** np.exp(-((omega - wp) ** 2) / (2.0 * sigma**2 * wp**2))
    return (1.0 - 0.287 * math.log(gamma)) * pm * peak


@functools.lru_cache(maxsize=16)
def _frequency_quantiles(spectrum: str, gamma: float) -> tuple[np.ndarray, np.ndarray]:
    """(ω/ω_p, cumulative energy fraction) on the band: the inverse CDF's table."""
    x = np.linspace(*BAND, 4001)
    density = spectral_density(x, 1.0, 2.0 * math.pi, spectrum, gamma)  # ω_p = 1 rad/s
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (density[1:] + density[:-1]) * np.diff(x))])
    return x, cdf / cdf[-1]


@functools.lru_cache(maxsize=16)
def _direction_quantiles(spreading: float) -> tuple[np.ndarray, np.ndarray]:
    """(β − β₀, cumulative fraction) of D(β) ∝ cos^{2s}((β − β₀)/2) on [−π, π]."""
    x = np.linspace(-math.pi, math.pi, 4001)
    density = np.cos(0.5 * x) ** (2.0 * spreading)
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (density[1:] + density[:-1]) * np.diff(x))])
    return x, cdf / cdf[-1]


@dataclass(frozen=True)
class WaveConfig:
    """A short-crested irregular sea: spectrum, height, period, spreading and resolution.

    ``direction`` is the mean direction the waves travel toward, from x (north) toward y
    (east) [rad]; ``spreading`` the s of D(β) ∝ cos^{2s}((β − β₀)/2) (Longuet-Higgins et al.
    1963; Goda 2000: s ≈ 10 for wind waves, 25-75 for swell; 0 is isotropic).
    ``update_interval`` is how often the kernels re-evaluate the field at the vehicle's
    position; in between they extrapolate it with its acceleration (docs/model.md §13.3).
    """

    significant_height: float = SEA_STATES[4][0]  # [m] H_s = 4 √m₀
    peak_period: float = SEA_STATES[4][1]  # [s] T_p
    spectrum: str = "jonswap"  # "jonswap" or "pierson_moskowitz"
    gamma: float = DEFAULT_GAMMA  # JONSWAP peak enhancement factor γ (DNV-RP-C205: 1 to 7)
    components: int = DEFAULT_COMPONENTS  # N
    spreading: float = 10.0  # s of cos-2s spreading
    direction: float = 0.0  # [rad] mean direction of travel β₀
    update_interval: float = 0.05  # [s]

    def __post_init__(self) -> None:
        def put(name: str, value: object) -> None:
            object.__setattr__(self, name, value)

        put(
            "significant_height",
            real(
                "waves significant_height",
                self.significant_height,
                0.0,
                MAX_HEIGHT,
                low_open=True,
                unit="m",
            ),
        )
        put("peak_period", real("waves peak_period", self.peak_period, *PERIOD_RANGE, unit="s"))
        put("spectrum", choice("waves spectrum", self.spectrum, SPECTRA))
        put("gamma", real("waves gamma", self.gamma, 1.0, 7.0))
        if self.spectrum == "pierson_moskowitz" and self.gamma != DEFAULT_GAMMA:
            _gamma_without_jonswap(self.gamma)
        put("components", integer("waves components", self.components, 1, MAX_COMPONENTS))
        put("spreading", real("waves spreading", self.spreading, 0.0, MAX_SPREADING))
        put(
            "direction",
            real("waves direction", self.direction, -2 * math.pi, 2 * math.pi, unit="rad"),
        )
        put(
            "update_interval",
            real("waves update_interval", self.update_interval, 0.0, 1.0, low_open=True, unit="s"),
        )
        steepness = self.significant_height / peak_wavelength(self.peak_period)
        if steepness > MAX_STEEPNESS:
            lowest = math.sqrt(2.0 * math.pi * self.significant_height / (GRAVITY * MAX_STEEPNESS))
            raise ValueError(
                f"waves: significant_height {self.significant_height:g} m at peak_period "
                f"{self.peak_period:g} s is {steepness / MAX_STEEPNESS:.3g}× the breaking "
                f"steepness H/L = 1/7 (L = g·T_p²/2π = {peak_wavelength(self.peak_period):.3g} "
                f"m): such a sea breaks; give peak_period ≥ {lowest:.3g} s or a lower height"
            )

    @classmethod
    def from_spec(cls, spec: WaveConfig | str | int | Mapping | None) -> WaveConfig | None:
        """None (no waves), a sea state ("sea_state_4" or 4: `SEA_STATES`), a dict of fields
        (with an optional "sea_state" key for the height and period; a significant_height or
        peak_period given with it replaces the sea state's), or itself. A "gamma" key with
        spectrum "pierson_moskowitz" is refused (it shapes JONSWAP only), even at 3.3."""
        if spec is None or isinstance(spec, WaveConfig):
            return spec
        if isinstance(spec, Mapping):
            names = [f.name for f in fields(cls)]
            given = keys_within("waves", spec, [*names, "sea_state"])
            if "sea_state" in given:
                height, period = _sea_state(given.pop("sea_state"))
                given = {"significant_height": height, "peak_period": period, **given}
            config = cls(**given)
            if "gamma" in given and config.spectrum == "pierson_moskowitz":
                _gamma_without_jonswap(given["gamma"])
            return config
        if isinstance(spec, (str, numbers.Integral)) and not isinstance(spec, bool):
            height, period = _sea_state(spec)
            return cls(significant_height=height, peak_period=period)
        raise ArgumentTypeError(
            f"waves must be None, a sea state {_PRESETS}, a dict of "
            f"WaveConfig fields or a WaveConfig, got {spec!r:.80}"
        )


_PRESETS = sorted(f"sea_state_{code}" for code in SEA_STATES)


def _gamma_without_jonswap(gamma: object) -> None:
    raise ValueError(
        f"waves gamma = {gamma!r} does nothing with spectrum 'pierson_moskowitz' (γ is "
        "JONSWAP's peak enhancement): leave gamma out or give spectrum 'jonswap'"
    )


def _sea_state(name: object) -> tuple[float, float]:
    """(H_s [m], T_p [s]) of a sea state's name or integer code; a float such as 4.0 is
    refused, as everywhere an integer belongs (`support.validation.integer`)."""
    if isinstance(name, str):
        code = int(name[10:]) if name.startswith("sea_state_") and name[10:].isdigit() else -1
    elif isinstance(name, numbers.Integral) and not isinstance(name, bool):
        code = int(name)
    else:
        raise ArgumentTypeError(
            f"waves sea_state must be a sea state {_PRESETS} or its integer code "
            f"{sorted(SEA_STATES)}, got {name!r:.80} ({type(name).__name__})"
        )
    if code not in SEA_STATES:
        raise ValueError(
            f"unknown waves sea state {name!r}; valid: {_PRESETS} or {sorted(SEA_STATES)}"
        )
    return SEA_STATES[code]


def draw_components(config: WaveConfig, rng: np.random.Generator) -> np.ndarray:
    """An episode's N components, shape (N, COMPONENT_DIM) (layout `COMPONENT_FIELDS`).

    Equal-energy discretisation: component i's frequency is drawn uniformly in energy within
    the i-th of N equal-energy bands of the spectrum on [0.5, 3] ω_p (so the record never
    repeats), its amplitude is a = √(2 m₀/N) with m₀ = (H_s/4)², so the surface variance is
    exactly m₀; its direction is drawn from the spreading function, its phase from U[0, 2π).
    """
    n = config.components
    x, cdf = _frequency_quantiles(config.spectrum, config.gamma)
    omega = np.interp((np.arange(n) + rng.uniform(size=n)) / n, cdf, x)
    omega *= 2.0 * math.pi / config.peak_period
    dx, dcdf = _direction_quantiles(config.spreading)
    beta = config.direction + np.interp(rng.uniform(size=n), dcdf, dx)
    phase = rng.uniform(0.0, 2.0 * math.pi, size=n)
    k = omega**2 / GRAVITY
    amplitude = math.sqrt(2.0 / n) * config.significant_height / 4.0
    out = np.empty((n, COMPONENT_DIM))
    out[:, COMPONENT.kx] = k * np.cos(beta)
    out[:, COMPONENT.ky] = k * np.sin(beta)
    out[:, COMPONENT.k] = k
    out[:, COMPONENT.omega] = omega
    out[:, COMPONENT.phase] = phase
    out[:, COMPONENT.a_omega] = amplitude * omega
    out[:, COMPONENT.cos_beta] = np.cos(beta)
    out[:, COMPONENT.sin_beta] = np.sin(beta)
    return out


def surface_elevation(components: np.ndarray, x: float, y: float, t: np.ndarray) -> np.ndarray:
    """ζ(x, y, t) [m], positive up, at the times t [s] (vectorised; tests and plots)."""
    c = components
    theta = (c[:, COMPONENT.kx] * x + c[:, COMPONENT.ky] * y + c[:, COMPONENT.phase])[:, None]
    theta = theta - c[:, COMPONENT.omega, None] * np.asarray(t, dtype=float)[None, :]
    amplitude = c[:, COMPONENT.a_omega] / c[:, COMPONENT.omega]
    return amplitude @ np.cos(theta)


@njit(cache=True, inline="always")
def wave_kinematics(row, start, n, x, y, depth, t):
    """Orbital velocity, local acceleration and its rate (v_x, v_y, v_z, a_x, a_y, a_z, j_x,
    j_y, j_z) in NED [m/s, m/s², m/s³] at (x, y) and ``depth`` [m] below the surface at time t
    [s], summed over the ``n`` components stored from column ``start`` of ``row``; per
    component ∂²v/∂t² = −ω² v, so j costs no further trigonometry. Above the surface
    (depth < 0) the surface value is used: linear theory ends at z = 0 (docs/model.md §13.1)."""
    d = max(depth, 0.0)
    vx = vy = vz = ax = ay = az = jx = jy = jz = 0.0
    for i in range(n):
        j = start + i * COMPONENT_DIM
        omega = row[j + COMPONENT.omega]
        theta = row[j + COMPONENT.kx] * x + row[j + COMPONENT.ky] * y - omega * t
        theta += row[j + COMPONENT.phase]
        c, s = math.cos(theta), math.sin(theta)
        e = row[j + COMPONENT.a_omega] * math.exp(-row[j + COMPONENT.k] * d)
        cb, sb = row[j + COMPONENT.cos_beta], row[j + COMPONENT.sin_beta]
        vh, ah = e * c, e * omega * s  # horizontal speed and its ∂/∂t along β
        w2 = omega * omega
        vx += vh * cb
        vy += vh * sb
        vz -= e * s
        ax += ah * cb
        ay += ah * sb
        az += e * omega * c
        jx -= w2 * vh * cb
        jy -= w2 * vh * sb
        jz += w2 * e * s
    return vx, vy, vz, ax, ay, az, jx, jy, jz
