"""Re-run the committed benchmark results and compare them with the committed files, exactly.

A refactoring that must not change behaviour passes only if every committed metric is
reproduced to the last bit:

1. `benchmarks/results/full/episodes.csv`: the command recorded in `episodes.json` is re-run into
   a temporary folder; every cell of every (scenario, policy, seed) row is compared as text (the
   CSV holds full-precision floats, so equal text is equal bits). The learned policies' cells
   (torch networks) reproduce within `AGENT_TOLERANCE` relative (float32 arithmetic rounds by
   CPU and BLAS build), counted apart from the exact ones. A reference agent retired since
   (`benchmarks.catalog.policies.REMOVED_POLICIES`) is not re-run: its committed rows stay as
   the record of what it did and are counted apart.
2. `benchmarks/results/paper/metrics.json`: `benchmarks.reports.paper_figures` is re-run with the
   recorded seed and duration; every metric value is compared (wall times and versions excepted).
3. With `--agents`, each shipped agent's `held_out_evaluation.json` is re-evaluated and compared
   value by value (bit-identical on the machine that trained it; elsewhere BLAS may round
   differently, so this check is opt-in; it runs in this process, as this machine does:
   `--machine` does not reach it).

    python -m benchmarks.checks.reproduction                # 1 + 2, about 4 minutes on 2 cores
    python -m benchmarks.checks.reproduction --agents       # 1 + 2 + 3

The committed `full` and `paper` results were made on an AVX2 machine, and a few of the
numbers an episode is built from round by the CPU: NumPy picks AVX-512 loops for `exp` and
`pow` where the CPU has them (the wave spectrum's tables, so every wave component's
frequency), and OpenBLAS picks its kernels by CPU (the norm of a 3-vector, a drawn survey's
curvature ramp by `np.convolve`: dot products, fused on AVX-512). The re-runs therefore run
as that machine did wherever the CPU can: NumPy without its AVX-512 loops
(``NPY_DISABLE_CPU_FEATURES``) and OpenBLAS on its Haswell kernels (``OPENBLAS_CORETYPE``,
where the CPU has AVX2 and FMA); `--machine native` leaves both their own choice
(docs/design.md §4, the bullet on OpenBLAS kernels).

Rows or columns present on one side only are listed; they are an error unless
`--allow-new` is given (a benchmark that gained a policy, scenario or metric on purpose must
still reproduce every committed cell it shares with the new run). Exit status 0: reproduced.
"""

from __future__ import annotations

import csv
import json
import math
import os
import shlex
import subprocess
import sys
import tempfile
from collections import Counter
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from auv_gym.support.files import numpy_dispatch, write_json
from benchmarks.arguments import parse_options, program_name, usage_errors, writable_location
from benchmarks.catalog.policies import REMOVED_POLICIES, PolicySpec
from benchmarks.options import option

RESULTS = Path(__file__).resolve().parents[1] / "results"
AGENTS = Path(__file__).resolve().parents[1] / "agents"
# A torch network's actions round differently by CPU and BLAS build (float32, ~1e-7): the
# episodes of the learned policies reproduce to this relative tolerance, the rest bit for bit.
AGENT_TOLERANCE = 1e-6
# differ by design (the machine record names the CPU the re-run ran on, not the results')
UNCOMPARED_KEYS = ("wall_time", "version", "agent_wall_time", "git_commit", "machine")
# Metrics `auv_gym.metrics.compute_metrics` gained after the committed results were recorded: a
# column or value of one of them that only the re-run holds is listed, not an error (the
# committed files predate it); every cell both sides hold must still match.
ADDED_METRICS = ("mean_path_speed",)


MACHINES = ("avx2", "native")  # --machine: as the committed results' machine, or as this one
_HASWELL_NEEDS = ("avx2", "fma")  # CPU flags (/proc/cpuinfo) OpenBLAS's Haswell kernels need


def cpu_flags(cpuinfo: Path = Path("/proc/cpuinfo")) -> set[str]:
    """The CPU's feature flags as Linux lists them (empty where it does not)."""
    try:
        text = cpuinfo.read_text()
    except OSError:
        return set()
    for line in text.splitlines():
        if line.startswith("flags"):
            return set(line.partition(":")[2].split())
    return set()


