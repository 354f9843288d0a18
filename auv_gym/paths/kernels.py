"""The kernel side of the paths: each kind's evaluation p(s), p'(s), p''(s) (`path_eval`, one
numba function inlined into the step kernels) and the layout of the SPLINE kind's data
(docs/model.md §3.1, §3.5). `auv_gym.paths` builds and checks the (kind, data) pairs; the
cubic-spline coefficients that data stores come from `auv_gym.paths.cubic` (plain numpy, outside
the kernels' sources; re-exported here).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from auv_gym.paths.cubic import clamped_cubic_coefficients, natural_cubic_coefficients

__all__ = [
    "HELIX",
    "LINE",
    "SPLINE",
    "clamped_cubic_coefficients",
    "natural_cubic_coefficients",
    "path_eval",
    "path_third_derivative",
    "spline_data",
]

HELIX, LINE, SPLINE = 0, 1, 2


@njit(cache=True, inline="always")
def _cubic(data, i, ds):
    """Value, first and second derivative of a0 + a1·ds + a2·ds² + a3·ds³, a = data[i:i + 4]."""
    a0, a1, a2, a3 = data[i], data[i + 1], data[i + 2], data[i + 3]
    return (
        a0 + ds * (a1 + ds * (a2 + ds * a3)),
        a1 + ds * (2.0 * a2 + 3.0 * ds * a3),
        2.0 * a2 + 6.0 * ds * a3,
    )


@njit(cache=True, inline="always")
def _spline_segment(data, s):
    """(offset of the segment's x coefficients in ``data``, s − its knot) of the spline segment
    holding s, by binary search, clamped to the end segments."""
    n_seg = int(data[0])
    lo, hi = 0, n_seg - 1
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if data[1 + mid] <= s:
            lo = mid
        else:
            hi = mid - 1
    return 1 + (n_seg + 1) + lo * 12, s - data[1 + lo]


@njit(cache=True, inline="always")  # inlined into the RK4 stages: ~7% faster kernel
def path_eval(kind, data, s):
    """(x, y, z, x', y', z', x'', y'', z'') of the path at parameter s [m, m/unit s, ...]."""
    if kind == HELIX:
        radius, omega, climb, x0, y0, z0 = data[0], data[1], data[2], data[3], data[4], data[5]
        c, sn = math.cos(omega * s), math.sin(omega * s)
        return (
            radius * c + x0,
            radius * sn + y0,
            z0 - climb * s,
            -radius * omega * sn,
            radius * omega * c,
            -climb,
            -radius * omega * omega * c,
            -radius * omega * omega * sn,
            0.0,
        )
    if kind == LINE:
        return (
            data[0] + s * data[3],
            data[1] + s * data[4],
            data[2] + s * data[5],
            data[3],
            data[4],
            data[5],
            0.0,
            0.0,
            0.0,
        )
    # SPLINE: data = [n_seg, knots[0..n_seg], coeffs[n_seg, 3 axes, 4]]; cubic in (s − knot_k)
    base, ds = _spline_segment(data, s)
    x, dx, ddx = _cubic(data, base, ds)
    y, dy, ddy = _cubic(data, base + 4, ds)
    z, dz, ddz = _cubic(data, base + 8, ds)
    return x, y, z, dx, dy, dz, ddx, ddy, ddz


@njit(cache=True, inline="always")
def path_third_derivative(kind, data, s):
    """p‴(s) = (x‴, y‴, z‴) [m per unit s³], for the torsion of the path preview."""
    if kind == HELIX:
        radius, omega = data[0], data[1]
        w3 = radius * omega * omega * omega
        return w3 * math.sin(omega * s), -w3 * math.cos(omega * s), 0.0
    if kind == LINE:
        return 0.0, 0.0, 0.0
    base, _ = _spline_segment(data, s)
    return 6.0 * data[base + 3], 6.0 * data[base + 7], 6.0 * data[base + 11]


def spline_data(knots: np.ndarray, coeffs: np.ndarray) -> np.ndarray:
    """The SPLINE kernel vector [n_seg, knots, coeffs (n_seg, 3, 4) flattened]."""
    return np.r_[float(len(knots) - 1), knots, coeffs.ravel()]
