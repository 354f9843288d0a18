"""Benchmark statistics with confidence intervals (rliable): IQM and mean, probability of
improvement, performance profiles, learning curves, Markdown tables (figures: `stats_figures`).

Conventions (Agarwal et al., "Deep RL at the edge of the statistical precipice", NeurIPS 2021):

* **Scores.** For each policy a matrix ``(n_runs, n_episodes)``: rows are training seeds (one
  row for a classical controller), columns are test episodes, in the same order for every policy
  (column j is the same scenario and episode seed for all). ``groups[j]`` names the scenario of
  column j. `summarize` reports every scenario and "aggregate" (all columns pooled).
* **Direction.** The metric is lower-is-better (RMS distance [m]); rliable assumes
  higher-is-better. IQM and mean do not depend on the direction and are computed on the metres,
  so their intervals are in metres. Probability of improvement is rliable's
  ``probability_of_improvement(-x, -y)``: P(policy's distance < reference's on the same
  episode), ties counting ½. Performance profiles are rliable's score distribution of ``-x``
  at ``-τ``: the fraction of (run, episode) scores strictly below τ [m].
* **Bootstrap.** Each replicate resamples, with replacement, the episodes of every scenario
  within that scenario (rliable's ``task_bootstrap`` stratified by scenario, so each keeps its
  weight in the aggregate), then for every resampled episode the runs (rliable's stratified
  bootstrap over runs). Intervals are percentile intervals. With one run (a classical
  controller) run resampling is the identity and the interval is over episode seeds alone;
  rliable's default (runs only) gives a zero-width interval there (checked with rliable 1.2.0).
  Probability of improvement resamples the same episodes for both policies (paired).
* **Reproducibility.** rliable 1.2.0 draws bootstrap indices from the global ``np.random``
  state, ignoring its ``random_state`` argument, so `_SeedEpisodeBootstrap` draws them from its
  own Generator, seeded by (seed, statistic, policy, episode groups): one seed gives
  bit-identical intervals, and adding a policy does not change another policy's intervals.
* **Speed.** `_iqm` is rliable's ``aggregate_iqm`` (scipy's 25 % ``trim_mean``) without scipy's
  per-call argument inspection; `_probability_lower` is rliable's Mann-Whitney U statistic
  vectorised over episodes (its loop calls scipy once per episode); tests check both equal it.
"""

from __future__ import annotations

import zlib
from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

import numpy as np
from rliable import library

from benchmarks.reports import table_format
from benchmarks.reports.table_format import EMPTY, format_number

AGGREGATE = "aggregate"
MIN_REPS = 100
# Bootstrap replicates at most: 50× the default 2000, whose intervals move by less than their
# printed digits; each replicate resamples every episode, so a typo like 1e9 would run for days.
MAX_REPS = 100_000


class Interval(NamedTuple):
    """A point estimate with its confidence interval (same unit as the scores)."""

    value: float
    low: float
    high: float


class _SeedEpisodeBootstrap(library.StratifiedIndependentBootstrap):
    """rliable's stratified bootstrap over runs, plus episodes resampled within their group.

    Takes one or more arrays ``(n_runs_i, n_episodes, ...)`` sharing their episode columns;
    every array gets the same resampled columns (paired) and its own resampled runs.
    """

    def __init__(self, *scores: np.ndarray, strata: np.ndarray, generator: np.random.Generator):
        super().__init__(*scores, seed=generator)
        order = np.argsort(strata, kind="stable")
        _, first, counts = np.unique(strata[order], return_index=True, return_counts=True)
        group = np.unique(strata, return_inverse=True)[1]
        self._members, self._start, self._size = order, first[group], counts[group]

    def update_indices(self) -> tuple[list[tuple[np.ndarray, np.ndarray]], dict]:
        rng = self.generator
        columns = self._members[self._start + rng.integers(self._size)]
        runs = [rng.integers(n, size=(n, columns.size)) for n in self._num_arg_items]
        return [(r, columns[np.newaxis, :]) for r in runs], {}


