"""A training schedule: an agent's whole recipe in one file, trained by one command.

An RL-Zoo hyper-parameter file (one env id's section, `benchmarks.training.config`) plus a
``schedule`` section::

    AUVPath3DPreview-v0:            # the first phase's hyper-parameters
      n_timesteps: !!float 8e6
      ...
    schedule:
      options: {task_set: validation_paper_start, eval_episodes: 64, eval_freq: 500000}
      stages: [envelope_guard, actuator_allocation]   # added to the exported agents
      phases:
        - {name: base}
        - {name: along_track, n_timesteps: !!float 2e6, learning_rate: lin_1e-4,
           obs_scales: {x_e: 0.25, x_e_integral: 0.5}}

Each phase is a multi-seed run (`benchmarks.training.seeds`) of the section with its changes and
those of the phases before it on top (``obs_scales`` merged entry by entry, every other key
replaced: a phase says what changes from the phase before), each seed
starting from the previous phase's agent of the same seed (its weights, optimiser state and
statistics: `benchmarks.training.warm_start`; the first phase from scratch, or from
``init_from``). A phase with a ``jump_start`` (`benchmarks.training.jump_start`) imitates a
classical expert instead of running PPO or SAC, and its changes are its own: the phase after it
trains with the section as the phases before the jump start left it, from the jump-started
agents (an off-policy jump start's flights go with them, to fill the next phase's replay
buffer: `benchmarks.training.transitions`, with the expert's labels for a phase that keeps
its SAC near them, ``demo_regularization``, and hands them on in turn)::

      phases:
        - {name: jump_start, jump_start: {expert: fbsm_colos, steps: 262144}}
        - {name: base}                      # PPO from the imitating agents

A phase's ``task_set`` names the validation set it and the phases after it select on (its
first ``eval_episodes`` seeds), in place of the command's: an as-built agent that learns both
plants is selected on the 6-DOF plant in its last phase.

``options`` are the defaults of the command's own options (the command line
wins); ``stages`` are added to the exported agents only, after training, behind the stages the
agent trained inside (`controllers.stages`: a file's own ``stages`` trains inside them).

``select_on`` chooses how the shipped seed is picked: ``network`` (the default) by the last
phase's validation of the bare networks, ``shipped`` by the same validation episodes flown by
each seed's agent with the export stages on (`benchmarks.training.shipped_selection`), since a
guard or a low-speed floor can change which seed flies best. The network's pick stays in the
last phase's summary; schedule.json adds ``shipped_selection`` (every seed's score as shipped).

Layout of OUT: ``phase_<k>_<name>/`` (each phase's multi-seed run; ``selected/agent_seed_<s>``
is each seed's agent, selected on validation, that the next phase starts from), ``configs/``
(each phase's hyper-parameter file) and ``schedule.json`` (the plan and every phase's
summary). A killed schedule continues with the same command plus ``--resume``: finished phases
are kept, the running one resumes. Every phase's configuration is checked before the first one
starts.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from auv_gym.support.files import replace_outputs, write_atomic, write_json, write_text
from benchmarks.training.checkpoints import SEED_AGENT_PREFIX, check_export_folder, export_agent
from benchmarks.training.config import ZOO_KEYS, read_zoo_config
from benchmarks.training.evaluation import EVAL_SEEDS, HELD_OUT_FILE, write_held_out_evaluation
from benchmarks.training.jump_start import JUMP_START_KEY
from benchmarks.training.learning_curve import EVAL_FILE
from benchmarks.training.seed_workers import seed_dir
from benchmarks.training.seeds import (
    PLAN_FILE,
    SUMMARY_FILE,
    SeedsOptions,
    check_obs_scales,
    check_out_folder,
    holds_work,
    train_seeds,
    validation_set,
    write_seed_outputs,
)
from benchmarks.training.shipped_selection import SELECT_ON, select_shipped
from benchmarks.training.transitions import TRANSITIONS_FILE
from benchmarks.training.vehicle_share import check_native
from benchmarks.training.warm_start import SEED_FIELD
from controllers.agent import METADATA_FILE
from controllers.algorithms import ALGORITHMS
from controllers.stages import check_stage_specs

__all__ = [
    "SCHEDULE_FILE",
    "SCHEDULE_KEY",
    "Phase",
    "Schedule",
    "read_schedule",
    "train_schedule",
]

SCHEDULE_KEY = "schedule"
SCHEDULE_FILE = "schedule.json"
CONFIGS = "configs"  # OUT/configs/phase_<k>_<name>.yml: each phase's hyper-parameter file
SELECTED = "selected"  # OUT/phase_<k>_<name>/selected/agent_seed_<s>: each seed's agent
SCHEDULE_KEYS = ("phases", "stages", "options", "select_on")
# The command's options a schedule may set (its defaults: the command line wins).
OPTION_KEYS = (
    "algo",
    "task_set",
    "eval_episodes",
    "eval_duration",
    "eval_freq",
    "checkpoint_freq",
)
PHASE_KEYS = ("name", "n_timesteps", "init_from", "task_set")  # besides the section's keys


@dataclass(frozen=True)
class Phase:
    """One phase: its name, and what it changes in the section (n_timesteps included)."""

    name: str
    changes: dict[str, Any]
    init_from: str | None = None  # the first phase only: an agent template ({seed})
    task_set: str | None = None  # the validation set it selects on, from here on


@dataclass(frozen=True)
class Schedule:
    """A checked schedule file: its env id, phases, export stages and option defaults."""

    path: Path
    env_id: str
    section: dict[str, Any]
    phases: tuple[Phase, ...]
    stages: tuple[dict[str, Any], ...]
    options: dict[str, Any]
    select_on: str = SELECT_ON[0]  # "shipped": the seed chosen with the stages on

    def phase_section(self, k: int) -> dict[str, Any]:
        """Phase ``k``'s hyper-parameters: the section with the changes of phases 0..k on top,
        in order (a phase changes what the phase before it trained with), except those of an
        earlier jump-start phase (they were its own)."""
        section = dict(self.section)
        for j, phase in enumerate(self.phases[: k + 1]):
            if j < k and JUMP_START_KEY in phase.changes:
                continue  # a jump start's changes are its own (module doc)
            for key, value in phase.changes.items():
                if key == "obs_scales" and isinstance(value, Mapping):
                    section[key] = {**(section.get(key) or {}), **value}
                else:
                    section[key] = value
        return section

    def folder(self, out: Path, k: int) -> Path:
        """Phase ``k``'s multi-seed run directory under OUT."""
        return out / f"phase_{k + 1}_{self.phases[k].name}"


