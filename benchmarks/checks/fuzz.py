"""Long fuzz run of the vector env: random valid configurations, random and extreme actions.

    python -m benchmarks.fuzz                          # 10^7 vehicle-steps (a few minutes)
    python -m benchmarks.fuzz --steps 1e6 --seed 3     # a shorter run with another seed

Each configuration is drawn across the documented argument space of `AUVPath3DEnv` (paths of
every kind and scale: helices, lines, waypoint splines, out-and-back lines with or without a
turn, user curves fitted by `fit_curve`, "random" and random `PathDistribution` configurations;
the v0, speed-limited and preview envs; RK4 steps 1 µs–0.1 s with 1–10 000 physics steps
per control step (half of the configurations 1–10), noise, currents, random currents and
noise, parameter uncertainty up to the limit of a vehicle with positive added mass, all
actuator models, random or far starts, every reward weight, …) and runs a batch of vehicles
(`AUVPath3DVectorEnv`, SAME_STEP autoreset) through several episodes. Actions mix uniform
[−1, 1], saturating [−3, 3], the corners ±1, zeros, huge finite values up to ±1.8e308 and
denormals. Every control step is checked for the invariants of tests/test_properties.py; the
counts are printed with a one-line verdict, and the exit code is 1 if any invariant was violated:

- NaN observations: a non-finite value in a returned observation (or final observation);
- non-finite rewards;
- exceptions: any exception from building, resetting or stepping a valid configuration;
- wrong truncations: `truncated` not exactly at the first control step with t >= max_time;
- out-of-space observations: outside `observation_space` without a failure termination
  (corridor, pitch, envelope, non_finite), a reset observation outside it;
- unknown reasons: `terminated` without a documented reason, or a reason without `terminated`;
- inconsistent infos: ``info["_final_obs"]`` not marking exactly the finished vehicles.

A draw that a constructor refuses with a named error (waypoints that double back, a curve that
stops, a parameter range that could draw an invalid vehicle) is counted as refused, not run.

Physics work per configuration is bounded (`--physics-budget`), so configurations with many
physics steps per control step contribute fewer control steps.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from auv_gym import PREVIEW_ENV_ID, SPEED_LIMIT_ENV_ID, VARIANTS
from auv_gym.config import MAX_SUBSTEPS, PHYSICS_DT_RANGE, SimConfig, path_turn_rates
from auv_gym.disturbances import (
    MAX_CURRENT_SPEED,
    MAX_CURRENT_TIME_CONSTANT,
    MAX_NOISE_AMPLITUDE,
    CurrentConfig,
    NoiseConfig,
)
from auv_gym.observation import ERROR_BOUND, PATH_RATE_BOUND, SPEED_BOUND
from auv_gym.path_generator import (
    FAMILIES,
    LENGTH_RANGE,
    MAX_FLIGHT_PATH_ANGLE_DEG,
    MIN_TURN_RADIUS,
    PathDistribution,
)
from auv_gym.paths import POSITION_BOUND, Helix, Path, Spline, StraightLine, fit_curve, make_path
from auv_gym.randomization import MAX_RANDOM_CURRENT, MAX_RANDOM_NOISE
from auv_gym.task import MAX_REWARD_WEIGHT, MIN_CORRIDOR, REWARD_TERMS, TERMINATION_REASONS
from auv_gym.vehicle import remus100
from benchmarks.arguments import ArgumentParser, finite_number, usage_errors

FAILURES = frozenset({"corridor", "pitch", "envelope", "non_finite"})  # may leave the space
COUNTERS = ("nan_observations", "non_finite_rewards", "exceptions", "wrong_truncations",
            "out_of_space_observations", "unknown_reasons", "inconsistent_infos")  # fmt: skip
EPISODE_PHYSICS = 20_000  # physics steps per episode at most: an episode stays in milliseconds
# A vehicle reset (a new episode drawn in Python, `Simulator.reset_rows`: 0.1-0.3 ms) costs
# about as much as this many physics steps: configurations whose episodes end at once (a
# corridor narrower than the start's distance) stop early instead of spending the run on resets.
RESET_WORK = 1000
# A reset that draws a spline from a PathDistribution costs milliseconds (a dense solve per
# drawn spline and its proven bounds): counted as this many physics steps.
RANDOM_PATH_RESET_WORK = 50_000
RANDOM_PATH_VEHICLES = 32  # vehicles per configuration with a PathDistribution, at most
VARIANT_IDS = ("AUVPath3D-v0", SPEED_LIMIT_ENV_ID, PREVIEW_ENV_ID)  # the envs fuzzed
RANDOM_START_REACH = 2.0 * math.sqrt(3.0)  # [m] the largest random start offset (±2 m per axis)


@dataclass
class Tally:
    """What the run saw: vehicle-steps, episodes, configurations and the violation counters."""

    steps: int = 0
    episodes: int = 0
    configurations: int = 0
    refused: int = 0  # draws a constructor refused with a named error (not violations)
    reasons: dict[str, int] = field(default_factory=dict)
    counts: dict[str, int] = field(default_factory=lambda: dict.fromkeys(COUNTERS, 0))
    examples: list[str] = field(default_factory=list)  # the first few violations, reproducible

    def violation(self, kind: str, number: int, where: str) -> None:
        if number:
            self.counts[kind] += int(number)
            if len(self.examples) < 5:
                self.examples.append(f"{kind} ×{number}: {where}")

    @property
    def violations(self) -> int:
        return sum(self.counts.values())


def log_uniform(rng: np.random.Generator, low: float, high: float) -> float:
    """A number spread evenly in log10 over [low, high]; the bounds themselves one time in 8."""
    if rng.random() < 0.125:
        return float(rng.choice([low, high]))
    return float(min(max(10.0 ** rng.uniform(math.log10(low), math.log10(high)), low), high))


PATH_KINDS = ("helix", "line", "waypoints", "Helix", "StraightLine", "Spline", "Reversal",
              "FittedCurve", "random", "PathDistribution")  # fmt: skip


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
        length=round(float(rng.uniform(*LENGTH_RANGE)), 1) if rng.random() < 0.7
        else round(float(rng.uniform(50.0, 400.0)), 1),
    )  # fmt: skip


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
        return Spline([(0.0, 0.0, 0.0), (length, 0.0, 0.0), *turn,
                       (float(rng.uniform(-length, length)), 2.0 * offset, 0.0)])  # fmt: skip
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
    kw.update(physics_dt=physics_dt, control_dt=control_dt,
              max_time=control_dt * (n_steps - 1 + fraction))  # fmt: skip
    hold = int(rng.integers(1, 1001)) * physics_dt
    amplitude = 0.0 if rng.random() < 0.2 else log_uniform(rng, 1e-3, MAX_NOISE_AMPLITUDE)
    noise = int(rng.integers(4))
    if noise == 0:
        kw["disturbance"] = "paper"
    elif noise == 1:
        kw["disturbance"] = "none"
    elif noise == 2:
        kw.update(disturbance=amplitude, noise_hold=hold)
    else:
        kw["disturbance"] = NoiseConfig((amplitude,) * 5, hold)
    if "noise_hold" not in kw and not isinstance(kw["disturbance"], NoiseConfig):
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
    kw["actuator"] = str(rng.choice(["paper", "fins", "random"]))
    kw["randomize_start"] = bool(rng.random() < 0.5)
    if rng.random() < 0.25:
        kw["random_current"] = float(rng.uniform(0.0, MAX_RANDOM_CURRENT))
    if rng.random() < 0.25:
        kw["random_noise"] = float(rng.uniform(0.0, MAX_RANDOM_NOISE))
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
    if "surge_limit" in kw:  # u_desired < surge_limit
        u_max = min(u_max, kw["surge_limit"] * (1.0 - 1e-9))
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
    return kw, n_steps


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


def fuzz_configuration(
    kw: dict[str, Any],
    n_steps: int,
    n_vehicles: int,
    control_steps: int,
    work_budget: float,
    rng: np.random.Generator,
    tally: Tally,
    where: str,
) -> None:
    """Run ``n_vehicles`` of one configuration for ``control_steps`` control steps (SAME_STEP
    autoresets), or until their work (physics vehicle-steps + `RESET_WORK` per reset) reaches
    ``work_budget``, checking every step; add what happened to ``tally``."""
    from auv_gym.vector_env import AUVPath3DVectorEnv

    tally.configurations += 1
    try:
        env = AUVPath3DVectorEnv(n_vehicles, autoreset_mode="SameStep", threads=1, **kw)
        obs, _ = env.reset(seed=int(rng.integers(2**31)))
    except Exception as error:  # a valid configuration must build and reset
        tally.violation("exceptions", 1, f"{where}: {type(error).__name__}: {error}")
        return
    tally.violation("nan_observations", int((~np.isfinite(obs)).any(axis=1).sum()), where)
    low, high = env.single_observation_space.low, env.single_observation_space.high
    outside = ~((obs >= low) & (obs <= high)).all(axis=1)
    tally.violation("out_of_space_observations", int(outside.sum()), f"reset, {where}")
    reset_work = RANDOM_PATH_RESET_WORK if env.config.randomized else RESET_WORK
    count = np.zeros(n_vehicles, dtype=np.int64)  # control steps since each vehicle's reset
    documented = set(TERMINATION_REASONS[1:])
    substeps = env.config.substeps
    work = 0.0
    for _ in range(control_steps):
        if work >= work_budget:
            break
        actions = draw_actions(rng, n_vehicles)
        try:
            obs, reward, terminated, truncated, info = env.step(actions)
        except Exception as error:
            tally.violation("exceptions", 1, f"step, {where}: {type(error).__name__}: {error}")
            return
        count += 1
        tally.steps += n_vehicles
        done = terminated | truncated
        work += n_vehicles * substeps + reset_work * int(done.sum())
        # Returned rows are the stepped vehicles' observations (not terminated: must be inside
        # the space) and, for finished ones, their reset observations (inside as well).
        tally.violation("nan_observations", int((~np.isfinite(obs)).any(axis=1).sum()), where)
        tally.violation("non_finite_rewards", int((~np.isfinite(reward)).sum()), where)
        outside = ~((obs >= low) & (obs <= high)).all(axis=1)
        tally.violation("out_of_space_observations", int(outside.sum()), where)
        wrong = truncated != (count == n_steps)
        tally.violation("wrong_truncations", int(wrong.sum()), f"{where}, steps {count[wrong]}")
        finished = info.get("_final_obs", np.zeros(n_vehicles, dtype=bool))
        tally.violation("inconsistent_infos", int((finished != done).sum()), where)
        if not finished.any():
            continue
        rows = np.flatnonzero(finished)
        final_obs = np.stack(list(info["final_obs"][rows]))
        given = info["final_info"].get("termination_reason")  # absent when none terminated
        reasons = ["" if given is None else given[i] or "" for i in rows]
        ended = terminated[rows]
        unknown = [(t and r not in documented) or (not t and r != "")
                   for t, r in zip(ended, reasons, strict=True)]  # fmt: skip
        tally.violation("unknown_reasons", sum(unknown), f"{where}, reasons {reasons}")
        tally.violation("nan_observations", int((~np.isfinite(final_obs)).any(axis=1).sum()),
                        f"final observation, {where}")  # fmt: skip
        inside = ((final_obs >= low) & (final_obs <= high)).all(axis=1)
        excused = np.array([t and r in FAILURES for t, r in zip(ended, reasons, strict=True)])
        tally.violation("out_of_space_observations", int((~inside & ~excused).sum()),
                        f"final observation, {where}")  # fmt: skip
        for r in reasons:
            key = r or "time_limit"
            tally.reasons[key] = tally.reasons.get(key, 0) + 1
        tally.episodes += len(rows)
        count[rows] = 0


def run(
    total_steps: int,
    seed: int = 0,
    physics_budget: int = 2_000_000,
    max_vehicles: int = 512,
    max_episode_steps: int = 1000,
    progress: bool = True,
) -> Tally:
    """Fuzz configurations until ``total_steps`` vehicle-steps (control steps) have run.

    A configuration with ``substeps`` physics steps per control step gets episodes of at most
    `EPISODE_PHYSICS` physics steps and about ``physics_budget`` physics vehicle-steps in all
    (`fuzz_configuration`; one vehicle at least).
    """
    from tqdm.auto import tqdm

    tally = Tally()
    bar = tqdm(total=total_steps, unit="veh-step", unit_scale=True, disable=not progress,
               desc="fuzz")  # fmt: skip
    while tally.steps < total_steps:
        index = tally.configurations
        rng = np.random.default_rng([seed, index])  # each configuration reproducible alone
        try:
            kw, n_steps = draw_config(rng, max_episode_steps)
            SimConfig.from_kwargs(**kw)
        except ValueError:  # a named refusal of an invalid draw (ArgumentTypeError too)
            tally.configurations += 1
            tally.refused += 1
            continue
        substeps = round(kw["control_dt"] / kw["physics_dt"])
        control_steps = 3 * n_steps + 3  # through at least three episodes per vehicle
        n_vehicles = int(np.clip(physics_budget // (control_steps * substeps), 1, max_vehicles))
        if isinstance(kw["path"], PathDistribution) or kw["path"] == "random":
            n_vehicles = min(n_vehicles, RANDOM_PATH_VEHICLES)  # resets of up to 0.2 s each
        before = tally.steps
        where = f"--seed {seed}, configuration {index}: {_brief(kw)}"
        fuzz_configuration(kw, n_steps, n_vehicles, control_steps, physics_budget, rng, tally,
                           where)  # fmt: skip
        bar.update(tally.steps - before)
        bar.set_postfix(configs=tally.configurations, violations=tally.violations, refresh=False)
    bar.close()
    return tally


def _brief(kw: dict[str, Any]) -> str:
    text = ", ".join(f"{k}={v!r}" for k, v in kw.items() if k != "params")
    return text if len(text) <= 400 else text[:397] + "..."


def report(tally: Tally, seconds: float) -> str:
    """The counts, the termination reasons, the first violations and a one-line verdict."""
    rate = tally.steps / max(seconds, 1e-9)
    lines = [
        f"vehicle-steps:             {tally.steps:,}",
        f"episodes:                  {tally.episodes:,}",
        f"configurations:            {tally.configurations:,} ({tally.refused:,} refused at "
        "construction with a named error)",
        f"NaN observations:          {tally.counts['nan_observations']}",
        f"non-finite rewards:        {tally.counts['non_finite_rewards']}",
        f"exceptions:                {tally.counts['exceptions']}",
        f"wrong truncations:         {tally.counts['wrong_truncations']}",
        f"out-of-space observations: {tally.counts['out_of_space_observations']}",
        f"unknown reasons:           {tally.counts['unknown_reasons']}",
        f"inconsistent infos:        {tally.counts['inconsistent_infos']}",
        "episode ends:              "
        + ", ".join(f"{k} {v:,}" for k, v in sorted(tally.reasons.items())),
        f"wall time:                 {seconds:.0f} s ({rate:,.0f} vehicle-steps/s)",
    ]
    lines += [f"  {example}" for example in tally.examples]
    verdict = (
        f"verdict: PASS - {tally.steps:,} fuzzed vehicle-steps, {tally.episodes:,} episodes, "
        "0 violations"
        if tally.violations == 0
        else f"verdict: FAIL - {tally.violations} violations in {tally.steps:,} vehicle-steps"
    )
    return "\n".join([*lines, verdict])


def main(argv: Sequence[str] | None = None) -> Tally:
    parser = ArgumentParser(
        prog="python -m benchmarks.fuzz",
        description=__doc__.split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--steps", type=float, default=1e7,
                        help="vehicle-steps to run, >= 1 (default 1e7)")  # fmt: skip
    parser.add_argument("--seed", type=int, default=0, help="seed of the fuzz (default 0)")
    parser.add_argument("--physics-budget", type=float, default=2e6,
                        help="physics vehicle-steps per configuration (default 2e6)")  # fmt: skip
    parser.add_argument("--max-vehicles", type=int, default=512,
                        help="vehicles per configuration, at most (default 512)")  # fmt: skip
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    with usage_errors(parser):
        finite_number("--steps", args.steps, 1.0, 1e12)
        finite_number("--physics-budget", args.physics_budget, 1e3, 1e10)
        if args.seed < 0:
            raise ValueError(f"--seed must be non-negative, got {args.seed}")
        if not 1 <= args.max_vehicles <= 65_536:
            raise ValueError(f"--max-vehicles must be in [1, 65536], got {args.max_vehicles}")
    start = time.perf_counter()
    tally = run(int(args.steps), args.seed, int(args.physics_budget), args.max_vehicles,
                progress=not args.quiet)  # fmt: skip
    print(report(tally, time.perf_counter() - start))
    if tally.violations:
        sys.exit(1)
    return tally


if __name__ == "__main__":
    main()
