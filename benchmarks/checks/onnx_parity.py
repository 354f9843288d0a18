"""Parity of the exported agents: their ONNX graphs against the Python agents on the test suite.

    python -m benchmarks.checks.onnx_parity --out benchmarks/results/onnx

For each reference agent (and each allocating agent exported for the propeller and fins), every
episode of the test suite (`benchmarks/tasks.toml`) that the agent flies is flown three times
(a set on an actuator the agent does not command, e.g. `fins` for the as-built agent, is not
flown, as in the suite, and is listed):

1. by the Python agent (`controllers.make("agent")`), with its ONNX export fed the same
   observations, episode starts and memory at every control step beside it: the largest
   |ONNX − Python| over all commands (target ≤ 1e-5 over 100,000 observations or more);
2. by the ONNX export alone (`controllers.make("onnx")`), closed loop: each episode's RMS
   distance against the Python agent's, relative difference (target ≤ 0.1 % per episode);
3. on a set where an episode passes that target, by the Python agent with every command
   nudged by ± the export's largest command difference on the set (`NudgedPolicy`): the same
   relative difference measures how far the closed loop itself carries a difference that
   size. Where it passes 0.1 % too (an agent flying a vehicle it was not trained for, whose
   RMS a 1e-6 nudge moves by tens of per cent), the per-episode target cannot tell the export
   from rounding; such a set is "sensitive", not "missed". One nudge is one draw of the signs;
   ``--nudges K`` flies K draws and keeps the largest difference (each row records its K).

Writes parity.json and parity.md (atomically, after each export) to --out and prints the
tables. With ``--agents`` naming some of the reference agents, the rows of the others already in
--out's parity.json (of the same episode length) are kept.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym import VARIANTS
from auv_gym.rollout import evaluate
from auv_gym.sim.observation import OBS_INDEX
from auv_gym.support.files import write_json, write_text
from benchmarks.arguments import (
    comma_names,
    finite_number,
    parse_options,
    program_name,
    usage_errors,
    writable_folder,
)
from benchmarks.catalog.policies import (
    AGENTS_DIR,
    REFERENCE_AGENTS,
    build_policy,
    check_policy_for_env,
    policy_env,
)
from benchmarks.catalog.tasks import test_suite
from benchmarks.options import option

__all__ = ["Exports", "ParityOptions", "TwinPolicy", "check", "main"]

COMMAND_TOLERANCE = 1e-5  # max |ONNX − Python| command, normalised units
RMS_TOLERANCE = 1e-3  # relative difference of an episode's RMS distance
NUDGE_FLOOR = 1e-7  # the smallest nudge of the sensitivity flight, about a float32 ulp at 1


class NudgedPolicy:
    """The Python agent with every command moved by ±``size`` (a seeded random sign per entry,
    kept in [−1, 1]): how far the closed loop carries a difference the size of the export's."""

    def __init__(self, python: Any, size: float, seed: int = 0) -> None:
        self.python = python
        self.size = size
        self.env_kwargs = python.env_kwargs
        self.rng = np.random.default_rng(seed)

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        action, state = self.python.predict(observation, state, episode_start, deterministic)
        action = np.asarray(action, np.float32)
        signs = self.rng.choice(np.array([-1.0, 1.0], np.float32), action.shape)
        return np.clip(action + self.size * signs, -1.0, 1.0).astype(np.float32), state


class TwinPolicy:
    """The Python agent flies; its export computes the same step beside it (own memory, same
    observations and episode starts). ``worst``: the largest |difference| so far; ``count``:
    observations compared."""

    def __init__(self, python: Any, exported: Any) -> None:
        self.python = python
        self.exported = exported
        self.env_kwargs = python.env_kwargs
        self.worst = 0.0
        self.worst_surge = float("nan")  # u [m/s] where the largest difference was seen
        self.count = 0

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        py_state, onnx_state = state if state is not None else (None, None)
        action, py_state = self.python.predict(observation, py_state, episode_start, deterministic)
        twin, onnx_state = self.exported.predict(
            observation, onnx_state, episode_start, deterministic
        )
        diff = np.abs(np.asarray(twin, np.float64) - np.asarray(action, np.float64))
        if diff.max() > self.worst:
            self.worst = float(diff.max())
            row = np.unravel_index(int(np.argmax(diff)), diff.shape)[0] if diff.ndim == 2 else 0
            self.worst_surge = float(np.atleast_2d(observation)[row, OBS_INDEX["u"]])
        self.count += int(np.atleast_2d(observation).shape[0])
        return action, (py_state, onnx_state)


