"""The comparison figures of `benchmarks.reports.figures` cannot mislead (issue 54, item 5): a
cell without a value is never a bar, a mean over fewer than all episodes says so, paired panels
name their scale, the horizontal view fills its panel, and the reference policies' colours stay
apart for colour-blind readers."""

from __future__ import annotations

import itertools
import re
from pathlib import Path

import numpy as np
import pytest
from matplotlib.colors import to_hex, to_rgb

from benchmarks.reports.figures import _bar_figure, _distance_figure, figure_captions
from benchmarks.reports.plotting import POLICY_COLOURS, new_figure, plot_track, policy_colours
from benchmarks.reports.tables import aggregate

ROOT = Path(__file__).resolve().parents[1]


def _records(policy: str, ends: list[tuple[float | None, str]]) -> list[dict]:
    """Episodes of ``policy`` on "paper": (settling time or None for never, how it ended)."""
    return [
        {
            "scenario": "paper",
            "policy": policy,
            "seed": seed,
            "metrics": {
                "rms_distance": 0.1 * (seed + 1),
                "settling_time_0p5": settle,
                "termination_reason": end,
            },
        }
        for seed, (settle, end) in enumerate(ends)
    ]


POLICIES = ["fbsm", "backstepping", "ppo_helix", "sac_generalist", "pid_los"]
RECORDS = [
    *_records("fbsm", [(30.0, "time_limit")] * 3),  # settles: a bar
    *_records("backstepping", [(None, "time_limit")] * 3),  # never settles: no settling time
    *_records("ppo_helix", [(12.0, "time_limit"), (9.0, "corridor"), (9.0, "pitch")]),  # 1 of 3
    *_records("sac_generalist", [(9.0, "corridor")] * 3),  # every episode failed
    *_records("pid_los", [(None, "time_limit"), (40.0, "time_limit"), (50.0, "corridor")]),
]


def _columns(ax) -> dict[str, list]:
    """Hatched patches by hatch, and the plain bars."""
    found: dict[str, list] = {"bars": []}
    for patch in ax.patches:
        found.setdefault(patch.get_hatch() or "bars", []).append(patch)
    return found


def _legend_texts(ax) -> list[str]:
    return [t.get_text() for t in ax.get_legend().get_texts()]


def test_never_settled_and_failed_cells_are_hatched_columns_with_legend_entries():
    """Was: a policy that never settled drew no bar (read as best), an all-failed cell was a
    bar at an arbitrary height, and a mean over 1 of 3 episodes looked like one over 3."""
    cells = aggregate(RECORDS)
    fig = _bar_figure(cells, POLICIES, ["paper"], "settling_time_0p5", "settling time [s]")
    fig.canvas.draw()
    (ax,) = fig.axes
    columns = _columns(ax)
    colours = policy_colours(POLICIES)
    # fbsm and ppo_helix: bars of their means over what finished
    assert sorted(round(p.get_height(), 6) for p in columns["bars"]) == [12.0, 30.0]
    # backstepping never settled, sac_generalist failed: hatched, in their colours, over the whole
    # height of the axes (off any scale), not a bar of some height
    axes_box = ax.get_window_extent()
    # (pid_los: one of three never settled, one failed: its mean is unbounded too)
    drawn = {"///": ["backstepping", "pid_los"], "xxx": ["sac_generalist"]}
    for hatch, policies in drawn.items():
        assert len(columns[hatch]) == len(policies)
        for column, policy in zip(columns[hatch], policies, strict=True):
            assert to_hex(column.get_edgecolor()) == to_hex(colours[policy])
            box = column.get_window_extent()
            assert box.y0 == pytest.approx(axes_box.y0) and box.y1 == pytest.approx(axes_box.y1)
    words = [t.get_text() for t in ax.texts]
    assert sorted(words) == ["failed", "n = 1/3", "never", "never 1/3"]
    legend = _legend_texts(ax)
    assert legend[: len(POLICIES)] == POLICIES
    assert any(text.startswith("never settled") for text in legend)
    assert any(text.startswith("every episode failed") for text in legend)
    assert any(text.startswith("n = k/N") for text in legend)
    hatches = {h.get_hatch() for h in ax.get_legend().legend_handles if hasattr(h, "get_hatch")}
    assert {"///", "xxx"} <= hatches
    assert ax.get_title().endswith("linear scale")


