"""How much of a policy's distance to the path its navigation leaves it: the as-built test sets
flown once, each error split into what the policy sees and what its estimate hides.

    python -m benchmarks.analysis.navigation_floor \\
        --policies pid_as_built,ppo_as_built=benchmarks/agents/ppo_as_built \\
        --out benchmarks/results/as_built/navigation_floor

A policy on the vehicle as built steers the error e^ = (x_e, y_e, z_e) [m] of the virtual point,
in body axes (docs/model.md §3.2), computed from the navigation estimate (the observation's
entries x_e, y_e, z_e); the benchmark scores the error e computed from the true state
(`auv_gym.rollout`). Their difference n = e − e^ is the navigation's share: the estimate's
position and attitude errors seen from the same path point. Per policy and set, over t ≥ 100 s
of every episode (the metrics window): RMS |e| (the benchmark's RMS distance, as the suite
computes it), RMS |e^| (the policy's tracking of its own estimate) and RMS |n|.

A policy that held e^ at zero would score RMS |n|, so the ratio RMS |n| / (the reference's
RMS |e|) says where the as-built target (≤ 0.8x the best classical policy, docs/results.md)
lies against the navigation. It is not a floor: a policy scores below RMS |n| where its own
error runs against the estimate's, as along the path, where the virtual point advances with
the true x_e (docs/model.md §14.4), so a policy that leaves the estimated x_e alone has a true
x_e near zero whatever the navigation. The floor is the share across the path, RMS |n_yz| of
(y_e, z_e): no policy can steer out an error its estimate does not show (if the filter's
estimate is the best one its measurements allow, which its consistency test measures,
docs/model.md §14.8). Episodes are the suite's (`auv-gym suite`: the same env arguments,
seeds and metric).

Each error is also split by time scale (`slow_part`): below `SLOW_HZ` (periods over 50 s, the
mean included) lie the navigation's drift between fixes and a current's steady push, above it
the waves, the turns and the loops' own motion; the table gives the cross-track parts.

What the target leaves a policy (`--classical`, the policies the target is measured against):
per set the target T = 0.8 × the best classical RMS |e|. Beyond the floor, a distance holds
its along-track error and its own tracking of the estimate across the path, the rest
√(|e|² − |n_yz|²) if those are uncorrelated with the floor's share (the correlation ρ of e^ and
n across the path, pooled over the set's windows, measures it: |e_yz|² = |e^_yz|² + |n_yz|² +
2ρ|e^_yz||n_yz|); the target allows a rest of √(T² − |n_yz|²). Their ratio is how much of
its rest a policy must shed, a sharper measure of the target's reach than |e| / T, whose floor
is not zero.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym.metrics import compute_metrics
from auv_gym.rollout import rollouts
from auv_gym.sim.observation import OBS
from auv_gym.sim.trajectory import TIME_LIMIT
from auv_gym.support.files import write_json, write_text
from benchmarks.analysis.plant_seeds import PER_SET_TARGET
from benchmarks.arguments import comma_names, parse_options, program_name, usage_errors
from benchmarks.catalog.policies import build_policy
from benchmarks.catalog.tasks import task_set
from benchmarks.options import option
from benchmarks.runner.suite_chunks import Chunk, resolve_policy

__all__ = ["SETS", "SLOW_HZ", "error_split", "main", "slow_part", "target_rest"]

SETS = (
    "scenario:as_built_helix",
    "scenario:as_built_survey",
    "scenario:as_built_coastal",
    "test_as_built_tight_deep",
    "test_as_built_strong_current",
)
ERRORS = ("x_e", "y_e", "z_e")  # observation entries and trajectory sample fields alike
SEEN = [getattr(OBS, name) for name in ERRORS]  # their observation columns
WINDOW_START = 100.0  # [s] as the benchmark metrics
DURATION = 300.0  # [s] as the as-built evaluation
# [Hz] the split by time scale: below it (periods over 50 s) the navigation's drift between
# fixes and a current's steady push, above it the waves, the turns and the loops' own motion
SLOW_HZ = 0.02


class _SeenErrors:
    """A policy recording the path-frame errors its observations carry; ``inner`` acts."""

    def __init__(self, inner: Any) -> None:
        self.inner = inner
        self.env_kwargs = getattr(inner, "env_kwargs", None)
        self.seen: list[np.ndarray] = []

    def predict(self, obs: np.ndarray, state: Any = None, episode_start: Any = None, **kw: Any):
        self.seen.append(np.array(obs[:, SEEN], dtype=np.float64))
        return self.inner.predict(obs, state=state, episode_start=episode_start, **kw)


def slow_part(series: np.ndarray, dt: float, slow_hz: float = SLOW_HZ) -> np.ndarray:
    """The components of ``series`` (samples along axis 0, ``dt`` [s] apart) below ``slow_hz``
    [Hz], its mean included: an ideal low-pass by the discrete Fourier transform, so the slow
    and the fast part (the rest) add up to the series and their mean squares to its own."""
    spectrum = np.fft.rfft(series, axis=0)
    spectrum[np.fft.rfftfreq(len(series), dt) >= slow_hz] = 0.0
    return np.fft.irfft(spectrum, n=len(series), axis=0)


def error_split(
    spec: str, set_name: str, duration: float = DURATION, window_start: float = WINDOW_START
) -> dict[str, Any]:
    """RMS |e|, |e^| and |n| [m] over t ≥ ``window_start`` [s] of the set's episodes of
    ``duration`` [s] flown by the suite policy ``spec`` (a name, or NAME=agent directory; its
    first run), means over episodes; |e| is the suite's metric (`auv_gym.metrics`), |e^| and |n|
    are taken at the observations' times. Per axis also the RMS of the slow and the fast part
    of each (`slow_part`, below and above `SLOW_HZ`)."""
    policy = resolve_policy(spec)
    run = policy.runs[0]
    task = task_set(set_name)
    env_kwargs = Chunk(policy.name, run, task, duration, window_start).env_kwargs
    recorder = _SeenErrors(build_policy(run.spec, env_kwargs, task.controller))
    flights = rollouts(recorder, list(task.seeds), **env_kwargs)
    seen = np.stack(recorder.seen, axis=1)  # (episodes, steps of the longest flight, 3)
    rms: dict[str, list[float]] = {"true": [], "seen": [], "navigation": [], "across": []}
    # Σ e^_yz·n_yz, Σ |e^_yz|², Σ |n_yz|² over every episode's window: their correlation
    across_sums = np.zeros(3)
    axes: dict[str, list[np.ndarray]] = {"true": [], "seen": [], "navigation": []}
    slow_axes: dict[str, list[np.ndarray]] = {key: [] for key in axes}
    fast_axes: dict[str, list[np.ndarray]] = {key: [] for key in axes}
    for i, flight in enumerate(flights):
        rms["true"].append(compute_metrics(flight, transient=window_start)["rms_distance"])
        steps = len(flight.t) - 1  # observations at t_0 … t_{K-1}
        window = flight.t[:steps] >= window_start
        e_true = np.stack([flight.samples[f][:steps] for f in ERRORS], axis=1)[window]
        e_seen = seen[i, :steps][window]
        if not window.any():  # ended before the window: no sample to score
            for parts in (axes, slow_axes, fast_axes):
                for key in parts:
                    parts[key].append(np.full(len(ERRORS), math.nan))
            for key in ("seen", "navigation", "across"):
                rms[key].append(math.nan)
            continue
        dt = float(flight.t[1] - flight.t[0])  # [s] the control step
        for key, e in (("true", e_true), ("seen", e_seen), ("navigation", e_true - e_seen)):
            axes[key].append(np.sqrt(np.mean(e**2, axis=0)))
            slow = slow_part(e, dt)
            slow_axes[key].append(np.sqrt(np.mean(slow**2, axis=0)))
            fast_axes[key].append(np.sqrt(np.mean((e - slow) ** 2, axis=0)))
            if key != "true":  # the suite's metric stands for |e|
                rms[key].append(math.sqrt(float(np.mean(np.sum(e**2, axis=1)))))
        across = (e_true - e_seen)[:, 1:]  # y_e, z_e: what no steering of the estimate removes
        rms["across"].append(math.sqrt(float(np.mean(np.sum(across**2, axis=1)))))
        seen_across = e_seen[:, 1:]
        across_sums += (
            np.sum(seen_across * across),
            np.sum(seen_across**2),
            np.sum(across**2),
        )
    return {
        "policy": policy.name,
        "set": set_name,
        "episodes": len(flights),
        "failed": sum(flight.termination_reason != TIME_LIMIT for flight in flights),
        "rms_distance_m": float(np.mean(rms["true"])),
        "rms_seen_m": float(np.mean(rms["seen"])),
        "rms_navigation_m": float(np.mean(rms["navigation"])),
        "rms_navigation_across_m": float(np.mean(rms["across"])),
        "corr_seen_navigation_across": _correlation(*across_sums),
        "rms_by_axis_m": _by_axis(axes),
        "rms_slow_by_axis_m": _by_axis(slow_axes),
        "rms_fast_by_axis_m": _by_axis(fast_axes),
    }


def _correlation(product: float, seen: float, navigation: float) -> float:
    """Σ e^·n / √(Σ |e^|² Σ |n|²) [–] from the three sums (NaN where either is all zero)."""
    scale = math.sqrt(seen * navigation)
    return product / scale if scale > 0.0 else math.nan


def _by_axis(parts: dict[str, list[np.ndarray]]) -> dict[str, dict[str, float]]:
    """Per kind, the mean over episodes of each axis's RMS [m]."""
    return {
        key: dict(zip(ERRORS, np.mean(values, axis=0).tolist(), strict=True))
        for key, values in parts.items()
    }