def avx512_dispatch() -> list[str]:
    """NumPy's dispatched feature names above AVX2 (``X86_V4``, ``AVX512_*``; the names vary by
    NumPy version), the ones ``NPY_DISABLE_CPU_FEATURES`` turns off to run as an AVX2 CPU."""
    dispatch = numpy_dispatch()
    dispatched = dispatch[0] if dispatch is not None else []
    return [name for name in dispatched if name == "X86_V4" or name.startswith("AVX512")]


def machine_environment(machine: str, flags: set[str], avx512: Sequence[str]) -> dict[str, str]:
    """The environment of a re-run: for ``machine="avx2"`` NumPy without its ``avx512`` loops
    and OpenBLAS on its Haswell kernels where the CPU has the ``flags`` they need (a kernel it
    cannot run would stop on an illegal instruction: then OpenBLAS's own choice, said on
    stderr); for ``"native"`` this process's environment unchanged."""
    env = dict(os.environ)
    if machine == "native":
        return env
    if avx512:
        env["NPY_DISABLE_CPU_FEATURES"] = " ".join(avx512)
    missing = [flag for flag in _HASWELL_NEEDS if flag not in flags]
    if missing:
        print(
            f"this CPU lacks {', '.join(missing)}: OpenBLAS picks its own kernels, so results "
            f"whose paths are drawn surveys or splines may differ in the last digit",
            file=sys.stderr,
        )
    else:
        env["OPENBLAS_CORETYPE"] = "Haswell"
    return env


def _run(module: str, args: Sequence[str], env: dict[str, str] | None = None) -> None:
    command = [sys.executable, "-m", module, *args]
    pinned = [
        f"{name}={shlex.quote(env[name])}"
        for name in ("NPY_DISABLE_CPU_FEATURES", "OPENBLAS_CORETYPE")
        if env is not None and env.get(name) and env.get(name) != os.environ.get(name)
    ]
    print("$", " ".join([*pinned, shlex.join(command[1:])]), flush=True)
    subprocess.run(command, check=True, env=env)


# The compare module as a recorded command names it: its former flat name (the committed results
# were recorded under it) or its package path; either is re-run as `COMPARE`.
COMPARE = "benchmarks.runner.compare"
COMPARE_NAMES = ("benchmarks.compare", COMPARE)


def _rerun_arguments(
    recorded_command: str,
    out: Path,
    workers: int,
    scenarios: Sequence[str] = (),
    policies: Sequence[str] = (),
) -> list[str]:
    """The recorded compare command's arguments (after its module, `COMPARE_NAMES`) with --out and
    --workers replaced and, given ``scenarios`` (the committed run's), --scenarios naming them:
    a recorded ``--scenarios all`` means the scenarios of its day, not those added since. Given
    ``policies``, --policies names them (the recorded ones an agent's retirement left).
    ValueError if the command names no compare module."""
    words = shlex.split(recorded_command)
    module = next((i for i, word in enumerate(words) if word in COMPARE_NAMES), None)
    if module is None:
        raise ValueError(
            f"recorded command {recorded_command!r} does not run {' or '.join(COMPARE_NAMES)}"
        )
    args = words[module + 1 :]
    kept: list[str] = []
    skip = False
    replaced = (
        "--out",
        "--workers",
        *(("--scenarios",) if scenarios else ()),
        *(("--policies",) if policies else ()),
    )
    for word in args:
        if skip:
            skip = False
            continue
        if word in replaced:
            skip = True
            continue
        if word.startswith(tuple(f"{option}=" for option in replaced)):
            continue
        kept.append(word)
    chosen = ["--scenarios", ",".join(scenarios)] if scenarios else []
    chosen += ["--policies", ",".join(policies)] if policies else []
    return [*kept, *chosen, "--out", str(out), "--workers", str(workers)]


def retired_policies(policies: Sequence[str]) -> tuple[list[str], list[str]]:
    """``policies`` split into those that still run and the reference agents retired since
    (`benchmarks.catalog.policies.REMOVED_POLICIES`): a retired agent's committed rows are kept
    as the record of what it did, and no longer re-run."""
    retired = [p for p in policies if p in REMOVED_POLICIES]
    return [p for p in policies if p not in retired], retired


def _rows(path: Path) -> dict[tuple[str, str, str], dict[str, str]]:
    with path.open(newline="") as f:
        return {(r["scenario"], r["policy"], r["seed"]): r for r in csv.DictReader(f)}


def _flatten(value: Any, prefix: str = "") -> Iterator[tuple[str, Any]]:
    if isinstance(value, dict):
        for key, item in value.items():
            yield from _flatten(item, f"{prefix}/{key}")
    elif isinstance(value, list):
        for index, item in enumerate(value):
            yield from _flatten(item, f"{prefix}[{index}]")
    else:
        yield prefix, value


