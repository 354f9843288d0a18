r"""The ocean beyond the uniform current: waves and a depth-profiled current (docs/model.md §13).

Each vehicle carries an *ocean row* (layout `OCEAN_FIELDS`, then the wave components of
`auv_gym.ocean.waves`), drawn at reset from its episode keys (`ocean_row`) and read by
`period.advance_period` through two calls per physics step: `refresh_waves` re-evaluates
the wave field at the vehicle's position every ``wave_every`` physics steps, and
`ocean_forcing` adds the waves' orbital velocity and the profiled current to the earth-frame
current of `auv_gym.ocean.disturbances` (held across the RK4 stages, like it). A row whose
``active`` is 0 (no waves, no profile) is never read beyond that flag, so such configurations
run the kernels' original arithmetic bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from auv_gym.ocean.current_profile import CurrentProfile, profile_velocity
from auv_gym.ocean.waves import COMPONENT_DIM, WaveConfig, draw_components, wave_kinematics
from auv_gym.support.records import field_indices

__all__ = [
    "NO_WAVE",
    "OCEAN",
    "OCEAN_FIELDS",
    "ocean_forcing",
    "ocean_row",
    "ocean_velocity",
    "ocean_width",
    "refresh_waves",
]

OCEAN_FIELDS = (
    "active",
    "wave_components",
    "wave_every",
    "profile",
    "surface_speed",
    "reference_speed",
    "reference_depth",
    "exponent",
    "direction",
    "drift_amplitude",
    "drift_omega",
    "drift_phase",
    "surface_z",
)
OCEAN_HEADER = len(OCEAN_FIELDS)
OCEAN = field_indices("OceanIndex", OCEAN_FIELDS, __name__)
# A stream id mixed with the episode keys: the ocean draws touch no other random sequence.
_OCEAN_STREAM = 0x0CEA
# The wave state between refreshes: velocity, acceleration, its rate and t₀ (`refresh_waves`).
NO_WAVE = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def ocean_width(waves: WaveConfig | None) -> int:
    """Columns of an ocean row."""
    return OCEAN_HEADER + (waves.components * COMPONENT_DIM if waves is not None else 0)


def ocean_row(
    waves: WaveConfig | None,
    profile: CurrentProfile | None,
    keys: np.ndarray,
    physics_dt: float,
    surface_z: float = 0.0,
) -> np.ndarray:
    """An episode's ocean row from its two 64-bit keys (`disturbances.draw_keys`): a function
    of the seed only, so batched and single envs draw the same sea. ``surface_z`` [m] is the
    NED z of the sea surface the waves and the profile are measured from (docs/model.md §13.8).
    """
    row = np.zeros(ocean_width(waves))
    if waves is None and profile is None:
        return row
    rng = np.random.default_rng([int(keys[0]), int(keys[1]), _OCEAN_STREAM])
    row[OCEAN.active] = 1.0
    row[OCEAN.surface_z] = surface_z
    if waves is not None:
        row[OCEAN.wave_components] = waves.components
        row[OCEAN.wave_every] = max(1, round(waves.update_interval / physics_dt))
        row[OCEAN_HEADER:] = draw_components(waves, rng).ravel()
    if profile is not None:
        row[OCEAN.profile] = 1.0
        row[OCEAN.surface_speed] = profile.surface_speed
        row[OCEAN.reference_speed] = profile.reference_speed
        row[OCEAN.reference_depth] = profile.reference_depth
        row[OCEAN.exponent] = profile.exponent
        row[OCEAN.direction] = profile.direction
        row[OCEAN.drift_amplitude] = profile.drift_amplitude
        row[OCEAN.drift_omega] = 2.0 * math.pi / profile.drift_period
        row[OCEAN.drift_phase] = rng.uniform(0.0, 2.0 * math.pi)
    return row


@njit(cache=True, inline="always")
def _row_profile(ocean, depth, t):
    """The profiled current of an ocean row at ``depth`` below its surface [m] and time t [s]
    (`current_profile.profile_velocity`) [m/s]."""
    return profile_velocity(
        ocean[OCEAN.surface_speed],
        ocean[OCEAN.reference_speed],
        ocean[OCEAN.reference_depth],
        ocean[OCEAN.exponent],
        ocean[OCEAN.direction],
        ocean[OCEAN.drift_amplitude],
        ocean[OCEAN.drift_omega],
        ocean[OCEAN.drift_phase],
        depth,
        t,
    )


@njit(cache=True, inline="always")
def refresh_waves(ocean, st, step, k, dt, wave):
    """The wave state at physics step ``step`` (the k-th of the control period): the field
    (`waves.wave_kinematics`: v, a, j) at the state's position and t₀ = step·dt [s] on every
    ``wave_every``-th step and the first of each period, else ``wave`` unchanged."""
    n = int(ocean[OCEAN.wave_components])
    if n == 0 or k % int(ocean[OCEAN.wave_every]) != 0:
        return wave
    t0 = step * dt
    depth = st[2] - ocean[OCEAN.surface_z]  # exactly z for the surface at z = 0
    field = wave_kinematics(ocean, OCEAN_HEADER, n, st[0], st[1], depth, t0)
    return (*field, t0)


@njit(cache=True, inline="always")
def ocean_forcing(ocean, st, t, wave, current, f, p):
    """(current, f) with the ocean added at time t [s] (docs/model.md §13.3-§13.5).

    The earth-frame ``current`` [m/s] gains the orbital velocity, extrapolated from the last
    refresh in time, v + a τ + j τ²/2 with τ = t − t₀, and the profiled current at the depth
    z − z_surface (st[2] − surface_z). The disturbance ``f`` gains the net fluid-inertia force
    (ρ∇ − m) R_Bᵀ a on
    (f_u, f_v, f_w), ρ∇ = m B/W, which vanishes for a neutral vehicle (B = W).
    """
    cx, cy, cz = current
    if ocean[OCEAN.wave_components] > 0.0:
        tau = t - wave[9]
        half_tau2 = 0.5 * tau * tau
        cx += wave[0] + wave[3] * tau + wave[6] * half_tau2
        cy += wave[1] + wave[4] * tau + wave[7] * half_tau2
        cz += wave[2] + wave[5] * tau + wave[8] * half_tau2
        if p.B != p.W:
            gain = p.m * (p.B / p.W - 1.0)
            cos_theta, sin_theta = math.cos(st[3]), math.sin(st[3])
            cos_psi, sin_psi = math.cos(st[4]), math.sin(st[4])
            ax, ay, az = wave[3], wave[4], wave[5]
            horizontal = cos_psi * ax + sin_psi * ay  # along the heading
            f = (
                f[0] + gain * (cos_theta * horizontal - sin_theta * az),
                f[1] + gain * (cos_psi * ay - sin_psi * ax),
                f[2] + gain * (sin_theta * horizontal + cos_theta * az),
                f[3],
                f[4],
            )
    if ocean[OCEAN.profile] != 0.0:
        px, py, pz = _row_profile(ocean, st[2] - ocean[OCEAN.surface_z], t)
        cx += px
        cy += py
        cz += pz
    return (cx, cy, cz), f


@njit(cache=True, inline="always")
def ocean_velocity(ocean, x, y, z, t):
    """The earth-frame velocity [m/s] an ocean row adds to the current at (x, y, z) [m] and
    time t [s]: the waves' orbital velocity, evaluated exactly, and the profiled current
    (docs/model.md §13); zero for an inactive row. What a bottom-tracking DVL sees beside the
    uniform current (`auv_gym.sim.navigation`)."""
    if ocean[OCEAN.active] == 0.0:
        return 0.0, 0.0, 0.0
    depth = z - ocean[OCEAN.surface_z]
    vx = vy = vz = 0.0
    n = int(ocean[OCEAN.wave_components])
    if n > 0:
        field = wave_kinematics(ocean, OCEAN_HEADER, n, x, y, depth, t)
        vx, vy, vz = field[0], field[1], field[2]
    if ocean[OCEAN.profile] != 0.0:
        px, py, pz = _row_profile(ocean, depth, t)
        vx, vy, vz = vx + px, vy + py, vz + pz
    return vx, vy, vz