@dataclass
class Options:
    """The command line of `python -m benchmarks.analysis.navigation_floor`."""

    policies: str = option(
        "pid_as_built,ppo_as_built=benchmarks/agents/ppo_as_built",
        "suite policies, comma-separated; the first is the reference of the floor ratio",
    )
    classical: str = option(
        "",
        "the policies of --policies (names) the as-built target is measured against, "
        "comma-separated (default: the first)",
    )
    sets: str = option(",".join(SETS), "task sets, comma-separated")
    out: str = option("benchmarks/results/as_built/navigation_floor", "folder for .md and .json")


def target_rest(rows: Sequence[dict[str, Any]], classical: Sequence[str]) -> list[dict[str, Any]]:
    """Per row: the set's target T [m] (`PER_SET_TARGET` × the best RMS |e| of the ``classical``
    policies there, and which), the row's rest √(|e|² − |n_yz|²) [m], the rest the target allows,
    √(T² − |n_yz|²) [m] (0 where the floor alone exceeds T), and rest / allowed."""
    best: dict[str, dict[str, Any]] = {}
    for r in rows:
        if r["policy"] in classical and (
            r["set"] not in best or r["rms_distance_m"] < best[r["set"]]["rms_distance_m"]
        ):
            best[r["set"]] = r
    out = []
    for r in rows:
        target = PER_SET_TARGET * best[r["set"]]["rms_distance_m"]
        floor = r["rms_navigation_across_m"]
        rest = math.sqrt(max(r["rms_distance_m"] ** 2 - floor**2, 0.0))
        allowed = math.sqrt(max(target**2 - floor**2, 0.0))
        out.append(
            {
                "policy": r["policy"],
                "set": r["set"],
                "best_classical": best[r["set"]]["policy"],
                "target_m": target,
                "rest_m": rest,
                "rest_allowed_m": allowed,
                "rest_ratio": rest / allowed if allowed > 0.0 else math.inf,
            }
        )
    return out