def _compared(key: str) -> bool:
    return not any(word in key for word in UNCOMPARED_KEYS)


class Report:
    """Counts differences and prints the first few of each check."""

    def __init__(self, allow_new: bool, shown: int = 20) -> None:
        self.allow_new, self.shown, self.failures = allow_new, shown, 0

    def differences(self, label: str, diffs: list[str], compared: int) -> None:
        print(f"{label}: {compared} values compared, {len(diffs)} differ")
        for line in diffs[: self.shown]:
            print("  DIFF", line)
        self.failures += len(diffs)

    def one_sided(self, label: str, items: Sequence[Any], new_run: bool = False) -> None:
        """Rows, columns or values one side holds: errors unless ``--allow-new``, except, on
        the re-run's side (``new_run``), those of `ADDED_METRICS`."""
        if new_run:
            added = [item for item in items if _added_metric(str(item))]
            if added:
                print(f"{label}: {len(added)} of metrics newer than these results: {added}")
            items = [item for item in items if not _added_metric(str(item))]
        if not items:
            return
        verdict = "allowed (--allow-new)" if self.allow_new else "ERROR"
        print(f"{label}: {len(items)} {verdict}: {list(items)[: self.shown]}")
        if not self.allow_new:
            self.failures += len(items)


def _added_metric(key: str) -> bool:
    """Whether a column name or a flattened JSON key (``.../metric``) is one of
    `ADDED_METRICS`."""
    return key.rsplit("/", 1)[-1] in ADDED_METRICS


def _within_rounding(old: str, new: str) -> bool:
    """Two cells of a learned policy's row that differ by float32 rounding only."""
    try:
        a, b = float(old), float(new)
    except ValueError:
        return False
    return math.isclose(a, b, rel_tol=AGENT_TOLERANCE, abs_tol=1e-12)


def compare_episodes(
    reference: Path,
    fresh: Path,
    report: Report,
    learned: Sequence[str] = (),
    retired: Sequence[str] = (),
) -> None:
    """Cell-by-cell comparison of two episodes.csv files: exact, except that the cells of the
    ``learned`` policies (torch networks) may differ within `AGENT_TOLERANCE` (counted apart).
    The committed rows of ``retired`` agents (not re-run) are counted and left out."""
    old, new = _rows(reference), _rows(fresh)
    left_out = [key for key in old if key[1] in retired]
    if left_out:
        print(
            f"episodes.csv: {len(left_out)} committed rows of retired agents "
            f"({', '.join(retired)}) are not re-run"
        )
    old = {key: row for key, row in old.items() if key[1] not in retired}
    report.one_sided("episode rows only in the committed file", sorted(set(old) - set(new)))
    report.one_sided("episode rows only in the new run", sorted(set(new) - set(old)))
    diffs, compared = [], 0
    columns_old = set(next(iter(old.values()), {}))
    columns_new = set(next(iter(new.values()), {}))
    report.one_sided("columns only in the committed file", sorted(columns_old - columns_new))
    report.one_sided("columns only in the new run", sorted(columns_new - columns_old), new_run=True)
    rounded = 0
    by_policy: Counter[str] = Counter()  # differing values per policy
    for key in sorted(set(old) & set(new)):
        for column in sorted(columns_old & columns_new):
            compared += 1
            before, after = old[key][column], new[key][column]
            if before == after:
                continue
            if key[1] in learned and _within_rounding(before, after):
                rounded += 1
            else:
                diffs.append(f"{key} {column}: {before} -> {after}")
                by_policy[key[1]] += 1
    report.differences("episodes.csv", diffs, compared)
    if by_policy:
        print(
            "  differing values by policy: " + ", ".join(f"{p} {n}" for p, n in by_policy.items())
        )
    if rounded:
        print(
            f"episodes.csv: {rounded} values of the learned policies ({', '.join(learned)}) "
            f"differ within {AGENT_TOLERANCE:g} relative: torch's float32 arithmetic rounds by "
            "CPU and BLAS build (every classical value must match to the last bit)"
        )


