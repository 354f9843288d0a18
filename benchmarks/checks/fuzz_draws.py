"""The draws of the fuzz run (`benchmarks.checks.fuzz`): a random valid configuration of the
vector env across its documented argument space (paths of every kind, envs, integration steps,
disturbances, uncertainty, actuators, starts, reward weights; the depth envelope, waves, current
profile, navigation suite, agent observation and safety cost) and random and extreme actions."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from auv_gym import PREVIEW_ENV_ID, SPEED_LIMIT_ENV_ID, VARIANTS
from auv_gym.ocean.disturbances import (
    MAX_CURRENT_SPEED,
    MAX_CURRENT_TIME_CONSTANT,
    MAX_NOISE_AMPLITUDE,
    CurrentConfig,
    NoiseConfig,
)
from auv_gym.ocean.waves import MAX_HEIGHT, MAX_STEEPNESS, PERIOD_RANGE, peak_wavelength
from auv_gym.paths.shapes import (
    POSITION_BOUND,
    Helix,
    Path,
    Spline,
    StraightLine,
    fit_curve,
    make_path,
)
from auv_gym.sim.config import MAX_SUBSTEPS, PHYSICS_DT_RANGE, path_turn_rates
from auv_gym.sim.observation import ERROR_BOUND, PATH_RATE_BOUND, SPEED_BOUND
from auv_gym.sim.path_generator import (
    FAMILIES,
    LENGTH_RANGE,
    MAX_FLIGHT_PATH_ANGLE_DEG,
    MIN_TURN_RADIUS,
    PathDistribution,
)
from auv_gym.sim.randomization import MAX_RANDOM_CURRENT, MAX_RANDOM_NOISE
from auv_gym.sim.task import MAX_REWARD_WEIGHT, MIN_CORRIDOR, REWARD_TERMS, VEHICLE_TOP_SPEED
from auv_gym.vehicle import remus100
from auv_gym.vehicle.remus6dof import REMUS6DOF
from auv_gym.vehicle.sensors import MAX_FILTER_NOISE, MAX_FIX_INTERVAL, MIN_FILTER_NOISE

EPISODE_PHYSICS = 20_000  # physics steps per episode at most: an episode stays in milliseconds
VARIANT_IDS = ("AUVPath3D-v0", SPEED_LIMIT_ENV_ID, PREVIEW_ENV_ID)  # the envs fuzzed
PLANT_SHARE = 0.3  # configurations on Fossen's 6-DOF plant
TORPEDO_SHARE = 0.3  # of those, the torpedo vehicle file
FILTER_SETTINGS = (
    "filter_velocity_noise",
    "filter_bias_noise",
    "filter_initial_scale",
    "filter_initial_heading",
)
RANDOM_START_REACH = 2.0 * math.sqrt(3.0)  # [m] the largest random start offset (±2 m per axis)

__all__ = [
    "EPISODE_PHYSICS",
    "PATH_KINDS",
    "RANDOM_START_REACH",
    "VARIANT_IDS",
    "draw_actions",
    "draw_config",
    "draw_curve",
    "draw_distribution",
    "draw_ocean",
    "draw_path",
    "log_uniform",
]


def log_uniform(rng: np.random.Generator, low: float, high: float) -> float:
    """A number spread evenly in log10 over [low, high]; the bounds themselves one time in 8."""
    if rng.random() < 0.125:
        return float(rng.choice([low, high]))
    return float(min(max(10.0 ** rng.uniform(math.log10(low), math.log10(high)), low), high))


PATH_KINDS = (
    "helix",
    "line",
    "waypoints",
    "Helix",
    "StraightLine",
    "Spline",
    "Reversal",
    "FittedCurve",
    "random",
    "PathDistribution",
)


def draw_distribution(rng: np.random.Generator) -> PathDistribution:
    """A `PathDistribution` anywhere in its documented ranges (narrow ranges included: they
    draw the same track shape every time)."""

    def span(low: float, high: float, log: bool = False) -> tuple[float, float]:
        a = log_uniform(rng, low, high) if log else float(rng.uniform(low, high))
        if rng.random() < 0.3:
            return a, a
        b = log_uniform(rng, low, high) if log else float(rng.uniform(low, high))
        return min(a, b), max(a, b)

    families = [f for f in FAMILIES if rng.random() < 0.5] or [str(rng.choice(FAMILIES))]
    return PathDistribution(
        families=tuple(families),
        radius=span(MIN_TURN_RADIUS, 1e4, log=True),
        climb_angle_deg=span(0.0, MAX_FLIGHT_PATH_ANGLE_DEG),
        piece_length=span(20.0, 1000.0, log=True),
        leg_length=span(20.0, 1000.0, log=True),
        length=round(float(rng.uniform(*LENGTH_RANGE)), 1)
        if rng.random() < 0.7
        else round(float(rng.uniform(50.0, 400.0)), 1),
    )


def draw_curve(rng: np.random.Generator) -> Path:
    """A user's curve p(s) fitted by `fit_curve` (raises ValueError if it refuses it)."""
    shape = int(rng.integers(3))
    a, b, c = (log_uniform(rng, 0.1, 100.0) for _ in range(3))
    k = log_uniform(rng, 1e-3, 1.0)
    s_end = log_uniform(rng, 1.0, 2000.0)
    if shape == 0:  # a helix with an arbitrary parameterisation speed

        def curve(s: float) -> tuple[float, float, float]:
            return a * math.cos(k * s), a * math.sin(k * s), -b * k * s
    elif shape == 1:  # a sinusoidal track

        def curve(s: float) -> tuple[float, float, float]:
            return s, a * math.sin(k * s), c * math.cos(0.5 * k * s)
    else:  # a Lissajous figure: may stop or double back, then refused

        def curve(s: float) -> tuple[float, float, float]:
            return a * math.sin(k * s), b * math.sin(2 * k * s + 0.3), c * math.sin(3 * k * s)

    return fit_curve(curve, s_end, tolerance=log_uniform(rng, 1e-3, 1.0))


