"""benchmarks.analysis.stats and benchmarks.analysis.stats_figures: hand-computed estimates,
bootstrap behaviour, determinism, bad input, Markdown cells and PNG files."""

from __future__ import annotations

import warnings
from functools import partial
from pathlib import Path

import numpy as np
import pytest

rliable = pytest.importorskip("rliable")
from rliable import library, metrics  # noqa: E402

from benchmarks.analysis import stats  # noqa: E402
from benchmarks.analysis.stats import Interval  # noqa: E402
from benchmarks.analysis.stats_figures import (  # noqa: E402
    improvement_figure,
    interval_figure,
    learning_curve_figure,
    profile_figure,
    save_figure,
)

REPS = 200  # small: these tests check behaviour, not precision
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
# Two runs x eight episodes; sorted: .1 .15 .2 .25 | .3 .35 .4 .45 .5 .55 .6 .65 | .7 .75 10 20
HAND = np.array(
    [
        [0.10, 0.20, 0.30, 0.40, 0.50, 0.60, 0.70, 10.0],
        [0.15, 0.25, 0.35, 0.45, 0.55, 0.65, 0.75, 20.0],
    ]
)


def test_iqm_and_mean_of_a_hand_computed_matrix():
    est = stats.interval_estimates({"a": HAND}, reps=REPS)
    # IQM: 16 values, 4 trimmed from each end, mean of .3 ... .65 = (.3 + .65) / 2.
    assert est["iqm"]["a"].value == pytest.approx(0.475, abs=1e-15)
    assert est["mean"]["a"].value == pytest.approx((2.8 + 10 + 3.15 + 20) / 16, abs=1e-15)
    assert est["iqm"]["a"].value == metrics.aggregate_iqm(HAND)
    for name in ("iqm", "mean"):
        iv = est[name]["a"]
        assert iv.low <= iv.value <= iv.high
        assert iv.high - iv.low > 0.05


def test_fast_iqm_and_probability_equal_rliable():
    rng = np.random.default_rng(3)
    for shape in [(1, 1), (1, 7), (2, 8), (3, 5), (5, 13), (4, 80)]:
        x = np.round(rng.random(shape), 1)  # rounding makes ties
        assert stats._iqm(x) == metrics.aggregate_iqm(x)
        y = np.round(rng.random((int(rng.integers(1, 4)), shape[1])), 1)
        expected = metrics.probability_of_improvement(-x, -y)
        assert stats._probability_lower(x, y) == pytest.approx(expected, abs=1e-12)
    curve = rng.random((6, 9))
    assert np.array_equal(stats._iqm(curve, axis=0), [metrics.aggregate_iqm(c) for c in curve.T])


def test_mean_interval_brackets_the_mean_with_normal_theory_width():
    x = np.random.default_rng(0).normal(1.0, 1.0, size=(1, 400))
    iv = stats.interval_estimates({"a": x}, reps=1000)["mean"]["a"]
    assert iv.low < x.mean() < iv.high
    # Normal theory: 2 * 1.96 * sigma / sqrt(n) = 0.196.
    assert iv.high - iv.low == pytest.approx(2 * 1.96 * x.std() / 20.0, rel=0.12)


def test_equal_scores_collapse_the_interval():
    for shape in [(1, 10), (5, 10)]:
        est = stats.interval_estimates({"a": np.full(shape, 0.0625)}, reps=REPS)
        for name in ("iqm", "mean"):
            assert tuple(est[name]["a"]) == (0.0625, 0.0625, 0.0625)


def test_one_run_gets_an_interval_over_episodes_where_rliable_default_has_none():
    x = np.arange(1.0, 11.0)[np.newaxis, :]
    iv = stats.interval_estimates({"classical": x}, reps=REPS)["mean"]["classical"]
    assert iv.low < 5.5 < iv.high and 1.0 <= iv.low and iv.high <= 10.0
    assert iv.high - iv.low > 2.0
    _, rliable_ci = library.get_interval_estimates({"c": x}, np.mean, reps=REPS)
    assert rliable_ci["c"][0] == rliable_ci["c"][1]  # runs only: zero width


