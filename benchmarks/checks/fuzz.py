"""Long fuzz run of the vector env: random valid configurations, random and extreme actions.

    python -m benchmarks.checks.fuzz                          # 10^7 vehicle-steps (a few minutes)
    python -m benchmarks.checks.fuzz --steps 1e6 --seed 3     # a shorter run with another seed

Each configuration is drawn across the documented argument space of `AUVPath3DEnv` (paths of
every kind and scale: helices, lines, waypoint splines, out-and-back lines with or without a
turn, user curves fitted by `fit_curve`, "random" and random `PathDistribution` configurations;
the v0, speed-limited and preview envs; RK4 steps 1 µs–0.1 s with 1–10 000 physics steps
per control step (half of the configurations 1–10), noise, currents, random currents and
noise, parameter uncertainty up to the limit of a vehicle with positive added mass, all
actuator models, random or far starts, every reward weight, …) and runs a batch of vehicles
(`AUVPath3DVectorEnv`, SAME_STEP autoreset) through several episodes. Actions mix uniform
[−1, 1], saturating [−3, 3], the corners ±1, zeros, huge finite values up to ±1.8e308 and
denormals (clipped to [−1, 1] for the realistic actuators, which refuse anything outside it).
Every control step is checked for the invariants of tests/test_properties.py; the counts are
printed with a one-line verdict, and the exit code is 1 if any invariant was violated:

- NaN observations: a non-finite value in a returned observation (or final observation);
- non-finite rewards;
- exceptions: any exception from building, resetting or stepping a valid configuration;
- wrong truncations: `truncated` not exactly at the first control step with t >= max_time;
- out-of-space observations: outside `observation_space` without a failure termination
  (`FAILURE_REASONS`: corridor, pitch, envelope, overspeed, broached, grounded, non_finite), a
  reset observation outside it;
- unknown reasons: `terminated` without a documented reason, or a reason without `terminated`;
- inconsistent infos: ``info["_final_obs"]`` not marking exactly the finished vehicles.

A draw that a constructor refuses with a named error (waypoints that double back, a curve that
stops, a parameter range that could draw an invalid vehicle) is counted as refused, not run.

Physics work per configuration is bounded (`--physics-budget`), so configurations with many
physics steps per control step contribute fewer control steps.
"""

from __future__ import annotations

import functools
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from auv_gym.sim.config import SimConfig
from auv_gym.sim.path_generator import PathDistribution
from auv_gym.sim.task import TERMINATION_REASONS
from auv_gym.sim.trajectory import FAILURE_REASONS
from benchmarks.arguments import finite_number, parse_options, program_name, usage_errors
from benchmarks.catalog.policies import AGENTS_DIR
from benchmarks.checks.fuzz_draws import EPISODE_PHYSICS, draw_actions, draw_config
from benchmarks.options import option

__all__ = [
    "EPISODE_PHYSICS",
    "FuzzOptions",
    "Tally",
    "draw_actions",
    "draw_config",
    "fuzz_configuration",
    "main",
    "report",
    "run",
]

# Failure ends may leave the observation space in their last step (a corridor, pitch, depth or
# speed limit crossed within one control period, which may be long): every documented failure.
FAILURES = FAILURE_REASONS
COUNTERS = (
    "nan_observations",
    "non_finite_rewards",
    "exceptions",
    "wrong_truncations",
    "out_of_space_observations",
    "unknown_reasons",
    "inconsistent_infos",
)
# A vehicle reset (a new episode drawn in Python, `Simulator.reset_rows`: 0.1-0.3 ms) costs
# about as much as this many physics steps: configurations whose episodes end at once (a
# corridor narrower than the start's distance) stop early instead of spending the run on resets.
RESET_WORK = 1000
# A reset that draws a spline from a PathDistribution costs milliseconds (a dense solve per
# drawn spline and its proven bounds): counted as this many physics steps.
RANDOM_PATH_RESET_WORK = 50_000
RANDOM_PATH_VEHICLES = 32  # vehicles per configuration with a PathDistribution, at most
EXPORT_SHARE = 0.3  # configurations flown by a fitting shipped ONNX export, when one fits


@dataclass
class Tally:
    """What the run saw: vehicle-steps, episodes, configurations and the violation counters."""

    steps: int = 0
    episodes: int = 0
    configurations: int = 0
    refused: int = 0  # draws a constructor refused with a named error (not violations)
    export_steps: int = 0  # vehicle-steps whose commands came from a shipped ONNX export
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


