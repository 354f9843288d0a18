"""The one table convention: significant figures, units, and failures never marked best."""

from __future__ import annotations

import math

import pytest

from benchmarks.reports.plotting import metrics_table
from benchmarks.reports.table_format import (
    EMPTY,
    METRIC_INFO,
    Cell,
    display_scale,
    format_mean_std,
    format_number,
    mark_best,
    markdown_table,
)
from benchmarks.reports.tables import aggregate, overview, overview_note, summarise


@pytest.mark.parametrize(
    ("value", "text"),
    [
        (0.01728, "0.0173"),
        (987.8, "988"),
        (9.996, "10.0"),
        (0.1, "0.100"),
        (5.627e-6, "5.63e-06"),
        (2.5e7, "2.50e+07"),
        (0.0, "0"),
        (math.nan, EMPTY),
        (None, EMPTY),
        (True, "yes"),
    ],
)
def test_three_significant_figures_in_positional_notation(value, text):
    assert format_number(value) == text


def test_inf_is_never_a_number():
    assert format_number(math.inf) == EMPTY
    assert format_number(math.inf, metric="settling_time_0p5") == "never"
    assert format_number(-math.inf) == EMPTY


def test_spread_to_the_means_last_decimal_and_no_float_noise():
    assert format_mean_std(0.01728, 3.5e-18) == "0.0173 ± 0"
    assert format_mean_std(987.8, 110.4) == "988 ± 110"
    assert format_mean_std(0.297, 0.0412) == "0.297 ± 0.041"
    assert format_mean_std(6.77e-4, 6.8e-5) == "6.77e-04 ± 6.8e-05"  # one notation per cell
    assert format_mean_std(4.84e-4, 5.4e-20) == "4.84e-04 ± 0"  # no float noise there either


def test_millimetres_where_metres_would_round_to_zero():
    assert display_scale("m", [0.0004, 0.002]) == ("mm", 1e3)
    assert display_scale("m", [0.0004, 0.02]) == ("m", 1.0)
    assert display_scale("m/s", [0.005]) == ("mm/s", 1e3)
    assert display_scale("s", [0.0004]) == ("s", 1.0)


def test_failed_entries_are_never_bold_and_ties_are_not_a_win():
    texts = ["a", "b", "c"]
    assert mark_best(texts, [0.1, 0.01, 0.2], [True, False, True], "min") == ["**a**", "b", "c"]
    assert mark_best(texts, [0.1, 0.1, 0.1], [True, True, True], "min") == texts
    assert mark_best(texts, [math.inf, 0.5, math.nan], [True, True, True], "min") == [
        "a",
        "**b**",
        "c",
    ]


def test_cell_counts_failures_and_is_empty_when_every_episode_failed():
    assert Cell((), failed=10).text() == EMPTY and Cell((), failed=10).episodes == 10
    assert Cell((0.1, 0.3), failed=1).text() == "0.200 ± 0.100 (n = 2/3)"
    assert Cell((31.0, math.inf)).text("settling_time_0p5") == "never in 1/2"
    assert Cell((math.inf, math.inf)).text("settling_time_0p5") == "never"


def test_a_mean_over_fewer_than_all_episodes_shows_its_sample_size():
    """Was: a mean over 1 of 3 episodes printed as a plain number, like a mean over 3."""
    assert Cell((0.3,), failed=2).text() == "0.300 (n = 1/3)"
    assert Cell((0.3,), failed=2).sample_size() == "n = 1/3"
    assert Cell((0.1, math.nan, 0.3)).text() == "0.200 ± 0.100 (n = 2/3)"  # one undefined
    assert Cell((0.1, 0.3)).text() == "0.200 ± 0.100" and Cell((0.1, 0.3)).sample_size() == ""
    assert Cell((), failed=3).sample_size() == "" and Cell((), failed=3).counted == 0
    assert Cell((31.0, math.inf), failed=1).text("settling_time_0p5") == "never in 1/3"


def test_markdown_table_refuses_ragged_rows():
    with pytest.raises(ValueError, match="every row needs 2 cells"):
        markdown_table(["a", "b"], [["1"]])


def _record(policy, seed, rms, reason="time_limit"):
    metrics = {"rms_distance": rms, "termination_reason": reason, "settling_time_0p5": 20.0}
    return {"scenario": "paper", "policy": policy, "seed": seed, "metrics": metrics}