@dataclass
class ParityOptions:
    """The command line of `python -m benchmarks.checks.onnx_parity`."""

    out: Path = option(Path("out/onnx_parity"), "folder of parity.json, parity.md")  # noqa: RUF009
    duration: float = option(300.0, "episode length [s]")
    agents: str = option(",".join(REFERENCE_AGENTS), "reference agents, comma-separated")
    nudges: int = option(1, "nudged flights per set beyond the RMS tolerance (seeds 0..K-1)")


class Exports:
    """An agent's exports by actuator: the shipped one (the paper's actuator), and for an agent
    that allocates its commands one per other actuator, exported into ``folder`` when needed."""

    def __init__(self, agent: str, folder: Path) -> None:
        from controllers.onnx_policy import read_contract

        self.agent = agent
        self.folder = folder
        self.shipped = AGENTS_DIR / agent / "policy.onnx"
        self.allocated = read_contract(self.shipped).allocated
        self.files: dict[str, Path] = {"paper": self.shipped}

    def for_actuator(self, actuator: str) -> Path:
        from controllers.onnx_export import export_onnx

        if not self.allocated or actuator == "random":
            return self.shipped
        if actuator not in self.files:
            target = self.folder / f"{self.agent}_{actuator}.onnx"
            export_onnx(AGENTS_DIR / self.agent, target, actuator=actuator)
            self.files[actuator] = target
        return self.files[actuator]


def check(
    exports: Exports, actuator: str | None, duration: float, nudges: int = 1
) -> dict[str, Any]:
    """Both flights of an agent's exports over the whole test suite (module doc), and
    ``nudges`` nudged flights (sign seeds 0..nudges-1) of each set beyond the RMS tolerance;
    ``actuator`` overrides every task's (None: each task's own)."""
    agent = exports.agent
    env_id, agent_env = policy_env(agent)
    episodes, count, worst, worst_surge = 0, 0, 0.0, float("nan")
    not_flown: dict[str, str] = {}
    rms_by_set: dict[str, float] = {}
    sensitivity_by_set: dict[str, float] = {}
    start = time.perf_counter()
    for task in test_suite():
        env = {**VARIANTS[env_id], **agent_env, **task.env, "max_time": duration}
        controller = dict(task.controller)
        if actuator is not None:  # the scenario's controllers are told it too
            env["actuator"] = actuator
            controller.pop("actuator", None)
        try:  # the suite's own rule: a set the agent cannot fly is not its set (the as-built
            # agent commands the propeller and fins and flies no set on another actuator)
            check_policy_for_env(agent, env, controller)
        except ValueError as error:
            not_flown[task.name] = str(error)
            print(f"  {task.name:<36} not flown: {error}", flush=True)
            continue
        onnx_spec = f"onnx:{exports.for_actuator(env.get('actuator', 'paper'))}"
        twin = TwinPolicy(
            build_policy(agent, env, controller), build_policy(onnx_spec, env, controller)
        )
        seeds = list(task.seeds)
        flown = evaluate(twin, seeds, **env)
        alone = evaluate(build_policy(onnx_spec, env, controller), seeds, **env)
        rms_by_set[task.name] = max_relative_difference(flown, alone)
        nudge = max(twin.worst, NUDGE_FLOOR)
        if rms_by_set[task.name] > RMS_TOLERANCE:  # only there is the loop's own spread asked
            nudged = [
                NudgedPolicy(build_policy(agent, env, controller), nudge, seed)
                for seed in range(nudges)
            ]
            sensitivity_by_set[task.name] = max(
                max_relative_difference(flown, evaluate(policy, seeds, **env)) for policy in nudged
            )
        episodes += len(seeds)
        count += twin.count
        if twin.worst > worst:
            worst, worst_surge = twin.worst, twin.worst_surge
        print(
            f"  {task.name:<36} {len(seeds):>3} episodes, max |Δ command| {twin.worst:.2g} "
            f"(at u = {twin.worst_surge:.2f} m/s); max relative RMS difference "
            f"{rms_by_set[task.name]:.2g}"
            + (
                f", agent nudged by ±{nudge:.2g}: {sensitivity_by_set[task.name]:.2g}"
                if task.name in sensitivity_by_set
                else ""
            ),
            flush=True,
        )
    if episodes == 0:
        raise ValueError(f"{agent}: flies none of the test suite's sets ({not_flown})")
    return {
        "agent": agent,
        "actuator": actuator or "each task's",
        "episodes": episodes,
        "observations": count,
        "max_abs_command_error": worst,
        "surge_at_max_error": worst_surge,
        "max_relative_rms_error": max(rms_by_set.values()),
        "max_relative_rms_error_by_set": rms_by_set,
        "nudged_relative_rms_difference_by_set": sensitivity_by_set,
        "nudges": nudges,
        "rms_target": rms_verdict(rms_by_set, sensitivity_by_set),
        "not_flown": sorted(not_flown),
        "wall_s": time.perf_counter() - start,
    }


