"""Validated settings of the path-following simulation: `SimConfig`, shared by both envs.

`SimConfig.from_kwargs` turns the environments' keyword arguments into settings (each bad value a
one-line error naming it, docs/design.md §3) and `SimConfig.packed` into the float64 row the
compiled step reads (`auv_gym.sim.integrator.CONFIG_FIELDS`).
"""

from __future__ import annotations

import dataclasses
import inspect
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from os import PathLike
from typing import Any

import numpy as np

from auv_gym.ocean.current_profile import CurrentProfile
from auv_gym.ocean.depth_envelope import DepthEnvelope, check_path_depths
from auv_gym.ocean.disturbances import (
    CurrentConfig,
    NoiseConfig,
    gauss_markov_coefficients,
)
from auv_gym.ocean.preset import OCEAN_PRESET, OCEAN_PRESET_NAME
from auv_gym.ocean.waves import WaveConfig
from auv_gym.paths.offset import shift_path
from auv_gym.paths.shapes import (
    POSITION_BOUND,
    Path,
    make_path,
    path_turn_rates,
)
from auv_gym.sim.config_args import (
    DISTURBANCE_PRESETS,
    disturbance_preset,
    noise_from,
    path_from,
    path_is_random,
    reward_from,
    start_rotation_from,
)
from auv_gym.sim.integrator import (
    ACTUATORS,
    CONFIG_FIELDS,
)
from auv_gym.sim.observation import (
    ERROR_BOUND,
    PATH_RATE_BOUND,
    SPEED_BOUND,
    ObservationConfig,
)
from auv_gym.sim.path_depths import check_below_the_surface, check_drawn_paths_fit
from auv_gym.sim.path_generator import PathDistribution
from auv_gym.sim.randomization import MAX_RANDOM_CURRENT, MAX_RANDOM_NOISE
from auv_gym.sim.safety_cost import SafetyCost
from auv_gym.sim.task import (
    VEHICLE_TOP_SPEED,
    RewardWeights,
    TaskLimits,
)
from auv_gym.support.validation import (
    ArgumentTypeError,
    choice,
    flag,
    is_real,
    real,
    vector,
    whole_steps,
)
from auv_gym.vehicle.actuators import ActuatorParams
from auv_gym.vehicle.params import AUVParams, remus100
from auv_gym.vehicle.record import (
    DEFAULT_VEHICLE,
    Vehicle,
    actuators_from,
    hull_from,
    load_vehicle,
)
from auv_gym.vehicle.remus6dof import REMUS6DOF, RK4_STEP_LIMIT, SixDofVehicle
from auv_gym.vehicle.sensors import SENSOR_PRESETS, SensorConfig
from auv_gym.vehicle.variation import HullVariation

__all__ = [
    "ACTUATOR_LIMITS",
    "DISTURBANCE_PRESETS",
    "ENV_KEYWORDS",
    "FIVE_DOF_PLANT",
    "MAX_EPISODE_TIME",
    "MAX_SUBSTEPS",
    "PHYSICS_DT_RANGE",
    "PLANTS",
    "SIX_DOF_PLANT",
    "SimConfig",
    "TopSpeedError",
    "config_from_kwargs",
    "path_is_random",
    "path_turn_rates",
]

# "paper" mode limits of REMUS 100 (docs/model.md §2.3): |X| <= 50 N, |M|, |N| <= 10 N·m.
ACTUATOR_LIMITS = AUVParams().actuator_limits
VIRTUAL_POINT_LAWS = {"corrected": 1.0, "printed": -1.0}
FIVE_DOF_PLANT, SIX_DOF_PLANT = "5dof", "6dof"
PLANTS = (FIVE_DOF_PLANT, SIX_DOF_PLANT)  # the `plant` argument's names
_SUBSTEP_TOL = 1e-9
# Documented ranges of the timing and start arguments (AUVPath3DEnv docstring, "Arguments").
PHYSICS_DT_RANGE = (1e-6, 0.1)  # [s] RK4 step
MAX_SUBSTEPS = 10_000  # physics steps per control step: bounds the cost of one step()
MAX_EPISODE_TIME = 1e6  # [s] max_time (11.6 days)
MAX_SURFACE_ABOVE_PATH = 11_000.0  # [m] the deepest ocean
HEADING_BOUND = 2.0 * math.pi  # [rad] |start_heading|
START_OFFSET = 2.0  # [m] per axis: a random start near the start point (`Simulator`) moves
START_JITTER = START_OFFSET * math.sqrt(3.0)  # [m] so far at most from the start point
START_HEADING_SPREAD = 0.2  # [rad] default half-width of randomize_start's near-start heading error