def _kinds_row(row: dict[str, Any], cells: Sequence[str]) -> str:
    """A table row: the row's set and policy, then one cell per kind (e, e^, n)."""
    label = row["set"].removeprefix("scenario:")
    return f"| `{label}` | {row['policy']} | " + " | ".join(cells) + " |"


def markdown(
    rows: Sequence[dict[str, Any]],
    policies: Sequence[str],
    command: str,
    classical: Sequence[str] = (),
) -> str:
    """The split as a table: per set and policy the three RMS values, then the floor ratio;
    the target's rest (`target_rest`) against ``classical`` (default: the first policy)."""
    reference = policies[0]
    lines = [
        "# How much of the distance the navigation leaves each policy",
        "",
        f"`{command}`: per set, 10 episodes of {DURATION:g} s (the suite's), means over "
        f"episodes of RMS values over t ≥ {WINDOW_START:g} s [m]. |e|: the benchmark's distance "
        "(true state); |e^|: the error the policy sees (navigation estimate); |n| = |e − e^|: the "
        "navigation's share, the distance of a policy that held e^ at zero; |n_yz|: its share "
        "across the path (y_e, z_e), the floor (along the path the virtual point follows the true "
        f"x_e). Ratios over {reference}'s RMS |e|. ρ: the correlation of e^ and n across the "
        "path (y_e, z_e), pooled over the set's windows; near 0 the rest below is what the "
        "policy keeps beyond the floor.",
        "",
        "| set | policy | failed | RMS \\|e\\| | RMS \\|e^\\| | RMS \\|n\\| | \\|n\\| / ref. "
        "| RMS \\|n_yz\\| | floor / ref. | ρ(e^, n) across |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    by_set: dict[str, float] = {
        r["set"]: r["rms_distance_m"] for r in rows if r["policy"] == reference
    }
    for r in rows:
        ratio = r["rms_navigation_m"] / by_set[r["set"]]
        floor = r["rms_navigation_across_m"] / by_set[r["set"]]
        lines.append(
            f"| `{r['set'].removeprefix('scenario:')}` | {r['policy']} | "
            f"{r['failed']}/{r['episodes']} | {r['rms_distance_m']:.3f} | "
            f"{r['rms_seen_m']:.3f} | {r['rms_navigation_m']:.3f} | {ratio:.2f} | "
            f"{r['rms_navigation_across_m']:.3f} | {floor:.2f} | "
            f"{r['corr_seen_navigation_across']:+.2f} |"
        )
    lines += [
        "",
        "By axis (body axes: x_e along the vehicle, y_e to its side, z_e below it), RMS [m], "
        "means over episodes:",
        "",
        "| set | policy | e: x_e, y_e, z_e | e^: x_e, y_e, z_e | n: x_e, y_e, z_e |",
        "|---|---|---|---|---|",
    ]
    for r in rows:
        parts = [
            ", ".join(f"{v:.3f}" for v in r["rms_by_axis_m"][key].values())
            for key in ("true", "seen", "navigation")
        ]
        lines.append(_kinds_row(r, parts))
    lines += [
        "",
        f"By time scale, across the path (y_e): the slow part (components below {SLOW_HZ:g} Hz, "
        f"periods over {1 / SLOW_HZ:g} s, the mean included: the navigation's drift between "
        "fixes, a current's push) and the fast part (the rest: waves, turns, the loops' own "
        "motion), RMS [m], means over episodes:",
        "",
        "| set | policy | e: slow, fast | e^: slow, fast | n: slow, fast |",
        "|---|---|---|---|---|",
    ]
    for r in rows:
        parts = [
            f"{r['rms_slow_by_axis_m'][key]['y_e']:.3f}, {r['rms_fast_by_axis_m'][key]['y_e']:.3f}"
            for key in ("true", "seen", "navigation")
        ]
        lines.append(_kinds_row(r, parts))
    classical = list(classical) or [reference]
    lines += [
        "",
        f"What the target leaves (T = {PER_SET_TARGET:g} × the best RMS |e| of "
        f"{', '.join(classical)} per set): rest = √(|e|² − |n_yz|²), what a distance holds "
        "beyond the navigation's share across the path (its along-track error and its own "
        "tracking of the estimate across it); allowed = √(T² − |n_yz|²), the rest a policy at "
        "the target keeps; rest / allowed above 1 is the share of its rest a policy must shed "
        "to meet the target. [m]:",
        "",
        "| set | policy | RMS \\|e\\| | target T (best classical) | rest | allowed "
        "| rest / allowed |",
        "|---|---|---:|---:|---:|---:|---:|",
    ]
    for r, t in zip(rows, target_rest(rows, classical), strict=True):
        lines.append(
            f"| `{r['set'].removeprefix('scenario:')}` | {r['policy']} | "
            f"{r['rms_distance_m']:.3f} | {t['target_m']:.3f} ({t['best_classical']}) | "
            f"{t['rest_m']:.3f} | {t['rest_allowed_m']:.3f} | {t['rest_ratio']:.2f} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> dict[str, Any]:
    name = program_name("benchmarks.analysis.navigation_floor")
    args, parser = parse_options(Options, argv, name, __doc__)
    with usage_errors(parser):  # every name checked before the first episode
        policies = comma_names(args.policies, "--policies")
        sets = comma_names(args.sets, "--sets")
        labels = [resolve_policy(spec).name for spec in policies]
        classical = comma_names(args.classical, "--classical") if args.classical else labels[:1]
        unknown = [name for name in classical if name not in labels]
        if unknown:
            raise ValueError(f"--classical names {unknown} that --policies does not fly ({labels})")
        for set_name in sets:
            task_set(set_name)
    rows = []
    for set_name in sets:
        for spec in policies:
            rows.append(error_split(spec, set_name))
            r = rows[-1]
            print(
                f"{set_name:32s} {r['policy']:16s} |e| {r['rms_distance_m']:.3f} "
                f"|e^| {r['rms_seen_m']:.3f} |n| {r['rms_navigation_m']:.3f} "
                f"failed {r['failed']}",
                flush=True,
            )
    command = f"python -m benchmarks.analysis.navigation_floor --policies {args.policies}"
    if args.classical:
        command += f" --classical {args.classical}"
    out = Path(args.out)
    write_text(out / "navigation_floor.md", markdown(rows, labels, command, classical))
    targets = target_rest(rows, classical)
    write_json(
        out / "navigation_floor.json",
        {"command": command, "classical": classical, "rows": rows, "targets": targets},
        indent=2,
    )
    return {"rows": rows}


if __name__ == "__main__":
    main()