def max_relative_difference(
    first: Sequence[dict[str, Any]], second: Sequence[dict[str, Any]]
) -> float:
    """The largest `relative_difference` of two flights' RMS distances, episode by episode."""
    return max(
        relative_difference(a["rms_distance"], b["rms_distance"])
        for a, b in zip(first, second, strict=True)
    )


def rms_verdict(export: dict[str, float], nudged: dict[str, float]) -> str:
    """ "met" when every set's export difference is within `RMS_TOLERANCE`; "sensitive" when the
    sets beyond it are sets where the Python agent nudged by the export's largest command
    difference moves as far (the per-episode target cannot tell the export from rounding
    there); "missed" otherwise."""
    beyond = [name for name, difference in export.items() if difference > RMS_TOLERANCE]
    if not beyond:
        return "met"
    if all(nudged.get(name, 0.0) > RMS_TOLERANCE for name in beyond):
        return "sensitive"
    return "missed"


def relative_difference(a: float, b: float) -> float:
    """|a − b|/|a|; 0 when both are NaN (an episode that ended before the metrics window, in
    both flights), inf when only one is."""
    if np.isnan(a) and np.isnan(b):
        return 0.0
    if np.isnan(a) or np.isnan(b):
        return np.inf
    return abs(a - b) / max(abs(a), 1e-12)


def table(rows: Sequence[dict[str, Any]]) -> str:
    """The markdown tables of the results: one row per export, then the sets where an export's
    RMS difference passed the tolerance, beside the nudged agent's."""
    lines = [
        "| export | episodes | observations | max abs command error | at surge [m/s] "
        "| max relative RMS error | agent nudged alike (sets beyond 0.1 %) | RMS target |",
        "|---|---:|---:|---:|---:|---:|---:|---|",
    ]
    beyond = []
    for r in rows:
        nudged = r["nudged_relative_rms_difference_by_set"]
        lines.append(
            f"| {r['label']} | {r['episodes']} | {r['observations']:,} | "
            f"{r['max_abs_command_error']:.2g} | {r['surge_at_max_error']:.2f} | "
            f"{r['max_relative_rms_error']:.2g} | "
            f"{format(max(nudged.values()), '.2g') if nudged else '–'} | "
            f"{r['rms_target']} |"
        )
        beyond += [
            f"| {r['label']} | {name} | {difference:.2g} | {nudged[name]:.2g} "
            f"| {r.get('nudges', 1)} |"
            for name, difference in r["max_relative_rms_error_by_set"].items()
            if difference > RMS_TOLERANCE
        ]
    text = "\n".join(lines) + "\n"
    if beyond:
        text += (
            f"\nSets beyond the RMS tolerance ({RMS_TOLERANCE:.1%}), with the Python agent's own "
            "difference when every command is nudged by ± the export's largest difference on "
            "the set (the largest over that many draws of the nudges' signs):\n\n"
            "| export | set | export | agent nudged | draws |\n|---|---|---:|---:|---:|\n"
            + "\n".join(beyond)
            + "\n"
        )
    return text