def read_schedule(path: str | Path) -> Schedule | None:
    """The schedule of a hyper-parameter file, checked; None when it has no ``schedule``.

    ValueError (one line naming the file and the key) for: a schedule that is not a mapping or
    has unknown keys, no phases, a phase without a unique identifier name, an unknown phase key
    (valid: the section's keys, `PHASE_KEYS`), ``init_from`` on a later phase, unknown stages or
    options, a file without exactly one env section.
    """
    import yaml

    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as error:
        problem = " ".join(str(error).split())
        raise ValueError(f"{path}: cannot be read as YAML: {problem}") from None
    if not isinstance(data, dict) or SCHEDULE_KEY not in data:
        return None
    where = f"{path}: {SCHEDULE_KEY}"
    spec = data[SCHEDULE_KEY]
    if not isinstance(spec, dict):
        raise ValueError(f"{where} must be a mapping of {list(SCHEDULE_KEYS)}")
    unknown = sorted(set(spec) - set(SCHEDULE_KEYS))
    if unknown:
        raise ValueError(f"{where}: unknown keys {unknown}; valid: {list(SCHEDULE_KEYS)}")
    envs = [key for key in data if key != SCHEDULE_KEY]
    if len(envs) != 1 or not isinstance(data[envs[0]], dict):
        raise ValueError(f"{path}: a schedule file holds one env section, found {envs}")
    env_id = envs[0]
    options = dict(spec.get("options") or {})
    unknown = sorted(set(options) - set(OPTION_KEYS))
    if unknown:
        raise ValueError(f"{where}.options: unknown keys {unknown}; valid: {list(OPTION_KEYS)}")
    algo = options.get("algo", "ppo")
    if algo not in ALGORITHMS:
        raise ValueError(f"{where}.options: unknown algo {algo!r}; valid: {sorted(ALGORITHMS)}")
    allowed = set(PHASE_KEYS) | set(ZOO_KEYS) | set(ALGORITHMS[algo].hyperparameters)
    phases = spec.get("phases")
    if not isinstance(phases, list) or not phases:
        raise ValueError(f"{where}.phases must be a non-empty list of phases")
    checked: list[Phase] = []
    for k, phase in enumerate(phases):
        at = f"{where}.phases[{k}]"
        if not isinstance(phase, dict):
            raise ValueError(f"{at} must be a mapping with a 'name', got {phase!r}")
        name = phase.get("name")
        if not isinstance(name, str) or not re.fullmatch(r"[a-z][a-z0-9_]*", name):
            raise ValueError(f"{at}: name must be a lower-case identifier, got {name!r}")
        if name in (p.name for p in checked):
            raise ValueError(f"{at}: phase name {name!r} is used twice")
        unknown = sorted(set(phase) - allowed)
        if unknown:
            raise ValueError(
                f"{at} ({name}): unknown keys {unknown}; a phase changes the section's "
                f"hyper-parameters (or {list(PHASE_KEYS)})"
            )
        init_from = phase.get("init_from")
        if init_from is not None and k > 0:
            raise ValueError(
                f"{at} ({name}): init_from belongs to the first phase (later phases start "
                "from the previous phase's agents)"
            )
        task_set = phase.get("task_set")
        if task_set is not None:
            validation_set(task_set, f"{at} ({name}): task_set:")
        changes = {
            key: v for key, v in phase.items() if key not in ("name", "init_from", "task_set")
        }
        checked.append(
            Phase(name, changes, None if init_from is None else str(init_from), task_set)
        )
    stages = check_stage_specs(spec.get("stages"), f"{where}.stages")
    # The exports carry the stages the agent trains inside (the section's), then these: each
    # once, in the stages' order.
    inside = check_stage_specs(data[env_id].get("stages"), f"{path}: {env_id}.stages")
    check_stage_specs([*inside, *stages], f"{where}.stages after {env_id}.stages")
    select_on = spec.get("select_on", SELECT_ON[0])
    if select_on not in SELECT_ON:
        raise ValueError(
            f"{where}.select_on: unknown value {select_on!r}; valid: {list(SELECT_ON)}"
        )
    if select_on == "shipped" and not stages:
        raise ValueError(
            f"{where}.select_on: shipped needs export stages (without them the agent ships "
            "as it trained, and the training's validation already chose it)"
        )
    return Schedule(path, env_id, dict(data[env_id]), tuple(checked), stages, options, select_on)