def test_runs_are_resampled_per_episode():
    x = np.array([[1.0], [2.0], [3.0], [4.0]])  # four seeds, one episode
    iv = stats.interval_estimates({"rl": x}, reps=REPS)["mean"]["rl"]
    assert 1.0 <= iv.low < 2.5 < iv.high <= 4.0


def test_episodes_are_resampled_within_their_scenario():
    # Scenario "a" scores 0, "b" scores 1: stratified, every replicate's mean is exactly 0.5.
    x = np.array([[0.0] * 5 + [1.0] * 5])
    groups = ["a"] * 5 + ["b"] * 5
    assert tuple(stats.interval_estimates({"p": x}, groups, reps=REPS)["mean"]["p"]) == (
        0.5,
        0.5,
        0.5,
    )
    pooled = stats.interval_estimates({"p": x}, reps=REPS)["mean"]["p"]
    assert pooled.high - pooled.low > 0.3


def test_one_scenario_matches_rliable_task_bootstrap():
    x = np.random.default_rng(5).gamma(2.0, 0.05, size=(5, 20))
    ours = stats.interval_estimates({"a": x}, reps=2000)["mean"]["a"]
    state = np.random.get_state()  # noqa: NPY002
    try:  # rliable draws from the global generator
        np.random.seed(11)  # noqa: NPY002
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            _, ci = library.get_interval_estimates(
                {"a": x}, metrics.aggregate_mean, task_bootstrap=True, reps=2000
            )
    finally:
        np.random.set_state(state)  # noqa: NPY002
    width = ci["a"][1, 0] - ci["a"][0, 0]
    assert ours.low == pytest.approx(ci["a"][0, 0], abs=0.1 * width)
    assert ours.high == pytest.approx(ci["a"][1, 0], abs=0.1 * width)


def test_probability_of_improvement_hand_cases():
    ref = np.array([[0.1, 0.2, 0.3, 0.4]])
    scores = {
        "fbsm": ref,
        "worse": ref + 1.0,
        "better": np.array([[0.01, 0.02, 0.03, 0.04], [0.05, 0.06, 0.07, 0.08]]),
        "same": ref.copy(),
        "half": np.array([[0.0, 0.0, 1.0, 1.0]]),
    }
    pi = stats.probability_of_improvement(scores, "fbsm", reps=REPS)
    assert "fbsm" not in pi
    assert tuple(pi["worse"]) == (0.0, 0.0, 0.0)
    assert tuple(pi["better"]) == (1.0, 1.0, 1.0)
    assert tuple(pi["same"]) == (0.5, 0.5, 0.5)
    assert pi["half"].value == 0.5 and pi["half"].low < 0.5 < pi["half"].high
    # Two seeds against one run on one episode: one beats it, one ties -> (1 + 0.5) / 2.
    one = stats.probability_of_improvement(
        {"r": np.array([[1.0]]), "p": np.array([[0.5], [1.0]])}, "r", reps=REPS
    )
    assert one["p"].value == 0.75


def test_performance_profile_hand_example():
    x = np.array([[0.1, 0.2, 0.3, 0.4]])
    tau = np.array([0.05, 0.15, 0.3, 0.5])
    prof = stats.performance_profile({"a": x}, tau, reps=REPS)["a"]
    assert np.array_equal(prof["fraction"], [0.0, 0.25, 0.5, 1.0])  # strictly below τ
    assert np.array_equal(prof["fraction"], library.score_distributions(-x, -tau))
    assert np.all(prof["low"] <= prof["fraction"]) and np.all(prof["fraction"] <= prof["high"])
    assert prof["low"][0] == prof["high"][0] == 0.0 and prof["low"][3] == prof["high"][3] == 1.0
    assert prof["high"][1] - prof["low"][1] > 0.2