def draw_path(rng: np.random.Generator) -> Any:
    """A path argument of any kind; ValueError when the kind's constructor refuses the draw
    (waypoints that double back, a curve that stops): `run` counts those as refused."""
    kind = str(rng.choice(PATH_KINDS))
    if kind in ("helix", "line", "waypoints", "random"):
        return kind
    if kind == "PathDistribution":
        return draw_distribution(rng)
    if kind == "FittedCurve":
        return draw_curve(rng)
    if kind == "Reversal":  # an out-and-back line, optionally with a turn at the far end
        length = log_uniform(rng, 1.0, 1000.0)
        offset = 0.0 if rng.random() < 0.3 else log_uniform(rng, 1e-4, length)
        turn = [(length + offset, offset, 0.0)] if rng.random() < 0.5 else []
        return Spline(
            [
                (0.0, 0.0, 0.0),
                (length, 0.0, 0.0),
                *turn,
                (float(rng.uniform(-length, length)), 2.0 * offset, 0.0),
            ]
        )
    end = math.inf if rng.random() < 0.5 else log_uniform(rng, 1e-3, 1e4)
    if kind == "Helix":
        radius, omega = log_uniform(rng, 1e-3, 1e5), log_uniform(rng, 1e-4, 1e3)
        climb = float(rng.uniform(-1e3, 1e3))
        if math.hypot(radius * omega, climb) < 1e-5:  # below the documented |p'| >= 1e-6
            climb = 1.0
        center = tuple(rng.uniform(-POSITION_BOUND, POSITION_BOUND, 3))
        return Helix(radius, omega, climb, center, s_end=end)
    if kind == "StraightLine":
        direction = rng.uniform(-1.0, 1.0, 3)
        while np.linalg.norm(direction) <= 1e-3:
            direction = rng.uniform(-1.0, 1.0, 3)
        start = tuple(rng.uniform(-POSITION_BOUND, POSITION_BOUND, 3))
        return StraightLine(start=start, direction=tuple(direction), length=end)
    n = int(rng.integers(2, 9))
    origin = rng.uniform(-POSITION_BOUND / 2, POSITION_BOUND / 2, 3)
    steps = rng.uniform(-1.0, 1.0, (n - 1, 3))
    steps[:, 0] = np.abs(steps[:, 0]) + 0.05  # distinct consecutive waypoints
    scale = log_uniform(rng, 0.1, 1e3)
    return Spline(origin + scale * np.vstack([np.zeros(3), np.cumsum(steps, axis=0)]))