def test_summary_never_marks_a_failed_policy_best_and_prints_no_inf():
    records = [
        _record("fbsm", 0, 0.06),
        _record("fbsm", 1, 0.07),
        _record("untrained", 0, 0.001, "corridor"),  # fails with a tiny partial metric
        _record("untrained", 1, math.inf, "corridor"),
        _record("ppo", 0, 0.3),
        _record("ppo", 1, 0.2, "overspeed"),
    ]
    text = summarise(records, {"seeds": 2, "duration": 100.0, "transient": 50.0})
    rows: dict[str, str] = {}  # the tracking table's row of each policy (the scenario's first)
    for line in text[text.index("## paper") :].splitlines():
        if line.startswith("| "):
            rows.setdefault(line.split(" | ")[0][2:], line)
    assert "inf" not in text
    assert rows["fbsm"].startswith("| fbsm | 0/2 | **0.0650 ± 0.0050** |")
    assert rows["untrained"].startswith(f"| untrained | 2/2 | {EMPTY} |")
    assert rows["ppo"].startswith("| ppo | 1/2 | 0.300 (n = 1/2) |")
    assert "| policy | failed | RMS d [m] |" in text
    assert max(len(line) for line in text.splitlines() if line.startswith("|")) < 120


def test_a_settling_time_never_reached_is_never_not_a_missing_value():
    """Episode records store a settling time never reached (+inf) as null; the summary read it
    back as NaN and printed "—" (as for a cell without a finished episode) and the bar chart
    drew no bar, which read as best."""
    records = [_record("slow", seed, 0.5) for seed in range(2)]
    for r in records:
        r["metrics"]["settling_time_0p5"] = None
    records += [_record("quick", seed, 0.1) for seed in range(2)]
    del records[-1]["metrics"]["settling_time_0p5"]  # not recorded: undefined, not "never"
    cells = aggregate(records)
    assert cells[("paper", "slow")]["settling_time_0p5"].mean() == math.inf
    assert cells[("paper", "quick")]["settling_time_0p5"].values[1] != math.inf
    text = summarise(records, {"seeds": 2, "duration": 100.0, "transient": 50.0})
    slow = next(line for line in text.splitlines() if line.startswith("| slow | 0/2 |"))
    assert slow.endswith("| never |")
    quick = next(line for line in text.splitlines() if line.startswith("| quick | 0/2 |"))
    assert quick.endswith("| **20.0 (n = 1/2)** |")


def test_the_summary_opens_with_the_overview_and_the_list_of_figures():
    records = [
        _record("fbsm", 0, 0.06),
        _record("fbsm", 1, 0.07),
        _record("fbsm", 2, 0.08),
        _record("ppo", 0, 0.3),
        _record("ppo", 1, 2.0, "corridor"),
        _record("ppo", 2, 2.0, "pitch"),
        *(_record("untrained", s, 9.0, "corridor") for s in range(3)),
    ]
    figures = [
        ("figures/track_paper.png", "paper: every policy's track"),
        ("figures/bars_rms_distance.png", "RMS distance [m]"),
    ]
    text = summarise(records, {"seeds": 3, "duration": 100.0, "transient": 50.0}, figures)
    lines = text.splitlines()
    assert lines[0] == "# Benchmark summary"
    assert lines[2] == overview_note(3, 50.0)
    assert lines[4:9] == [
        "| policy | paper |",
        "|---|---:|",
        "| fbsm | 0.07 |",
        "| ppo | 0.3 (n = 1/3) |",
        "| untrained | all 3 failed |",
    ]
    assert lines[10:15] == [
        "## Figures",
        "",
        "- [`track_paper.png`](figures/track_paper.png): paper: every policy's track",
        "- [`bars_rms_distance.png`](figures/bars_rms_distance.png): RMS distance [m]",
        "",
    ]
    assert "## paper" in text and text.index("## Figures") < text.index("## paper")
    console = overview(records).splitlines()  # the console's table: the same cells
    assert console[2].split() == ["ppo", "0.3", "(n", "=", "1/3)"]
    assert console[3].split() == ["untrained", "all", "3", "failed"]
    bare = summarise(records, {"seeds": 3, "duration": 100.0, "transient": 50.0})
    assert "## Figures\n\nNone: this run drew no figures.\n" in bare


