"""`AUVPath3D-v0`: the Gymnasium environment (glue around `simulator.Simulator`)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from os import PathLike
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.envs.registration import EnvSpec
from gymnasium.error import ResetNeeded

from auv_gym.envs.checks import check_reset_observations, validate_actions
from auv_gym.envs.info import single_info, track_point
from auv_gym.envs.rendering import EpisodeRenderer
from auv_gym.ocean.current_profile import CurrentProfile
from auv_gym.ocean.depth_envelope import DepthEnvelope
from auv_gym.ocean.disturbances import CurrentConfig, NoiseConfig
from auv_gym.ocean.waves import WaveConfig
from auv_gym.paths.shapes import Path
from auv_gym.sim.config import SimConfig
from auv_gym.sim.observation import ObservationConfig
from auv_gym.sim.path_generator import PathDistribution
from auv_gym.sim.safety_cost import SafetyCost
from auv_gym.sim.simulator import Simulator
from auv_gym.sim.task import NON_FINITE, RewardWeights
from auv_gym.support.validation import ArgumentTypeError
from auv_gym.vehicle.actuators import ActuatorParams
from auv_gym.vehicle.params import AUVParams
from auv_gym.vehicle.record import Vehicle
from auv_gym.vehicle.remus6dof import SixDofVehicle
from auv_gym.vehicle.sensors import SensorConfig
from auv_gym.vehicle.variation import HullVariation

__all__ = ["AUVPath3DEnv", "check_reset_observations", "validate_actions"]


class AUVPath3DEnv(gym.Env):
    r"""3D path following of an underactuated AUV (Liang et al. 2018, IJFS 20:640).

    ## Description
    A REMUS 100 vehicle, modelled in five degrees of freedom (surge, sway, heave, pitch, yaw;
    docs/model.md §2), must follow a 3D path with a Serret–Frenet virtual point that moves with
    u_p = u_D(1 + tanh(x_e/σ)) (docs/model.md §3.3). It has three inputs only — surge thrust X,
    pitch moment M, yaw moment N — so sway and heave are unactuated. The defaults reproduce the
    paper's simulation: the helix x = 20 cos(πs/20) + 10, y = 20 sin(πs/20), z = −8 − s, start at
    (15, 5, 0) m at rest with ψ = θ = 0, and bounded white-noise disturbances of ±35 N / N·m.

    ## Frames and signs (docs/model.md §2.0)
    Earth frame North-East-Down (NED): x north, y east, **z down** [m], so a larger z is deeper
    and depth below the origin is +z. Heading ψ is measured from north, positive clockwise seen
    from above (ψ = π/2 heads east); pitch θ is positive **nose-up**, so with forward speed a
    positive θ makes the vehicle rise (ż = −u sin θ + w cos θ). Body axes: x forward, y to
    starboard, z down through the keel; w is positive downwards, q nose-up, r to starboard; the
    inputs M and N are positive nose-up and to starboard. The default helix, z = −8 − s, lies at
    negative z, i.e. *above* the start point: it climbs about 97 m in 300 s. The origin is a
    reference point, not the sea surface: the model has no free surface and nothing depends
    on depth, so a vertical shift of path and start changes nothing (to make z a true depth,
    shift both by at least 100 m, docs/model.md §2.0: ``path_offset=(0, 0, 110)``, and add the
    sea surface and seabed with `depth_envelope`, docs/model.md §12).

    ## Action Space
    `Box(-1, 1, (3,), float32)`: normalised (X, M, N). "paper" actuators scale by
    (50 N, 10 N·m, 10 N·m); "fins" scale X by 50 N and M, N by the fin authority
    6.15·u|u|·π/6 N·m (docs/model.md §2.3). "realistic": normalised commands (n, δ_s, δ_r) of
    the propeller shaft speed and the stern-plane and rudder angles, which must lie in the box
    (docs/model.md §2.6). Values beyond ±1 saturate otherwise (the only clipping);
    NaN, inf or a wrong shape raise ValueError, strings, booleans and complex numbers TypeError.

    ## Observation Space
    `Box(OBS_LOW, OBS_HIGH, (15,), float32)`, physical SI units, layout `auv_gym.OBS_NAMES`:

    | idx | name        | unit  | idx | name        | unit  |
    |-----|-------------|-------|-----|-------------|-------|
    | 0   | x_e         | m     | 8   | w           | m/s   |
    | 1   | y_e         | m     | 9   | q           | rad/s |
    | 2   | z_e         | m     | 10  | r           | rad/s |
    | 3   | psi_error   | rad   | 11  | u_D         | m/s   |
    | 4   | theta       | rad   | 12  | u_p         | m/s   |
    | 5   | theta_F     | rad   | 13  | psi_F_dot   | rad/s |
    | 6   | u           | m/s   | 14  | theta_F_dot | rad/s |
    | 7   | v           | m/s   |     |             |       |

    (x_e, y_e, z_e) is vehicle minus virtual point in the body frame; psi_error = ψ − ψ_F
    wrapped to (−π, π]; velocities are relative to the water.

    With ``observation="preview"`` (the default of `AUVPath3DPreview-v0`) the observation is the
    agent observation, `Box(low, high, (21 + 5K,), float32)`: these 15 entries, then what a real
    AUV's navigation system and planner know — velocity over ground u_ground, v_ground,
    w_ground [m/s] (body frame, what a DVL with bottom lock measures), the previous saturated
    action a_X_prev, a_M_prev, a_N_prev, and K path points Δs [m] of arc apart ahead of the
    virtual point (vector from the vehicle, body frame [m], with the curvature and torsion there
    [1/m]). Defaults K = 5, Δs = 2 m; ``observation={"points": K, "spacing": Δs}`` sets them.
    Names, units and bounds: ``env.unwrapped.config.observation`` (`auv_gym.ObservationConfig`)
    and `auv_gym.sim.observation` (docs/design.md §3.12).

    ## Rewards
    r = w_progress·min(u_p/u_D, 1) + w_tracking·exp(−d²/1 m²) − w_distance·d/corridor
    − w_speed·min(((u − u_D)/u_D)², 1) − w_overspeed·min(max(u − u_D, 0)/(u_max − u_D), 1)²
    − w_effort·|a|²/3 + w_precision·exp(−d²/0.01 m²) − w_termination·[failure], with d the
    distance to the virtual point and
    u_max = `surge_limit` (`auv_gym.sim.task`). Idling scores about −1.5 per step, following about
    +2; every term is reported in `info` as `reward_<term>`.

    Realistic speed: the speed term is capped at u = 2u_D, so an agent may buy accuracy by
    sprinting far beyond REMUS 100's top speed (~2.3-2.5 m/s). A finite `surge_limit` u_max
    adds the overspeed penalty (0 at u_D, w_overspeed at u_max) and ends the episode as
    "overspeed" when u > u_max. `AUVPath3DSpeedLimit-v0` and `AUVPath3DPreview-v0` set
    u_max = 2.0 m/s; in v0 (u_max = inf) the
    overspeed term is −0.0 and the rewards are those of the first release bit for bit.

    ## Starting State
    The path's default start (paper: (15, 5, 0) m, ψ = θ = 0, ν = 0, s = 0), or
    `start_position` and `start_heading` where given. With `randomize_start=True`, half of the
    episodes start within ±2 m of that start with a heading error of up to
    ±`start_heading_spread` (0.2 rad; the paper's own start is π/2 off the path), the rest
    anywhere on the first turn of the path with up to 8 m offset, ±60° heading error and
    0–1.5 m/s surge, whatever start was given (the training distribution's recovery half).
    `start_rotation` turns the start about p(0) (−π/2: the paper helix's 90°-across start on any
    path, docs/model.md §3.5).
    The arguments' ranges (below) keep every reset observation inside the observation space;
    `reset` raises ValueError, naming the component, if a start still falls outside it.
    `reset` takes no `options` (None or an empty dict).

    ## Info
    `x_e`, `y_e`, `z_e`, `distance` [m], `s`, `u_p` [m/s], `t` [s]; `tau` — the applied
    (X, M, N) after saturation [N, N·m] and `disturbance` — the white-noise (f_u, f_v, f_w, f_q,
    f_r) [N, N·m], both averaged over the physics steps of the control period; `reward_<term>`
    for each reward term; `cost` — the step's safety cost (`auv_gym.sim.safety_cost`,
    Safety-Gymnasium's convention, not part of the reward); `termination_reason` when the episode
    terminates.

    ## Episode End
    Terminated (`info["termination_reason"]`): "corridor" — distance to the virtual point above
    `corridor` (30 m); "pitch" — |θ| above `max_pitch` (60°); "non_finite" — the state or the
    observation is no longer finite (NaN, inf or beyond the float32 range; the last observation
    returned before is returned again); "envelope" — the observation left its documented
    bounds; "path_end" — s reached the end of a finite path; "overspeed" — u above
    `surge_limit` (none in v0); with a `depth_envelope` only, "broached" — z < 0, above the sea
    surface, and "grounded" — z below the seabed (docs/model.md §12). Every other step returns an
    observation inside `observation_space`, and every reward is finite.

    Truncated at `max_time`: `truncated` is True from the first control step at which
    t ≥ `max_time` (after ⌈max_time/control_dt⌉ steps; 300 s = 6000 steps of 0.05 s), whether or
    not that step also terminates — the env owns its time limit for every `control_dt`, so
    `gym.make` adds no `TimeLimit` and `env.spec.max_episode_steps` is that step count.

    ## Arguments
    Every argument is checked when the env is built: a value of the wrong type raises
    `auv_gym.support.validation.ArgumentTypeError` (a TypeError, and a ValueError), a value outside
    the range below ValueError; both name the argument, the value and the allowed range. Nothing is
    coerced silently (``randomize_start="False"`` is an error, not True).

    | argument | default | meaning |
    |---|---|---|
    | `path` | "helix" | "helix", "line", "waypoints", "random", a `Path`, waypoints (below) |
    | `disturbance` | "paper" | "paper" (±35), "none", "ocean", amplitude, `NoiseConfig`, dict |
    | `current` | None | earth-frame mean [m/s] 3-vector, dict or `CurrentConfig` (Gauss–Markov) |
    | `param_uncertainty` | None | ε: coefficients × (1 + U[−ε, ε]) per episode (None: 0) |
    | `hull_variation` | None | {mass, cg_offset, added_mass, damping}: drawn per episode (§15.3) |
    | `actuator` | "paper" | "paper", "fins", "realistic" or "random" ("paper" or "fins", ½ each) |
    | `actuator_params` | defaults | `ActuatorParams` or dict of its fields ("realistic" only) |
    | `random_current` | None | V [m/s]: per episode a current of speed U[0, V] (None: 0) |
    | `random_noise` | 0.0 | ε: white-noise amplitudes × (1 + U[−ε, ε]) per episode |
    | `control_dt` | 0.05 | control period [s], a multiple of `physics_dt` |
    | `physics_dt` | 0.01 | RK4 step [s] |
    | `noise_hold` | None | white-noise hold [s]; None: the `NoiseConfig`'s, ocean's 1 s or 0.01 s |
    | `max_time` | 300.0 | truncation time [s] |
    | `randomize_start` | False | random initial offset (training) |
    | `start_heading_spread` | 0.2 | heading error [rad] of `randomize_start`'s near-start half |
    | `start_rotation` | 0.0 | [rad] turns the start about p(0); (low, high): drawn per episode |
    | `u_desired`, `sigma` | 1.0, 0.5 | u_D [m/s] and σ [m] of the virtual-point law |
    | `virtual_point_law` | "corrected" | "printed" restores the paper's unstable 1 − tanh |
    | `corridor`, `max_pitch` | 30.0, 60° | termination limits [m], [rad] |
    | `surge_limit` | inf | u_max [m/s], "vehicle": `params.max_surge`; overspeed term (Rewards) |
    | `reward_weights` | defaults | `RewardWeights` or dict of the weights above |
    | `params` | REMUS 100 | `AUVParams` of the true vehicle (limits X_max …), or a dict, `scale` |
    | `start_position`, `start_heading` | None | override the start [m], [rad] |
    | `render_mode` | None | "rgb_array": 3-D track and errors over time (`envs.rendering`) |
    | `observation` | "paper" | "paper" (15 entries), "preview" (above), {points, spacing} |
    | `path_offset` | None | (dx, dy, dz) [m] moving the path and its default start (real depth) |
    | `depth_envelope` | None | True, {seabed_depth, margin} or `DepthEnvelope`: surface z = 0 |
    | `safety_cost` | defaults | {depth, speed, pitch, speed_limit, pitch_limit}: `info["cost"]` |
    | `waves` | None | "sea_state_3" … "sea_state_5", dict or `WaveConfig` (§13); False: none |
    | `current_profile` | None | dict, `CurrentProfile`: current vs depth (§13.5); False: none |
    | `sensors` | "ideal" | "ideal" (exact state), "typical", dict, `SensorConfig`: model.md §14 |
    | `surface_above_path` | None | [m] surface above the path's top (§13.8); False: z = 0 |
    | `plant` | "5dof" | "5dof" (the paper's model) or "6dof" (with roll, model.md §15) |
    | `plant_params` | REMUS 100 | "6dof" only: `SixDofVehicle` or a complete dict of its fields |
    | `vehicle` | "remus100" | a shipped name, a `.toml` vehicle file, a dict or a `Vehicle` |

    ``vehicle`` is the data file of the vehicle flown (docs/vehicles.md): its limits, 5-DOF
    model, propeller and fins, 6-DOF hull and navigation suite. ``params``, ``actuator_params``
    and ``plant_params`` change parts of it (a dict of ``params`` or ``actuator_params`` replaces
    the named fields of the vehicle's), ``sensors="vehicle"`` takes the suite it carries.

    ``disturbance="ocean"`` is the ocean a REMUS-class vehicle meets in service
    (`auv_gym.ocean.preset`, docs/model.md §16): unmodelled-dynamics noise sized to the fins,
    a random, Gauss–Markov and depth-sheared current, sea state 3 and ±20 % coefficients. It
    fills `current`, `random_current`, `param_uncertainty`, `waves`, `current_profile` and,
    without a `depth_envelope`, `surface_above_path` (10 m, while waves or a profile are on) where
    they are left at None; False switches off `waves`, `current_profile` or `surface_above_path`.
    `noise_hold` replaces the hold of its noise (1 s), and a dict of `NoiseConfig` fields over a
    preset its noise, e.g. ``disturbance={"preset": "ocean", "amplitude": 0.0}`` (no noise); a
    `NoiseConfig` alone is that noise without the ocean.

    Allowed values (`auv_gym.support.validation`; the constants live in `simulator`, `disturbances`,
    `task` and `paths`):
    - `physics_dt` in [1e-6, 0.1] s; `control_dt` a whole multiple of it, at most 10 000 physics
      steps per control step (bounds the cost of one `step`); `max_time` in [control_dt, 1e6] s.
    - `noise_hold` ≤ 1e6 s; the hold (also the 0.01 s default and "ocean"'s 1 s) a whole multiple
      of `physics_dt` unless there is no noise ("none" or amplitude 0), where `noise_hold` and
      `random_noise` are refused (they would do nothing); given together with a `NoiseConfig`
      or a dict's `hold` it must equal it (no silent override). Amplitudes in [0, 1e4] N or N·m.
    - `current`: mean and std per axis within ±10 m/s (std ≥ 0), time constant in (0, 1e6] s.
    - `surge_limit` in (u_desired, 10] m/s, inf or "vehicle" (`params.max_surge`); a random
      start's surge stays below 0.75 `surge_limit` (0-1.5 m/s otherwise).
    - `param_uncertainty` in [0, 1); `u_desired` in (0, 10] m/s, so that u_D and u_p ≤ 2u_D stay
      inside their observation bounds; `sigma` > 0 m.
    - `corridor` in [0.01, 500] m, inside the ±500 m bounds of the observed errors; `max_pitch`
      in (0, π/2) rad; reward weights in [0, 1e6] (the formula gives each term its sign).
    - `start_position` within 500 m of the path's start p(0) (496.5 m with `randomize_start`),
      so that the reset errors are observable; `start_heading` in [−2π, 2π] rad;
      `start_heading_spread` in [0, π] rad, other than 0.2 only with `randomize_start`;
      `start_rotation` in [−π, π] rad (a range: low ≤ high).
    - `randomize_start` a bool; `params` an `AUVParams` (finite fields, positive inertias) or a
      dict of its field values and an optional `scale` dict of factors, e.g. ``{"m": 32.0,
      "scale": {"X_uu": 1.2}}`` (an unknown name is an error naming it).
    - `random_current` in [0, 1] m/s (no headway against ~1 m/s at u_D = 1 m/s);
      `random_noise` in [0, 1]; `actuator="random"` draws "paper" or "fins" per episode.
    - `sensors`: each σ finite and ≥ 0 (at most 1 m/s, 0.5 rad, 0.5 rad/s, 10 m, 100 m for the
      fixes), `dvl_dropout` in [0, 0.99], `fix_interval` a whole multiple of `control_dt` (0:
      every step) or None, `delay` an integer in [0, 1000] control steps
      (`auv_gym.vehicle.sensors`); the navigation filter's `filter_*` settings in [1e-6, 10]
      and only with ``navigation="kalman"``, which also needs `fix_noise` >= 1e-6 m.
    - `plant_params`: `length` in [0.01, 1000] m, `diameter` in [length/1000, length),
      `water_density` in [1, 1e4] kg/m³, `gravity` in (0, 100] m/s², damping time constants
      > 0 and ratios in [0, 100]; and every mode of the hull steppable by RK4 at
      `physics_dt`: |λ|·physics_dt <= 2.5, at the stiff end of `param_uncertainty`'s draws
      (REMUS 100 at 0.01 s: time constants >= 0.004 s, roll damping ratio <= 19.3,
      `param_uncertainty` <= 0.996; the error names the coefficient and its bound, or, for the
      vehicle's own hull, `param_uncertainty` when only its draws are too stiff, docs/model.md
      §15.1).

    Paths (`auv_gym.paths`): coordinates (centre, start, waypoints) within ±1e6 m; `Helix` radius
    in (0, 1e5] m, ω in [−1e3, 0) ∪ (0, 1e3] rad per unit s (ω > 0 a starboard, ω < 0 a port
    turn), |climb| ≤ 1e5 m per unit s (> 0 climbs), |p'| ≥ 1e-6; a `StraightLine` direction
    non-zero; a `Spline` through 2 to 1000 distinct waypoints that never doubles back (|p'| ≥ 1e-6
    everywhere). The path's turn rate must keep the
    virtual point's ψ̇_F and θ̇_F within their ±10 rad/s bounds for u_p ≤ 2u_D (checked exactly
    for helix and line; for a spline by a proven bound over every segment, naming the waypoint).

    User paths: a list of (x, y, z) waypoints [m] (``path=[(0, 0, 5), (40, 10, 8), ...]``)
    becomes the natural cubic `Spline` through them, parameterised by chord length, ending at
    the last waypoint ("path_end"). A parametric curve p(s) (a Python callable) becomes a
    kernel path with ``auv_gym.fit_curve(p, s_end)`` (a C² spline in the same s, position error
    ≤ 1 mm by default; docs/model.md §3.8). A user path starts like the built-in ones: the
    vehicle at rest at p(0) + R_z(ψ_F(0))·(−15, 5, 0) m + (0, 0, 8) m (15 m behind the path's
    start, 5 m to starboard, 8 m deeper: the paper's initial errors), heading ψ_F(0), θ = 0; use
    `start_position` and `start_heading` to override it.

    Random paths (``path="random"``, a `auv_gym.sim.path_generator.PathDistribution` or a dict of
    its fields): every reset draws one path, a function of the seed only — a helix (either turn,
    ascending or descending), a straight line in any direction, a smooth random spline or a
    lawnmower survey — radius of curvature ≥ 15 m and |flight-path angle| ≤ 20° by default,
    never beyond the vehicle's 8 m and 25° (docs/model.md §3.8). Each starts at the origin with
    the default start above (`start_position`, `start_heading` are refused); the vector env
    draws each vehicle's own path exactly as the single env would for its seed.

    ## Vectorized environment
    `gym.make_vec("AUVPath3D-v0", num_envs=n)` returns the native `AUVPath3DVectorEnv`, which
    runs the same compiled kernel over all vehicles.

    ## Version History
    * v0: initial release (REMUS 100 in the paper's 5-DOF form, docs/model.md §6 corrections).
      Later v0 fixes, default behaviour unchanged: the env owns truncation at `max_time` (was a
      registered `TimeLimit` of 6000 steps, wrong for any other `control_dt`); every argument is
      range-checked; a non-finite observation ends the episode as "non_finite"; the
      `surge_limit` argument (default inf: no limit, rewards unchanged bit for bit).
      New arguments with defaults that change nothing: waypoint lists, fitted curves and port
      helices as paths; ``path="random"`` (a `PathDistribution`), `random_current`,
      `random_noise`, ``actuator="random"`` and `params` as a dict (docs/model.md §3.8).
      Also without effect on v0: the `observation` argument and the "precision" reward term
      (weight 0 by default), `waves` and `current_profile` (None by default), and
      ``actuator="realistic"`` with `actuator_params` (propeller and fin dynamics, docs/model.md
      §2.6).
    * `AUVPath3DSpeedLimit-v0` (a name of its own, not v1 of v0's, so that v0 is not reported
      "out of date"): realistic speed — the v0 environment with
      `surge_limit` = "vehicle" by default, the vehicle record's top speed
      (`AUVParams.max_surge`, 2.0 m/s for REMUS 100): the overspeed reward term and the "overspeed"
      termination (docs/design.md §3). Everything else, including every other default, is v0's.
    * `AUVPath3DPreview-v0`: the RL task — the speed limit and ``observation="preview"``;
      integral action is an option of it: ``observation="preview_integral"`` adds leaky
      integrals of x_e, y_e and z_e [m·s] (T = 10 s), each clipped to ±1 m·s (anti-windup).
      ``observation={"kind": "preview", "integral_time": T, "integral_errors": "yz" | "xyz",
      "integral_limit": L}`` sets them one by one; ``"history_steps": H, "history_interval": Δ``
      adds the observed x_e, y_e, z_e [m] of Δ, 2Δ … HΔ seconds ago.

    Registered ids and their fixed arguments: `auv_gym.VARIANTS` (docs/design.md §3.8).
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 20}

    def __init__(
        self,
        path: str | Path | PathDistribution | Sequence[Sequence[float]] | Mapping = "helix",
        disturbance: str | float | NoiseConfig | Mapping = "paper",
        current: CurrentConfig | Sequence[float] | dict | None = None,
        param_uncertainty: float | None = None,
        actuator: str = "paper",
        control_dt: float = 0.05,
        physics_dt: float = 0.01,
        noise_hold: float | None = None,
        max_time: float = 300.0,
        randomize_start: bool = False,
        u_desired: float = 1.0,
        sigma: float = 0.5,
        virtual_point_law: str = "corrected",
        corridor: float = 30.0,
        max_pitch: float = math.radians(60.0),
        surge_limit: float | str = math.inf,
        reward_weights: RewardWeights | dict | None = None,
        params: AUVParams | Mapping[str, Any] | None = None,
        start_position: Sequence[float] | None = None,
        start_heading: float | None = None,
        start_heading_spread: float = 0.2,
        start_rotation: float | Sequence[float] = 0.0,
        render_mode: str | None = None,
        random_current: float | None = None,
        random_noise: float = 0.0,
        observation: str | Mapping | ObservationConfig | None = None,
        path_offset: Sequence[float] | None = None,
        depth_envelope: DepthEnvelope | Mapping | bool | None = None,
        safety_cost: SafetyCost | Mapping | None = None,
        waves: WaveConfig | str | int | Mapping | bool | None = None,
        current_profile: CurrentProfile | Mapping | bool | None = None,
        actuator_params: ActuatorParams | Mapping[str, Any] | None = None,
        sensors: str | Mapping | SensorConfig | None = None,
        surface_above_path: float | bool | None = None,
        plant: str = "5dof",
        plant_params: SixDofVehicle | Mapping[str, Any] | None = None,
        vehicle: str | PathLike | Mapping[str, Any] | Vehicle | None = None,
        hull_variation: HullVariation | Mapping[str, Any] | None = None,
    ) -> None:
        self.config = SimConfig.from_kwargs(
            path=path,
            disturbance=disturbance,
            current=current,
            param_uncertainty=param_uncertainty,
            actuator=actuator,
            control_dt=control_dt,
            physics_dt=physics_dt,
            noise_hold=noise_hold,
            max_time=max_time,
            randomize_start=randomize_start,
            u_desired=u_desired,
            sigma=sigma,
            virtual_point_law=virtual_point_law,
            corridor=corridor,
            max_pitch=max_pitch,
            surge_limit=surge_limit,
            params=params,
            start_position=start_position,
            start_heading=start_heading,
            start_heading_spread=start_heading_spread,
            start_rotation=start_rotation,
            reward_weights=reward_weights,
            random_current=random_current,
            random_noise=random_noise,
            observation=observation,
            path_offset=path_offset,
            depth_envelope=depth_envelope,
            safety_cost=safety_cost,
            waves=waves,
            current_profile=current_profile,
            actuator_params=actuator_params,
            sensors=sensors,
            surface_above_path=surface_above_path,
            plant=plant,
            plant_params=plant_params,
            vehicle=vehicle,
            hull_variation=hull_variation,
        )
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be None or one of {self.metadata['render_modes']}, "
                f"got {render_mode!r:.80}"
            )
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": max(1, round(1.0 / control_dt))}
        self.sim = Simulator(self.config, 1)
        self.observation_space = spaces.Box(self.sim.obs_low, self.sim.obs_high, dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
        self._truncation_index = self.config.max_steps * self.config.substeps
        self._last_obs = np.zeros(self.observation_space.shape, np.float32)  # the last returned
        self._needs_reset = True  # until a reset succeeds: no episode to step
        self._renderer = (
            EpisodeRenderer(
                self.config.path, self.config.max_time, envelope=self.config.depth_envelope
            )
            if render_mode
            else None
        )

    @property
    def spec(self) -> EnvSpec | None:
        """The spec `gym.make` set, with ``max_episode_steps`` = the steps to `max_time`.

        The env truncates there by itself (the registration has no `TimeLimit`), so the spec
        states the episode length of these arguments, whatever their `control_dt`.
        """
        if self._spec is None:
            return None
        return dataclasses.replace(self._spec, max_episode_steps=self.config.max_steps)

    @spec.setter
    def spec(self, value: EnvSpec | None) -> None:
        self._spec = value

    _spec: EnvSpec | None = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        self._needs_reset = True  # a refused reset leaves no episode half-started
        if options is not None and not isinstance(options, Mapping):
            raise ArgumentTypeError(f"options must be None or a dict, got {options!r:.80}")
        if options:
            raise ValueError(
                f"AUVPath3DEnv.reset takes no options, got {sorted(map(str, options))}"
            )
        super().reset(seed=seed)
        self.sim.reset_row(0, self.np_random)
        obs = self.sim.observations()[0]
        check_reset_observations(
            obs[None],
            [0],
            self.config.observation,
            self.config.current_speed_bound,
            self.sim.speed_bound,
        )
        self._last_obs[:] = obs
        self._needs_reset = False
        if self._renderer is not None:
            self._renderer.reset(*track_point(self.sim, 0), path=self.sim.paths[0])
        return obs, single_info(self.sim, self.config.physics_dt, 0, reset=True)

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if self._needs_reset:
            raise ResetNeeded("AUVPath3DEnv: call reset() before step() (no episode is running)")
        sim = self.sim
        sim.step(validate_actions(action, (3,))[None])
        code = int(sim.code[0])
        # Truncated whenever max_time is reached, terminated or not, as under `TimeLimit`.
        truncated = int(sim.step_index[0]) >= self._truncation_index
        if code == NON_FINITE:  # the last observation returned: finite and inside the space
            obs = self._last_obs.copy()
        else:
            obs = sim.observations()[0]
            self._last_obs[:] = obs
        if self._renderer is not None:
            t = int(sim.step_index[0]) * self.config.physics_dt
            self._renderer.append(*track_point(sim, 0), t)
        info = single_info(sim, self.config.physics_dt, code, reset=False)
        return obs, float(sim.reward[0]), code != 0, truncated, info

    @property
    def state(self) -> np.ndarray:
        """The simulator state (x, y, z, θ, ψ, u, v, w, q, r, s) [m, rad, m/s, rad/s, -]."""
        return self.sim.state[0].copy()

    @property
    def actuator(self) -> str:
        """The actuator model of the current episode, "paper", "fins" or "realistic": the
        configured one, or the one the episode drew (``actuator="random"``)."""
        return str(self.sim.actuators[0])

    def render(self) -> np.ndarray | None:
        """RGB frame (320, 960, 3) uint8 of the episode so far (`auv_gym.envs.rendering`), or
        None."""
        if self._renderer is None:
            return None
        return self._renderer.frame()
