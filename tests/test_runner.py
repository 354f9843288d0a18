"""The one resumable runner of benchmark work (`benchmarks.runner.cache` on
`benchmarks.runner.pool`), which compare's episodes and the suite's chunks both go through."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import pytest

from auv_gym.support.files import write_json
from benchmarks.runner.cache import run_resumable, stored_record
from benchmarks.runner.pool import MAX_WORKERS, check_pool_options

CALLS: list[int] = []


@dataclass(frozen=True)
class Square:
    """A unit of work: its record holds value²; the fingerprint holds the version of the code."""

    value: int
    version: str = "1"

    def fingerprint(self) -> str:
        return f"{self.value}-{self.version}"

    def record_file(self, out: Path) -> Path:
        return out / "cache" / f"{self.value}.json"

    def files(self, out: Path) -> tuple[Path, ...]:
        return (self.record_file(out),)


def square(unit: Square, out: Path) -> dict:
    CALLS.append(unit.value)
    record = {"fingerprint": unit.fingerprint(), "square": unit.value**2}
    write_json(unit.record_file(out), record)
    return record


def test_finished_units_are_reused_and_changed_or_damaged_ones_rerun(tmp_path):
    CALLS.clear()
    units = [Square(v) for v in (3, 1, 2)]
    first = run_resumable(units, tmp_path, tmp_path / "cache", square, workers=1, progress=False)
    assert [r["square"] for r in first] == [9, 1, 4] and CALLS == [3, 1, 2]
    (tmp_path / "cache" / "2.json").write_text("{truncated")  # a damaged record
    (tmp_path / "cache" / ".2.json.auv-gym.a1b2c3d4.tmp").write_text("")  # a killed write
    again = run_resumable(
        [*units[:2], Square(2), Square(1, "2")],
        tmp_path,
        tmp_path / "cache",
        square,
        workers=1,
        progress=False,
    )
    assert [r["square"] for r in again] == [9, 1, 4, 1]
    assert CALLS == [3, 1, 2, 2, 1]  # the damaged one and the one whose code changed
    assert not (tmp_path / "cache" / ".2.json.auv-gym.a1b2c3d4.tmp").exists()
    assert stored_record(Square(1, "2"), tmp_path) == {"fingerprint": "1-2", "square": 1}
    assert stored_record(Square(5), tmp_path) is None
    assert json.loads((tmp_path / "cache" / "1.json").read_text())["fingerprint"] == "1-2"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ((0,), f"--workers must be an integer in [1, {MAX_WORKERS}], got 0"),
        ((MAX_WORKERS + 1,), f"--workers must be an integer in [1, {MAX_WORKERS}], got 1025"),
        ((1, "slurm"), "--backend must be one of ['local', 'ray'], got 'slurm'"),
        ((1, "local", "host:6379"), "--address needs --backend ray"),
    ],
)
def test_pool_options_are_checked_in_one_place(args, message):
    with pytest.raises(ValueError) as error:
        check_pool_options(*args)
    assert str(error.value) == message


def test_the_suite_takes_the_pool_options_of_compare(tmp_path):
    from benchmarks.runner.evaluate_suite import build_parser, parse_args

    options = {a.dest for a in build_parser()._actions}
    assert {"workers", "backend", "address"} <= options
    with pytest.raises(SystemExit) as stop:
        parse_args(
            [
                "--policies",
                "fbsm",
                "--sets",
                "test_steep",
                "--address",
                "h:1",
                "--out",
                str(tmp_path / "o"),
            ]
        )
    assert stop.value.code == 2


def test_ray_without_a_cluster_to_join_is_refused_and_nothing_listens(monkeypatch):
    """Was: a local cluster whose GCS, raylet and workers listened on every interface."""
    ray = pytest.importorskip("ray")
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    if ray.is_initialized():
        pytest.skip("a Ray instance of this process is running")
    before = _listening_ports()
    with pytest.raises(ValueError, match=r"--backend ray needs --address HOST:PORT .* no cluster"):
        check_pool_options(1, "ray")
    assert not ray.is_initialized()
    assert _listening_ports() <= before  # no new listening socket


def _listening_ports() -> set[int]:
    """Ports with a listening TCP socket on this machine (/proc/net/tcp and tcp6)."""
    ports = set()
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            lines = Path(table).read_text().splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            fields = line.split()
            if fields[3] == "0A":  # TCP_LISTEN
                ports.add(int(fields[1].rsplit(":", 1)[1], 16))
    return ports