def test_summary_scopes_and_consistency_with_direct_calls():
    rng = np.random.default_rng(1)
    groups = ["line"] * 4 + ["helix"] * 4
    scores = {"fbsm": rng.random((1, 8)), "ppo": rng.random((3, 8))}
    summ = stats.summarize(scores, groups, reps=REPS, seed=4)
    assert summ["scopes"] == ["line", "helix", "aggregate"]
    assert summ["n_runs"] == {"fbsm": 1, "ppo": 3}
    assert set(summ["improvement"]["helix"]) == {"ppo"}
    helix = {p: s[:, 4:] for p, s in scores.items()}
    direct = stats.interval_estimates(helix, groups[4:], reps=REPS, seed=4)
    assert summ["iqm"]["helix"] == direct["iqm"] and summ["mean"]["helix"] == direct["mean"]
    agg = stats.interval_estimates(scores, groups, reps=REPS, seed=4)
    assert summ["iqm"]["aggregate"] == agg["iqm"]
    no_ref = stats.summarize({"ppo": scores["ppo"]}, groups, reps=REPS)
    assert no_ref["improvement"] == {}


def test_same_seed_is_bit_identical_and_policies_are_independent():
    rng = np.random.default_rng(2)
    scores = {"a": rng.random((3, 12)), "b": rng.random((1, 12))}
    groups = ["x", "y", "z"] * 4
    first = stats.summarize(scores, groups, reference="b", reps=REPS, seed=9)
    again = stats.summarize(scores, groups, reference="b", reps=REPS, seed=9)
    for key in ("iqm", "mean", "improvement"):
        assert first[key] == again[key]
    for scope in first["scopes"]:
        for p in scores:
            for k in ("low", "high"):
                assert np.array_equal(
                    first["profiles"][scope][p][k], again["profiles"][scope][p][k]
                )
    other_seed = stats.interval_estimates(scores, groups, reps=REPS, seed=10)
    assert other_seed["iqm"]["a"] != first["iqm"]["aggregate"]["a"]
    alone = stats.interval_estimates({"a": scores["a"]}, groups, reps=REPS, seed=9)
    assert alone["iqm"]["a"] == first["iqm"]["aggregate"]["a"]


def test_learning_curve_shared_steps():
    steps = np.array([1e5, 2e5, 3e5])
    # Four seeds: IQM of four values is the mean of the middle two.
    y = np.array([[1.0, 0.5, 0.2], [2.0, 0.6, 0.1], [3.0, 0.7, 0.3], [100.0, 0.8, 0.4]])
    c = stats.learning_curve(steps, y, reps=REPS)
    assert np.array_equal(c["x"], steps) and c["n_runs"] == 4
    assert c["iqm"] == pytest.approx([2.5, 0.65, 0.25], abs=1e-15)
    assert np.all(c["low"] <= c["iqm"]) and np.all(c["iqm"] <= c["high"])
    assert c["low"][0] >= 1.0 and c["high"][0] <= 100.0


def test_learning_curve_interpolates_wall_time_onto_the_common_span():
    wall = np.array([[0.0, 10.0, 20.0], [5.0, 15.0, 25.0]])
    y = np.stack([wall[0] / 10.0, 2.0 * wall[1] / 10.0])  # each seed linear in its wall time
    c = stats.learning_curve(wall, y, reps=REPS)
    assert np.array_equal(c["x"], [5.0, 12.5, 20.0])
    # Seed 0 at the grid: .5, 1.25, 2; seed 1: 1, 2.5, 4; IQM of two values is their mean.
    assert c["iqm"] == pytest.approx([0.75, 1.875, 3.0], abs=1e-12)
    per_episode = stats.learning_curve(wall, np.stack([y, y + 1.0], axis=2), n_grid=4, reps=REPS)
    assert per_episode["x"].shape == (4,) and per_episode["iqm"][0] == pytest.approx(1.25)
    with pytest.raises(ValueError, match="no extrapolation"):
        stats.learning_curve(wall, y, grid=[0.0, 10.0], reps=REPS)
    with pytest.raises(ValueError, match="share no span"):
        stats.learning_curve([[0.0, 1.0], [2.0, 3.0]], [[1.0, 1.0], [1.0, 1.0]], reps=REPS)
    with pytest.raises(ValueError, match="strictly increasing"):
        stats.learning_curve([[0.0, 0.0, 1.0]], [[1.0, 1.0, 1.0]], reps=REPS)