def main(argv: Sequence[str] | None = None) -> list[dict[str, Any]]:
    args, parser = parse_options(
        ParityOptions, argv, program_name("benchmarks.checks.onnx_parity"), __doc__
    )
    with usage_errors(parser):
        agents = comma_names(args.agents, "--agents")
        unknown = sorted(set(agents) - set(REFERENCE_AGENTS))
        if unknown:
            raise ValueError(f"--agents: unknown {unknown}; valid: {list(REFERENCE_AGENTS)}")
        finite_number("--duration", args.duration, 10.0, 1000.0, unit="s")
        if not 1 <= args.nudges <= 100:
            raise ValueError(f"--nudges: {args.nudges} nudged flights; use 1 to 100")
        writable_folder(args.out)
    kept = kept_rows(args.out, args.duration, agents)  # the other agents' rows stay
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        for agent in agents:
            exports = Exports(agent, Path(scratch))
            runs = [(agent, None)]
            if exports.allocated:
                runs.append((f"{agent} on propeller and fins", "realistic"))
            for label, actuator in runs:
                print(f"{label}:", flush=True)
                rows.append(
                    {"label": label, **check(exports, actuator, args.duration, args.nudges)}
                )
                # an export's row, kept at once, beside the rows of the agents not re-run
                write_results(args.out, args.duration, in_agent_order([*kept, *rows]))
    rows = in_agent_order([*kept, *rows])
    commands = all(r["max_abs_command_error"] <= COMMAND_TOLERANCE for r in rows)
    verdicts = sorted({r["rms_target"] for r in rows})
    print(table(rows) + f"command target met: {commands}; RMS target: {', '.join(verdicts)}")
    return rows


def kept_rows(out: Path, duration: float, agents: Sequence[str]) -> list[dict[str, Any]]:
    """The rows of OUT/parity.json for the reference agents not in ``agents``, when that file
    was written for episodes of ``duration`` [s] (re-checking one agent must not lose the
    others' rows); none otherwise (another duration's rows would not be comparable)."""
    import json

    try:
        earlier = json.loads((out / "parity.json").read_text())
    except (OSError, ValueError):
        return []
    if not isinstance(earlier, dict) or earlier.get("duration_s") != duration:
        return []
    return [
        row
        for row in earlier.get("rows") or []
        if isinstance(row, dict)
        and row.get("agent") in REFERENCE_AGENTS
        and row.get("agent") not in agents
    ]


def in_agent_order(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """``rows`` in the order of `REFERENCE_AGENTS` (an agent's rows in their own order)."""
    return sorted(rows, key=lambda row: REFERENCE_AGENTS.index(row["agent"]))


def write_results(out: Path, duration: float, rows: Sequence[dict[str, Any]]) -> None:
    """parity.json and parity.md of the rows so far, each written atomically."""
    write_json(out / "parity.json", {"duration_s": duration, "rows": list(rows)})
    note = (
        "\nSets an export does not fly (the suite flies none of them either: another actuator "
        "than the one it commands): "
        + "; ".join(f"{r['label']}: {', '.join(r['not_flown'])}" for r in rows if r["not_flown"])
        + "\n"
        if any(r["not_flown"] for r in rows)
        else ""
    )
    write_text(
        out / "parity.md",
        f"ONNX exports against the Python agents, test suite, {duration:g}-s episodes "
        f"(targets: command ≤ {COMMAND_TOLERANCE:g}, RMS ≤ {RMS_TOLERANCE:.1%} per episode)\n\n"
        + table(rows)
        + note,
    )


if __name__ == "__main__":
    main()
