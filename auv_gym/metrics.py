"""Scalar metrics of a recorded episode (`compute_metrics`): errors, speed, actuation, outcome.

The metrics window (docs/design.md §3.9) is one rule shared by `compute_metrics`, the benchmark
(`benchmarks.runner.compare`, `benchmarks.reports.paper_figures`) and the training evaluation:
windowed metrics use the samples with t ≥ transient, where transient is given explicitly or, by
default, `window_start` = min(`DEFAULT_TRANSIENT`, T/2) of the planned episode length T = max_time:
it skips the approach from the start point and always leaves half of a short episode to measure.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np

from auv_gym.sim.trajectory import FAILURE_REASONS, TAU_FIELDS, Trajectory

__all__ = [
    "DEFAULT_TRANSIENT",
    "FIN_RATE_LIMITED",
    "ROLL_ANGLE",
    "SHAFT_POWER",
    "MetricsWindowWarning",
    "check_window",
    "compute_metrics",
    "window_start",
]

DEFAULT_TRANSIENT = 100.0  # [s] longest default start of the metrics window
# The trajectory extra with the realistic actuators' rate-limited fraction per control step.
FIN_RATE_LIMITED = "fin_rate_limited"
SHAFT_POWER = "shaft_power"  # extras: the propeller shaft power at each interval's end [W]
ROLL_ANGLE = "roll"  # extras: the 6-DOF plant's roll angle φ at each interval's end [rad]
_SAT_TOL = 1e-9
_T_TOL = 1e-9  # [s] sample times k·control_dt are compared with this tolerance


class MetricsWindowWarning(UserWarning):
    """An episode that did not fail left fewer than two samples in its metrics window."""


def window_start(duration: float, transient: float | None = None) -> float:
    """Start [s] of the metrics window of an episode planned to last ``duration`` [s].

    ``transient`` [s] if given, else min(`DEFAULT_TRANSIENT`, duration/2) (docs/design.md §3.9):
    100 s for the 300-s benchmark, half of any episode shorter than 200 s.
    """
    if transient is not None:
        if not (math.isfinite(transient) and transient >= 0):
            raise ValueError(f"transient must be a non-negative time in s, got {transient}")
        return float(transient)
    if not (math.isfinite(duration) and duration > 0):
        raise ValueError(f"duration must be a positive time in s, got {duration}")
    return min(DEFAULT_TRANSIENT, duration / 2.0)


def check_window(duration: float, transient: float | None, control_dt: float) -> float:
    """`window_start`, after checking that an episode running to ``duration`` [s] puts at least
    two samples (one control period, ``control_dt`` [s]) into the window; ValueError otherwise.

    Call it before running episodes: a window that cannot hold a metric is a configuration error.
    """
    start = window_start(duration, transient)
    if duration - start < control_dt - _T_TOL:
        # the shortest episode whose window holds two samples: transient + control_dt, or
        # 2 control_dt under the default rule min(100 s, duration/2)
        shortest = control_dt + (transient if transient is not None else control_dt)
        longer = f"an episode of at least {shortest:g} s"
        latest = duration - control_dt  # the latest transient that would do: none below 0
        remedy = f"a transient ≤ {latest:g} s or {longer}" if latest >= 0.0 else longer
        raise ValueError(
            f"the metrics window t ≥ {start:g} s of a {duration:g}-s episode holds fewer than two "
            f"samples (control period {control_dt:g} s), so every windowed metric would be "
            f"undefined: use {remedy} (docs/design.md §3.9)"
        )
    return start


def _window_rms(t: np.ndarray, values: np.ndarray, start: float) -> float:
    mask = t >= start - _T_TOL
    if not mask.any():
        return math.nan
    return float(np.sqrt(np.mean(np.square(values[mask]))))


def _trapezoid(values: np.ndarray, t: np.ndarray) -> float:
    """∫ values dt by the trapezoid rule (0 for a single sample)."""
    return float(0.5 * np.sum((values[1:] + values[:-1]) * np.diff(t)))


def _settling_time(t: np.ndarray, distance: np.ndarray, threshold: float) -> float:
    """First t_k with distance < threshold at every sample from k on; inf if none."""
    outside = ~(distance < threshold)  # NaN counts as outside
    if outside[-1]:
        return math.inf
    if not outside.any():
        return float(t[0])
    return float(t[np.flatnonzero(outside)[-1] + 1])


def compute_metrics(
    trajectory: Trajectory,
    transient: float | None = None,
    success_distance: float = 1.0,
    final_window: float = 10.0,
) -> dict[str, Any]:
    """Scalar metrics of one episode. Units: m, s, m/s; τ normalised by `actuator_limits`.

    Windowed metrics use the samples (or intervals) with t ≥ ``transient`` [s]; None applies
    the shared rule `window_start` to the planned episode length (the recorded ``max_time``,
    else the duration): min(100 s, max_time/2). ``window_samples`` counts the samples in the
    window. Windowed metrics are NaN exactly when it is 0 (chattering and iae_distance_window
    when it is below 2): the episode ended before t = transient. A failed episode says why in
    termination_reason; any other episode that leaves fewer than two samples in the window
    also raises a `MetricsWindowWarning`. With d the distance to the virtual point,
    e = (x_e, y_e, z_e), τ̄_j = τ_j / τ_max,j and a_j the policy's action:

    Distance and errors [m]:
      rms_distance, rms_x_e, rms_y_e, rms_z_e — √mean(·²) over the window;
      max_distance_window — max d over the window; final_distance — d at the last sample;
      iae_distance — ∫ d dt over the whole episode (trapezoid) [m·s];
      iae_distance_window — the same over the window [m·s];
      settling_time_0p5, settling_time_0p1 — the first t_k with d < 0.5 (0.1) m at every
      later sample [s]; inf if the last sample is not below the threshold (never settled) or
      the episode ended in failure.
    Speed [m/s]:
      surge_overshoot — max_k (u − u_D) over the episode (negative if u never reaches u_D);
      surge_overshoot_percent — 100·surge_overshoot/u_D;
      rms_speed_error — √mean((u − u_D)²) over the window;
      mean_path_speed — mean virtual-point speed u_p over the window: the pace at which the
      path is flown (u_D for a vehicle on the virtual point; one that keeps ahead of it,
      x_e > 0, drives it faster, u_p = u_D(1 + tanh(x_e/σ)), docs/model.md §3.3; with a
      guidance computer the speed it held, from the estimated x_e, §14.9);
      max_surge — max_k u over the episode (realistic speed: REMUS 100 tops out near
      2.3-2.5 m/s); overspeed_fraction — fraction of the episode's control intervals
      [t_k, t_{k+1}) whose end sample has u > the vehicle's top speed `Trajectory.top_speed`
      (`AUVParams.max_surge`, 2.0 m/s for REMUS 100) [-].
    Actuation:
      control_effort — Σ_k Σ_j τ̄_j² Δt over the episode, i.e. ∫ of the squared normalised τ [s];
      chattering — Σ_k Σ_j abs(τ̄_j(t_{k+1}) − τ̄_j(t_k)) / window length, the total variation
      of the normalised τ per second of window [1/s];
      saturation_fraction — fraction of control steps with any abs(a_j) ≥ 1 (saturated
      command); control_effort_X/_M/_N, chattering_X/_M/_N, saturation_fraction_X/_M/_N — per
      channel; fin_rate_saturation (realistic actuators only) — fraction of the episode's
      physics steps in which a fin moved at its rate limit (docs/model.md §2.6).
    Propulsion (realistic actuators only, over the window; `_propulsion`):
      mean_shaft_power — mean propeller shaft power [W]; energy_per_km — shaft energy per
      kilometre the vehicle travelled [kJ/km].
    Roll (the 6-DOF plant only, docs/model.md §15): max_roll — max |φ| over the episode [rad].
    Outcome:
      success — no failure termination (`FAILURE_REASONS`) and RMS d over the final
      ``final_window`` s ≤ ``success_distance`` (default 1 m, about one REMUS length);
      episode_return — Σ reward; episode_cost — Σ safety cost (`auv_gym.sim.safety_cost`; NaN
      for a file recorded before the cost existed); termination_reason — the episode end
      (`EPISODE_ENDS`);
      duration [s], steps; transient — the window start used [s]; window_samples — the
      number of samples with t ≥ transient.
    """
    tr = trajectory
    transient = window_start(float(tr.metadata.get("max_time") or tr.duration), transient)
    if not (success_distance > 0 and final_window > 0):
        raise ValueError("success_distance and final_window must be positive")
    t, t_int, dt = tr.t, tr.t_interval, tr.control_dt
    distance = tr["distance"]
    failed = tr.termination_reason in FAILURE_REASONS
    window = t >= transient - _T_TOL
    window_int = t_int >= transient - _T_TOL
    window_samples = int(window.sum())
    if window_samples < 2 and not failed:
        warnings.warn(
            MetricsWindowWarning(
                f"the metrics window t ≥ {transient:g} s holds {window_samples} sample(s) of an "
                f"episode that ended at t = {tr.duration:g} s ({tr.termination_reason}): "
                "windowed metrics are undefined (NaN); use a shorter transient or a longer "
                "episode (docs/design.md §3.9)"
            ),
            stacklevel=2,
        )
    speed_error = tr["u"] - tr.u_desired
    tau_norm = tr.tau / np.asarray(tr.actuator_limits)
    actions = tr.actions
    metrics: dict[str, Any] = {}
    for name, values in (
        ("distance", distance),
        ("x_e", tr["x_e"]),
        ("y_e", tr["y_e"]),
        ("z_e", tr["z_e"]),
    ):
        metrics[f"rms_{name}"] = _window_rms(t, values, transient)
    metrics["max_distance_window"] = float(distance[window].max()) if window.any() else math.nan
    metrics["iae_distance"] = _trapezoid(distance, t)
    metrics["iae_distance_window"] = (
        _trapezoid(distance[window], t[window]) if window.sum() > 1 else math.nan
    )
    for label, threshold in (("0p5", 0.5), ("0p1", 0.1)):
        settle = _settling_time(t, distance, threshold)
        metrics[f"settling_time_{label}"] = math.inf if failed else settle
    overshoot = float(speed_error.max())
    metrics["surge_overshoot"] = overshoot
    metrics["surge_overshoot_percent"] = 100.0 * overshoot / tr.u_desired
    metrics["rms_speed_error"] = _window_rms(t, speed_error, transient)
    metrics["mean_path_speed"] = float(tr["u_p"][window].mean()) if window.any() else math.nan
    surge = tr["u"]
    metrics["max_surge"] = float(surge.max())
    overspeed = surge[1:] > tr.top_speed
    metrics["overspeed_fraction"] = float(overspeed.mean()) if tr.steps else 0.0
    per_channel_effort = (tau_norm**2).sum(axis=0) * dt
    metrics["control_effort"] = float(per_channel_effort.sum())
    # Chattering: total variation inside the window, per second of window.
    tv_window = tau_norm[window_int]
    span = tv_window.shape[0] * dt
    if tv_window.shape[0] > 1:
        variation = np.abs(np.diff(tv_window, axis=0)).sum(axis=0) / span
    else:
        variation = np.full(3, math.nan)
    metrics["chattering"] = float(variation.sum())
    saturated = np.abs(actions) >= 1.0 - _SAT_TOL
    steps = tr.steps
    metrics["saturation_fraction"] = float(saturated.any(axis=1).mean()) if steps else 0.0
    for j, axis in enumerate(TAU_FIELDS):
        metrics[f"control_effort_{axis}"] = float(per_channel_effort[j])
        metrics[f"chattering_{axis}"] = float(variation[j])
        metrics[f"saturation_fraction_{axis}"] = float(saturated[:, j].mean()) if steps else 0.0
    if FIN_RATE_LIMITED in tr.extras:  # realistic actuators only (`auv_gym.rollout`)
        metrics["fin_rate_saturation"] = float(np.mean(tr.extras[FIN_RATE_LIMITED]))
    if SHAFT_POWER in tr.extras:  # the propeller's (`auv_gym.rollout`)
        metrics.update(_propulsion(tr, window))
    if ROLL_ANGLE in tr.extras:  # the 6-DOF plant's (`auv_gym.rollout`)
        metrics["max_roll"] = float(np.max(np.abs(tr.extras[ROLL_ANGLE]), initial=0.0))
    metrics["final_distance"] = float(distance[-1])
    final = t >= t[-1] - final_window + 1e-9
    final_rms = float(np.sqrt(np.mean(np.square(distance[final]))))
    metrics["success"] = bool(not failed and final_rms <= success_distance)
    metrics["episode_return"] = float(tr["reward"].sum())
    metrics["episode_cost"] = float(tr["cost"].sum())
    metrics["termination_reason"] = tr.termination_reason
    metrics["duration"] = tr.duration
    metrics["steps"] = steps
    metrics["transient"] = float(transient)
    metrics["window_samples"] = window_samples
    return metrics


def _propulsion(tr: Trajectory, window: np.ndarray) -> dict[str, float]:
    """mean_shaft_power [W] and energy_per_km [kJ/km] over the window's samples: the shaft power
    recorded at each interval's end (`SHAFT_POWER`), integrated by the trapezoid rule between
    consecutive window samples, per kilometre of the vehicle's track between them (which
    follows the path to its RMS distance, so it is the path's length to that accuracy)."""
    power = np.asarray(tr.extras[SHAFT_POWER], dtype=np.float64)  # at t[1:], the ends
    ends = window[1:]
    if ends.sum() < 2:
        return {"mean_shaft_power": math.nan, "energy_per_km": math.nan}
    p, t = power[ends], tr.t[1:][ends]
    position = np.column_stack([tr["x"], tr["y"], tr["z"]])[1:][ends]
    track_km = float(np.linalg.norm(np.diff(position, axis=0), axis=1).sum()) / 1000.0
    energy_kj = _trapezoid(p, t) / 1000.0
    span = float(t[-1] - t[0])
    return {
        "mean_shaft_power": _trapezoid(p, t) / span,
        "energy_per_km": energy_kj / track_km if track_km > 0 else math.nan,
    }
