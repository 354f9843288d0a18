"""The both-plant table of a multi-seed agent (`benchmarks.analysis.plant_seeds`) on the committed
as-built suites: the per-seed means, ratios and targets by hand from episodes.csv, the folders
merged in run order, and evaluations that are not one experiment refused by name."""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import numpy as np
import pytest

from benchmarks.analysis.plant_seeds import main, markdown, plant_table, read_plant

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "seeds" / "ppo_as_built_plants"
PAIRS = ("suite_seeds_4_5", "suite_seeds_2_3")  # out of run order on purpose


def _folders(plant: str, pairs=PAIRS) -> list[Path]:
    return [RESULTS / f"{pair}_{plant}" for pair in pairs]


def _hand_mean(folder: Path, policy: str, run: int) -> tuple[float, int]:
    """Mean score [m] (a failed episode: the 30-m corridor) and failures, from the csv."""
    with (folder / "episodes.csv").open() as f:
        rows = [r for r in csv.DictReader(f) if r["policy"] == policy and int(r["run"]) == run]
    failed = [r["termination_reason"] != "time_limit" for r in rows]
    scores = [
        30.0 if bad else float(r["rms_distance"]) for r, bad in zip(rows, failed, strict=True)
    ]
    return float(np.mean(scores)), sum(failed)


def test_the_table_of_the_committed_seeds_matches_their_episodes():
    plants = {p: read_plant(_folders(p), "plants", "pid_as_built") for p in ("5dof", "6dof")}
    assert plants["5dof"].runs["plants"] == [2, 3, 4, 5]
    record = plant_table(plants, "plants", "pid_as_built", reps=200)
    for run, folder_pair in ((2, "suite_seeds_2_3"), (5, "suite_seeds_4_5")):
        entry = record["runs"][str(run)]
        for plant in ("5dof", "6dof"):
            mean, failed = _hand_mean(RESULTS / f"{folder_pair}_{plant}", "plants", run)
            assert entry[plant]["mean"][0] == pytest.approx(mean, rel=1e-12)
            assert entry[plant]["failed"] == failed
            low, high = entry[plant]["mean"][1:]
            assert low < mean < high
        assert entry["ratio"] == pytest.approx(entry["6dof"]["mean"][0] / entry["5dof"]["mean"][0])
    assert record["runs"]["2"]["ratio"] == pytest.approx(1.40, abs=0.01)
    assert record["runs"]["4"]["ratio"] == pytest.approx(2.31, abs=0.01)
    assert [record["runs"][r]["meets_plants"] for r in "2345"] == [True, True, False, True]
    assert record["meets_plants"] == 3 and record["meets_per_set"] == 0
    tight = record["runs"]["3"]["set_ratios_5dof"]["test_as_built_tight_deep"]
    assert tight == pytest.approx(1.36, abs=0.01)  # the set that misses the per-set target
    looser = plant_table(plants, "plants", "pid_as_built", max_per_set=1.4, reps=200)
    assert looser["meets_per_set"] == 4