IE, PI = stats.interval_estimates, stats.probability_of_improvement
PP, LC = stats.performance_profile, stats.learning_curve
ONE = {"a": [[1.0]]}


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (partial(IE, {"a": [[0.1, np.nan]]}), r"scores\['a'\]: 1 non-finite .* index \(0, 1\)"),
        (partial(IE, {"a": [[0.1, np.inf]]}), "non-finite"),
        (partial(IE, {"a": [0.1, 0.2]}), r"shape \(2,\), need a non-empty \(n_runs, n_ep"),
        (partial(IE, {"a": np.zeros((0, 4))}), r"shape \(0, 4\)"),
        (partial(IE, {}), "non-empty mapping"),
        (partial(IE, {"a": [[1.0], [1.0, 2.0]]}), "not a numeric"),
        (partial(IE, {"a": [[1.0]], "b": [[1.0, 2.0]]}), "different numbers of episodes"),
        (partial(IE, {"a": [[1.0, 2.0]]}, ["x"]), "1 labels for 2"),
        (partial(IE, ONE, reps=10), "reps=10: need an integer in \\[100, 100000\\]"),
        (partial(IE, ONE, confidence=95), "confidence=95"),
        (partial(IE, ONE, seed=-1), "seed=-1"),
        (partial(PI, ONE, "fbsm"), "reference='fbsm': not among"),
        (partial(PP, ONE, [0.1, np.nan]), "tau_m: 1 non-finite"),
        (partial(LC, [1.0, 2.0], [[np.nan, 1.0]]), "scores: 1 non-finite"),
        (partial(LC, [1.0, 2.0, 3.0], [[1.0, 1.0]]), r"x: shape \(3,\)"),
        (partial(LC, [1.0, 2.0], [[1.0, 1.0]], n_grid=1), "n_grid=1"),
    ],
)
def test_bad_input_names_the_problem(call, message):
    kwargs = {} if "reps" in call.keywords else {"reps": REPS}
    with pytest.raises(ValueError, match=message):
        call(**kwargs)


def test_markdown_cells_and_table():
    assert stats.format_interval(Interval(0.0642, 0.0611, 0.0678)) == "0.0642 [0.0611, 0.0678]"
    assert stats.format_interval(Interval(0.5, 0.25, 0.75), digits=2) == "0.50 [0.25, 0.75]"
    # Sub-millimetre values keep their figures instead of printing 0.000.
    tiny = stats.format_interval(Interval(4.2e-4, 4.1e-4, 4.3e-4))
    assert tiny == "4.20e-04 [4.10e-04, 4.30e-04]"
    table = {"line": {"fbsm": Interval(0.07, 0.06, 0.08), "ppo": Interval(0.6, 0.5, 0.7)}}
    table["aggregate"] = {"ppo": Interval(1.0, 0.9, 1.1)}
    assert stats.markdown_table(table).splitlines() == [
        "| policy | line | aggregate |",
        "|---|---|---|",
        "| fbsm | 0.0700 [0.0600, 0.0800] | — |",
        "| ppo | 0.600 [0.500, 0.700] | 1.00 [0.900, 1.10] |",
    ]


