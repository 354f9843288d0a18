"""How an agent is scored, during training and afterwards: seeded paper-scenario episodes.

Seeds: the evaluation during training uses `EVAL_SEEDS`; reported results use `HELD_OUT_SEEDS`
(the seeds 0..9 of `benchmarks.runner.compare`); training environments are seeded from
`TRAIN_SEED_BASE` + 1000·seed upwards, so none of them is ever a training seed.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym import ENV_ID, VARIANTS, resolve_env_id
from auv_gym.metrics import check_window, window_start
from auv_gym.rollout import evaluate
from auv_gym.sim.trajectory import env_termination_reason
from auv_gym.support.files import write_json
from benchmarks.catalog.tasks import VARIED
from benchmarks.training.selection_rule import DEFAULT_RULE
from controllers.agent import agent_env_kwargs
from controllers.loader import load_policy
from controllers.residual import base_kwargs_for_env

__all__ = [
    "EVAL_SEEDS",
    "HELD_OUT_FILE",
    "HELD_OUT_SEEDS",
    "TRAIN_SEED_BASE",
    "chattering_mean",
    "check_evaluation_duration",
    "evaluate_policy_on_seeds",
    "held_out_evaluation",
    "score",
    "summarize",
    "variant_groups",
    "write_held_out_evaluation",
]

EVAL_SEEDS = (100, 101, 102, 103, 104)
HELD_OUT_SEEDS = tuple(range(10))
TRAIN_SEED_BASE = 1_000_000
HELD_OUT_FILE = "held_out_evaluation.json"  # written beside an exported agent


def evaluate_policy_on_seeds(
    policy: Any,
    seeds: Sequence[int] = HELD_OUT_SEEDS,
    transient: float | None = None,
    extra_metrics: Sequence[str] = (),
    **env_kwargs: Any,
) -> list[dict[str, Any]]:
    """Seeded episodes of `policy` through `auv_gym.rollout.evaluate` (batched rows).

    Returns one dict per seed with seed, rms_distance and rms_x_e, rms_y_e, rms_z_e [m] over
    t ≥ transient (None: the shared rule min(100 s, max_time/2), docs/design.md §3.9),
    max_distance [m] over that window, window_samples (0 when the episode ended before the
    window: then the rms values are NaN), duration [s], max_surge [m/s] and overspeed_fraction
    (time with u above the vehicle's top speed) over the episode, and termination_reason in the
    env's spelling ("" when the episode ran to max_time,
    `auv_gym.sim.trajectory.env_termination_reason`), then the `auv_gym.metrics` named in
    ``extra_metrics`` (e.g. "chattering" [1/s]) as floats.
    """
    results = evaluate(policy, list(seeds), transient=transient, **env_kwargs)
    return [
        {
            "seed": int(r["seed"]),
            "rms_distance": float(r["rms_distance"]),
            "rms_x_e": float(r["rms_x_e"]),
            "rms_y_e": float(r["rms_y_e"]),
            "rms_z_e": float(r["rms_z_e"]),
            "max_distance": float(r["max_distance_window"]),
            "duration": float(r["duration"]),
            "window_samples": int(r["window_samples"]),
            "max_surge": float(r["max_surge"]),
            "overspeed_fraction": float(r["overspeed_fraction"]),
            "termination_reason": env_termination_reason(str(r["termination_reason"])),
            **{name: float(r[name]) for name in extra_metrics},
        }
        for r in results
    ]


def variant_groups(env_kwargs: dict[str, Any]) -> list[tuple[str | None, dict[str, Any]]]:
    """The (label, env keyword arguments) of each variant an evaluation flies: one per value
    when ``plant`` or ``actuator`` is a list (a validation set's ``vary``,
    `benchmarks.catalog.tasks`), labelled by the value; else ``[(None, env_kwargs)]``."""
    for key in VARIED:
        values = env_kwargs.get(key)
        if isinstance(values, (list, tuple)):
            return [(str(value), {**env_kwargs, key: value}) for value in values]
    return [(None, env_kwargs)]


def summarize(results: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Mean ± std of rms_distance over seeds, the number of terminated episodes and the largest
    surge speed [m/s] of any episode; results on several variants (rows with a "variant":
    plants or actuators, `variant_groups`) add "per_variant": each one's summary."""
    variants = list(dict.fromkeys(r["variant"] for r in results if "variant" in r))
    if not variants:
        return _summary(results)
    per_variant = {v: _summary([r for r in results if r.get("variant") == v]) for v in variants}
    return {**_summary(results), "per_variant": per_variant}


def _summary(results: Sequence[dict[str, Any]]) -> dict[str, Any]:
    rms = np.array([r["rms_distance"] for r in results], dtype=float)
    terminated = [r["termination_reason"] for r in results if r["termination_reason"]]
    finite = rms[np.isfinite(rms)]
    per_axis = {}
    for key in ("rms_x_e", "rms_y_e", "rms_z_e"):
        values = np.array([r.get(key, math.nan) for r in results], dtype=float)
        values = values[np.isfinite(values)]
        per_axis[f"{key}_mean"] = float(values.mean()) if values.size else math.nan
    return {
        **per_axis,
        "rms_distance_mean": float(finite.mean()) if finite.size else math.nan,
        "rms_distance_std": float(finite.std()) if finite.size else math.nan,
        "rms_distance_max": float(finite.max()) if finite.size else math.nan,
        "max_surge_max": max((r.get("max_surge", math.nan) for r in results), default=math.nan),
        "n_episodes": len(results),
        "n_terminated": len(terminated),
        "terminations": sorted(set(terminated)),
    }


