"""Building a spline path costs time linear in its length (issue 54, item 8: a drawn 879-m
lawnmower cost a user 1.2 s of CPU per reset, over 300× the default 400-m lawnmower's 3.6 ms,
from a dense O(n³) solve of the spline's tridiagonal system). Paths of up to 128 knots keep
the dense solve, bit for bit (`auv_gym.paths.cubic.DENSE_ROWS_MAX`); longer ones are solved in
linear time.

The timing tests are loose guards of the algorithm's complexity, not speed targets: each compares
best-of-N times measured in the same test (a ratio, robust to the machine's speed and load) and
passes if any of three measurements keeps the bound. The spline-build test tells the two solves
apart by far (8× the waypoints: 2–3× the time now, 24–126× with the dense solve, bound 16×);
the draw test guards the rest of a draw (track, checks, proven bounds) loosely. The figures are
`auv-gym speed resets`' (benchmarks/speed/resets.py, docs/performance.md).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
import pytest

from auv_gym.paths import cubic
from auv_gym.paths.shapes import Spline
from auv_gym.sim.path_generator import PathDistribution
from benchmarks.speed.resets import lawnmower_track


def _best(run: Callable[[], object], repeats: int = 5) -> float:
    """[s] the fastest of ``repeats`` calls."""
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - start)
    return best


def _ratios(ratio: Callable[[], float], bound: float) -> list[float]:
    """Up to three measurements of ``ratio()``, stopping at the first below ``bound``."""
    ratios = [ratio()]
    while ratios[-1] >= bound and len(ratios) < 3:
        ratios.append(ratio())
    return ratios


def _product(lower, diag, upper, x) -> np.ndarray:
    """The tridiagonal matrix times x (n, k)."""
    out = diag[:, None] * x
    out[1:] += lower[1:, None] * x[:-1]
    out[:-1] += upper[:-1, None] * x[1:]
    return out


@pytest.mark.parametrize("n", [2, 3, 4, 5, 7, 8, 9, 64, 129, 1000])
def test_solve_tridiagonal_is_the_dense_solution(n: int) -> None:
    """Diagonally dominant systems as the splines build them (random spacings 0.01–20 m, three
    right-hand sides): the dense solution to rounding (up to 129 rows; the residual at 1000, the
    most waypoints a spline takes); identity rows give exact zeros."""
    rng = np.random.default_rng(n)
    h = rng.uniform(0.01, 20.0, n)
    lower, upper = np.r_[0.0, h[:-1]], np.r_[h[1:], 0.0]
    diag = 2.0 * (lower + upper) + (upper == 0) * h + (lower == 0) * h
    rhs = rng.normal(0.0, 10.0, (n, 3))
    x = cubic.solve_tridiagonal(lower, diag, upper, rhs)
    if n <= 129:
        dense = np.diag(diag) + np.diag(lower[1:], -1) + np.diag(upper[:-1], 1)
        want = np.linalg.solve(dense, rhs)
        np.testing.assert_allclose(x, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
    scale = np.abs(rhs).max()
    np.testing.assert_allclose(_product(lower, diag, upper, x), rhs, rtol=0, atol=1e-13 * scale)
    # Natural ends: identity rows with zero right-hand sides.
    lower[-1] = upper[0] = 0.0
    diag[0] = diag[-1] = 1.0
    rhs[0] = rhs[-1] = 0.0
    x = cubic.solve_tridiagonal(lower, diag, upper, rhs)
    assert np.all(x[[0, -1]] == 0.0)
    np.testing.assert_allclose(_product(lower, diag, upper, x), rhs, rtol=0, atol=1e-13 * scale)


@pytest.mark.parametrize("n", [3, 81, cubic.DENSE_ROWS_MAX, cubic.DENSE_ROWS_MAX + 1, 400])
def test_short_paths_keep_the_dense_solve_bit_for_bit(n: int) -> None:
    """Up to `DENSE_ROWS_MAX` knots (every shipped scenario's path: at most 121) the second
    derivatives are the dense LAPACK solve's to the last bit (committed results reproduce);
    above, cyclic reduction's."""
    rng = np.random.default_rng(n)
    h = rng.uniform(2.0, 6.0, n)
    lower, upper = np.r_[0.0, h[1:]], np.r_[h[:-1], 0.0]
    diag = 2.0 * (lower + upper) + 1.0
    rhs = rng.normal(size=(n, 3))
    got = cubic.spline_second_derivatives(lower, diag, upper, rhs)
    if n <= cubic.DENSE_ROWS_MAX:
        dense = np.diag(diag) + np.diag(lower[1:], -1) + np.diag(upper[:-1], 1)
        np.testing.assert_array_equal(got, np.linalg.solve(dense, rhs))
    else:
        np.testing.assert_array_equal(got, cubic.solve_tridiagonal(lower, diag, upper, rhs))


def test_spline_build_time_is_linear_in_waypoints() -> None:
    """8× the waypoints (100 → 800, 0.5 → 4 km of lawnmower) cost < 16× the time, natural and
    clamped: linear is about 2–3× with the fixed costs, the dense solve was over 25×."""
    tracks = {n: lawnmower_track(n) for n in (100, 800)}
    for clamped in (False, True):

        def build(n: int, clamped: bool = clamped) -> Callable[[], object]:
            track, ends = tracks[n]
            return lambda: Spline(track, end_tangents=ends if clamped else None)

        ratios = _ratios(lambda: _best(build(800)) / _best(build(100)), 16.0)
        assert ratios[-1] < 16.0, (clamped, ratios)


def test_drawn_lawnmower_time_per_build_is_linear_in_length(monkeypatch) -> None:
    """A drawn lawnmower 8× longer (250 → 2000 m) costs < 16× the time per spline it builds
    (a draw that misses the limits redraws up to 20 times: the count is the distribution's, the
    time per build the algorithm's)."""
    builds = [0]
    solve = cubic.spline_second_derivatives

    def counted(*args: np.ndarray) -> np.ndarray:
        builds[0] += 1
        return solve(*args)

    monkeypatch.setattr(cubic, "spline_second_derivatives", counted)

    def per_build(length: float) -> float:
        distribution = PathDistribution(families=("lawnmower",), length=length)
        total, count = 0.0, 0
        for seed in range(3):
            builds[0] = 0
            total += _best(lambda seed=seed: distribution.draw(np.random.default_rng(seed)), 3)
            count += builds[0] // 3
        return total / count

    ratios = _ratios(lambda: per_build(2000.0) / per_build(250.0), 16.0)
    assert ratios[-1] < 16.0, ratios