def _write_phase_config(schedule: Schedule, k: int, out: Path) -> Path:
    import yaml

    text = yaml.safe_dump({schedule.env_id: schedule.phase_section(k)}, sort_keys=False)
    (out / CONFIGS).mkdir(parents=True, exist_ok=True)
    return write_text(out / CONFIGS / f"{schedule.folder(out, k).name}.yml", text)


def check_schedule(schedule: Schedule, algo: str, out: Path, vec_env: str = "auto") -> list[Path]:
    """Write and check every phase's configuration (`read_zoo_config`, a plant share on the
    ``vec_env`` it trains on) before any training; the config files, one per phase. Errors
    name the phase."""
    configs = []
    carries = False  # the phase before hands on labelled transitions (`demo_regularization`)
    for k, phase in enumerate(schedule.phases):
        config = _write_phase_config(schedule, k, out)
        try:
            cfg = read_zoo_config(config, schedule.env_id, algo)
            check_obs_scales(cfg, schedule.env_id, str(config))
            check_native(cfg.vehicle_share, vec_env, str(config))
        except ValueError as error:
            raise ValueError(
                f"{schedule.path}: phase {phase.name!r}: {error}".replace(f"{config}: ", "")
            ) from None
        tuned = cfg.demo_regularization is not None and cfg.jump_start is None
        if tuned and k > 0 and not carries:
            raise ValueError(
                f"{schedule.path}: phase {phase.name!r}: demo_regularization needs the labelled "
                "transitions of an off-policy jump start: put the phase after a jump_start phase"
            )
        carries = cfg.jump_start is not None or tuned
        configs.append(config)
    first = schedule.phases[0].init_from
    if first is not None and SEED_FIELD not in first and not Path(first).is_dir():
        raise ValueError(
            f"{schedule.path}: phase {schedule.phases[0].name!r}: init_from {first!r} does not "
            "exist (an agent folder, or a template with {seed})"
        )
    return configs


