"""Latency of one control step, batch 1: each reference agent's ONNX export against its torch
policy.

    python -m benchmarks.speed.onnx [--steps 3000]      (auv-gym speed onnx)
    python -m benchmarks.speed.onnx --agent runs/x/ensemble3 --onnx out/x3.onnx

For each agent, one closed-loop episode of its own env records the observations the vehicle
gives it; both policies (`controllers.make("onnx")`, onnxruntime on one thread, and
`controllers.make("agent")`, torch on one thread) then predict them one at a time, interleaved
call by call so that the machine's load falls on both alike. Printed: the median and the 99th
percentile of the wall time per call [µs], the whole `predict` (normalisation, network, stages;
the residual agent's base controller too, which both run in numpy). ``--agent FOLDER --onnx
FILE`` times one agent (or ensemble, docs/design.md §3.23) and its export instead of the
reference agents.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import controllers
from auv_gym.rollout import rollouts
from benchmarks.arguments import parse_options, program_name
from benchmarks.catalog.policies import AGENTS_DIR, REFERENCE_AGENTS
from benchmarks.options import option

__all__ = ["latencies", "main"]


class Recorder:
    """A policy that records the observations it is given before its own ``policy`` acts."""

    def __init__(self, policy: Any) -> None:
        self.policy = policy
        self.env_kwargs = policy.env_kwargs
        self.seen: list[np.ndarray] = []

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        self.seen.append(np.array(observation, dtype=np.float32, copy=True))
        return self.policy.predict(observation, state, episode_start, deterministic)


def observations(agent: Path, steps: int) -> np.ndarray:
    """(steps, d) observations of one episode of the agent in folder ``agent`` in its own env
    (seed 0; repeated when the episode is shorter)."""
    recorder = Recorder(controllers.make("agent", path=str(agent)))
    rollouts(recorder, [0], max_time=min(steps * 0.05, 600.0))
    obs = np.concatenate([np.atleast_2d(o) for o in recorder.seen])
    return np.resize(obs, (steps, obs.shape[1]))


def latencies(agent: Path, onnx_file: Path, steps: int) -> dict[str, dict[str, float]]:
    """Per-call wall times [µs] of the agent in folder ``agent`` and its export ``onnx_file``
    over ``steps`` observations: median and p99."""
    obs = observations(agent, steps)
    policies = {
        "onnx": controllers.make("onnx", path=str(onnx_file)),
        "torch": controllers.make("agent", path=str(agent), num_threads=1),
    }
    times: dict[str, list[float]] = {name: [] for name in policies}
    states: dict[str, Any] = dict.fromkeys(policies)
    start = np.array([True])
    for k in range(steps + 50):  # the first 50 calls warm up
        for name, policy in policies.items():
            tic = time.perf_counter()
            _, states[name] = policy.predict(obs[k % steps], states[name], start)
            if k >= 50:
                times[name].append(time.perf_counter() - tic)
        start = np.array([False])
    return {
        name: {
            "median_us": 1e6 * float(np.median(t)),
            "p99_us": 1e6 * float(np.percentile(t, 99)),
        }
        for name, t in times.items()
    }


@dataclass
class Options:
    """The command line of `auv-gym speed onnx`."""

    steps: int = option(3000, "timed calls per policy and agent")
    agent: str = option("", "an agent or ensemble folder to time instead of the reference agents")
    onnx: str = option("", "its export (.onnx), with --agent")


def main(argv: list[str] | None = None) -> dict[str, Any]:
    args, parser = parse_options(Options, argv, program_name("benchmarks.speed.onnx"), __doc__)
    if not 100 <= args.steps <= 1_000_000:
        parser.error(f"--steps must be in [100, 1000000], got {args.steps}")
    if bool(args.agent) != bool(args.onnx):
        parser.error("--agent and --onnx go together (an agent folder and its export)")
    pairs = {
        agent: (AGENTS_DIR / agent, AGENTS_DIR / agent / "policy.onnx")
        for agent in REFERENCE_AGENTS
    }
    if args.agent:
        for path in (Path(args.agent), Path(args.onnx)):
            if not path.exists():
                parser.error(f"{path} does not exist")
        pairs = {Path(args.agent).name: (Path(args.agent), Path(args.onnx))}
    print("\nLatency per control step, batch 1, one thread [µs]: ONNX runtime vs torch policy")
    width = max(len(agent) for agent in pairs)
    print(
        f"{'agent':<{width}} {'onnx median':>12} {'onnx p99':>10} {'torch median':>13} "
        f"{'torch p99':>10} {'speed-up':>9}"
    )
    results = {}
    for agent, (folder, onnx_file) in pairs.items():
        out = latencies(folder, onnx_file, args.steps)
        results[agent] = out
        onnx, torch = out["onnx"], out["torch"]
        print(
            f"{agent:<{width}} {onnx['median_us']:>12.0f} {onnx['p99_us']:>10.0f} "
            f"{torch['median_us']:>13.0f} {torch['p99_us']:>10.0f} "
            f"{torch['median_us'] / onnx['median_us']:>8.1f}×"
        )
    return results


if __name__ == "__main__":
    main()
