"""First rung of the off-policy ladder: how far the controllers' commands reach, and how long an
episode of uniformly random actions lasts inside a box of action bounds.

    python -m benchmarks.analysis.action_bounds [--episodes 32] [--duration 100] [--out FILE.json]

SAC explores with a squashed Gaussian over its whole action box from the first step. In this
env a random full-scale surge thrust and pitch/yaw moment ends an episode early (corridor, pitch
or the surge limit), so the replay buffer starts with crashes only. This prints, on the
validation episodes of the training distribution under AUVPath3DPreview-v0 (paper actuators, so
that the classical controllers' commands mean the same forces):

1. percentiles of |a_X|, |a_M|, |a_N| commanded by FBSM + CO-LOS (saturated to 1), the reach
   a bound must keep;
2. for each box of bounds, the episodes of uniformly random actions inside it: mean length,
   the fraction that reach the time limit, and the ending reasons.

The boxes compared: the whole actuator box, ±(99th percentile) rounded up to 0.05, and that box
with the surge thrust centred on the median command (the cruise thrust). An off-policy config
sets its box with the ``action_bounds`` key of its RL-Zoo file (`benchmarks.training.config`).
"""

from __future__ import annotations

import collections
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from tqdm import tqdm

import controllers
from auv_gym import PREVIEW_ENV_ID, VARIANTS
from auv_gym.rollout import rollouts
from auv_gym.support.files import write_json
from benchmarks.arguments import parse_options, program_name
from benchmarks.catalog.tasks import task_set
from benchmarks.options import option

PERCENTILES = (50.0, 95.0, 99.0, 99.9)
AXES = ("a_X", "a_M", "a_N")


Box = tuple[tuple[float, float, float], tuple[float, float, float]]  # (low, high) per axis


class UniformPolicy:
    """Uniform random actions in [low, high] per axis, seeded: the exploration of an untrained
    squashed-Gaussian agent whose action box is ``box``."""

    def __init__(self, box: Box, seed: int = 0) -> None:
        self.low, self.high = (np.asarray(b, dtype=np.float64) for b in box)
        self.rng = np.random.default_rng(seed)

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        n = np.asarray(observation).shape[0]
        return self.rng.uniform(self.low, self.high, size=(n, 3)), state


def command_percentiles(env_kwargs: dict[str, Any], seeds: list[int]) -> dict[str, list[float]]:
    """Percentiles (`PERCENTILES`) of FBSM + CO-LOS's saturated |commands| per axis."""
    policy = controllers.make("fbsm_colos", env=env_kwargs)
    trajectories = rollouts(policy, seeds, **env_kwargs)
    actions = np.concatenate([np.clip(np.abs(t.actions), 0.0, 1.0) for t in trajectories])
    return {
        axis: np.percentile(actions[:, j], PERCENTILES).round(4).tolist()
        for j, axis in enumerate(AXES)
    }


def random_episodes(env_kwargs: dict[str, Any], seeds: list[int], box: Box) -> dict[str, Any]:
    """Length [s] and endings of uniformly random episodes inside ``box``."""
    trajectories = rollouts(UniformPolicy(box), seeds, **env_kwargs)
    durations = np.array([t.duration for t in trajectories])
    endings = collections.Counter(t.termination_reason for t in trajectories)
    return {
        "low": list(box[0]),
        "high": list(box[1]),
        "mean_duration_s": float(durations.mean()),
        "median_duration_s": float(np.median(durations)),
        "time_limit_fraction": float(
            np.mean([t.termination_reason == "time_limit" for t in trajectories])
        ),
        "endings": dict(sorted(endings.items())),
    }


def reach(percentiles: dict[str, list[float]], level: float = 99.0) -> tuple[float, ...]:
    """The ``level`` percentile of each axis rounded up to 0.05 (at most 1)."""
    j = PERCENTILES.index(level)
    return tuple(min(1.0, math.ceil(p[j] / 0.05 - 1e-9) * 0.05) for p in percentiles.values())


def boxes(percentiles: dict[str, list[float]]) -> dict[str, Box]:
    """The boxes compared: the whole actuator box; ±(the 99th percentile); and that box with the
    surge thrust shifted to centre on the median command (the cruise thrust), whose midpoint —
    an untrained squashed Gaussian's mean action — then holds the speed instead of idling."""
    b = reach(percentiles)
    cruise = percentiles["a_X"][PERCENTILES.index(50.0)]
    low_x = round(-b[0] + cruise, 3)
    return {
        "full": ((-1.0, -1.0, -1.0), (1.0, 1.0, 1.0)),
        "p99": ((-b[0], -b[1], -b[2]), b),
        "p99, cruise-centred": ((low_x, -b[1], -b[2]), (round(b[0] + cruise, 3), b[1], b[2])),
    }


@dataclass
class Options:
    """The options of ``python -m benchmarks.analysis.action_bounds``."""

    episodes: int = option(32, "validation episodes")
    duration: float = option(100.0, "episode length [s]")
    out: str | None = option(None, "write the figures to this JSON file")


def main(argv: list[str] | None = None) -> None:
    args, parser = parse_options(
        Options, argv, program_name("benchmarks.analysis.action_bounds"), __doc__
    )
    if args.episodes < 1 or not args.duration > 0:
        parser.error("--episodes must be >= 1 and --duration > 0")
    validation = task_set("validation_paper_actuator")
    env_kwargs = {**VARIANTS[PREVIEW_ENV_ID], **validation.env, "max_time": args.duration}
    seeds = list(validation.seeds)[: args.episodes]
    steps = tqdm(total=4, desc="action bounds", unit="run")
    percentiles = command_percentiles(env_kwargs, seeds)
    steps.update()
    compared = boxes(percentiles)
    random_runs = {}
    for name, box in compared.items():
        random_runs[name] = random_episodes(env_kwargs, seeds, box)
        steps.update()
    steps.close()
    print(
        f"\nFBSM + CO-LOS |commands| on {len(seeds)} validation episodes of "
        f"{args.duration:g} s ({PREVIEW_ENV_ID}, paper actuators)"
    )
    print("axis  " + "  ".join(f"p{p:g}".rjust(7) for p in PERCENTILES))
    for axis, values in percentiles.items():
        print(f"{axis:5} " + "  ".join(f"{v:7.3f}" for v in values))
    print("\nuniformly random actions in a box (low..high per axis X, M, N)")
    print("box                   a_X          mean length  median  reach the limit  endings")
    for name, run in random_runs.items():
        x = f"{run['low'][0]:.3g}..{run['high'][0]:.3g}"
        print(
            f"{name:21} {x:12} {run['mean_duration_s']:9.1f} s {run['median_duration_s']:6.1f} s "
            f"{100 * run['time_limit_fraction']:14.0f} %  {run['endings']}"
        )
    if args.out:
        write_json(
            args.out,
            {
                "episodes": len(seeds),
                "duration_s": args.duration,
                "env_id": PREVIEW_ENV_ID,
                "command_percentiles": percentiles,
                "percentiles": list(PERCENTILES),
                "random": random_runs,
            },
            indent=2,
        )


if __name__ == "__main__":
    main()
