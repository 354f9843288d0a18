"""How far the navigation estimate is from the truth on the as-built scenarios: the Kalman filter
beside dead reckoning (docs/model.md §14.8).

    python -m benchmarks.analysis.navigation_error [--seeds 10] [--policy pid_as_built]
        [--out benchmarks/results/as_built/navigation.md]

Each scenario is flown by one classical policy (closed loop on the estimate it navigates by),
once with the scenario's "typical_kalman" suite and once with the same suite dead-reckoning
between fixes ("typical"); seeds 0..N−1 (the test seeds of the scenarios). The horizontal
position error |p̂ − p| [m] is reported as its RMS and its largest value over t ≥ 100 s (the
metrics window) and over the whole episode, with the ratio filter / dead reckoning.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import controllers
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.support.files import write_json, write_text
from benchmarks.arguments import parse_options, program_name
from benchmarks.catalog.scenarios import load_scenarios
from benchmarks.options import option

SCENARIOS = ("as_built_helix", "as_built_survey", "as_built_coastal")
MODES = {"kalman": "typical_kalman", "dead_reckoning": "typical"}
WINDOW_START = 100.0  # [s] as the benchmark metrics


def position_errors(
    scenario: str, sensors: str, seeds: int, policy: str, duration: float
) -> np.ndarray:
    """|p̂ − p| [m] of vehicles seeded 0..seeds−1, shape (steps, seeds)."""
    spec = load_scenarios()[scenario]
    env_kwargs = {**spec.env, "sensors": sensors, "max_time": duration}
    env = AUVPath3DVectorEnv(seeds, **env_kwargs)
    controller = controllers.make(policy, **spec.controller)
    obs, _ = env.reset(seed=0)
    state, start = None, np.ones(seeds, dtype=bool)
    errors = []
    for _ in range(env.config.max_steps):
        action, state = controller.predict(obs, state=state, episode_start=start)
        start = np.zeros(seeds, dtype=bool)
        obs, _, terminated, truncated, _ = env.step(action)
        estimate, truth = env.sim.navigation.estimate, env.sim.state
        errors.append(np.hypot(estimate[:, 0] - truth[:, 0], estimate[:, 1] - truth[:, 1]))
        if (terminated | truncated).any():  # every vehicle truncates at max_time together
            if terminated.any():
                raise RuntimeError(f"{policy} failed on {scenario}: navigation error undefined")
            break
    return np.array(errors)


@dataclass
class Options:
    """The command line of `python -m benchmarks.analysis.navigation_error`."""

    seeds: int = option(10, "episodes per scenario (seeds 0..N−1)")
    policy: str = option("pid_as_built", "classical policy that flies the scenarios")
    duration: float = option(300.0, "episode length [s]")
    out: str = option("benchmarks/results/as_built/navigation.md", "markdown table (and .json)")


def main(argv: list[str] | None = None) -> dict:
    args, _ = parse_options(
        Options, argv, program_name("benchmarks.analysis.navigation_error"), __doc__
    )
    rows, lines = [], []
    lines.append(
        "| scenario | navigation | RMS after 100 s [m] | worst after 100 s [m] | "
        "worst, whole episode [m] |"
    )
    lines.append("|---|---|---:|---:|---:|")
    for scenario in SCENARIOS:
        result = {}
        for mode, sensors in MODES.items():
            errors = position_errors(scenario, sensors, args.seeds, args.policy, args.duration)
            window = errors[int(WINDOW_START / 0.05) :]
            result[mode] = {
                "rms_window": math.sqrt(float(np.mean(window**2))),
                "worst_window": float(window.max()),
                "worst": float(errors.max()),
            }
            r = result[mode]
            lines.append(
                f"| `{scenario}` | {mode.replace('_', ' ')} | {r['rms_window']:.3f} | "
                f"{r['worst_window']:.3f} | {r['worst']:.3f} |"
            )
            print(lines[-1], flush=True)
        ratio = result["kalman"]["rms_window"] / result["dead_reckoning"]["rms_window"]
        rows.append({"scenario": scenario, **result, "rms_ratio": ratio})
    lines.append("")
    lines.append(
        "RMS ratio filter / dead reckoning (target ≤ 0.5): "
        + ", ".join(f"`{r['scenario']}` {r['rms_ratio']:.2f}" for r in rows)
    )
    header = (
        f"# Navigation error on the as-built scenarios\n\n`python -m "
        f"benchmarks.analysis.navigation_error --seeds {args.seeds} --policy {args.policy}`: "
        f"horizontal position error |p̂ − p| of the navigation estimate, seeds 0–"
        f"{args.seeds - 1}, {args.duration:g}-s episodes flown by `{args.policy}` on the "
        "estimate (docs/model.md §14.8).\n\n"
    )
    write_text(args.out, header + "\n".join(lines) + "\n")
    write_json(args.out.removesuffix(".md") + ".json", {"policy": args.policy, "rows": rows})
    return {"rows": rows}


if __name__ == "__main__":
    main()