def _pass_transitions(run: Path, selected: Path) -> None:
    """Copy an off-policy jump start's flights (`TRANSITIONS_FILE` of the seed's run folder)
    beside its selected agent, where the next phase's warm start finds them; atomically, and
    only there: exported agents and results never carry them."""
    source, target = run / TRANSITIONS_FILE, selected / TRANSITIONS_FILE
    if source.is_file() and not target.is_file():
        import shutil

        with source.open("rb") as data:
            write_atomic(target, lambda fh: shutil.copyfileobj(data, fh))


def _with_stages(agent: Path, stages: tuple[dict[str, Any], ...]) -> None:
    """Add ``stages`` after the stages a copied agent trained inside (its metadata's, written
    atomically); nothing when there are none."""
    if not stages:
        return
    meta_file = agent / METADATA_FILE
    metadata = json.loads(meta_file.read_text())
    inside = list(metadata.get("stages") or [])
    metadata["stages"] = [dict(s) for s in check_stage_specs([*inside, *stages], str(meta_file))]
    write_json(meta_file, metadata, indent=2, sort_keys=True)


def _finished(folder: Path, seeds: tuple[int, ...]) -> dict[str, Any] | None:
    """A phase's summary when it finished every seed of this command, else None."""
    summary_file = folder / SUMMARY_FILE
    if not summary_file.is_file():
        return None
    summary = json.loads(summary_file.read_text())
    done = sorted(entry["seed"] for entry in summary.get("seeds", ()))
    return summary if done == sorted(seeds) else None


def train_schedule(opts: SeedsOptions, schedule: Schedule) -> dict[str, Any]:
    """Train every phase of ``schedule`` for every seed of ``opts`` (module doc); returns the
    summary written to OUT/schedule.json. ``opts.train.config`` is the schedule's file."""
    check_out_folder(opts.out)
    out = Path(opts.out)
    if opts.export is not None:  # written at the end: refused now, not after the training
        check_export_folder(opts.export, "--export", out)
    if not opts.resume and out.exists() and any(out.iterdir()):
        raise ValueError(f"output folder {out} is not empty; pass --resume or another --out")
    if opts.train.init_from is not None:
        raise ValueError(
            "--init-from: a schedule's first phase names its initial agent (init_from)"
        )
    created = not out.exists()
    try:
        return _train_schedule(opts, schedule, out)
    except (ValueError, FileNotFoundError):  # refused before training (`train_seeds`)
        if not opts.resume and not holds_work(schedule.folder(out, 0)):
            _remove_refused_start(schedule, out, created)
        raise


def _remove_refused_start(schedule: Schedule, out: Path, created: bool) -> None:
    """Remove what a fresh schedule refused before training wrote in OUT (its phase configs,
    schedule.json, phase folders holding no work), so that the corrected command finds OUT as it
    was; nothing else is touched."""
    import shutil

    for k in range(len(schedule.phases)):
        config = out / CONFIGS / f"{schedule.folder(out, k).name}.yml"
        config.unlink(missing_ok=True)
        folder = schedule.folder(out, k)
        if folder.is_dir() and not holds_work(folder):
            shutil.rmtree(folder, ignore_errors=True)
    (out / SCHEDULE_FILE).unlink(missing_ok=True)
    for folder in (out / CONFIGS, *((out,) if created else ())):
        if folder.is_dir() and not any(folder.iterdir()):
            folder.rmdir()