def test_the_command_writes_both_tables(tmp_path, capsys):
    args = [
        "--policy=plants",
        "--suites-5dof=" + ",".join(map(str, _folders("5dof"))),
        "--suites-6dof=" + ",".join(map(str, _folders("6dof"))),
        f"--out={tmp_path}",
        "--reps=200",
    ]
    record = main(args)
    assert record["suites"]["6dof"] == ["suite_seeds_4_5_6dof", "suite_seeds_2_3_6dof"]
    text = (tmp_path / "plant_seeds.md").read_text()
    assert "| 2 | 0.301" in text and "3 of 4" in text
    assert (tmp_path / "plant_seeds.json").is_file()
    assert "plants target" in capsys.readouterr().out
    assert (tmp_path / "plant_seeds.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_figure_draws_each_runs_ratios_and_the_targets():
    from benchmarks.analysis.plant_seeds import figure

    plants = {p: read_plant(_folders(p), "plants", "pid_as_built") for p in ("5dof", "6dof")}
    record = plant_table(plants, "plants", "pid_as_built", reps=200)
    per_set, plants = figure(record).axes
    runs = list(record["runs"].values())
    markers = [line for line in per_set.lines if line.get_label().startswith("seed")]
    assert len(markers) == len(runs) == 4
    for line, entry in zip(markers, runs, strict=True):
        want = [entry["set_ratios_5dof"][s] for s in record["sets"]]
        np.testing.assert_allclose(line.get_ydata(), want, rtol=0, atol=0)
    ratios = [line.get_ydata()[0] for line in plants.lines if len(line.get_xdata()) == 1]
    assert ratios == [entry["ratio"] for entry in runs]
    targets = [line.get_ydata()[0] for ax in (per_set, plants) for line in ax.lines[-1:]]
    assert targets == [record["max_per_set"], record["max_ratio"]]


def test_evaluations_that_are_not_one_experiment_are_refused(tmp_path):
    with pytest.raises(ValueError, match=r"runs \[2, 3\] of 'plants' are in another folder"):
        read_plant(
            [*_folders("5dof", ("suite_seeds_2_3",)), RESULTS / "suite_seeds_2_3_no_floor_5dof"],
            "plants",
            "pid_as_built",
        )
    with pytest.raises(ValueError, match=r"no policy 'starts'"):
        read_plant(_folders("5dof"), "starts", "pid_as_built")
    changed = tmp_path / "changed"
    shutil.copytree(RESULTS / "suite_seeds_4_5_5dof", changed)
    rows = (changed / "episodes.csv").read_text().splitlines()
    k = next(i for i, line in enumerate(rows) if line.startswith("pid_as_built,"))
    cells = rows[k].split(",")
    cells[5] = str(float(cells[5]) + 0.01)  # rms_distance of one reference episode
    rows[k] = ",".join(cells)
    (changed / "episodes.csv").write_text("\n".join(rows) + "\n")
    with pytest.raises(ValueError, match=r"'pid_as_built' scores differ .* not the same"):
        read_plant([RESULTS / "suite_seeds_2_3_5dof", changed], "plants", "pid_as_built")
    five = read_plant(_folders("5dof"), "plants", "pid_as_built")
    six = read_plant(_folders("6dof", ("suite_seeds_2_3",)), "plants", "pid_as_built")
    with pytest.raises(ValueError, match=r"runs \[2, 3, 4, 5\] on the 5-DOF plant and \[2, 3\]"):
        plant_table({"5dof": five, "6dof": six}, "plants", "pid_as_built", reps=200)


def test_bad_arguments_are_one_line_errors(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["--policy=plants", f"--out={tmp_path}", "--suites-6dof=x"])
    assert exit_info.value.code == 2
    assert "--suites-5dof must name at least one" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(
            ["--policy=plants", f"--out={tmp_path}", f"--suites-5dof={tmp_path}", "--suites-6dof=x"]
        )
    assert "no episodes.csv" in capsys.readouterr().err


def test_several_references_take_the_best_per_set():
    """The two-plant residual's ten seeds against the guarded PID and the guarded climb-speed
    PID: per set the better of the two (by hand from the reference's own means), every ratio
    the single-reference table's for that reference."""
    seeds = ROOT / "benchmarks" / "results" / "seeds" / "ppo_residual_as_built_plants"
    folders = {p: [seeds / f"suite_{p}"] for p in ("5dof", "6dof")}
    both = ("pid_as_built_guarded", "pid_as_built_climb_guarded")
    plants = {p: read_plant(folders[p], "ppo_residual_as_built_plants", both) for p in folders}
    record = plant_table(plants, "ppo_residual_as_built_plants", both, reps=200)
    single = {
        name: plant_table(
            {p: read_plant(folders[p], "ppo_residual_as_built_plants", name) for p in folders},
            "ppo_residual_as_built_plants",
            name,
            reps=200,
        )
        for name in both
    }
    for s in record["sets"]:
        means = {n: single[n]["reference_summary"]["5dof"]["per_set"][s] for n in both}
        assert record["per_set_reference"][s] == min(means, key=means.get)
        for run, entry in record["runs"].items():
            chosen = single[record["per_set_reference"][s]]["runs"][run]["set_ratios_5dof"][s]
            assert entry["set_ratios_5dof"][s] == pytest.approx(chosen, rel=1e-12)
    # the climb-speed PID is the better reference on every set (docs/model.md §4.9)
    assert set(record["per_set_reference"].values()) == {"pid_as_built_climb_guarded"}
    assert record["meets_per_set"] == single["pid_as_built_climb_guarded"]["meets_per_set"] == 0
    assert single["pid_as_built_guarded"]["meets_per_set"] == 4  # docs/results.md
    text = markdown(record)
    assert "best of pid_as_built_guarded, pid_as_built_climb_guarded" in text
    assert "| pid_as_built_climb_guarded | 0.32" in text