@dataclass
class FuzzOptions:
    """The options of ``python -m benchmarks.checks.fuzz`` (`run`'s arguments)."""

    steps: float = option(1e7, "vehicle-steps to run, >= 1")
    seed: int = option(0, "seed of the fuzz")
    physics_budget: float = option(2e6, "physics vehicle-steps per configuration")
    max_vehicles: int = option(512, "vehicles per configuration, at most")
    progress: bool = option(True, "no progress bar", flag="--quiet", invert=True)

    def check(self) -> None:
        """ValueError naming the option that is out of its range."""
        finite_number("--steps", self.steps, 1.0, 1e12)
        finite_number("--physics-budget", self.physics_budget, 1e3, 1e10)
        if self.seed < 0:
            raise ValueError(f"--seed must be non-negative, got {self.seed}")
        if not 1 <= self.max_vehicles <= 65_536:
            raise ValueError(f"--max-vehicles must be in [1, 65536], got {self.max_vehicles}")


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
    from auv_gym.envs.vector_env import AUVPath3DVectorEnv

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
    exported = fitting_export(env, rng) if rng.random() < EXPORT_SHARE else None
    state = None
    reset_work = RANDOM_PATH_RESET_WORK if env.config.randomized else RESET_WORK
    count = np.zeros(n_vehicles, dtype=np.int64)  # control steps since each vehicle's reset
    documented = set(TERMINATION_REASONS[1:])
    substeps = env.config.substeps
    work = 0.0
    for _ in range(control_steps):
        if work >= work_budget:
            break
        try:
            # a non-finite observation is counted above; the export would refuse it (a test)
            if exported is None or not np.isfinite(obs).all():
                actions = draw_actions(rng, n_vehicles)
                if env.config.actuator == "realistic":  # it refuses commands outside [-1, 1]
                    actions = np.clip(actions, -1.0, 1.0)
            else:  # the export path: the graph, its state and its output checks, every step
                actions, state = exported.predict(obs, state, episode_start=count == 0)
                tally.export_steps += n_vehicles
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
        unknown = [
            (t and r not in documented) or (not t and r != "")
            for t, r in zip(ended, reasons, strict=True)
        ]
        tally.violation("unknown_reasons", sum(unknown), f"{where}, reasons {reasons}")
        tally.violation(
            "nan_observations",
            int((~np.isfinite(final_obs)).any(axis=1).sum()),
            f"final observation, {where}",
        )
        inside = ((final_obs >= low) & (final_obs <= high)).all(axis=1)
        excused = np.array([t and r in FAILURES for t, r in zip(ended, reasons, strict=True)])
        tally.violation(
            "out_of_space_observations",
            int((~inside & ~excused).sum()),
            f"final observation, {where}",
        )
        for r in reasons:
            key = r or "time_limit"
            tally.reasons[key] = tally.reasons.get(key, 0) + 1
        tally.episodes += len(rows)
        count[rows] = 0


def fitting_export(env: Any, rng: np.random.Generator) -> Any:
    """A shipped agent's ONNX export (`controllers.onnx_policy.OnnxPolicy`) that takes this
    env's observation and was built for its actuator, drawn at random; None when none fits or
    onnxruntime is not installed."""
    fitting = _fitting_exports(tuple(env.config.observation.names), env.config.actuator)
    return fitting[int(rng.integers(len(fitting)))] if fitting else None


@functools.cache
def _fitting_exports(names: tuple[str, ...], actuator: str) -> tuple[Any, ...]:
    try:
        import controllers
        from controllers.onnx_policy import onnxruntime_module

        onnxruntime_module("fuzz")
    except ImportError:
        return ()
    fitting = []
    for path in sorted(AGENTS_DIR.glob("*/policy.onnx")):
        try:
            policy = controllers.make(
                "onnx", path=str(path), observation_names=names, actuator=actuator
            )
        except ValueError:  # another observation or actuator: refused, as it should be
            continue
        if policy.base is None:  # a residual agent's base is built for its own scenario
            fitting.append(policy)
    return tuple(fitting)


def run(
    total_steps: int,
    seed: int = 0,
    physics_budget: int = int(FuzzOptions.physics_budget),
    max_vehicles: int = FuzzOptions.max_vehicles,
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
    bar = tqdm(
        total=total_steps, unit="veh-step", unit_scale=True, disable=not progress, desc="fuzz"
    )
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
        fuzz_configuration(
            kw, n_steps, n_vehicles, control_steps, physics_budget, rng, tally, where
        )
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
        f"of them from ONNX exports: {tally.export_steps:,}",
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
    args, parser = parse_options(
        FuzzOptions, argv, program_name("benchmarks.checks.fuzz"), __doc__.split("\n\n")[0]
    )
    with usage_errors(parser):
        args.check()
    start = time.perf_counter()
    tally = run(
        int(args.steps),
        args.seed,
        int(args.physics_budget),
        args.max_vehicles,
        progress=args.progress,
    )
    print(report(tally, time.perf_counter() - start))
    if tally.violations:
        sys.exit(1)
    return tally


if __name__ == "__main__":
    main()