def test_a_chart_without_such_cells_has_no_such_legend_entries_and_says_its_log_scale():
    records = [
        *_records("fbsm", [(30.0, "time_limit")] * 3),
        *_records("ppo_helix", [(0.1, "time_limit")] * 3),
    ]
    for record in records[3:]:
        record["metrics"]["rms_distance"] = 40.0  # 200 times fbsm's mean: a log axis
    fig = _bar_figure(aggregate(records), ["fbsm", "ppo_helix"], ["paper"], "rms_distance", "m")
    (ax,) = fig.axes
    assert _legend_texts(ax) == ["fbsm", "ppo_helix"]
    assert not [p for p in ax.patches if p.get_hatch()] and not ax.texts
    assert ax.get_yscale() == "log" and ax.get_title().endswith("log scale")


def test_many_scenarios_wrap_onto_rows_instead_of_a_strip():
    """Was: 19 scenarios of 7 policies drew one 19 × 4.6-in strip (benchmarks/results/full)."""
    names = [f"s{k}" for k in range(19)]
    policies = [f"p{k}" for k in range(7)]
    records = [
        {"scenario": n, "policy": p, "seed": 0, "metrics": {"rms_distance": 1.0 + k}}
        for n in names
        for k, p in enumerate(policies)
    ]
    fig = _bar_figure(aggregate(records), policies, names, "rms_distance", "m")
    assert len(fig.axes) == 3
    shown = [[t.get_text() for t in ax.get_xticklabels()] for ax in fig.axes]
    assert [len(row) for row in shown] == [7, 7, 5]
    assert [name for row in shown for name in row] == names
    width, height = fig.get_size_inches()
    assert width / height < 1.2
    assert len({ax.get_ylim() for ax in fig.axes}) == 1  # one scale for every row


def test_paired_distance_panels_are_labelled_with_their_scale(monkeypatch):
    from auv_gym.rollout import rollouts

    monkeypatch.syspath_prepend(str(ROOT / "tests"))
    from user_policy import policy

    (episode,) = rollouts(policy, [0], max_time=4.0)
    fig = _distance_figure("paper", {"pursuit": episode}, 0)
    linear, log = fig.axes
    assert (linear.get_title(), linear.get_yscale()) == ("linear scale", "linear")
    assert (log.get_title(), log.get_yscale()) == ("log scale", "log")


def test_the_horizontal_view_of_a_long_path_fills_its_panel():
    """Was: a 150-m stretch of the waypoint spline with 20-m turns was drawn in x and y to one
    scale by shrinking its panel to a strip, and the path ran on to its end, twice as far as the
    vehicles got."""
    from auv_gym.paths import StraightLine

    path = StraightLine()
    s = np.linspace(0.0, 150.0, 300)
    points = path.evaluate(s)[0]
    track = points + np.column_stack([np.zeros_like(s), 2.0 * np.sin(s / 10.0), np.zeros_like(s)])
    fig = new_figure(13.0, 4.6, 60)
    plot_track(fig, path, {"fbsm": track}, s_max=150.0)
    fig.canvas.draw()
    _, ax_xy, ax_xz = fig.axes
    assert ax_xy.get_position().height == pytest.approx(ax_xz.get_position().height, rel=0.05)
    x0, x1 = ax_xy.get_xlim()
    y0, y1 = ax_xy.get_ylim()
    box = ax_xy.get_window_extent()
    # still one scale: metres per pixel equal in x and y
    assert (x1 - x0) / box.width == pytest.approx((y1 - y0) / box.height, rel=0.02)
    drawn = ax_xy.lines[0].get_xydata()  # the path: up to where the episodes got
    assert np.linalg.norm(drawn[-1] - points[-1, :2]) < 1e-6