class TopSpeedError(ValueError):
    """``surge_limit="vehicle"`` (an agent's env id, `AUVPath3DSpeedLimit-v0`) on a vehicle
    whose top speed ``top_speed`` [m/s] is not above the desired speed ``u_desired`` [m/s]: a
    policy trained under that limit cannot fly such a task (the benchmark reports the pair as
    not applicable, a direct call is refused)."""

    def __init__(self, message: str, top_speed: float = math.nan, u_desired: float = math.nan):
        super().__init__(message)
        self.top_speed, self.u_desired = float(top_speed), float(u_desired)


@dataclass(frozen=True)
class SimConfig:
    """Validated simulation settings (units: s, m, m/s, N, N·m)."""

    # A fixed path, or a `PathDistribution` drawing one per episode (`randomization.draw_task`).
    path: Path | PathDistribution = field(default_factory=lambda: make_path("helix"))
    vehicle: str = DEFAULT_VEHICLE  # the vehicle's name (its records are the fields below)
    params: AUVParams = field(default_factory=remus100)
    noise: NoiseConfig = field(default_factory=NoiseConfig)
    current: CurrentConfig = field(default_factory=CurrentConfig)
    param_uncertainty: float = 0.0  # ε: coefficients scaled by 1 + U[−ε, ε] per episode
    # mass, centre of gravity, added mass and damping drawn per episode (docs/model.md §15.3)
    hull_variation: HullVariation = field(default_factory=HullVariation)
    actuator: str = "paper"  # "paper", "fins", "realistic" or "random" (paper or fins per episode)
    # The propeller, motor, fins and servos of actuator="realistic" (docs/model.md §2.6).
    actuator_params: ActuatorParams = field(default_factory=ActuatorParams)
    random_current: float = 0.0  # [m/s] largest speed of a random horizontal current per episode
    random_noise: float = 0.0  # ε: noise amplitudes × (1 + U[−ε, ε]) per episode
    control_dt: float = 0.05  # [s]
    physics_dt: float = 0.01  # [s]
    max_time: float = 300.0  # [s]
    u_desired: float = 1.0  # [m/s] u_D
    sigma: float = 0.5  # [m] virtual-point law width σ
    # "corrected": u_p = u_D(1 + tanh(x_e/σ)) (docs/model.md §3.3); "printed": the paper's misprint
    # u_D(1 − tanh(x_e/σ)), unstable, kept only for the sign-regression tests (docs/model.md §8.9).
    virtual_point_law: str = "corrected"
    randomize_start: bool = False
    # [rad] half-width of the heading error of `randomize_start`'s near-start draws (its other
    # half draws ±π/3 anywhere on the first turn); π/2 covers the paper's start, 90° off the path
    start_heading_spread: float = START_HEADING_SPREAD
    # [rad] turns the start (its position about p(0), and its heading) about the vertical before
    # any random draw: −π/2 gives every path the paper helix's start geometry (docs/model.md §3.5)
    start_rotation: float | tuple[float, float] = 0.0  # or (low, high): drawn per episode
    start_position: tuple[float, float, float] | None = None  # [m]; None: the path's default
    start_heading: float | None = None  # [rad]
    reward: RewardWeights = field(default_factory=RewardWeights)
    limits: TaskLimits = field(default_factory=TaskLimits)
    # "paper": the paper's 15 entries; "preview": the agent observation (`auv_gym.sim.observation`)
    observation: ObservationConfig = field(default_factory=ObservationConfig)
    # [m] added to every drawn path; `from_kwargs` moves a fixed path itself (`path_offset`)
    path_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    depth_envelope: DepthEnvelope | None = None  # None: no surface, no seabed (the paper's)
    safety_cost: SafetyCost = field(default_factory=SafetyCost)
    waves: WaveConfig | None = None  # None: a flat sea (docs/model.md §13)
    current_profile: CurrentProfile | None = None  # None: the uniform current only (§13.5)
    # [m] the sea surface lies this far above the shallowest point of each episode's path and
    # start (the waves and the profile act at that operating depth, docs/model.md §13.8);
    # None: the surface is z = 0. Set by the "ocean" preset without a depth envelope.
    surface_above_path: float | None = None
    # "ideal": the observation is the exact state; else from a navigation estimate (`sensors`)
    sensors: SensorConfig = field(default_factory=lambda: SENSOR_PRESETS["ideal"])
    # "5dof": the paper's model (docs/model.md §2); "6dof": Fossen's 6-DOF REMUS 100 (§15), its
    # hull from `plant_params` (the REMUS 100's by default)
    plant: str = FIVE_DOF_PLANT
    plant_params: SixDofVehicle = REMUS6DOF

    @classmethod
    def from_kwargs(
        cls,
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
        params: AUVParams | Mapping[str, Any] | None = None,
        start_position: Sequence[float] | None = None,
        start_heading: float | None = None,
        reward_weights: RewardWeights | dict | None = None,
        random_current: float | None = None,
        start_heading_spread: float = START_HEADING_SPREAD,
        start_rotation: float | Sequence[float] = 0.0,
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
    ) -> SimConfig:
        """Build from the environments' keyword arguments; see `AUVPath3DEnv` for their meaning
        and ranges. Bad input raises `ArgumentTypeError` (a TypeError) or ValueError, naming the
        argument, its value and the allowed range. ``disturbance="ocean"`` (or a dict with
        "preset": "ocean") fills the ocean's arguments left at None from
        `auv_gym.ocean.preset.OCEAN_PRESET`; ``noise_hold`` or the dict's NoiseConfig fields
        replace its noise only, and False switches off ``waves``, ``current_profile`` or
        ``surface_above_path`` (the surface at z = 0). ``vehicle`` (a shipped
        name, a ``.toml`` file, a mapping or a `Vehicle`; None: REMUS 100) gives the records that
        ``params``, ``actuator_params``, ``plant_params`` and ``sensors="vehicle"`` start from."""
        the_vehicle = load_vehicle(vehicle)
        ocean = OCEAN_PRESET if disturbance_preset(disturbance) == OCEAN_PRESET_NAME else None
        if ocean is not None:  # its parts left at None (its noise: `noise_from`)
            current = ocean.current if current is None else current
            random_current = ocean.random_current if random_current is None else random_current
            if param_uncertainty is None:
                param_uncertainty = ocean.param_uncertainty
            waves = ocean.waves if waves is None else waves
            current_profile = ocean.current_profile if current_profile is None else current_profile
        # False switches a part off, the ocean preset's too: no waves, no current profile, the
        # sea surface at z = 0
        surface_off = surface_above_path is False
        waves, current_profile, surface_above_path = (
            None if part is False else part for part in (waves, current_profile, surface_above_path)
        )
        if (
            ocean is not None
            and surface_above_path is None
            and not surface_off
            and depth_envelope in (None, False)
            and (waves is not None or current_profile is not None)  # what reads the surface
        ):
            surface_above_path = ocean.surface_above_path
        the_path = path_from(path)
        offset = (0.0, 0.0, 0.0)
        if path_offset is not None:
            offset = vector("path_offset", path_offset, 3, -POSITION_BOUND, POSITION_BOUND, "m")
        if isinstance(the_path, Path):
            the_path, offset = shift_path(the_path, offset), (0.0, 0.0, 0.0)
        s_end = the_path.s_end if isinstance(the_path, Path) else math.inf
        if plant_params is not None and plant == SIX_DOF_PLANT and the_vehicle.hull_5dof is None:
            # the derived 5-DOF record (gains, limits, bounds) is the flown hull's
            the_vehicle = dataclasses.replace(
                the_vehicle, hull_6dof=SixDofVehicle.from_record(plant_params)
            )
        hull = hull_from(the_vehicle, params)
        if isinstance(surge_limit, str):  # the one name: the vehicle record's top speed
            if surge_limit != VEHICLE_TOP_SPEED:
                raise ValueError(
                    f"surge_limit must be a speed in m/s, inf or {VEHICLE_TOP_SPEED!r}"
                    f" (params.max_surge), got {surge_limit!r:.80}"
                )
            surge_limit = hull.max_surge
            if is_real(u_desired) and not u_desired < surge_limit <= SPEED_BOUND:
                where = "params.max_surge"  # or the vehicle file's, unless params replace it
                if surge_limit == the_vehicle.max_surge:
                    where = f"{the_vehicle.source or the_vehicle.name}: [limits] max_surge"
                raise TopSpeedError(
                    f"surge_limit={VEHICLE_TOP_SPEED!r} is the vehicle's top speed ({where} = "
                    f"{surge_limit:g} m/s), which must be above u_desired = {u_desired:g} m/s "
                    f"and at most {SPEED_BOUND:g} m/s (the speed arguments' range); give this "
                    "env a surge_limit in m/s or inf, or a slower u_desired",
                    surge_limit,
                    u_desired,
                )
        elif not is_real(surge_limit):
            raise ArgumentTypeError(
                f"surge_limit must be a speed in m/s, inf or {VEHICLE_TOP_SPEED!r}"
                f" (params.max_surge), got {surge_limit!r:.80} ({type(surge_limit).__name__})"
            )
        if actuator_params is not None and actuator != "realistic":
            raise ValueError(
                f"actuator_params configure the propeller and fins of actuator='realistic'; "
                f"with actuator={actuator!r} they would do nothing: drop them or give "
                "actuator='realistic'"
            )
        if plant_params is not None and plant != SIX_DOF_PLANT:
            raise ValueError(
                f"plant_params describe the hull of plant={SIX_DOF_PLANT!r}; with plant="
                f"{plant!r:.40} they would do nothing: drop them or give plant={SIX_DOF_PLANT!r}"
            )
        if the_vehicle.hull_5dof is None and (plant, actuator) != (SIX_DOF_PLANT, "realistic"):
            raise ValueError(
                f"vehicle {the_vehicle.name!r} has no [model_5dof]: it flies on plant='6dof' "
                f"with actuator='realistic' only, got plant={plant!r:.20}, "
                f"actuator={actuator!r:.20}"
            )
        if isinstance(sensors, str) and sensors == "vehicle":
            sensors = the_vehicle.sensors
            try:  # the vehicle file's suite against this env's control period: name the file
                if is_real(control_dt) and control_dt > 0.0:
                    sensors.fix_steps(control_dt)
            except (TypeError, ValueError) as error:
                where = the_vehicle.source or f"vehicle {the_vehicle.name!r}"
                raise type(error)(f"{where}: [sensors] {error}") from None
        if plant == SIX_DOF_PLANT and plant_params is None:  # the vehicle's hull, not given
            _check_uncertainty_steps(the_vehicle.hull_6dof, physics_dt, param_uncertainty)
        noise = noise_from(disturbance, noise_hold)
        if not any(noise.amplitude):  # no noise: its hold and its amplitude's draw do nothing
            given = f"disturbance = {disturbance!r:.60} has no noise (every amplitude 0)"
            if noise_hold is not None:
                raise ValueError(
                    f"noise_hold = {noise_hold!r} s would hold nothing: {given}; drop it or "
                    "give the noise an amplitude"
                )
            if is_real(random_noise) and random_noise > 0.0:
                raise ValueError(
                    f"random_noise = {random_noise!r} scales the noise's amplitude per episode, "
                    f"and {given}; drop it or give the noise an amplitude"
                )
        return cls(
            vehicle=the_vehicle.name,
            plant=plant,
            plant_params=the_vehicle.hull_6dof
            if plant_params is None
            else SixDofVehicle.from_record(plant_params),
            path=the_path,
            params=hull,
            noise=noise,
            current=CurrentConfig.from_spec(current),
            param_uncertainty=0.0 if param_uncertainty is None else param_uncertainty,
            hull_variation=HullVariation.from_spec(hull_variation),
            actuator=actuator,
            actuator_params=actuators_from(the_vehicle, actuator_params),
            random_current=0.0 if random_current is None else random_current,
            random_noise=random_noise,
            control_dt=control_dt,
            physics_dt=physics_dt,
            max_time=max_time,
            u_desired=u_desired,
            sigma=sigma,
            virtual_point_law=virtual_point_law,
            randomize_start=randomize_start,
            start_heading_spread=start_heading_spread,
            start_rotation=start_rotation,
            start_position=start_position,
            start_heading=start_heading,
            reward=reward_from(reward_weights),
            limits=TaskLimits(
                corridor=corridor,
                max_pitch=max_pitch,
                s_end=s_end,
                surge_limit=surge_limit,
            ),
            observation=ObservationConfig.from_spec(observation),
            path_offset=offset,
            depth_envelope=DepthEnvelope.from_spec(depth_envelope),
            safety_cost=SafetyCost.from_spec(safety_cost),
            waves=WaveConfig.from_spec(waves),
            current_profile=CurrentProfile.from_spec(current_profile),
            sensors=SensorConfig.from_spec(sensors),
            surface_above_path=surface_above_path,
        )

    def __post_init__(self) -> None:
        def put(name: str, value: object) -> None:  # canonical value (float, tuple) of a field
            object.__setattr__(self, name, value)

        if not isinstance(self.path, PathDistribution):
            if not isinstance(self.path, Path):
                raise ArgumentTypeError(f"path must be a Path, got {self.path!r:.80}")
            self.path.check_kernel_data()
        for name, kind in (
            ("params", AUVParams),
            ("noise", NoiseConfig),
            ("current", CurrentConfig),
            ("reward", RewardWeights),
            ("limits", TaskLimits),
            ("actuator_params", ActuatorParams),
            ("observation", ObservationConfig),
            ("safety_cost", SafetyCost),
            ("sensors", SensorConfig),
            ("plant_params", SixDofVehicle),
            ("hull_variation", HullVariation),
        ):
            if not isinstance(getattr(self, name), kind):
                raise ArgumentTypeError(
                    f"{name} must be an {kind.__name__}, got {getattr(self, name)!r:.80}"
                )
        if not isinstance(self.depth_envelope, DepthEnvelope | None):
            raise ArgumentTypeError(
                f"depth_envelope must be a DepthEnvelope or None, got {self.depth_envelope!r:.80}"
            )
        put(
            "path_offset",
            vector("path_offset", self.path_offset, 3, -POSITION_BOUND, POSITION_BOUND, "m"),
        )
        if any(self.path_offset) and not isinstance(self.path, PathDistribution):
            raise ValueError(
                f"path_offset {self.path_offset} m moves drawn paths here; a fixed "
                "path is moved by from_kwargs (the env argument) or ShiftedPath"
            )
        for name, kind in (("waves", WaveConfig), ("current_profile", CurrentProfile)):
            if not isinstance(getattr(self, name), (kind, type(None))):
                raise ArgumentTypeError(
                    f"{name} must be None or a {kind.__name__}, got {getattr(self, name)!r:.80}"
                )
        if self.surface_above_path is not None:
            put(
                "surface_above_path",
                real(
                    "surface_above_path",
                    self.surface_above_path,
                    0.0,
                    MAX_SURFACE_ABOVE_PATH,
                    unit="m",
                ),
            )
            if self.depth_envelope is not None:
                raise ValueError(
                    "surface_above_path places the sea surface above a path whose z is a "
                    "reference height; with a depth_envelope z is a true depth and the surface "
                    "is z = 0: give one of them"
                )
        put("actuator", choice("actuator", self.actuator, [*ACTUATORS, "random"]))
        put("plant", choice("plant", self.plant, PLANTS))
        if not (isinstance(self.vehicle, str) and self.vehicle):
            raise ArgumentTypeError(f"vehicle must be a vehicle's name, got {self.vehicle!r:.80}")
        put(
            "random_current",
            real("random_current", self.random_current, 0.0, MAX_RANDOM_CURRENT, unit="m/s"),
        )
        put("random_noise", real("random_noise", self.random_noise, 0.0, MAX_RANDOM_NOISE))
        put(
            "virtual_point_law",
            choice("virtual_point_law", self.virtual_point_law, VIRTUAL_POINT_LAWS),
        )
        put(
            "param_uncertainty",
            real("param_uncertainty", self.param_uncertainty, 0.0, 1.0, high_open=True),
        )
        self.params.check_perturbation(self.param_uncertainty)  # every draw valid, or refused
        put("physics_dt", real("physics_dt", self.physics_dt, *PHYSICS_DT_RANGE, unit="s"))
        if self.plant == SIX_DOF_PLANT:  # a hull RK4 can step at physics_dt, every draw
            self.plant_params.check_step(self.physics_dt, self.param_uncertainty)
        six_dof_hull = self.plant_params if self.plant == SIX_DOF_PLANT else None
        self.hull_variation.check(
            self.params, six_dof_hull, self.physics_dt, self.param_uncertainty
        )
        most = MAX_SUBSTEPS * self.physics_dt
        put(
            "control_dt",
            real(
                "control_dt",
                self.control_dt,
                0.0,
                most,
                low_open=True,
                unit=f"s (<= {MAX_SUBSTEPS} physics steps)",
            ),
        )
        put(
            "max_time",
            real(
                "max_time",
                self.max_time,
                self.control_dt,
                MAX_EPISODE_TIME,
                unit="s (at least one control_dt)",
            ),
        )
        put(
            "u_desired",
            real(
                "u_desired",
                self.u_desired,
                0.0,
                SPEED_BOUND,
                low_open=True,
                unit="m/s, the observation's bound on u_D",
            ),
        )
        put("sigma", real("sigma", self.sigma, 0.0, math.inf, low_open=True, unit="m"))
        surge_limit = self.limits.surge_limit
        if not (self.u_desired < surge_limit <= SPEED_BOUND or surge_limit == math.inf):
            raise ValueError(
                f"surge_limit must be above u_desired = {self.u_desired} m/s and at most "
                f"{SPEED_BOUND} m/s, or inf, got {surge_limit!r} m/s"
            )
        self.sensors.fix_steps(self.control_dt)  # the fix interval: whole control steps
        if self.observation.history_steps:  # the history's interval: likewise
            self.observation.history_stride(self.control_dt)
        put("randomize_start", flag("randomize_start", self.randomize_start))
        put(
            "start_heading_spread",
            real("start_heading_spread", self.start_heading_spread, 0.0, math.pi, unit="rad"),
        )
        if not self.randomize_start and self.start_heading_spread != START_HEADING_SPREAD:
            raise ValueError(
                f"start_heading_spread = {self.start_heading_spread:g} rad sets the heading "
                "error of randomize_start's draws; with randomize_start=False it would do "
                "nothing: drop it or give randomize_start=True"
            )
        put("start_rotation", start_rotation_from(self.start_rotation))
        if self.start_position is not None:
            put(
                "start_position",
                vector(
                    "start_position", self.start_position, 3, -POSITION_BOUND, POSITION_BOUND, "m"
                ),
            )
        if self.start_heading is not None:
            put(
                "start_heading",
                real(
                    "start_heading",
                    self.start_heading,
                    -HEADING_BOUND,
                    HEADING_BOUND,
                    unit="rad (±2π)",
                ),
            )
        whole_steps("control_dt", self.control_dt, self.physics_dt, "physics_dt")
        if any(self.noise.amplitude):  # a noise to hold (none: its hold is never read)
            self._check_noise_hold()
        if isinstance(self.path, PathDistribution):
            # Generated paths start at the origin with a drawn heading: a fixed start would
            # be meaningless (docs/model.md §3.8); their turn rates (≤ 1/8 m) always fit.
            for name in ("start_position", "start_heading"):
                if getattr(self, name) is not None:
                    raise ValueError(
                        f"{name} cannot be given with a random path (path = "
                        "'random' or a PathDistribution): each episode starts at "
                        "its own path's default start"
                    )
        else:
            self._check_path_fits_the_observation()
            self._check_start_fits_the_observation()
            self.check_depths(self.path)
        check_below_the_surface(self)  # waves and a current profile act below it
        check_drawn_paths_fit(self)  # so that no reset is refused (`path_depths.draw_path`)

    def _check_noise_hold(self) -> None:
        """The white noise is held a whole number of physics steps; else a one-line error
        naming a hold that is one."""
        hold, dt = self.noise.hold, self.physics_dt
        try:
            whole_steps("noise hold", hold, dt, "physics_dt")
        except ValueError:
            fit = f"{max(1, round(hold / dt)) * dt:.12g}"
            raise ValueError(
                f"noise hold = {hold} s (noise_hold, else the hold of the NoiseConfig or of "
                f"disturbance's preset: 0.01 s, 'ocean' 1 s) must be a whole multiple of "
                f"physics_dt = {dt} s: give noise_hold = {fit} s, say (with a NoiseConfig or "
                "a disturbance dict: that hold)"
            ) from None

    def check_depths(self, path: Path, drawn: bool = False) -> None:
        """The path (a drawn one at its reset) and the start lie inside the depth envelope's
        safe band (`depth_envelope.check_path_depths`); nothing to check without one."""
        if self.depth_envelope is None:
            return
        given = self.start_position is not None and not drawn
        start = self.start_position if given else path.default_start()[0]
        check_path_depths(
            path,
            self.depth_envelope,
            start_z=float(start[2]),
            u_desired=self.u_desired,
            max_time=self.max_time,
            randomize_start=self.randomize_start,
            drawn=drawn,
        )

    @property
    def current_speed_bound(self) -> float:
        """Largest current speed [m/s] an episode can meet: per axis |mean| + the random current
        + 8 stationary standard deviations of the Gauss–Markov part (exceeded with probability
        about 1e-15 per draw), combined over the three axes."""
        axes = [
            abs(m) + self.random_current + 8.0 * s
            for m, s in zip(self.current.mean, self.current.std, strict=True)
        ]
        return math.sqrt(sum(a * a for a in axes))

    @property
    def randomized(self) -> bool:
        """True if episodes draw their own path, current, noise amplitude or actuator."""
        return (
            isinstance(self.path, PathDistribution)
            or self.random_current > 0.0
            or self.random_noise > 0.0
            or self.actuator == "random"
        )

    def _check_path_fits_the_observation(self) -> None:
        """ψ̇_F and θ̇_F stay within ±PATH_RATE_BOUND for every u_p <= 2 u_D: a proven bound
        on the whole path, so no start or s later in an episode can leave the bounds."""
        limit = PATH_RATE_BOUND / (2.0 * self.u_desired)
        bound = max(self.path.turn_rate_bounds(accept_below=limit), key=lambda b: b.upper)
        rate = bound.upper
        if rate > limit and 2.0 * self.u_desired * rate > PATH_RATE_BOUND:
            where = self.path.turn_location(bound)
            raise ValueError(
                f"path turns at up to {rate:.4g} rad/m{where}: with u_desired = "
                f"{self.u_desired} m/s the virtual point (u_p <= 2 u_D) turns at up to "
                f"{2.0 * self.u_desired * rate:.4g} rad/s, beyond the observation bound "
                f"{PATH_RATE_BOUND} rad/s; use u_desired <= {PATH_RATE_BOUND / (2 * rate):.4g} m/s "
                "or a gentler path (a waypoint path that nearly doubles back needs a turn "
                "waypoint beside the reversal)"
            )

    def _check_start_fits_the_observation(self) -> None:
        """The start's errors to p(0) lie within the observation's ±ERROR_BOUND."""
        p0 = self.path.evaluate(0.0)[0]
        given = self.start_position is not None
        start = np.asarray(self.start_position) if given else self.path.default_start()[0]
        distance = float(np.linalg.norm(start - p0))
        allowed = ERROR_BOUND - (START_JITTER if self.randomize_start else 0.0)
        if not distance <= allowed:
            name = "start_position" if given else "the path's default start"
            raise ValueError(
                f"{name} {tuple(start.tolist())} m is {distance:.4g} m from the path's start "
                f"p(0) = {tuple(p0.tolist())} m; the observation bounds the position errors to "
                f"±{ERROR_BOUND:g} m, so the start must lie within {allowed:.4g} m of p(0)"
                + (" (less the random offset of randomize_start)" if self.randomize_start else "")
            )

    @property
    def kernel_sigma(self) -> float:
        """σ as the kernels use it: u_D(1 + tanh(x_e/σ)) with σ < 0 gives the printed law."""
        return VIRTUAL_POINT_LAWS[self.virtual_point_law] * self.sigma

    @property
    def substeps(self) -> int:
        """Physics steps per control step."""
        return round(self.control_dt / self.physics_dt)

    @property
    def max_steps(self) -> int:
        """Control steps until truncation at `max_time`."""
        return math.ceil(self.max_time / self.control_dt - _SUBSTEP_TOL)

    def packed(self) -> np.ndarray:
        """The float64 row `period.advance_period` reads (layout `CONFIG_FIELDS`)."""
        gm_a, gm_b = gauss_markov_coefficients(self.current, self.physics_dt)
        values = {
            "n_sub": self.substeps,
            "physics_dt": self.physics_dt,
            # at least 1: a config without noise need not hold it a whole number of steps
            "hold_steps": max(1, round(self.noise.hold / self.physics_dt)),
            "u_d": self.u_desired,
            "sigma": self.kernel_sigma,
            "actuator": ACTUATORS.get(self.actuator, 0),  # "random": set per episode
            "gm_a": gm_a,
        }
        for c, name in enumerate(("f_u", "f_v", "f_w", "f_q", "f_r")):
            values[f"noise_{name}"] = self.noise.amplitude[c]
        for c, axis in enumerate("XMN"):
            values[f"limit_{axis}"] = self.params.actuator_limits[c]
        for c, axis in enumerate("xyz"):
            values[f"current_{axis}"] = self.current.mean[c]
            values[f"gm_b_{axis}"] = gm_b[c]
        values.update(self.actuator_params.packed(self.physics_dt))
        return np.array([float(values[name]) for name in CONFIG_FIELDS])


