"""Add the policies of a second suite evaluation to a committed one, once its episodes match.

A committed test-suite evaluation (`benchmarks.runner.evaluate_suite`, e.g.
`benchmarks/results/suite`) takes hours to re-run for every policy; a new agent needs only its own
rows. This command takes an evaluation of the new policies run *together with a reference policy
already in the target* (FBSM, say) and appends the new policies' rows, after checking that the two
evaluations are the same experiment:

- the same test sets (names, seeds and env settings), episode duration and metrics window;
- every column of the target's episodes.csv (a metric the code gained since the target was
  evaluated is left out of the added rows, since the target's other rows cannot gain it without
  re-running them; the addition lists it under ``dropped_columns``);
- the shared policies' rows are equal cell for cell (the episodes and the code that ran them
  give the same numbers), except cells whose relative difference is below ``--rtol`` (default
  1e-12: the last digits that another machine's BLAS rounds differently on spline paths);
- no policy to add is already in the target, unless ``--replace`` says to replace it (a
  reference agent retrained or replaced: its rows go, the new ones come, and the addition
  records which policies it replaced).

Then OUT/episodes.csv gains the rows, OUT/suite.json the policies and an "additions" entry (the
command, commit and versions of the second evaluation), both written atomically; re-run
`python -m benchmarks.runner.evaluate_suite --stats-only --out OUT` for the statistics.

    python -m benchmarks.runner.evaluate_suite --policies fbsm,NEW=DIR --out runs/suite_new \\
        --no-stats
    python -m benchmarks.analysis.suite_merge --from runs/suite_new \\
        --into benchmarks/results/suite --policies NEW
"""

from __future__ import annotations

import csv
import io
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from auv_gym.support.files import write_json, write_text
from benchmarks.analysis.suite_stats import parsed_episode_rows, read_suite_json
from benchmarks.arguments import parse_options, program_name
from benchmarks.options import option

__all__ = ["MergeOptions", "main", "merge_suites"]

_KEY = ("policy", "run", "set", "seed")


@dataclass
class MergeOptions:
    """The options of ``python -m benchmarks.analysis.suite_merge``; the folders and policies have
    no default on the command line."""

    source: str | None = option(None, "evaluation to take rows from", flag="--from", required=True)
    target: str | None = option(None, "evaluation to add them to", flag="--into", required=True)
    policies: str = option("", "comma-separated policy names to add", required=True)
    rtol: float = option(1e-12, "relative tolerance for the shared policies' cells")
    replace: bool = option(
        False, "replace the rows of named policies already in the target (an agent replaced)"
    )


def _read(folder: Path) -> tuple[dict[str, Any], list[str], list[dict[str, str]]]:
    suite_file, rows_file = folder / "suite.json", folder / "episodes.csv"
    for file in (suite_file, rows_file):
        if not file.is_file():
            raise FileNotFoundError(f"{file}: no such file (not a suite evaluation folder)")
    suite = read_suite_json(suite_file)
    with rows_file.open(newline="") as fh:
        reader = csv.DictReader(fh)
        rows = list(reader)
        header = list(reader.fieldnames or [])
    parsed_episode_rows(rows_file, header, rows)  # every row whole, every number a number
    return suite, header, rows


def _without_nones(value: Any) -> Any:
    """``value`` with every mapping entry whose value is None left out, at any depth: a set's
    field added in a later release with None for "not used" (e.g. ``vary``) is the same set as
    an earlier record without it."""
    if isinstance(value, dict):
        return {k: _without_nones(v) for k, v in value.items() if v is not None}
    if isinstance(value, list):
        return [_without_nones(v) for v in value]
    return value


def _differs(a: str, b: str, rtol: float) -> bool:
    if a == b:
        return False
    try:
        x, y = float(a), float(b)
    except ValueError:
        return True
    if math.isnan(x) and math.isnan(y):
        return False
    return not abs(x - y) <= rtol * max(abs(x), abs(y))


