"""The one table convention: significant figures, units, and failures never marked best."""

from __future__ import annotations

import math

import pytest

from benchmarks.reports.plotting import metrics_table
from benchmarks.reports.table_format import (
    EMPTY,
    Cell,
    display_scale,
    format_mean_std,
    format_number,
    mark_best,
    markdown_table,
)
from benchmarks.reports.tables import summarise


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
    assert Cell((0.1, 0.3), failed=1).text() == "0.200 ± 0.100"
    assert Cell((31.0, math.inf)).text("settling_time_0p5") == "never"


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
    rows: dict[str, str] = {}  # the tracking table's row of each policy (it comes first)
    for line in text.splitlines():
        if line.startswith("| "):
            rows.setdefault(line.split(" | ")[0][2:], line)
    assert "inf" not in text
    assert rows["fbsm"].startswith("| fbsm | 0/2 | **0.0650 ± 0.0050** |")
    assert rows["untrained"].startswith(f"| untrained | 2/2 | {EMPTY} |")
    assert rows["ppo"].startswith("| ppo | 1/2 | 0.300 |")
    assert "| policy | failed | RMS d [m] |" in text
    assert max(len(line) for line in text.splitlines() if line.startswith("|")) < 120


def test_metrics_table_never_bolds_a_failed_episode():
    results = {
        "A": {"rms_distance": 0.04, "termination_reason": "time_limit"},
        "B": {"rms_distance": 0.004, "termination_reason": "corridor"},
    }
    lines = metrics_table(results, ["rms_distance"]).splitlines()
    assert lines[2] == "| RMS distance, t ≥ transient | m | **0.0400** | 0.00400 |"