def _check_uncertainty_steps(hull: object, physics_dt: object, uncertainty: object) -> None:
    """A 6-DOF hull the env was not given (``plant_params`` None: the vehicle's) that RK4 at
    ``physics_dt`` steps as it is but not at the stiff end of ``uncertainty``'s draws
    (`SixDofVehicle.check_step`): a one-line error naming param_uncertainty, the largest that
    fits and the physics_dt that would step it. Anything else is left to `SimConfig`'s checks."""
    low, high = PHYSICS_DT_RANGE
    if not (
        isinstance(hull, SixDofVehicle)
        and is_real(physics_dt)
        and low <= physics_dt <= high
        and is_real(uncertainty)
        and 0.0 < uncertainty < 1.0
    ):
        return
    spread, dt = float(uncertainty), float(physics_dt)

    def steps(step: float, epsilon: float) -> bool:
        try:
            hull.check_step(step, epsilon)
        except ValueError:
            return False
        return True

    if steps(dt, spread) or not steps(dt, 0.0):  # fine, or the hull itself: its own error
        return
    fits, too_wide = 0.0, spread  # the widest spread RK4 can step (stiffer as it grows)
    short, long = low, dt  # the longest step that steps this spread
    for _ in range(60):
        middle = 0.5 * (fits + too_wide)
        fits, too_wide = (middle, too_wide) if steps(dt, middle) else (fits, middle)
        middle = math.sqrt(short * long)
        short, long = (middle, long) if steps(middle, spread) else (short, middle)
    shorter = f" or physics_dt <= {_round_down(short)} s" if steps(short, spread) else ""
    raise ValueError(
        f"param_uncertainty = {spread:.12g} draws 6-DOF hulls too stiff for RK4 at physics_dt = "
        f"{dt:g} s (the vehicle's damping time constants × (1 − {spread:.12g}) at the stiff end; "
        f"|λ|·dt <= {RK4_STEP_LIMIT:g}, docs/model.md §15.1): give param_uncertainty <= "
        f"{_round_down(fits)}{shorter}"
    )


def _round_down(value: float, digits: int = 3) -> str:
    """``value`` > 0 rounded down to ``digits`` significant digits, as typed."""
    if value <= 0.0:
        return "0"
    scale = 10.0 ** (digits - 1 - math.floor(math.log10(value)))
    return f"{math.floor(value * scale) / scale:.{digits}g}"


# The env's keyword arguments: what `gym.make`, a scenario's or task set's ``env`` table and a
# rollout's ``env_kwargs`` may set.
ENV_KEYWORDS = tuple(inspect.signature(SimConfig.from_kwargs).parameters)


def config_from_kwargs(env_kwargs: Mapping[str, Any]) -> SimConfig:
    """`SimConfig.from_kwargs` of ``env_kwargs``, an unknown keyword (a typo in a file's ``env``
    table, say) refused by a ValueError that lists the valid ones."""
    unknown = sorted(set(env_kwargs) - set(ENV_KEYWORDS))
    if unknown:
        raise ValueError(f"unknown env keyword arguments {unknown}; valid: {sorted(ENV_KEYWORDS)}")
    return SimConfig.from_kwargs(**env_kwargs)