def compare_json(label: str, reference: Path, fresh: Path, report: Report) -> None:
    """Value-by-value comparison of two JSON files (run-dependent keys excepted)."""
    old = {k: v for k, v in _flatten(json.loads(reference.read_text())) if _compared(k)}
    new = {k: v for k, v in _flatten(json.loads(fresh.read_text())) if _compared(k)}
    report.one_sided(f"{label}: values only in the committed file", sorted(set(old) - set(new)))
    report.one_sided(
        f"{label}: values only in the new run", sorted(set(new) - set(old)), new_run=True
    )
    shared = sorted(set(old) & set(new))
    diffs = [f"{k}: {old[k]!r} -> {new[k]!r}" for k in shared if old[k] != new[k]]
    report.differences(label, diffs, len(shared))


@dataclass
class ReproductionOptions:
    """The options of ``python -m benchmarks.checks.reproduction``."""

    # A Path is immutable: one shared default is safe.
    results: Path = option(RESULTS, "committed results folder")  # noqa: RUF009
    workers: int = option(2, "benchmark worker processes")
    agents: bool = option(False, "also re-evaluate shipped agents")
    allow_new: bool = option(False, "rows/columns on one side only are not errors")
    keep: Path | None = option(None, "write the re-run here (kept)", parse=Path)  # noqa: RUF009
    machine: str = option("avx2", "run as the results' AVX2 machine or as this one (avx2, native)")


def compare_held_out(agents: Path, out: Path, report: Report) -> None:
    """Re-evaluate every agent folder under ``agents`` that holds a held-out evaluation (a
    single agent or an ensemble), write the re-run to ``out`` and compare it value by value."""
    from benchmarks.training import HELD_OUT_FILE, held_out_evaluation

    for recorded_file in sorted(agents.glob(f"*/{HELD_OUT_FILE}")):
        committed = json.loads(recorded_file.read_text())
        # under the env id the agent records (an ensemble's: its members', which agree): its
        # surge limit, its scenario label
        fresh = held_out_evaluation(recorded_file.parent, committed["duration_s"])
        fresh_file = out / f"{recorded_file.parent.name}_{HELD_OUT_FILE}"
        write_json(fresh_file, fresh)
        compare_json(f"{recorded_file.parent.name} held-out", recorded_file, fresh_file, report)


def main(argv: Sequence[str] | None = None) -> int:
    args, parser = parse_options(
        ReproductionOptions,
        argv,
        program_name("benchmarks.checks.reproduction"),
        __doc__.split("\n\n")[0],
        negatable=False,
    )
    if args.workers < 1:
        parser.error(f"--workers must be ≥ 1, got {args.workers}")
    if args.machine not in MACHINES:
        parser.error(f"--machine must be one of {', '.join(MACHINES)}, got {args.machine!r}")
    if args.keep is not None:  # refused now, not after the first re-run has finished
        with usage_errors(parser):
            writable_location(args.keep, "--keep")
    episodes_json = args.results / "full" / "episodes.json"
    paper_json = args.results / "paper" / "metrics.json"
    for required in (episodes_json, paper_json):
        if not required.is_file():
            parser.error(f"committed result {required} not found")

    committed = json.loads(episodes_json.read_text())["config"]
    recorded, scenarios = committed["command"], list(committed["scenarios"])
    with usage_errors(parser):  # a command that runs no compare is refused before any re-run
        _rerun_arguments(recorded, Path(), args.workers)

    report = Report(args.allow_new)
    env = machine_environment(args.machine, cpu_flags(), avx512_dispatch())
    with tempfile.TemporaryDirectory(prefix="auv-gym-repro-") as scratch:
        out = args.keep if args.keep is not None else Path(scratch)
        running, retired = retired_policies(committed["policies"])
        rerun = _rerun_arguments(
            recorded, out / "full", args.workers, scenarios, running if retired else ()
        )
        _run(COMPARE, rerun, env)
        learned = [p for p in running if PolicySpec.parse(p).kind != "classical"]
        compare_episodes(
            args.results / "full" / "episodes.csv",
            out / "full/episodes.csv",
            report,
            learned,
            retired,
        )

        paper = json.loads(paper_json.read_text())
        _run(
            "benchmarks.reports.paper_figures",
            [
                "--out",
                str(out / "paper"),
                "--seed",
                str(paper["seed"]),
                "--duration",
                str(paper["duration"]),
                "--transient",
                str(paper["transient"]),
            ],
            env,
        )
        compare_json("paper metrics.json", paper_json, out / "paper/metrics.json", report)

        if args.agents:
            compare_held_out(AGENTS, out, report)

    verdict = "REPRODUCED bit for bit" if report.failures == 0 else f"{report.failures} problems"
    print(verdict)
    return 0 if report.failures == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