def _train_schedule(opts: SeedsOptions, schedule: Schedule, out: Path) -> dict[str, Any]:
    configs = check_schedule(schedule, opts.train.algo, out, opts.train.vec_env)
    plan = {
        "config_file": str(schedule.path),
        "env_id": schedule.env_id,
        "phases": [
            {"name": p.name, **p.changes, **({"task_set": p.task_set} if p.task_set else {})}
            for p in schedule.phases
        ],
        "stages": list(schedule.stages),
        "seeds": list(opts.seeds),
        **({"select_on": schedule.select_on} if schedule.select_on != SELECT_ON[0] else {}),
    }
    write_json(out / SCHEDULE_FILE, {"plan": plan, "phases": []}, indent=2, sort_keys=True)
    summaries: list[dict[str, Any]] = []
    selection = opts  # the validation of the phases so far: the command's, then theirs
    for k, phase in enumerate(schedule.phases):
        folder = schedule.folder(out, k)
        if phase.task_set is not None:  # its own set's first eval_episodes seeds
            selection = replace(
                opts,
                task_set=phase.task_set,
                train=replace(opts.train, eval_seeds=tuple(EVAL_SEEDS)),
            )
        summary = _finished(folder, opts.seeds)
        if summary is None:
            if k == 0:
                init_from = phase.init_from
            else:
                previous = schedule.folder(out, k - 1) / SELECTED  # each seed's agent there
                init_from = str(previous / f"{SEED_AGENT_PREFIX}{SEED_FIELD}")
            if opts.progress:
                print(f"phase {k + 1}/{len(schedule.phases)}: {phase.name}", flush=True)
            phase_opts = replace(
                selection,
                out=str(folder),
                resume=(folder / PLAN_FILE).is_file(),
                export=None,
                results=None,
                train=replace(
                    selection.train,
                    config=str(configs[k]),
                    env_id=schedule.env_id,
                    init_from=init_from,
                    n_timesteps=None,
                ),
            )
            summary = train_seeds(phase_opts)
        for entry in summary["seeds"]:  # what the next phase starts from, seed by seed
            selected = folder / SELECTED / f"{SEED_AGENT_PREFIX}{entry['seed']}"
            if not selected.is_dir():
                export_agent(Path(entry["agent"]), selected)
            _pass_transitions(seed_dir(folder, entry["seed"]), selected)
        summaries.append({"name": phase.name, "summary": summary})
        write_json(
            out / SCHEDULE_FILE, {"plan": plan, "phases": summaries}, indent=2, sort_keys=True
        )
    last = summaries[-1]["summary"]
    selected_seed, shipped = last["selected_seed"], None
    if schedule.select_on == "shipped":
        progress = (lambda line: print(line, flush=True)) if opts.progress else None
        selected_seed, shipped = select_shipped(out, last["seeds"], schedule.stages, progress)
    chosen = next(e for e in last["seeds"] if e["seed"] == selected_seed)
    if opts.export:
        export_agent(Path(chosen["agent"]), Path(opts.export))
        _with_stages(Path(opts.export), schedule.stages)
        report = json.loads((Path(chosen["agent"]) / HELD_OUT_FILE).read_text())
        if schedule.stages:  # the test episodes flown again as the agent ships, stages on
            write_held_out_evaluation(opts.export, report["duration_s"], schedule.env_id)
        else:
            write_json(Path(opts.export) / HELD_OUT_FILE, report, indent=2, sort_keys=True)
    result = {"plan": plan, "phases": summaries, "selected_seed": selected_seed}
    if shipped is not None:  # the network's pick stays in the last phase's summary
        result["shipped_selection"] = shipped
    write_json(out / SCHEDULE_FILE, result, indent=2, sort_keys=True)
    if opts.results:
        _write_results(Path(opts.results), schedule, out, last, result)
    return result


def _write_results(
    results: Path, schedule: Schedule, out: Path, last: dict[str, Any], record: dict[str, Any]
) -> None:
    """RESULTS, as a one-phase run's (`benchmarks.training.seeds.write_seed_outputs`): per seed
    its agent with the stages (``agent_seed_<s>/``, for `auv-gym suite`), its held-out test
    evaluation and its last phase's learning curve (``seed_<s>_learning_curve.csv``), every
    phase's curve (``phase_<k>_<name>_seed_<s>_curve.csv``); and schedule.json (all atomic).
    Files an earlier run with other seeds wrote there are removed (`replace_outputs`)."""
    last_phase = len(schedule.phases) - 1
    written = [results / SCHEDULE_FILE]
    for entry in last["seeds"]:
        seed = entry["seed"]
        curve = seed_dir(schedule.folder(out, last_phase), seed) / EVAL_FILE
        written += write_seed_outputs(results, entry, curve)
        _with_stages(results / f"{SEED_AGENT_PREFIX}{seed}", schedule.stages)
        for k in range(len(schedule.phases)):
            phase_curve = seed_dir(schedule.folder(out, k), seed) / EVAL_FILE
            if phase_curve.is_file():  # a jump-start phase keeps no learning curve
                name = f"{schedule.folder(out, k).name}_seed_{seed}_curve.csv"
                written.append(write_text(results / name, phase_curve.read_text()))
    write_json(results / SCHEDULE_FILE, record, indent=2, sort_keys=True)
    replace_outputs(results, written)