def _check_options(reps: int, confidence: float, seed: int) -> None:
    if not isinstance(reps, (int, np.integer)) or not MIN_REPS <= reps <= MAX_REPS:
        raise ValueError(f"reps={reps!r}: need an integer in [{MIN_REPS}, {MAX_REPS}]")
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence={confidence!r}: need 0 < confidence < 1")
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed={seed!r}: need an integer >= 0")


def _check_array(name: str, value: Any, ndims: tuple[int, ...], layout: str) -> np.ndarray:
    try:
        array = np.ascontiguousarray(value, dtype=np.float64)  # layout-independent sums
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: not a numeric {layout} ({exc})") from None
    if array.ndim not in ndims or 0 in array.shape:
        raise ValueError(f"{name}: shape {array.shape}, need a non-empty {layout}")
    bad = np.argwhere(~np.isfinite(array))
    if bad.size:
        where = tuple(int(i) for i in bad[0])
        raise ValueError(
            f"{name}: {len(bad)} non-finite value(s), first {array[where]} at index {where}; "
            "scores must be finite (give terminated episodes a documented finite value)"
        )
    return array


def _check_scores(
    scores: Mapping[str, Any], groups: Sequence[str] | None
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    if not isinstance(scores, Mapping) or not scores:
        raise ValueError("scores: need a non-empty mapping policy -> (n_runs, n_episodes) array")
    arrays = {
        p: _check_array(f"scores[{p!r}]", s, (2,), "(n_runs, n_episodes) array")
        for p, s in scores.items()
    }
    widths = {p: a.shape[1] for p, a in arrays.items()}
    if len(set(widths.values())) > 1:
        raise ValueError(f"scores: policies have different numbers of episodes {widths}")
    n = next(iter(widths.values()))
    strata = np.zeros(n, dtype=str) if groups is None else np.asarray(groups, dtype=str)
    if strata.shape != (n,):
        raise ValueError(f"groups: {strata.size} labels for {n} episode columns")
    return arrays, strata


def _seeded_bootstrap(arrays, strata, key: str, seed: int) -> _SeedEpisodeBootstrap:
    """The bootstrap of ``arrays``, its generator seeded by (seed, key, strata)."""
    crc = zlib.crc32("|".join([key, *strata.tolist()]).encode())
    gen = np.random.default_rng([int(seed), crc])
    return _SeedEpisodeBootstrap(*arrays, strata=strata, generator=gen)


def _bootstrap(func, arrays, strata, key: str, reps: int, confidence: float, seed: int):
    """(low, high) percentile bounds of ``func(*arrays)``, seeded by (seed, key, strata)."""
    bs = _seeded_bootstrap(arrays, strata, key, seed)
    return bs.conf_int(func, reps=reps, method="percentile", size=confidence)


def _iqm(scores: np.ndarray, axis: int | None = None) -> np.ndarray:
    """25 % trimmed mean, as rliable's aggregate_iqm (axis=None: over all runs and episodes)."""
    a = scores.ravel() if axis is None else np.moveaxis(scores, axis, 0)
    n = a.shape[0]
    cut = n // 4  # scipy: int(0.25 n) from each end
    return np.mean(np.partition(a, (cut, n - cut - 1), axis=0)[cut : n - cut], axis=0)


def _iqm_and_mean(scores: np.ndarray) -> np.ndarray:
    return np.array([_iqm(scores), np.mean(scores)])


def interval_estimates(
    scores: Mapping[str, Any],
    groups: Sequence[str] | None = None,
    *,
    reps: int = 2000,
    confidence: float = 0.95,
    seed: int = 0,
) -> dict[str, dict[str, Interval]]:
    """IQM and mean of each policy's scores with bootstrap CIs: {"iqm"|"mean": {policy: ...}}."""
    _check_options(reps, confidence, seed)
    arrays, strata = _check_scores(scores, groups)
    out: dict[str, dict[str, Interval]] = {"iqm": {}, "mean": {}}
    for policy, x in arrays.items():
        low, high = _bootstrap(_iqm_and_mean, [x], strata, f"iqm|{policy}", reps, confidence, seed)
        for k, (name, value) in enumerate(zip(("iqm", "mean"), _iqm_and_mean(x), strict=True)):
            out[name][policy] = Interval(float(value), float(low[k]), float(high[k]))
    return out


def mean_interval(
    x: Any,
    groups: Sequence[str] | None = None,
    *,
    key: str = "",
    reps: int = 2000,
    confidence: float = 0.95,
    seed: int = 0,
) -> Interval:
    """Mean of the finite entries of one policy's ``(n_runs, n_episodes)`` matrix (NaN: no value,
    e.g. an episode that ended before the metrics window) with its bootstrap CI; ``key`` names the
    statistic in the bootstrap seed. NaN if no entry is finite."""
    _check_options(reps, confidence, seed)
    a = np.asarray(x, dtype=float)
    # NaN marks a missing value; the rest must pass the usual checks
    _check_scores({"x": np.where(np.isnan(a), 0.0, a)}, groups)
    strata = np.zeros(a.shape[1], dtype=str) if groups is None else np.asarray(groups, dtype=str)
    if not np.isfinite(a).any():
        return Interval(np.nan, np.nan, np.nan)

    def finite_mean(m: np.ndarray) -> np.ndarray:
        return np.array([np.mean(m[np.isfinite(m)]) if np.isfinite(m).any() else np.nan])

    bs = _seeded_bootstrap([a], strata, f"mean|{key}", seed)
    # a replicate that drew only missing values has no mean: the percentiles skip it
    replicates = bs.apply(finite_mean, reps)[:, 0]
    tail = 50.0 * (1.0 - confidence)
    low, high = np.nanpercentile(replicates, [tail, 100.0 - tail])
    return Interval(float(finite_mean(a)[0]), float(low), float(high))


def paired_difference(
    x: Any,
    y: Any,
    groups: Sequence[str] | None = None,
    *,
    key: str = "",
    reps: int = 2000,
    confidence: float = 0.95,
    seed: int = 0,
) -> dict[str, Interval]:
    """mean(x) − mean(y) for two score matrices on the same episode columns (a policy and its
    reference, e.g. a residual agent and its base), and that difference relative to mean(y),
    with CIs: {"difference": ..., "relative": ...}. Paired: every replicate resamples the same
    episodes for both (within their group) and the runs of each separately."""
    _check_options(reps, confidence, seed)
    arrays, strata = _check_scores({"x": x, "y": y}, groups)

    def both(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        diff = np.mean(a) - np.mean(b)
        return np.array([diff, diff / np.mean(b)])

    a, b = arrays["x"], arrays["y"]
    low, high = _bootstrap(both, [a, b], strata, f"paired|{key}", reps, confidence, seed)
    value = both(a, b)
    return {
        name: Interval(float(value[k]), float(low[k]), float(high[k]))
        for k, name in enumerate(("difference", "relative"))
    }


def _probability_lower(x: np.ndarray, y: np.ndarray) -> float:
    """rliable's probability_of_improvement(-x, -y) (Mann-Whitney U / (n_x n_y) per episode,
    averaged), vectorised over episodes: P(x < y) + ½ P(x = y)."""
    a, b = x[:, np.newaxis, :], y[np.newaxis, :, :]
    return float(np.mean(np.mean(a < b, axis=(0, 1)) + 0.5 * np.mean(a == b, axis=(0, 1))))


def probability_of_improvement(
    scores: Mapping[str, Any],
    reference: str,
    groups: Sequence[str] | None = None,
    *,
    reps: int = 2000,
    confidence: float = 0.95,
    seed: int = 0,
) -> dict[str, Interval]:
    """P(policy's score < reference's score on an episode), with CI, for every other policy."""
    _check_options(reps, confidence, seed)
    arrays, strata = _check_scores(scores, groups)
    if reference not in arrays:
        raise ValueError(f"reference={reference!r}: not among the policies {list(arrays)}")
    out = {}
    for policy, x in arrays.items():
        if policy == reference:
            continue
        pair, key = [x, arrays[reference]], f"improvement|{reference}|{policy}"
        low, high = _bootstrap(_probability_lower, pair, strata, key, reps, confidence, seed)
        value = _probability_lower(*pair)
        out[policy] = Interval(value, float(low[0]), float(high[0]))
    return out


def default_thresholds(arrays: Mapping[str, np.ndarray], n: int = 65) -> np.ndarray:
    """τ grid [m] spanning all scores: geometric from min/1.25 to 1.25 max (linear if min ≤ 0)."""
    values = np.concatenate([np.ravel(a) for a in arrays.values()])
    lo, hi = float(values.min()), float(values.max()) * 1.25 + 1e-12
    return np.geomspace(lo / 1.25, hi, n) if lo > 0 else np.linspace(min(lo, 0.0), hi, n)


def performance_profile(
    scores: Mapping[str, Any],
    tau_m: Any = None,
    groups: Sequence[str] | None = None,
    *,
    reps: int = 2000,
    confidence: float = 0.95,
    seed: int = 0,
) -> dict[str, dict[str, np.ndarray]]:
    """Fraction of (run, episode) scores below each τ [m] with CI bands (`default_thresholds`
    if ``tau_m`` is None): {policy: {"tau_m", "fraction", "low", "high"}}."""
    _check_options(reps, confidence, seed)
    arrays, strata = _check_scores(scores, groups)
    tau = (
        default_thresholds(arrays)
        if tau_m is None
        else _check_array("tau_m", tau_m, (1,), "1-D array")
    )
    opts = (reps, confidence, seed)

    def fraction_below(x: np.ndarray) -> np.ndarray:
        return np.mean(x.reshape(-1, 1) < tau, axis=0)

    out = {}
    for policy, x in arrays.items():
        low, high = _bootstrap(fraction_below, [x], strata, f"profile|{policy}", *opts)
        out[policy] = {"tau_m": tau, "fraction": fraction_below(x), "low": low, "high": high}
    return out


def summarize(
    scores: Mapping[str, Any],
    groups: Sequence[str],
    *,
    reference: str = "fbsm",
    tau_m: Any = None,
    reps: int = 2000,
    confidence: float = 0.95,
    seed: int = 0,
) -> dict[str, Any]:
    """Every statistic per scenario (in order of first appearance) and for "aggregate":
    {"scopes", "policies", "reference", "iqm"/"mean"/"improvement": {scope: {policy: Interval}},
    "profiles": {scope: {policy: profile}}, "n_runs": {policy: int}, "reps", "confidence",
    "seed"}. Without ``reference`` among the policies, "improvement" is empty."""
    arrays, strata = _check_scores(scores, groups)
    scopes = [*dict.fromkeys(strata.tolist()), AGGREGATE]
    out: dict[str, Any] = {"scopes": scopes, "policies": list(arrays), "reference": reference}
    out |= {"iqm": {}, "mean": {}, "improvement": {}, "profiles": {}}
    opts = {"reps": reps, "confidence": confidence, "seed": seed}
    for scope in scopes:
        cols = np.ones(strata.size, bool) if scope == AGGREGATE else strata == scope
        part, labels = {p: a[:, cols] for p, a in arrays.items()}, strata[cols]
        both = interval_estimates(part, labels, **opts)
        out["iqm"][scope], out["mean"][scope] = both["iqm"], both["mean"]
        if reference in part:
            out["improvement"][scope] = probability_of_improvement(part, reference, labels, **opts)
        out["profiles"][scope] = performance_profile(part, tau_m, labels, **opts)
    return out | {"n_runs": {p: a.shape[0] for p, a in arrays.items()}, **opts}


def _common_grid(x: np.ndarray, grid: Any, n_grid: int | None) -> np.ndarray | None:
    """The points to interpolate every run onto, or None when the runs share theirs."""
    if grid is not None:
        grid = _check_array("grid", grid, (1,), "1-D array")
    elif np.all(x == x[0]):
        return None
    lo, hi = float(x[:, 0].max()), float(x[:, -1].min())
    if grid is None:
        if lo >= hi:
            raise ValueError(f"x: the runs share no span (latest start {lo} >= earliest end {hi})")
        return np.linspace(lo, hi, n_grid or x.shape[1])
    if grid.min() < lo or grid.max() > hi:
        raise ValueError(
            f"grid: spans [{grid.min()}, {grid.max()}], every run covers only "
            f"[{lo}, {hi}] (no extrapolation)"
        )
    return grid


def learning_curve(
    x: Any,
    scores: Any,
    *,
    grid: Any = None,
    n_grid: int | None = None,
    reps: int = 2000,
    confidence: float = 0.95,
    seed: int = 0,
) -> dict[str, Any]:
    """IQM over runs (× episodes) at each evaluation point with CI band: {"x", "iqm", "low",
    "high", "n_runs"}.

    ``scores``: (n_runs, n_points) or (n_runs, n_points, n_episodes); ``x``: (n_points,) shared
    or (n_runs, n_points) per run, strictly increasing (env steps, or wall time [s]). When the
    runs' x differ (wall time), each run's scores are linearly interpolated onto ``grid``
    (default: ``n_grid`` points, as many as evaluations, evenly over the span every run covers;
    never extrapolated), i.e. a run's score between two evaluations is taken to change linearly.
    """
    _check_options(reps, confidence, seed)
    y = _check_array("scores", scores, (2, 3), "(n_runs, n_points[, n_episodes]) array")
    y = y if y.ndim == 3 else y[:, :, np.newaxis]
    xs = _check_array("x", x, (1, 2), "1-D or 2-D array")
    if xs.shape not in (y.shape[1:2], y.shape[:2]):
        raise ValueError(f"x: shape {xs.shape}, scores need {y.shape[1:2]} or {y.shape[:2]}")
    xs = np.broadcast_to(xs, y.shape[:2])
    if np.any(np.diff(xs, axis=1) <= 0):
        raise ValueError("x: each run's evaluation points must be strictly increasing")
    if n_grid is not None and (not isinstance(n_grid, (int, np.integer)) or n_grid < 2):
        raise ValueError(f"n_grid={n_grid!r}: need an integer >= 2")
    points = _common_grid(xs, grid, n_grid)
    if points is None:
        points = xs[0].copy()
    else:
        y = np.stack(
            [
                np.stack([np.interp(points, xi, c) for c in yi.T], axis=1)
                for xi, yi in zip(xs, y, strict=True)
            ]
        )
    tasks = np.swapaxes(y, 1, 2)  # rliable layout (n_runs, n_tasks, n_points)

    def iqm_per_point(s: np.ndarray) -> np.ndarray:
        return _iqm(s.reshape(-1, s.shape[-1]), axis=0)

    strata = np.zeros(tasks.shape[1], dtype=str)
    low, high = _bootstrap(iqm_per_point, [tasks], strata, "curve", reps, confidence, seed)
    return {"x": points, "iqm": iqm_per_point(tasks), "low": low, "high": high, "n_runs": len(y)}


def format_interval(interval: Interval, digits: int = 3) -> str:
    """'0.0640 [0.0610, 0.0680]': each bound with ``digits`` significant figures."""
    value, low, high = (format_number(x, digits) for x in interval[:3])
    return f"{value} [{low}, {high}]"


def markdown_table(
    table: Mapping[str, Mapping[str, Interval]], digits: int = 3, corner: str = "policy"
) -> str:
    """Markdown table of {column (scope): {row (policy): Interval}}; missing cells are '–'."""
    columns = list(table)
    rows = [
        [r, *(format_interval(table[c][r], digits) if r in table[c] else EMPTY for c in columns)]
        for r in dict.fromkeys(r for col in table.values() for r in col)
    ]
    return table_format.markdown_table([corner, *columns], rows, ["l"] * (len(columns) + 1))