def merge_suites(
    source: Path,
    target: Path,
    policies: Sequence[str],
    rtol: float = MergeOptions.rtol,
    replace: bool = False,
) -> dict[str, int]:
    """Append ``policies``' rows of ``source`` to ``target`` (module doc); returns rows per policy.
    With ``replace``, a named policy already in ``target`` loses its rows there first (a
    reference agent replaced; the addition records it), and is not one of the shared policies
    the episodes are checked on.

    ValueError, naming the difference, when the evaluations are not the same experiment.
    """
    if not policies:
        raise ValueError("--policies: name at least one policy to add")
    if not (rtol >= 0 and math.isfinite(rtol)):
        raise ValueError(f"--rtol must be a finite number >= 0, got {rtol}")
    source_suite, source_header, source_rows = _read(Path(source))
    target_suite, target_header, target_rows = _read(Path(target))
    for key in ("sets", "duration_s", "transient_s"):
        if _without_nones(source_suite.get(key)) != _without_nones(target_suite.get(key)):
            raise ValueError(f"{source} and {target} differ in {key!r}: not the same test suite")
    lacking = [c for c in target_header if c not in source_header]
    if lacking:
        raise ValueError(
            f"{source}/episodes.csv lacks the columns {lacking} that {target}'s rows have"
        )
    # a metric the code added since the target was evaluated: the target's rows cannot gain it
    # without their agents, so the added rows keep the target's columns (the addition says so)
    dropped = [c for c in source_header if c not in target_header]
    source_policies = set(source_suite["policies"])
    missing = [p for p in policies if p not in source_policies]
    if missing:
        raise ValueError(
            f"--policies {missing}: not in {source} (it has {sorted(source_policies)})"
        )
    present = [p for p in policies if p in target_suite["policies"]]
    if present and not replace:
        raise ValueError(f"--policies {present}: already in {target} (--replace replaces them)")
    target_rows = [r for r in target_rows if r["policy"] not in present]
    shared = sorted(source_policies & set(target_suite["policies"]) - set(policies))
    if not shared:
        raise ValueError(
            f"{source} shares no policy with {target}: evaluate a reference policy (e.g. fbsm) "
            "with the new ones, so that the episodes can be checked equal"
        )
    target_index = {tuple(r[k] for k in _KEY): r for r in target_rows}
    compared = 0
    for row in source_rows:
        if row["policy"] not in shared:
            continue
        other = target_index.get(tuple(row[k] for k in _KEY))
        if other is None:
            raise ValueError(f"episode {dict((k, row[k]) for k in _KEY)} is not in {target}")
        for column in target_header:
            if _differs(row[column], other[column], rtol):
                raise ValueError(
                    f"{row['policy']} run {row['run']} set {row['set']} seed {row['seed']}: "
                    f"{column} = {row[column]} here but {other[column]} in {target} "
                    f"(relative tolerance {rtol:g}): not the same episodes or code"
                )
        compared += 1
    episodes = {(r["set"], r["seed"]) for r in target_rows if r["policy"] == shared[0]}
    for policy in policies:
        runs: dict[str, set[tuple[str, str]]] = {}
        for r in source_rows:
            if r["policy"] == policy:
                runs.setdefault(r["run"], set()).add((r["set"], r["seed"]))
        for run, cells in runs.items():
            if cells != episodes:
                raise ValueError(
                    f"{source}/episodes.csv: {policy} run {run} has {len(cells & episodes)} of "
                    f"the {len(episodes)} episodes {shared[0]} has in {target}"
                    + (f" and {len(cells - episodes)} others" if cells - episodes else "")
                    + " (a partial or damaged evaluation)"
                )
    added = [{c: r[c] for c in target_header} for r in source_rows if r["policy"] in policies]
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=target_header, lineterminator="\n")
    writer.writeheader()
    writer.writerows([*target_rows, *added])
    suite = dict(target_suite)
    suite["policies"] = {
        **target_suite["policies"],
        **{p: source_suite["policies"][p] for p in policies},
    }
    suite["agents"] = {**target_suite.get("agents", {}), **source_suite.get("agents", {})}
    suite["additions"] = [
        *target_suite.get("additions", []),
        {
            "policies": list(policies),
            "command": source_suite.get("command"),
            "checked_equal": {"policies": shared, "episodes": compared, "rtol": rtol},
            **({"replaced": present} if present else {}),
            **({"dropped_columns": dropped} if dropped else {}),
            **{k: source_suite.get(k) for k in ("git_commit", "versions", "code")},
        },
    ]
    write_text(Path(target) / "episodes.csv", buffer.getvalue())
    write_json(Path(target) / "suite.json", suite, indent=1)
    return {p: sum(r["policy"] == p for r in added) for p in policies}


def main(argv: Sequence[str] | None = None) -> int:
    args, _ = parse_options(
        MergeOptions,
        argv,
        program_name("benchmarks.analysis.suite_merge"),
        __doc__.split("\n\n")[0],
    )
    names = [p.strip() for p in args.policies.split(",") if p.strip()]
    try:
        added = merge_suites(Path(args.source), Path(args.target), names, args.rtol, args.replace)
    except (ValueError, FileNotFoundError) as exc:
        print(f"suite_merge: error: {exc}", file=sys.stderr)
        return 2
    print(f"added to {args.target}: " + ", ".join(f"{p} ({n} rows)" for p, n in added.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
