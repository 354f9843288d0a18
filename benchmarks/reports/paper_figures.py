"""The paper's Figs. 3–9 (FBSM against backstepping under ±35 white noise) and a metrics table.

    python -m benchmarks.reports.paper_figures --out out/paper_figures [--duration 300] [--seed 0]

Both controllers (`controllers.make("fbsm")`, `controllers.make("backstepping")`) run the same
seeded episode of `AUVPath3D-v0` with the env defaults — the paper's helix, start (15, 5, 0) m at
rest, bounded white noise ±35 N / N·m on all five channels held 0.01 s (docs/model.md §2.5) — and
the script writes into ``--out``:

    fig3_path_3d.png … fig9_controls.png   3D path, horizontal and vertical projections, errors
                                           x_e, y_e, z_e, surge speed, attitude, inputs X, M, N
    fig10_adaptive_norms.png               adaptive-parameter norms (if a controller has any)
    fig11_distance.png                     distance to the virtual point (log scale)
    metrics.md                             `auv_gym.metrics.compute_metrics` side by side
    metrics.json                           the same numbers, with the settings, versions, commit
    trajectories/<policy>.npz              the recorded time series (`Trajectory.load`)

Every file is written atomically. ``--duration 60`` gives a quick run; the metrics window then
starts at min(100 s, duration/2) = 30 s (docs/design.md §3.9).
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from auv_gym import ENV_ID, VARIANTS
from auv_gym.rollout import policy_name
from auv_gym.sim.config import MAX_EPISODE_TIME, SimConfig
from auv_gym.support.files import environment, jsonable, replace_outputs, write_json, write_text
from benchmarks.arguments import (
    comma_names,
    exit_with_usage_error,
    finite_number,
    locked_folder,
    parse_options,
    program_name,
    usage_errors,
    writable_folder,
)
from benchmarks.catalog.policies import (
    POLICY_SPEC_FORMS,
    build_policy,
    check_policy_spec,
    policy_env,
    policy_label,
)
from benchmarks.options import option

DEFAULT_POLICIES = ("fbsm", "backstepping")
DPI_RANGE = (20, 1200)  # figure resolution [dots per inch]
LABELS = {"fbsm": "FBSM", "backstepping": "backstepping"}


def _policy_specs(text: str) -> tuple[str, ...]:
    """The specs of ``--policies`` ("fbsm,backstepping"): ValueError for none, an empty one or
    one given twice."""
    return tuple(comma_names(text, "--policies"))


@dataclass
class Args:
    """The options of ``python -m benchmarks.reports.paper_figures`` (``env``: extra env keyword
    arguments for programmatic callers, no option)."""

    out: Path = option(Path("out/paper_figures"), "output folder")  # noqa: RUF009
    duration: float = option(300.0, "episode length [s]")
    seed: int = option(0, "reset seed shared by the policies (same noise)")
    policies: tuple[str, ...] = option(
        DEFAULT_POLICIES,
        f"comma-separated specs: controllers.make names, reference agent names, "
        f"{POLICY_SPEC_FORMS}",
        parse=_policy_specs,
    )
    control_dt: float = option(SimConfig.control_dt, "control period [s]")
    transient: float | None = option(
        None,
        "metrics window start [s] in [0, duration); None: min(100, duration/2) "
        "(docs/design.md §3.9)",
    )
    dpi: int = option(150, f"figure resolution [dots/in], in {list(DPI_RANGE)}")
    env: dict[str, Any] = field(default_factory=dict)


def parse_args(argv: Sequence[str] | None = None) -> Args:
    """The arguments, every one checked before any episode runs (a bad one exits with code 2
    and a one-line message)."""
    args, parser = parse_options(
        Args, argv, program_name("benchmarks.reports.paper_figures"), __doc__.split("\n\n")[0]
    )
    with usage_errors(parser):
        validate(args)
        writable_folder(args.out)  # last: a bad argument above creates no folder
    return args


def validate(args: Args) -> None:
    """ValueError naming the bad argument: ranges, policy specs and labels, env settings."""
    finite_number("--duration", args.duration, 0.0, MAX_EPISODE_TIME, low_open=True, unit="s")
    if args.seed < 0:
        raise ValueError(f"--seed must be non-negative, got {args.seed}")
    if not args.policies:
        raise ValueError("--policies must name at least one controller")
    if args.transient is not None:
        finite_number("--transient", args.transient, 0.0, args.duration, high_open=True, unit="s")
    if not DPI_RANGE[0] <= args.dpi <= DPI_RANGE[1]:
        raise ValueError(f"--dpi must be an integer in {list(DPI_RANGE)}, got {args.dpi}")
    finite_number("--control-dt", args.control_dt, 0.0, low_open=True, unit="s")
    try:
        SimConfig.from_kwargs(control_dt=args.control_dt, max_time=args.duration, **args.env)
    except (TypeError, ValueError) as error:
        raise ValueError(f"--control-dt/--duration: {error}") from None
    labels: dict[str, str] = {}
    for spec in args.policies:
        check_policy_spec(spec)
        label = policy_label(LABELS.get(spec, spec))
        if label in labels:  # both would write trajectories/<label>.npz
            raise ValueError(f"--policies {labels[label]!r} and {spec!r} share the label {label!r}")
        labels[label] = spec


def build_policies(names: Sequence[str], env: Any) -> dict[str, Any]:
    """label → policy for each spec (`benchmarks.catalog.policies`: "fbsm", "backstepping", any
    other `controllers.make` name, a reference agent name, "agent:PATH" or "module:attribute"),
    built for ``env`` (a
    `SimConfig` or env keyword arguments: control period, vehicle, actuator model).

    Classical controllers are labelled as in the paper ("FBSM"), an imported object by its
    `policy_name`, an agent by its spec.
    """
    policies: dict[str, Any] = {}
    for spec in names:
        kind = check_policy_spec(spec).kind
        policy = build_policy(spec, env)
        label = policy_name(policy) if kind == "import" else LABELS.get(spec, spec)
        if policy_label(label) in {policy_label(other) for other in policies}:
            raise ValueError(f"--policies: two policies share the label {label!r}")
        policies[label] = policy
    return policies


def make_figures(
    policies: Mapping[str, Any],
    out: str | os.PathLike,
    duration: float = Args.duration,
    seed: int = Args.seed,
    transient: float | None = None,
    dpi: int = Args.dpi,
    env_ids: Mapping[str, str] | None = None,
    agent_envs: Mapping[str, Mapping[str, Any]] | None = None,
    **env_kwargs: Any,
) -> dict[str, Any]:
    """Run each policy on the seeded episode, write figures, tables and trajectories to ``out``.

    ``env_ids`` maps a label to the env id whose defaults its episode starts from (an agent's
    training env, `benchmarks.catalog.policies.policy_env`; default `auv_gym.ENV_ID`) and
    ``agent_envs`` a label to the env arguments an agent carries (its observation), so an agent
    meets its speed limit and sees its observation here as in `compare` and the suite.

    Returns {"figures": stem → file, "files": the other files written, "metrics": label →
    metrics, "wall_time": label → s}.
    ``env_kwargs`` override the env defaults (the paper's scenario); ``max_time`` = duration.
    """
    from auv_gym.metrics import check_window, compute_metrics
    from auv_gym.paths import make_path
    from auv_gym.rollout import rollout
    from benchmarks.reports.episode_figures import paper_figures
    from benchmarks.reports.plotting import metrics_table

    if not policies:
        raise ValueError("make_figures needs at least one policy")
    out = Path(out)
    (out / "trajectories").mkdir(parents=True, exist_ok=True)
    window = check_window(duration, transient, env_kwargs.get("control_dt", SimConfig.control_dt))
    trajectories, metrics, wall = {}, {}, {}
    for label, policy in policies.items():
        start = time.perf_counter()
        env_id = (env_ids or {}).get(label, ENV_ID)
        own = (agent_envs or {}).get(label, {})
        tr = rollout(
            policy, seed, name=label, max_time=duration, **{**VARIANTS[env_id], **own, **env_kwargs}
        )
        wall[label] = time.perf_counter() - start
        trajectories[label] = tr
        metrics[label] = compute_metrics(tr, transient=window)
        tr.save(out / "trajectories" / f"{policy_label(label)}.npz")
    path = make_path(env_kwargs.get("path", "helix"))
    figures = paper_figures(trajectories, out, path=path, dpi=dpi, zoom_from=window)
    noise = env_kwargs.get("disturbance", "paper")
    header = (
        f"# Paper scenario: {' vs '.join(policies)}\n\n"
        f"Helix of docs/model.md §3.5, start (15, 5, 0) m at rest, disturbance {noise!r} "
        f'("paper": uniform white noise ±35 N / N·m on all five channels, held 0.01 s), '
        f"seed {seed}, {duration:g} s, windowed metrics over t ≥ {window:g} s. "
        f"Best value per row in bold.\n\n"
    )
    write_text(out / "metrics.md", header + metrics_table(metrics))
    payload = {
        "seed": seed,
        "duration": duration,
        "transient": window,
        "env_kwargs": trajectories[next(iter(trajectories))].metadata["env_kwargs"],
        "wall_time_s": wall,
        "metrics": jsonable(metrics, non_finite="text"),
        **environment(),
    }
    write_json(out / "metrics.json", payload, indent=1)
    files = [out / "metrics.md", out / "metrics.json"]
    files += [out / "trajectories" / f"{policy_label(label)}.npz" for label in trajectories]
    return {"figures": figures, "files": files, "metrics": metrics, "wall_time": wall}


def main(argv: Sequence[str] | None = None) -> dict[str, Any]:
    args = parse_args(argv)
    start = time.perf_counter()
    try:  # agents are loaded here, before any episode: a corrupt one is a usage error
        policies = build_policies(args.policies, {**args.env, "control_dt": args.control_dt})
        envs = {
            label: policy_env(spec) for spec, label in zip(args.policies, policies, strict=True)
        }
        env_ids = {label: env_id for label, (env_id, _) in envs.items()}
        agent_envs = {label: own for label, (_, own) in envs.items() if own}
    except (ValueError, TypeError, OSError) as error:
        exit_with_usage_error(program_name("benchmarks.reports.paper_figures"), error)
    # One run per folder: a second one is refused, a killed one's temporary files removed.
    with locked_folder(program_name("benchmarks.reports.paper_figures"), args.out):
        result = make_figures(
            policies,
            args.out,
            duration=args.duration,
            seed=args.seed,
            transient=args.transient,
            dpi=args.dpi,
            control_dt=args.control_dt,
            env_ids=env_ids,
            agent_envs=agent_envs,
            **args.env,
        )
        written = [*map(Path, result["figures"].values()), *result["files"]]
        replace_outputs(args.out, written)  # e.g. no fig10 or trajectory of other policies
    print((args.out / "metrics.md").read_text(encoding="utf-8"))
    for label, seconds in result["wall_time"].items():
        print(f"{label}: {args.duration:g}-s episode in {seconds:.2f} s of wall time")
    print(
        f"wrote {len(result['figures'])} figures to {args.out} "
        f"in {time.perf_counter() - start:.1f} s"
    )
    result["args"] = asdict(args)
    return result


if __name__ == "__main__":
    main(sys.argv[1:])