def test_a_failed_track_ends_in_a_cross_and_says_so():
    from auv_gym.paths import Helix

    track = np.column_stack([np.arange(5.0), np.zeros(5), np.zeros(5)])
    fig = new_figure(13.0, 4.6, 60)
    plot_track(
        fig, Helix(), {"fbsm": track, "ppo_helix": track + 1}, 10.0, failed={"fbsm": "pitch"}
    )
    texts = [t.get_text() for t in fig.legends[0].get_texts()]
    assert texts == ["path", "fbsm (failed: pitch)", "ppo_helix", "end of a failed episode"]


def test_captions_say_what_each_figure_shows(tmp_path):
    files = [tmp_path / "figures" / f"{n}.png" for n in ("track_paper", "bars_settling_time_0p5")]
    captions = dict(figure_captions(files, tmp_path))
    assert captions["figures/track_paper.png"].startswith("paper: every policy's track, seed 0")
    assert "never settled" in captions["figures/bars_settling_time_0p5.png"]


# ------------------------------------------------------------------ colour-blind-safe colours
# Colour-vision deficiencies simulated with the matrices of Machado, Oliveira & Fernandes
# (2009), severity 1, on linear sRGB; differences as CIE 1976 ΔE*ab.
_CVD = {
    "protanopia": [[0.152286, 1.052583, -0.204868], [0.114503, 0.786281, 0.099216],
                   [-0.003882, -0.048116, 1.051998]],
    "deuteranopia": [[0.367322, 0.860646, -0.227968], [0.280085, 0.672501, 0.047413],
                     [-0.011820, 0.042940, 0.968881]],
    "tritanopia": [[1.255528, -0.076749, -0.178779], [-0.078411, 0.930809, 0.147602],
                   [0.004733, 0.691367, 0.303900]],
}  # fmt: skip


def _linear(rgb):
    rgb = np.asarray(rgb, dtype=float)
    return np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)


def _lab(linear_rgb):
    xyz = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
    t = xyz @ np.clip(linear_rgb, 0.0, 1.0) / np.array([0.95047, 1.0, 1.08883])
    f = np.where(t > (6 / 29) ** 3, np.cbrt(t), t / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def _closest_pair(colours: dict[str, str]) -> tuple[float, str, str, str]:
    """(ΔE, vision, a, b) of the two colours least apart, in normal and simulated vision."""
    visions = {"normal": np.eye(3), **{k: np.array(m) for k, m in _CVD.items()}}
    pairs = []
    for vision, matrix in visions.items():
        seen = {n: _lab(matrix @ _linear(to_rgb(c))) for n, c in colours.items()}
        for a, b in itertools.combinations(colours, 2):
            pairs.append((float(np.linalg.norm(seen[a] - seen[b])), vision, a, b))
    return min(pairs)


def _reference_policies() -> list[str]:
    """The main job's policies (scripts/main.sh) and the shipped agents."""
    from benchmarks.catalog.policies import REFERENCE_AGENTS

    main = (ROOT / "scripts" / "main.sh").read_text()
    listed = re.search(r"--policies\s+(\S+)", main).group(1).split(",")
    return list(dict.fromkeys([*listed, *REFERENCE_AGENTS]))


def test_the_reference_policies_stay_apart_for_colour_blind_readers():
    """Was: tab10's red (ppo_generalist) beside pid_los's rose and ppo_as_built's pink; for a
    protanope backstepping's green and ppo_helix's orange were 4.6 ΔE apart."""
    names = _reference_policies()
    colours = {n: POLICY_COLOURS[n] for n in names}
    assert len(set(colours.values())) == len(names)
    distance, vision, a, b = _closest_pair(colours)
    assert distance > 15.0, f"{a} and {b} are {distance:.1f} ΔE apart in {vision}"
    was = {"ppo_generalist": "#d62728", "pid_los": "#d6616b", "backstepping": "#2ca02c",
           "ppo_helix": "#ff7f0e", "ppo_as_built": "#e377c2"}  # fmt: skip
    assert _closest_pair(was)[0] < 10.0  # the test tells the old palette apart