def draw_config(rng: np.random.Generator, max_episode_steps: int) -> tuple[dict[str, Any], int]:
    """Valid keyword arguments of `AUVPath3DEnv` across the documented ranges, and the number of
    control steps to max_time, at most ``max_episode_steps`` and `EPISODE_PHYSICS` physics
    steps (the space of tests/test_properties.py's `env_kwargs`)."""
    kw: dict[str, Any] = {"path": draw_path(rng)}
    physics_dt = log_uniform(rng, *PHYSICS_DT_RANGE)
    # Half the configurations near the default (5 physics steps per control step), half over
    # the whole range: the long run then spends its physics on many control steps.
    few = rng.random() < 0.5
    substeps = int(rng.integers(1, 11)) if few else int(log_uniform(rng, 1, MAX_SUBSTEPS))
    control_dt = substeps * physics_dt
    n_steps = int(rng.integers(1, max(1, min(max_episode_steps, EPISODE_PHYSICS // substeps)) + 1))
    fraction = 1.0 if n_steps == 1 or rng.random() < 0.25 else float(rng.uniform(0.01, 1.0))
    kw.update(
        physics_dt=physics_dt, control_dt=control_dt, max_time=control_dt * (n_steps - 1 + fraction)
    )
    hold = int(rng.integers(1, 1001)) * physics_dt
    amplitude = 0.0 if rng.random() < 0.2 else log_uniform(rng, 1e-3, MAX_NOISE_AMPLITUDE)
    noise = int(rng.integers(4))
    if noise == 0:
        kw["disturbance"] = "paper"
    elif noise == 1:
        kw["disturbance"] = "none"
    elif noise == 2:
        kw["disturbance"] = amplitude
        if amplitude > 0.0:  # a hold without noise is refused: it would hold nothing
            kw["noise_hold"] = hold
    else:
        kw["disturbance"] = NoiseConfig((amplitude,) * 5, hold)
    silent = kw["disturbance"] == "none" or kw["disturbance"] == 0.0
    if "noise_hold" not in kw and not isinstance(kw["disturbance"], NoiseConfig) and not silent:
        ratio = 0.01 / physics_dt
        if abs(ratio - round(ratio)) >= 1e-9 * ratio or physics_dt > 0.01:
            kw["noise_hold"] = hold  # the default hold 0.01 s is no whole number of RK4 steps
    if rng.random() < 0.5:
        kw["current"] = CurrentConfig(
            mean=tuple(rng.uniform(-MAX_CURRENT_SPEED, MAX_CURRENT_SPEED, 3)),
            std=tuple(rng.uniform(0.0, MAX_CURRENT_SPEED, 3)),
            time_constant=log_uniform(rng, 1e-3, MAX_CURRENT_TIME_CONSTANT),
        )
    kw["param_uncertainty"] = 0.0 if rng.random() < 0.5 else float(rng.uniform(0.0, 0.999))
    kw["actuator"] = str(rng.choice(["paper", "fins", "random", "realistic"]))
    kw["randomize_start"] = bool(rng.random() < 0.5)
    if rng.random() < 0.25:
        kw["random_current"] = float(rng.uniform(0.0, MAX_RANDOM_CURRENT))
    if rng.random() < 0.25:
        scale = float(rng.uniform(0.0, MAX_RANDOM_NOISE))
        silent = silent or (isinstance(kw["disturbance"], NoiseConfig) and amplitude == 0.0)
        if not silent:  # the amplitude's per-episode scale: refused without noise
            kw["random_noise"] = scale
    variant = str(rng.choice(list(VARIANT_IDS)))
    kw.update(VARIANTS[variant])
    random_path = isinstance(kw["path"], PathDistribution) or kw["path"] == "random"
    if random_path:  # drawn paths turn within MAX_TURN_RATE: any u_desired fits
        turn = 0.0
    else:
        path = make_path(kw["path"])
        turn = max(path_turn_rates(path))
    u_max = SPEED_BOUND if turn == 0 else min(SPEED_BOUND, PATH_RATE_BOUND / (2 * turn))
    u_max *= 1 - 1e-12  # the env's check 2·u·turn <= bound must not fail by one rounding
    if "surge_limit" in kw:  # u_desired < surge_limit; every drawn vehicle keeps REMUS's top speed
        limit = kw["surge_limit"]
        limit = remus100().max_surge if limit == VEHICLE_TOP_SPEED else limit
        u_max = min(u_max, limit * (1.0 - 1e-9))
    kw["u_desired"] = u_max * (1.0 if rng.random() < 0.2 else log_uniform(rng, 1e-4, 1.0))
    kw["sigma"] = log_uniform(rng, 1e-6, 1e6)
    kw["virtual_point_law"] = str(rng.choice(["corrected", "printed"]))
    kw["corridor"] = log_uniform(rng, MIN_CORRIDOR, ERROR_BOUND)
    kw["max_pitch"] = float(rng.uniform(0.01, math.pi / 2 - 1e-6))
    if rng.random() < 0.5:
        kw["reward_weights"] = {
            t: 0.0 if rng.random() < 0.2 else log_uniform(rng, 1e-6, MAX_REWARD_WEIGHT)
            for t in REWARD_TERMS
        }
    if rng.random() < 0.5 and not random_path:
        kw["start_heading"] = float(rng.uniform(-2 * math.pi, 2 * math.pi))
    if rng.random() < 0.5 and not random_path:  # anywhere the errors stay observable
        offset = rng.uniform(-1.0, 1.0, 3)
        reach = ERROR_BOUND - RANDOM_START_REACH - 1e-6
        distance = rng.uniform(0.0, reach)
        start = path.evaluate(0.0)[0] + offset / max(np.linalg.norm(offset), 1e-9) * distance
        if np.abs(start).max() <= POSITION_BOUND:
            kw["start_position"] = tuple(float(x) for x in start)
    choice = rng.random()
    if choice < 0.4:
        kw["params"] = remus100().perturbed(rng, 0.5)
    elif choice < 0.6:  # a positive added mass: param_uncertainty up to its documented limit
        m = remus100().m
        added = float(rng.uniform(0.0, 0.99 * m))
        kw["params"] = {"X_udot": added, "Y_vdot": float(rng.uniform(-50.0, 0.99 * m))}
        limit = min(m / max(added, kw["params"]["Y_vdot"]) - 1.0, 0.999)
        kw["param_uncertainty"] = float(rng.uniform(0.0, limit)) * (1.0 - 1e-9)
    if rng.random() < 0.5:
        draw_ocean(rng, kw)
    if rng.random() < PLANT_SHARE:
        draw_plant(rng, kw)
    return kw, n_steps


def draw_plant(rng: np.random.Generator, kw: dict[str, Any]) -> None:
    """Fossen's 6-DOF plant (docs/model.md §15): the REMUS 100's hull, a hull drawn around it
    (size, centre of gravity, time constants, damping ratios) or the torpedo vehicle file (its
    own hull, four fins and propeller, docs/vehicles.md). A drawn hull that RK4 cannot step at
    the drawn physics_dt is refused at construction (`SixDofVehicle.check_step`) and counted so."""
    kw["plant"] = "6dof"
    if rng.random() < TORPEDO_SHARE:  # a vehicle without a 5-DOF model flies only as built
        kw.update(vehicle="torpedo", actuator="realistic")
        kw.pop("params", None)
        return
    if rng.random() < 0.5:
        kw["plant_params"] = dataclasses.replace(  # a hull around the REMUS 100's
            REMUS6DOF,
            **{
                "length": 1.6 * log_uniform(rng, 0.5, 2.0),
                "diameter": 0.19 * log_uniform(rng, 0.5, 2.0),
                "r_bg": (0.0, 0.0, float(rng.uniform(0.005, 0.05))),
                "surge_time_constant": log_uniform(rng, 5.0, 60.0),
                "sway_time_constant": log_uniform(rng, 5.0, 60.0),
                "heave_time_constant": log_uniform(rng, 5.0, 60.0),
                "yaw_time_constant": log_uniform(rng, 0.3, 3.0),
                "roll_damping_ratio": float(rng.uniform(0.1, 1.0)),
                "pitch_damping_ratio": float(rng.uniform(0.3, 1.5)),
            },
        )


def draw_ocean(rng: np.random.Generator, kw: dict[str, Any]) -> None:
    """The options of the vehicle as built and its ocean, each on or off, valid for the drawn
    configuration: for a drawn path, a depth deep enough for its whole episode (it starts at the
    offset, its start 8 ± 8 m lower, and climbs at most its largest flight-path angle over
    u_desired·max_time) with a depth envelope below it, waves (sea states or any sea below the
    breaking steepness) and a current profile; for every path without a depth envelope a sea
    surface above it (waves, sometimes the whole ocean preset); the typical navigation suite
    with fixes every whole number of control periods (or none), dead-reckoning or filtered, the
    agent observation with integrals and the safety cost."""
    distribution = kw["path"]
    if distribution == "random":
        distribution = PathDistribution()
    if isinstance(distribution, PathDistribution):
        climb = math.radians(distribution.climb_angle_deg[1] + 0.5)
        reach = kw["u_desired"] * kw["max_time"] * math.sin(climb) + 16.0  # [m] up or down
        margin = float(rng.uniform(0.1, 5.0))
        depth = reach + margin + float(rng.uniform(0.0, 100.0))
        kw["path_offset"] = (0.0, 0.0, depth)
        if rng.random() < 0.5:
            kw["depth_envelope"] = {
                "seabed_depth": depth + reach + margin + float(rng.uniform(0.1, 200.0)),
                "margin": margin,
            }
        if rng.random() < 0.5:
            if rng.random() < 0.5:
                kw["waves"] = f"sea_state_{int(rng.integers(3, 6))}"
            else:
                period = float(rng.uniform(*PERIOD_RANGE))
                highest = min(MAX_HEIGHT, MAX_STEEPNESS * peak_wavelength(period))
                kw["waves"] = {
                    "significant_height": float(rng.uniform(0.01, highest)),
                    "peak_period": period,
                    "components": int(rng.integers(1, 65)),
                    "spreading": float(rng.uniform(0.0, 100.0)),
                    "direction": float(rng.uniform(-math.pi, math.pi)),
                }
        if rng.random() < 0.4:
            kw["current_profile"] = {
                "surface_speed": float(rng.uniform(0.0, 1.0)),
                "reference_depth": float(rng.uniform(1.0, 500.0)),
                "reference_speed": float(rng.uniform(0.0, 0.5)),
                "exponent": float(rng.uniform(0.05, 1.0)),
                "direction": float(rng.uniform(-math.pi, math.pi)),
                "drift_amplitude": float(rng.uniform(0.0, 1.0)),
                "drift_period": float(log_uniform(rng, 10.0, 1e4)),
            }
    if "depth_envelope" not in kw and rng.random() < 0.3:  # a sea surface above any path
        kw["surface_above_path"] = float(rng.uniform(0.5, 50.0))
        kw.setdefault("waves", "sea_state_3")
        ratio = 1.0 / kw["physics_dt"]  # the ocean preset's noise is held 1 s
        if rng.random() < 0.5 and abs(ratio - round(ratio)) < 1e-9 * ratio:
            kw["disturbance"] = "ocean"
            kw.pop("noise_hold", None)
    if rng.random() < 0.4:  # the typical suite, with fixes every whole number of periods
        periods = int(rng.integers(1, max(2, int(MAX_FIX_INTERVAL / kw["control_dt"]))))
        fix = None if rng.random() < 0.2 else min(periods * kw["control_dt"], MAX_FIX_INTERVAL)
        kalman = fix is not None and rng.random() < 0.5  # the filter needs fixes
        kw["sensors"] = {
            "preset": "typical",
            "fix_interval": fix,
            "navigation": "kalman" if kalman else "dead_reckoning",
        }
        if kalman and rng.random() < 0.5:  # the filter's assumed errors, its whole range
            for name in FILTER_SETTINGS:
                if rng.random() < 0.5:
                    kw["sensors"][name] = log_uniform(rng, MIN_FILTER_NOISE, MAX_FILTER_NOISE)
    if rng.random() < 0.3 and kw.get("observation") is None:
        kw["observation"] = "preview_integral"
    if rng.random() < 0.3:
        kw["safety_cost"] = {}


def draw_actions(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 3) actions: per vehicle one of uniform [−1, 1], saturating [−3, 3], corners ±1,
    zeros, huge finite (|a| up to the float64 maximum) or denormal magnitudes."""
    kind = rng.choice(6, size=(n, 1), p=[0.4, 0.2, 0.2, 0.05, 0.1, 0.05])
    sign = rng.choice([-1.0, 1.0], size=(n, 3))
    largest = np.finfo(np.float64).max
    huge = np.where(rng.random((n, 3)) < 0.1, largest, 10.0 ** rng.uniform(0.0, 308.0, (n, 3)))
    options = (
        rng.uniform(-1.0, 1.0, (n, 3)),
        rng.uniform(-3.0, 3.0, (n, 3)),
        sign,
        np.zeros((n, 3)),
        sign * huge,
        sign * 5e-324 * rng.integers(1, 1000, (n, 3)),
    )
    return np.choose(kind, options)
