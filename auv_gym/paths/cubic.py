"""The cubic-spline coefficients the SPLINE kernel kind stores (docs/model.md §3.1): natural or
clamped ends, from one tridiagonal solve each, in time linear in the number of waypoints.

The second derivatives m_i = p''(s_i) at the knots solve a tridiagonal system (one right-hand
side per axis). Each interior row is h_{i-1} m_{i-1} + 2 (h_{i-1} + h_i) m_i + h_i m_{i+1} =
6 (Δp_i/h_i − Δp_{i-1}/h_{i-1}), with h_i the knot spacing [m]: strictly diagonally dominant
(the diagonal is twice the sum of the off-diagonal entries), and so are the clamped end rows.
`solve_tridiagonal` solves it by cyclic reduction, which is stable without pivoting on such
systems: O(n) arithmetic in O(log n) whole-array steps, no Python loop over the rows. (The
dense `numpy.linalg.solve` of the n × n matrix costs O(n³) on spinning OpenBLAS threads: up to
1.9 s per reset of a drawn 879-m lawnmower, which solves twenty-one 176-row systems;
docs/performance.md.)

Every system takes the linear solve, whatever its size. Its whole-array steps are numpy's
elementwise IEEE operations, which round alike on every x86-64 CPU; the dense LAPACK solve it
replaced (kept for up to 128 rows until 0.1.0's last changes) takes the kernels OpenBLAS picks
for the CPU it runs on, and its bits differed between CPUs (spline systems of 8 to 121 knots
solved with OpenBLAS's Nehalem kernels and with its Haswell or Zen kernels differ in the last
digits), so a committed result on a spline path did not reproduce bit for bit on another machine
(docs/performance.md).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "clamped_cubic_coefficients",
    "natural_cubic_coefficients",
    "solve_tridiagonal",
    "spline_second_derivatives",
]


def solve_tridiagonal(
    lower: np.ndarray, diag: np.ndarray, upper: np.ndarray, rhs: np.ndarray
) -> np.ndarray:
    """x (n, k) with lower[i]·x[i−1] + diag[i]·x[i] + upper[i]·x[i+1] = rhs[i] for every row i
    (lower[0] and upper[n−1] are ignored), for a diagonally dominant matrix.

    Cyclic reduction: the system is padded with identity rows to N = 2^j − 1 rows; each level
    eliminates the even rows (0, 2, …) from the odd ones, leaving an (N − 1)/2-row tridiagonal
    system of the odd unknowns, down to one row; the even unknowns then follow level by level.
    """
    n = len(diag)
    size = (1 << n.bit_length()) - 1  # the smallest 2^j − 1 >= n
    a, b, c = np.zeros(size), np.ones(size), np.zeros(size)
    d = np.zeros((size, rhs.shape[1]))
    a[1:n], b[:n], c[: n - 1], d[:n] = lower[1:], diag, upper[:-1], rhs
    levels = []
    while len(b) > 1:
        levels.append((a, b, c, d))
        # Row i (odd) plus alpha × row i−1 plus beta × row i+1 drops x[i−1] and x[i+1].
        alpha = -a[1::2] / b[:-1:2]
        beta = -c[1::2] / b[2::2]
        a, b, c, d = (
            alpha * a[:-1:2],
            b[1::2] + alpha * c[:-1:2] + beta * a[2::2],
            beta * c[2::2],
            d[1::2] + alpha[:, None] * d[:-1:2] + beta[:, None] * d[2::2],
        )
    x = d / b[:, None]
    for a, b, c, d in reversed(levels):
        near = np.zeros((len(b) + 2, x.shape[1]))  # x[j] at near[j + 1]; 0 beyond both ends
        near[2:-1:2] = x
        full = np.empty((len(b), x.shape[1]))
        full[1::2] = x
        full[::2] = (d[::2] - a[::2, None] * near[:-2:2] - c[::2, None] * near[2::2]) / b[::2, None]
        x = full
    return x[:n]


def spline_second_derivatives(
    lower: np.ndarray, diag: np.ndarray, upper: np.ndarray, rhs: np.ndarray
) -> np.ndarray:
    """The knots' second derivatives (n, 3) [1/m] from the tridiagonal system, by
    `solve_tridiagonal` at every size: the same bits on every machine (module doc)."""
    return solve_tridiagonal(lower, diag, upper, rhs)


def natural_cubic_coefficients(knots: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Per-segment cubic coefficients (a0..a3) of the natural spline, shape (n_seg, 3, 4)."""
    n = len(knots)
    h = np.diff(knots)
    # Second derivatives m_i; natural ends m_0 = m_{n−1} = 0 (identity rows).
    lower, diag, upper = np.zeros(n), np.ones(n), np.zeros(n)
    rhs = np.zeros((n, 3))
    i = np.arange(1, n - 1)
    lower[i], diag[i], upper[i] = h[i - 1], 2.0 * (h[i - 1] + h[i]), h[i]
    rhs[i] = 6.0 * ((pts[i + 1] - pts[i]) / h[i, None] - (pts[i] - pts[i - 1]) / h[i - 1, None])
    return _cubic_coefficients(knots, pts, spline_second_derivatives(lower, diag, upper, rhs))


def clamped_cubic_coefficients(
    knots: np.ndarray, pts: np.ndarray, slope0: np.ndarray, slope1: np.ndarray
) -> np.ndarray:
    """Coefficients (n_seg, 3, 4) of the cubic spline with end slopes p'(s_0), p'(s_n) given:
    fourth-order accurate up to the ends (a natural spline's p'' = 0 there is only second)."""
    n = len(knots)
    h = np.diff(knots)
    lower, diag, upper = np.zeros(n), np.zeros(n), np.zeros(n)
    rhs = np.zeros((n, 3))
    diag[0], upper[0] = 2.0 * h[0], h[0]
    rhs[0] = 6.0 * ((pts[1] - pts[0]) / h[0] - slope0)
    lower[-1], diag[-1] = h[-1], 2.0 * h[-1]
    rhs[-1] = 6.0 * (slope1 - (pts[-1] - pts[-2]) / h[-1])
    i = np.arange(1, n - 1)
    lower[i], diag[i], upper[i] = h[i - 1], 2.0 * (h[i - 1] + h[i]), h[i]
    rhs[i] = 6.0 * ((pts[i + 1] - pts[i]) / h[i, None] - (pts[i] - pts[i - 1]) / h[i - 1, None])
    return _cubic_coefficients(knots, pts, spline_second_derivatives(lower, diag, upper, rhs))


def _cubic_coefficients(knots: np.ndarray, pts: np.ndarray, m: np.ndarray) -> np.ndarray:
    """(a0..a3) per segment, shape (n_seg, 3, 4), of the cubic spline with knot values ``pts``
    and second derivatives ``m``."""
    h = np.diff(knots)
    a0 = pts[:-1]
    a1 = (pts[1:] - pts[:-1]) / h[:, None] - h[:, None] * (2.0 * m[:-1] + m[1:]) / 6.0
    a2 = m[:-1] / 2.0
    a3 = (m[1:] - m[:-1]) / (6.0 * h[:, None])
    return np.stack([a0, a1, a2, a3], axis=-1)
