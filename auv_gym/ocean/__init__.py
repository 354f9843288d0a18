"""The water around the vehicle: disturbances, current, waves and the water column.

- `disturbances`: bounded white noise, the ocean current (constant + Gauss–Markov), parameter
  uncertainty, and the counter-based random numbers of an episode;
- `current_profile`: a current that varies with depth (`CurrentProfile`);
- `waves`: a seeded wave field and its orbital velocities (`WaveConfig`);
- `forcing`: the per-vehicle ocean row and the forcing the integrator adds (waves + profile);
- `depth_envelope`: the sea surface and an optional seabed (`DepthEnvelope`).

Imports `auv_gym.support` and `auv_gym.paths` (a path must lie inside the depth envelope).
"""

from __future__ import annotations

from auv_gym.ocean.current_profile import CurrentProfile
from auv_gym.ocean.depth_envelope import DepthEnvelope
from auv_gym.ocean.disturbances import CurrentConfig, NoiseConfig
from auv_gym.ocean.waves import SEA_STATES, SPECTRA, WaveConfig

__all__ = [
    "SEA_STATES",
    "SPECTRA",
    "CurrentConfig",
    "CurrentProfile",
    "DepthEnvelope",
    "NoiseConfig",
    "WaveConfig",
]