def check_evaluation_duration(duration: float, control_dt: float = 0.05) -> float:
    """The metrics window start [s] of evaluation episodes of ``duration`` [s]; ValueError (one
    line, naming the duration) if such episodes cannot produce a windowed metric."""
    try:
        return check_window(duration, None, control_dt)
    except ValueError as error:
        raise ValueError(f"evaluation duration {duration!r} s: {error}") from None


def score(summary: dict[str, Any], chattering_weight: float = 0.0) -> tuple[int, float]:
    """Lower is better: first fewer terminated episodes, then lower mean rms distance [m] plus
    ``chattering_weight`` λ [m·s] times the mean chattering [1/s] (``summary["chattering_mean"]``,
    needed when λ > 0; residual agents, docs/design.md §3.10): the default
    `benchmarks.training.selection_rule.SelectionRule` (a file's ``selection`` changes it)."""
    return DEFAULT_RULE.score(summary, chattering_weight)


def chattering_mean(results: Sequence[dict[str, Any]]) -> float:
    """Mean chattering [1/s] (`auv_gym.metrics`) over the episodes where it is finite."""
    values = np.array([r.get("chattering", math.nan) for r in results], dtype=float)
    values = values[np.isfinite(values)]
    return float(values.mean()) if values.size else math.nan


# What a training env may fix about the vehicle an agent flies, in the order labels name them.
PLATFORM_KEYS = ("vehicle", "plant", "actuator")


def trained_platform(env_kwargs: Mapping[str, Any]) -> dict[str, Any]:
    """The vehicle, plant and actuator of a training env's arguments where it names one other
    than the default (REMUS 100, the 5-DOF plant, the paper's actuator; a shipped name, a path
    or a mapping for the vehicle, and not the per-episode "random" actuator): the agent's
    validation and held-out test fly them, around the paper scenario's paths and disturbances,
    unless the evaluation's own arguments set them."""
    from auv_gym.sim.config import FIVE_DOF_PLANT, PLANTS
    from auv_gym.sim.integrator import ACTUATORS
    from auv_gym.vehicle.record import DEFAULT_VEHICLE

    out: dict[str, Any] = {}
    if env_kwargs.get("vehicle") not in (None, DEFAULT_VEHICLE):
        out["vehicle"] = env_kwargs["vehicle"]
    plant, actuator = env_kwargs.get("plant"), env_kwargs.get("actuator")
    if isinstance(plant, str) and plant in PLANTS and plant != FIVE_DOF_PLANT:
        out["plant"] = plant
    if isinstance(actuator, str) and actuator in ACTUATORS and actuator != "paper":
        out["actuator"] = actuator
    return out


def held_out_evaluation(
    agent: str | os.PathLike, duration: float = 300.0, env_id: str | None = None
) -> dict[str, Any]:
    """An agent on the paper scenario over the held-out seeds 0-9: summary and per-seed results.

    ``env_id`` (a key of `auv_gym.VARIANTS`; None: the one the agent records, an ensemble's its
    members') adds its fixed arguments, e.g. the surge limit of AUVPath3DSpeedLimit-v0, under
    which an agent faster than 2.0 m/s terminates as "overspeed".
    """
    from controllers.agent import check_agent

    metadata = check_agent(agent).metadata
    env_id = env_id or metadata.get("env_id", ENV_ID)
    platform = trained_platform(metadata.get("env_kwargs") or {})
    # a residual agent's base takes the actuator it was trained on (`load_policy`'s default)
    base_kwargs = base_kwargs_for_env({**VARIANTS[resolve_env_id(env_id)], **platform})
    policy = load_policy(agent, base_kwargs=base_kwargs)
    # the env it carries, under ``env_id``, on the vehicle and plant it was trained on
    fixed = {**platform, **agent_env_kwargs(policy.metadata, env_id)}
    results = evaluate_policy_on_seeds(policy, HELD_OUT_SEEDS, max_time=float(duration), **fixed)
    named = "".join(f", {key} {fixed[key]!r}" for key in PLATFORM_KEYS if key in fixed)
    return {
        "scenario": f"paper (helix, white noise ±35 N / N·m, defaults of {env_id}{named})",
        "seeds": list(HELD_OUT_SEEDS),
        "duration_s": float(duration),
        "transient_s": window_start(float(duration)),
        "summary": summarize(results),
        "results": results,
        "agent_num_timesteps": policy.metadata.get("num_timesteps"),
        "agent_wall_time_s": policy.metadata.get("wall_time_s"),
    }


def write_held_out_evaluation(
    agent: str | os.PathLike, duration: float = 300.0, env_id: str | None = None
) -> dict[str, Any]:
    """`held_out_evaluation` of an agent directory, written to AGENT/held_out_evaluation.json."""
    report = held_out_evaluation(agent, duration, env_id)
    write_json(Path(agent) / HELD_OUT_FILE, report, indent=2, sort_keys=True)
    return report
