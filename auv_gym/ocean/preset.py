"""The ocean a REMUS-class vehicle meets in service: the ``disturbance="ocean"`` preset.

The paper's ±35 N·m white noise is ten times the fins' moment authority at 1 m/s (3.2 N·m,
docs/model.md §2.6): it measures the noise model, not the controllers. This preset sizes every
part to the vehicle as built (docs/model.md §16, where each value's source, or its status as an
assumption, is given):

- unmodelled dynamics: bounded white noise held 1 s, ±1 N on (f_u, f_v, f_w) and ±0.3 N·m on
  (f_q, f_r), a tenth of the fins' authority at 1 m/s (assumption);
- ocean current: a random horizontal current up to 0.2 m/s per episode, a Gauss–Markov
  variation (σ 0.05/0.05/0.01 m/s, τ = 300 s) and a sheared profile 0.2 m/s at the surface
  falling to 0.05 m/s at 100 m, turning ±0.3 rad over 20 min;
- waves of sea state 3 (H_s 0.88 m, T_p 7.5 s);
- the hydrodynamic coefficients ±20 % per episode.

It serves any path. With a `depth_envelope` z is a true depth and the surface is z = 0 (the
path must lie below it, `path_depths.check_below_the_surface`). Without one the origin is a
reference point (docs/model.md §2.0): the preset then places the sea surface
`SURFACE_ABOVE_PATH` above the shallowest point an episode's path and start reach
(``surface_above_path``), so the waves act at the operating depth of every path. The parts are
defaults (`auv_gym.sim.config.SimConfig.from_kwargs`): an argument given explicitly replaces its
part only; False switches off ``waves``, ``current_profile`` or ``surface_above_path``;
``noise_hold`` replaces the noise's hold and ``disturbance={"preset": "ocean", ...}`` with
`NoiseConfig` fields the noise.
"""

from __future__ import annotations

from dataclasses import dataclass

from auv_gym.ocean.current_profile import CurrentProfile
from auv_gym.ocean.disturbances import CurrentConfig, NoiseConfig
from auv_gym.ocean.waves import WaveConfig

__all__ = ["OCEAN_PRESET", "OCEAN_PRESET_NAME", "SURFACE_ABOVE_PATH", "OceanPreset"]

OCEAN_PRESET_NAME = "ocean"
SURFACE_ABOVE_PATH = 10.0  # [m] shallowest operating depth of a path without a depth envelope


@dataclass(frozen=True)
class OceanPreset:
    """The parts of the ocean preset (module docstring), each an env argument's value."""

    noise: NoiseConfig
    current: CurrentConfig
    random_current: float  # [m/s]
    current_profile: CurrentProfile
    waves: WaveConfig
    param_uncertainty: float  # ε of (1 + U[−ε, ε])
    surface_above_path: float  # [m], without a depth envelope


OCEAN_PRESET = OceanPreset(
    noise=NoiseConfig(amplitude=(1.0, 1.0, 1.0, 0.3, 0.3), hold=1.0),
    current=CurrentConfig(mean=(0.0, 0.0, 0.0), std=(0.05, 0.05, 0.01), time_constant=300.0),
    random_current=0.2,
    current_profile=CurrentProfile(
        surface_speed=0.2,
        reference_depth=100.0,
        reference_speed=0.05,
        exponent=1.0,
        direction=0.0,
        drift_amplitude=0.3,
        drift_period=1200.0,
    ),
    waves=WaveConfig.from_spec("sea_state_3"),
    param_uncertainty=0.2,
    surface_above_path=SURFACE_ABOVE_PATH,
)