def test_figures_are_written_as_png_atomically(tmp_path: Path):
    rng = np.random.default_rng(7)
    groups = ["line"] * 5 + ["helix"] * 5
    scores = {"fbsm": rng.gamma(2, 0.03, (1, 10)), "ppo": rng.gamma(2, 0.1, (3, 10))}
    summ = stats.summarize(scores, groups, reps=REPS)
    steps = np.arange(1, 6) * 1e5
    wall = np.cumsum(rng.uniform(50, 70, (3, 5)), axis=1)
    y = np.exp(-np.arange(5))[np.newaxis, :] + rng.random((3, 5))
    curves = {
        "env steps": {"ppo": stats.learning_curve(steps, y, reps=REPS)},
        "wall time [s]": {"ppo": stats.learning_curve(wall, y, reps=REPS)},
    }
    figures = {
        "intervals.png": interval_figure(summ),
        "improvement.png": improvement_figure(summ),
        "profile.png": profile_figure(summ),
        "curves.png": learning_curve_figure(curves),
    }
    for name, fig in figures.items():
        path = save_figure(fig, tmp_path / "out" / name, dpi=60)
        data = path.read_bytes()
        assert data.startswith(PNG_SIGNATURE) and len(data) > 5_000
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == sorted(figures)
    with pytest.raises(ValueError):  # unknown format: nothing written, no temporary left
        save_figure(interval_figure(summ), tmp_path / "out" / "bad.xyz")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == sorted(figures)
    with pytest.raises(ValueError, match="not among the policies"):
        improvement_figure(stats.summarize({"ppo": scores["ppo"]}, groups, reps=REPS))
    with pytest.raises(ValueError, match="scope='storm'"):
        profile_figure(summ, "storm")


def test_paired_difference_hand_example():
    x = np.array([[1.0, 2.0, 3.0, 4.0], [2.0, 3.0, 4.0, 5.0]])  # run 1 is 1 worse everywhere
    y = np.array([[1.0, 2.0, 3.0, 4.0]])
    groups = ["a", "a", "b", "b"]
    out = stats.paired_difference(x, y, groups, reps=REPS)
    assert out["difference"].value == 0.5 and out["relative"].value == pytest.approx(0.2)
    # paired: the episodes cancel, only the run offset (0 or 1 per draw) varies
    assert 0.0 <= out["difference"].low < 0.5 < out["difference"].high <= 1.0
    same = stats.paired_difference(y, y, groups, reps=REPS)
    assert same["difference"] == Interval(0.0, 0.0, 0.0)
    better = stats.paired_difference(y - 0.1, y, groups, reps=REPS)["difference"]
    assert better.value == pytest.approx(-0.1) and better.high < 0.0


def test_mean_interval_leaves_missing_values_out():
    x = np.array([[1.0, np.nan, 3.0], [np.nan, 5.0, np.nan]])
    iv = stats.mean_interval(x, reps=REPS)
    assert iv.value == 3.0 and 1.0 <= iv.low <= 3.0 <= iv.high <= 5.0
    assert np.isnan(stats.mean_interval(np.full((1, 2), np.nan), reps=REPS).value)
    with pytest.raises(ValueError, match="non-finite"):
        stats.mean_interval(np.array([[1.0, np.inf]]), reps=REPS)


def test_policy_colors_stay_distinct_beyond_ten_policies():
    from matplotlib.colors import to_hex

    from benchmarks.analysis.stats_figures import policy_colors

    assert len(set(policy_colors(["a", "b"]).values())) == 2
    eleven = policy_colors([f"p{k}" for k in range(11)])
    assert len({to_hex(c) for c in eleven.values()}) == 11  # C10 would repeat C0
    shipped = [
        *(f"p{k}" for k in range(6)),
        "fbsm",
        "ppo_residual",
        "ppo_generalist",
        "sac_generalist",
    ]
    assert len({to_hex(c) for c in policy_colors(shipped).values()}) == len(shipped)
