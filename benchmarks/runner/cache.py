"""One resumable cache of benchmark work: every finished unit (an episode of
`benchmarks.runner.jobs`, a chunk of seeds of `benchmarks.runner.evaluate_suite`) is stored
atomically as a JSON record holding a fingerprint of everything that determines it, so a run
restarted with the same arguments reuses what is finished and redoes only the rest.

A unit of work has ``fingerprint()`` (a hash), ``record_file(out)`` (its JSON record) and
``files(out)`` (every file it writes, the record among them: a unit is finished only when all
exist and the record's fingerprint matches). `run_resumable` removes the temporary files of a
killed run, loads what is finished, runs the rest on the process pool
(`benchmarks.runner.pool`) with a progress bar, and returns the records in the order of the
units.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Protocol

from auv_gym.support.files import remove_temporaries, zip_is_whole
from benchmarks.runner.pool import execute

__all__ = ["Work", "run_resumable", "stored_record"]


class Work(Protocol):
    """A unit of cached work (module doc)."""

    def fingerprint(self) -> str: ...

    def record_file(self, out: Path) -> Path: ...

    def files(self, out: Path) -> Sequence[Path]: ...


def stored_record(work: Work, out: Path) -> dict[str, Any] | None:
    """The stored record of finished ``work`` with a matching fingerprint, else None (missing
    or unreadable files count as unfinished, a time series whose zip is cut short too)."""
    files = work.files(out)
    if not all(f.exists() for f in files):
        return None
    if any(f.suffix == ".npz" and not zip_is_whole(f) for f in files):
        return None
    try:
        record = json.loads(work.record_file(out).read_text())
    except (OSError, json.JSONDecodeError):
        return None
    if not isinstance(record, dict) or record.get("fingerprint") != work.fingerprint():
        return None
    return record


def run_resumable(
    units: Sequence[Work],
    out: Path,
    cache: Path,
    function: Callable[[Any, Path], dict[str, Any]],
    *,
    workers: int,
    backend: str = "local",
    address: str | None = None,
    progress: bool = True,
    desc: str = "episodes",
    sizes: Sequence[int] | None = None,
) -> list[dict[str, Any]]:
    """The records of all ``units``, in their order: stored ones reused, the others computed by
    ``function(unit, out)`` (a module-level function that stores the record itself, atomically)
    on the pool. ``cache``: the folder under ``out`` the units write to (its temporary files of
    a killed run are removed first; callers hold the output folder). ``sizes``: episodes per
    unit, for the progress bar (default 1 each)."""
    from tqdm.auto import tqdm

    remove_temporaries(cache)
    sizes = [1] * len(units) if sizes is None else list(sizes)
    records: dict[int, dict[str, Any]] = {}
    for index, unit in enumerate(units):
        done = stored_record(unit, out)
        if done is not None:
            records[index] = done
    todo = [i for i in range(len(units)) if i not in records]
    bar = tqdm(
        total=sum(sizes),
        initial=sum(sizes[i] for i in records),
        desc=desc,
        unit="ep",
        disable=not progress,
    )
    for index, record in execute(
        function, [units[i] for i in todo], todo, out, workers, backend, address
    ):
        records[index] = record
        bar.update(sizes[index])
    bar.close()
    return [records[i] for i in range(len(units))]
