"""Where a policy holds the path: its steady error on the paper's helix, and how stiffly.

For each policy, on the paper's helix (start, path and 300-s episodes of the paper scenario):

    calm      no disturbance, seed 0: the mean of x_e, y_e, z_e over t ≥ `transient` [m] (a
              static policy's offset is constant there: its standard deviation is 0)
    noisy     the paper's white noise, seeds 0…n−1: mean and standard deviation of the errors
              over the window, RMS distance, failures
    max pitch the largest |θ| over all episodes [deg] (the episode ends beyond 60°)
    stiffness with ``--bias b``: the calm run again with b added to the normalised pitch
              command; Δz̄_e / b [m per unit command] says how far the policy lets a constant
              pitch moment push it (a controller with integral action: 0)
    surge     with ``--surge-bias b``: the calm run again with b added to the normalised thrust
              command; Δū / b [m/s per unit command] and Δx̄_e / b [m per unit command]. A
              policy that flies a wrong speed because its thrust is mis-calibrated moves with
              the bias; one whose feedback holds u at a set-point of its own hardly does (the
              gen. 4 agents: 1.03-1.07 m/s; docs/results.md, "The along-track phase")

Each policy runs under the benchmark's env id for it (`benchmarks.catalog.policies`): an agent
under the env its metadata names (its observation and surge limit), a classical controller
under ``AUVPath3D-v0`` (docs/results.md, "Where the remaining error sits").

    python -m benchmarks.analysis.steady_offset \\
        --policies fbsm,net256=benchmarks/agents/ppo_preview_net256 --seeds 4 --bias 0.05 \\
        --surge-bias 0.05
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from auv_gym.files import write_json
from auv_gym.table_format import markdown_table
from auv_gym.trajectory import FAILURE_REASONS
from benchmarks.arguments import parse_options, program_name, usage_errors, writable_location
from benchmarks.catalog.policies import (
    AGENT_PREFIX,
    build_policy,
    check_policy_spec,
    policy_env_id,
)
from benchmarks.options import option

ERRORS = ("x_e", "y_e", "z_e")


PITCH, SURGE = 1, 0  # action channels: (X, M, N) normalised


class CommandBias:
    """``policy`` with a constant ``bias`` added to one normalised command (saturated)."""

    def __init__(self, policy: Any, bias: float, channel: int = PITCH) -> None:
        self.policy, self.bias, self.channel = policy, np.float32(bias), channel

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        action, state = self.policy.predict(observation, state, episode_start, deterministic)
        action = np.array(action, dtype=np.float32, copy=True)
        action[..., self.channel] = np.clip(action[..., self.channel] + self.bias, -1.0, 1.0)
        return action, state


def policy_and_env(text: str) -> tuple[str, Any, dict[str, Any]]:
    """(label, policy, env keyword arguments) of ``label=agent-folder`` or a benchmark policy
    spec (`benchmarks.catalog.policies`), run under its env id (an agent's training env)."""
    from auv_gym import VARIANTS

    label, _, path = text.partition("=")
    spec = f"{AGENT_PREFIX}{path}" if path else label
    check_policy_spec(spec)
    env_kwargs = dict(VARIANTS[policy_env_id(spec)])
    return label, build_policy(spec, env_kwargs), env_kwargs


def measure(
    policy: Any,
    env_kwargs: dict[str, Any],
    seeds: int,
    transient: float,
    bias: float | None,
    surge_bias: float | None = None,
) -> dict[str, Any]:
    """The module docstring's quantities for one policy."""
    from auv_gym.rollout import rollouts

    def window(traj: Any) -> np.ndarray:
        keep = traj.t >= transient
        return np.stack([traj.samples[name][keep] for name in (*ERRORS, "u")], axis=1)

    calm_env = {**env_kwargs, "disturbance": "none"}

    calm = rollouts(policy, [0], **calm_env)[0]
    noisy = rollouts(policy, list(range(seeds)), **{**env_kwargs, "disturbance": "paper"})
    row: dict[str, Any] = {"calm_failed": calm.termination_reason in FAILURE_REASONS}
    calm_window = None if row["calm_failed"] else window(calm).mean(axis=0)
    row["calm_mean"] = None if calm_window is None else calm_window[:3].tolist()
    row["calm_surge"] = None if calm_window is None else float(calm_window[3])
    kept = [window(t)[:, :3] for t in noisy if t.termination_reason not in FAILURE_REASONS]
    row["noisy_failed"] = len(noisy) - len(kept)
    if kept:
        errors = np.concatenate(kept)
        row["noisy_mean"] = errors.mean(axis=0).tolist()
        row["noisy_std"] = errors.std(axis=0).tolist()
        row["rms_distance"] = float(np.mean([np.sqrt((w**2).sum(1).mean()) for w in kept]))
    row["max_pitch_deg"] = math.degrees(
        max(np.abs(t.samples["theta"]).max() for t in [calm, *noisy])
    )

    def response(value: float, channel: int) -> np.ndarray | None:
        """Change of the calm window's mean (x_e, y_e, z_e, u) per unit bias on ``channel``."""
        shifted = rollouts(CommandBias(policy, value, channel), [0], **calm_env)[0]
        if shifted.termination_reason in FAILURE_REASONS:
            return None
        return (window(shifted).mean(axis=0) - calm_window) / value

    if calm_window is not None:
        if bias is not None and (change := response(bias, PITCH)) is not None:
            row["stiffness_z"] = float(change[2])
        if surge_bias is not None and (change := response(surge_bias, SURGE)) is not None:
            row["surge_u"], row["surge_x"] = float(change[3]), float(change[0])
    return row


@dataclass
class Options:
    """The command line of `python -m benchmarks.analysis.steady_offset`."""

    policies: str = option("fbsm", "comma-separated classical names or label=agent-folder")
    seeds: int = option(4, "noisy episodes per policy (seeds 0…)")
    transient: float = option(100.0, "the window starts here [s]")
    bias: float | None = option(None, "pitch-command bias for the stiffness (normalised)")
    surge_bias: float | None = option(None, "thrust-command bias for the surge response (normed)")
    json: str | None = option(None, "also write the rows to this file")


def main(argv: list[str] | None = None) -> dict[str, dict[str, Any]]:
    prog = program_name("benchmarks.analysis.steady_offset")
    args, parser = parse_options(Options, argv, prog, __doc__)
    with usage_errors(parser):
        if args.json:
            writable_location(args.json, "--json", folder=False)
        if args.seeds < 1 or not (0.0 <= args.transient < 300.0):
            raise ValueError("--seeds must be >= 1 and --transient in [0, 300) s")
        for flag, value in (("--bias", args.bias), ("--surge-bias", args.surge_bias)):
            if value is not None and not (math.isfinite(value) and 0 < abs(value) <= 1):
                raise ValueError(f"{flag} must be finite with 0 < |b| <= 1, got {value}")
        specs = [s for s in args.policies.split(",") if s]
        built = [policy_and_env(spec) for spec in specs]
    rows = {
        label: measure(policy, env, args.seeds, args.transient, args.bias, args.surge_bias)
        for label, policy, env in built
    }

    def triple(values: Any) -> str:
        return "n/a" if values is None else ", ".join(f"{v:+.3f}" for v in values)

    header = [
        "policy",
        "calm mean (x_e, y_e, z_e) [m]",
        "noisy mean [m]",
        "noisy std [m]",
        "RMS distance [m]",
        "failed",
        "largest pitch [deg]",
        "Δz̄_e/bias [m]",
        "calm ū [m/s]",
        "Δū/surge bias [m/s]",
        "Δx̄_e/surge bias [m]",
    ]
    cells = [
        [
            label,
            triple(r["calm_mean"]),
            triple(r.get("noisy_mean")),
            triple(r.get("noisy_std")),
            f"{r.get('rms_distance', math.nan):.3f}",
            f"{r['noisy_failed']} of {args.seeds}",
            f"{r['max_pitch_deg']:.1f}",
            f"{r['stiffness_z']:+.2f}" if "stiffness_z" in r else "n/a",
            "n/a" if r["calm_surge"] is None else f"{r['calm_surge']:.4f}",
            f"{r['surge_u']:+.3f}" if "surge_u" in r else "n/a",
            f"{r['surge_x']:+.3f}" if "surge_x" in r else "n/a",
        ]
        for label, r in rows.items()
    ]
    print(
        f"The paper's helix, 300-s episodes, window t >= {args.transient:g} s; noisy: the "
        f"paper's white noise, seeds 0-{args.seeds - 1}"
    )
    print(markdown_table(header, cells))
    if args.json:
        write_json(args.json, {"options": vars(args), "rows": rows}, indent=2)
    return rows


if __name__ == "__main__":
    main()