def test_metrics_table_never_bolds_a_failed_episode():
    results = {
        "A": {"rms_distance": 0.04, "termination_reason": "time_limit"},
        "B": {"rms_distance": 0.004, "termination_reason": "corridor"},
    }
    lines = metrics_table(results, ["rms_distance"]).splitlines()
    assert lines[2] == "| RMS distance, t ≥ transient | m | **0.0400** | 0.00400 |"


TORPEDO_ENV = {"vehicle": "torpedo", "plant": "6dof", "actuator": "realistic"}


def _speed_record(scenario, policy, seed, max_surge, overspeed):
    metrics = {
        "rms_distance": 0.5,
        "termination_reason": "time_limit",
        "surge_overshoot": 0.07,
        "rms_speed_error": 0.003,
        "max_surge": max_surge,
        "overspeed_fraction": overspeed,
        "mean_path_speed": 2.0,
    }
    return {"scenario": scenario, "policy": policy, "seed": seed, "metrics": metrics}


def _run_config(seeds: int, duration: float, **scenarios: dict) -> dict:
    """A compare run's config: ``seeds`` per scenario, ``duration`` [s] long (its transient
    half of it), the scenarios' env arguments by name."""
    described = {name: {"name": name, "env": env} for name, env in scenarios.items()}
    return {"seeds": seeds, "duration": duration, "transient": duration / 2, "scenarios": described}


def _speed_header(text, scenario):
    section = text[text.index(f"## {scenario}") :]
    return section[section.index("speed:") :].splitlines()[2]  # the speed table's header


def test_the_overspeed_column_names_the_vehicles_own_top_speed():
    """overspeed_fraction counts time above the vehicle's max_surge (2.5 m/s for the torpedo):
    the header said "time u > 2 m/s" on every vehicle, so a torpedo's max u = 2.08 m/s beside
    "time u > 2 m/s" = 0 read as a wrong number."""
    records = [
        _speed_record("torpedo_helix", "pid_los", 0, 2.08, 0.0),
        _speed_record("six_dof_helix", "pid_los", 0, 2.06, 0.4),
    ]
    config = _run_config(1, 300.0, torpedo_helix=TORPEDO_ENV, six_dof_helix={"plant": "6dof"})
    text = summarise(records, config)
    assert _speed_header(text, "torpedo_helix") == (
        "| policy | failed | overshoot [m/s] | RMS(u − u_D) [mm/s] | max u [m/s] "
        "| time u > 2.5 m/s | pace u_p [m/s] |"
    )
    assert "| time u > 2 m/s |" in _speed_header(text, "six_dof_helix")  # REMUS 100: as before
    assert "| pid_los | 0/1 | 0.0700 | 3.00 | 2.08 | 0 | 2.00 |" in text
    # a scenario the config does not describe: the header names the vehicle's field
    bare = summarise(records, {"seeds": 1, "duration": 300.0, "transient": 100.0})
    assert "| time u > max_surge |" in _speed_header(bare, "torpedo_helix")
    assert "2 m/s" not in bare and "2.0 m/s" not in METRIC_INFO["overspeed_fraction"][0]


def test_a_scenario_every_policy_is_na_on_keeps_its_overview_column():
    """docs/usage.md: a policy that cannot fly a scenario's vehicle has an n/a cell. When no
    policy flew a scenario it had no record, and its column vanished from summary.md."""
    records = [
        *(_record("ppo_residual", s, 0.05) for s in range(2)),
        *(_record("fbsm_colos_lowpass", s, 0.03) for s in range(2)),
    ]
    for r in records:
        r["scenario"] = "my_helix"
    config = _run_config(2, 100.0, my_torp=TORPEDO_ENV, my_helix={})
    config["not_applicable"] = {"my_torp": ["fbsm_colos_lowpass", "ppo_residual"]}
    lines = summarise(records, config).splitlines()
    assert lines[4:8] == [
        "| policy | my_torp | my_helix |",
        "|---|---:|---:|",
        "| ppo_residual | n/a | 0.05 |",
        "| fbsm_colos_lowpass | n/a | 0.03 |",
    ]
    torp = lines.index("## my_torp")
    assert lines[torp + 2].startswith("n/a: no policy ran an episode here")
    assert lines.index("## my_helix") > torp
    console = overview(records, scenarios=["my_torp", "my_helix"]).splitlines()
    assert console[1].split() == ["ppo_residual", "n/a", "0.05"]
