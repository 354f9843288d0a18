"""Adding a policy to a committed suite evaluation only when the episodes are the same."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from benchmarks.analysis.suite_merge import main, merge_suites

HEADER = ["policy", "run", "set", "seed", "rms_distance", "termination_reason"]


def _suite(
    folder: Path, rows: list[list[str]], policies: list[str], header=HEADER, **extra
) -> Path:
    folder.mkdir(parents=True)
    suite = {
        "command": f"evaluate {folder.name}",
        "sets": {"a": {"seeds": {"first": 0, "count": 2}}},
        "duration_s": 300.0,
        "transient_s": 100.0,
        "policies": {p: {"name": p, "kind": "agent"} for p in policies},
        "agents": {},
        "git_commit": "abc",
        **extra,
    }
    (folder / "suite.json").write_text(json.dumps(suite))
    with (folder / "episodes.csv").open("w", newline="") as fh:
        writer = csv.writer(fh, lineterminator="\n")
        writer.writerow(header)
        writer.writerows(rows)
    return folder


FBSM = [
    ["fbsm", "0", "a", "0", "0.0641", "time_limit"],
    ["fbsm", "0", "a", "1", "0.0702", "time_limit"],
]
NEW = [["new", "0", "a", "0", "0.15", "time_limit"], ["new", "0", "a", "1", "30.0", "corridor"]]


def test_rows_and_provenance_are_added(tmp_path):
    target = _suite(tmp_path / "target", FBSM, ["fbsm"])
    source = _suite(tmp_path / "source", [*FBSM, *NEW], ["fbsm", "new"])
    assert merge_suites(source, target, ["new"]) == {"new": 2}
    rows = list(csv.reader((target / "episodes.csv").open()))
    assert rows == [HEADER, *FBSM, *NEW]
    suite = json.loads((target / "suite.json").read_text())
    assert list(suite["policies"]) == ["fbsm", "new"]
    (addition,) = suite["additions"]
    assert addition["command"] == "evaluate source" and addition["policies"] == ["new"]
    assert addition["checked_equal"] == {"policies": ["fbsm"], "episodes": 2, "rtol": 1e-12}


def test_different_shared_episodes_are_refused(tmp_path):
    changed = [FBSM[0], ["fbsm", "0", "a", "1", "0.0703", "time_limit"]]
    target = _suite(tmp_path / "target", FBSM, ["fbsm"])
    source = _suite(tmp_path / "source", [*changed, *NEW], ["fbsm", "new"])
    with pytest.raises(ValueError, match=r"fbsm run 0 set a seed 1: rms_distance = 0.0703 here"):
        merge_suites(source, target, ["new"])
    assert list(csv.reader((target / "episodes.csv").open())) == [HEADER, *FBSM]  # untouched
    # Below the tolerance (another machine's last digits) it is the same experiment.
    assert merge_suites(source, target, ["new"], rtol=0.01) == {"new": 2}


def test_not_the_same_suite_or_nothing_to_check(tmp_path, capsys):
    target = _suite(tmp_path / "target", FBSM, ["fbsm"])
    other = _suite(tmp_path / "other", [*FBSM, *NEW], ["fbsm", "new"], duration_s=200.0)
    with pytest.raises(ValueError, match="differ in 'duration_s'"):
        merge_suites(other, target, ["new"])
    alone = _suite(tmp_path / "alone", NEW, ["new"])
    with pytest.raises(ValueError, match="shares no policy"):
        merge_suites(alone, target, ["new"])
    same = _suite(tmp_path / "same", [*FBSM, *NEW], ["fbsm", "new"])
    with pytest.raises(ValueError, match=r"\['fbsm'\]: already in"):
        merge_suites(same, target, ["fbsm"])
    code = main(["--from", str(tmp_path / "missing"), "--into", str(target), "--policies", "x"])
    assert code == 2 and "no such file" in capsys.readouterr().err


def test_a_replaced_policy_loses_its_rows_and_the_addition_says_so(tmp_path):
    old = [
        ["new", "0", "a", "0", "0.30", "time_limit"],
        ["new", "0", "a", "1", "0.31", "time_limit"],
    ]
    target = _suite(tmp_path / "target", [*FBSM, *old], ["fbsm", "new"])
    source = _suite(tmp_path / "source", [*FBSM, *NEW], ["fbsm", "new"])
    with pytest.raises(ValueError, match=r"\['new'\]: already in .*--replace replaces them"):
        merge_suites(source, target, ["new"])
    assert (
        main(["--from", str(source), "--into", str(target), "--policies", "new", "--replace"]) == 0
    )
    assert list(csv.reader((target / "episodes.csv").open())) == [HEADER, *FBSM, *NEW]
    (addition,) = json.loads((target / "suite.json").read_text())["additions"]
    assert addition["replaced"] == ["new"]
    assert addition["checked_equal"] == {"policies": ["fbsm"], "episodes": 2, "rtol": 1e-12}


def test_a_set_field_added_later_as_none_is_the_same_set(tmp_path):
    """A record written before a set field existed matches one with the field at None; a real
    value in it is a different set."""
    target = _suite(tmp_path / "target", FBSM, ["fbsm"])
    later = {"a": {"seeds": {"first": 0, "count": 2}, "vary": None}}
    source = _suite(tmp_path / "source", [*FBSM, *NEW], ["fbsm", "new"], sets=later)
    assert merge_suites(source, target, ["new"]) == {"new": 2}
    varied = {"a": {"seeds": {"first": 0, "count": 2}, "vary": {"actuator": ["fins"]}}}
    other = _suite(tmp_path / "other", [*FBSM, *NEW], ["fbsm", "new"], sets=varied)
    with pytest.raises(ValueError, match="differ in 'sets'"):
        merge_suites(other, _suite(tmp_path / "again", FBSM, ["fbsm"]), ["new"])


def test_a_metric_added_since_keeps_the_target_columns(tmp_path):
    """A source evaluated after the code gained a metric adds its rows without that column
    (the target's other rows cannot gain it) and says so; a source lacking one is refused."""
    target = _suite(tmp_path / "target", FBSM, ["fbsm"])
    wider = [*HEADER[:5], "mean_path_speed", HEADER[5]]
    rows = [[*r[:5], "1.01", r[5]] for r in [*FBSM, *NEW]]
    source = _suite(tmp_path / "source", rows, ["fbsm", "new"], header=wider)
    assert merge_suites(source, target, ["new"]) == {"new": 2}
    with (target / "episodes.csv").open() as fh:
        merged = list(csv.DictReader(fh))
    assert list(merged[0]) == HEADER and len(merged) == 4
    assert merged[3]["rms_distance"] == "30.0" and merged[3]["termination_reason"] == "corridor"
    suite = json.loads((target / "suite.json").read_text())
    assert suite["additions"][-1]["dropped_columns"] == ["mean_path_speed"]
    narrow = _suite(
        tmp_path / "narrow", [r[:5] for r in [*FBSM, *NEW]], ["fbsm", "new"], header=HEADER[:5]
    )
    with pytest.raises(ValueError, match=r"lacks the columns \['termination_reason'\]"):
        merge_suites(narrow, _suite(tmp_path / "t2", FBSM, ["fbsm"]), ["new"])


def test_a_partial_or_damaged_source_is_refused_before_the_target_changes(tmp_path):
    """Was: 14 of a set's 20 rows, the last one cut short, were added and the target broke
    (`auv-gym suite --stats-only` then failed on it); cells of -1000 or "abc" went in too."""
    target = _suite(tmp_path / "target", FBSM, ["fbsm"])
    before = (target / "episodes.csv").read_bytes()
    partial = _suite(tmp_path / "partial", [*FBSM, NEW[0]], ["fbsm", "new"])
    with pytest.raises(ValueError, match=r"new run 0 has 1 of the 2 episodes fbsm has in .+target"):
        merge_suites(partial, target, ["new"])
    cut = _suite(tmp_path / "cut", [*FBSM, NEW[0], NEW[1][:4]], ["fbsm", "new"])
    with pytest.raises(ValueError, match=r"cut/episodes.csv: line 5 has another number of cells"):
        merge_suites(cut, target, ["new"])
    for bad, message in (("abc", "'abc' is not a number"), ("-1000", "'-1000' is negative")):
        row = [*NEW[1][:4], bad, NEW[1][5]]
        source = _suite(tmp_path / f"bad{bad}", [*FBSM, NEW[0], row], ["fbsm", "new"])
        with pytest.raises(ValueError, match=rf"line 5: rms_distance = {message}"):
            merge_suites(source, target, ["new"])
    assert (target / "episodes.csv").read_bytes() == before
