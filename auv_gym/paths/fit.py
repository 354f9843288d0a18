"""A user's parametric curve p(s) as a kernel path: `fit_curve` interpolates it by a clamped
cubic spline in the same parameter s, a `FittedCurve` (docs/model.md §3.8).

Importable from `auv_gym.paths` too (``auv_gym.paths.fit_curve``), which re-exports it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from auv_gym.paths.base import MAX_WAYPOINTS, MIN_TANGENT, POSITION_BOUND, Path, check_tangent
from auv_gym.paths.kernels import SPLINE, clamped_cubic_coefficients, spline_data
from auv_gym.support.validation import ArgumentTypeError, integer, real, vector

__all__ = ["FIT_TOLERANCE", "MIN_FIT_SEGMENTS", "FittedCurve", "fit_curve"]


# fit_curve: the check points inside each segment and the finite-difference steps.
_CHECK_FRACTIONS = (0.25, 0.5, 0.75)
FIT_TOLERANCE = 1e-3  # [m] default largest position error of a fitted curve
MIN_FIT_SEGMENTS = 8


class FittedCurve(Path):
    """A user's parametric curve p(s), s in [0, s_end], as a clamped cubic spline in the SAME
    parameter s (kernel kind SPLINE); build it with `fit_curve`.

    ``position_error`` [m] is the largest |spline(s) − p(s)| and ``tangent_error`` [rad] the
    largest angle between the spline's tangent and p'(s) (central differences of the callable),
    both over three check points inside every segment (¼, ½, ¾ of it).
    """

    kind = SPLINE

    def __init__(
        self, knots: np.ndarray, coeffs: np.ndarray, position_error: float, tangent_error: float
    ) -> None:
        self.s_end = float(knots[-1])
        self.data = spline_data(knots, coeffs)
        self.position_error = position_error
        self.tangent_error = tangent_error
        self.segments = len(knots) - 1


def _curve_points(curve: Callable[[float], Sequence[float]], s: np.ndarray) -> np.ndarray:
    out = np.empty((len(s), 3))
    for k, x in enumerate(s):
        out[k] = vector(
            f"curve(s) at s = {x:.6g}", curve(float(x)), 3, -POSITION_BOUND, POSITION_BOUND, "m"
        )
    return out


def _one_sided_slope(w: np.ndarray, end: np.ndarray, samples: np.ndarray) -> np.ndarray:
    """Σ w_k p_k over the end point and its four samples, term by term: a BLAS product
    (`w @ samples`) would round by the CPU's kernels (`auv_gym.paths.cubic`)."""
    return (
        w[0] * end + w[1] * samples[0] + w[2] * samples[1] + w[3] * samples[2] + w[4] * samples[3]
    )


def fit_curve(
    curve: Callable[[float], Sequence[float]],
    s_end: float,
    *,
    tolerance: float = FIT_TOLERANCE,
    max_segments: int = MAX_WAYPOINTS - 1,
) -> FittedCurve:
    """A kernel path of the user's curve ``curve(s) -> (x, y, z)`` [m], s in [0, s_end].

    The curve is sampled at uniform knots and interpolated by a C² cubic spline whose end slopes
    are the curve's (fourth-order one-sided differences), so the path parameter is the user's s
    and ṡ = u_p/|p'(s)| holds as for the built-in paths. The number of segments doubles from 8
    until the largest position error at the check points is at most ``tolerance`` [m]; a curve
    that needs more than ``max_segments`` raises ValueError with the error reached. Cubic
    interpolation errors fall as h⁴ (position) and h³ (tangent) with the knot spacing h: the
    default helix sampled over 200 units of s fits to 1 mm with 64 segments (docs/model.md §3.8).
    The fitted path's |p'(s)| >= `MIN_TANGENT` is checked everywhere (a proven bound,
    `check_tangent`), not only at the check points.
    """
    if not callable(curve):
        raise ArgumentTypeError(f"curve must be a callable s -> (x, y, z), got {curve!r:.80}")
    s_end = real("fit_curve s_end", s_end, 0.0, POSITION_BOUND, low_open=True, unit="unit s")
    tolerance = real("fit_curve tolerance", tolerance, 0.0, math.inf, low_open=True, unit="m")
    max_segments = integer(
        "fit_curve max_segments", max_segments, MIN_FIT_SEGMENTS, MAX_WAYPOINTS - 1
    )
    n = MIN_FIT_SEGMENTS
    while True:
        knots = np.linspace(0.0, s_end, n + 1)
        h = s_end / n
        pts = _curve_points(curve, knots)
        # Fourth-order one-sided differences for the end slopes, step h/4.
        d = h / 4.0
        ahead = _curve_points(curve, np.array([d, 2 * d, 3 * d, 4 * d]))
        behind = _curve_points(curve, s_end - np.array([d, 2 * d, 3 * d, 4 * d]))
        w = np.array([-25.0, 48.0, -36.0, 16.0, -3.0]) / (12.0 * d)
        slope0 = _one_sided_slope(w, pts[0], ahead)
        slope1 = -_one_sided_slope(w, pts[-1], behind)
        coeffs = clamped_cubic_coefficients(knots, pts, slope0, slope1)
        if not np.all(np.isfinite(coeffs)):
            raise ValueError("fit_curve: the curve's samples give non-finite coefficients")
        fitted = FittedCurve(knots, coeffs, math.nan, math.nan)
        check = (knots[:-1, None] + h * np.array(_CHECK_FRACTIONS)).ravel()
        p_fit, dp_fit, _ = fitted.evaluate(check)
        position_error = float(np.linalg.norm(p_fit - _curve_points(curve, check), axis=1).max())
        if position_error <= tolerance or 2 * n > max_segments:
            break
        n *= 2
    if position_error > tolerance:
        raise ValueError(
            f"fit_curve: {n} segments fit the curve to {position_error:.3g} m, above tolerance = "
            f"{tolerance:g} m; raise max_segments (<= {MAX_WAYPOINTS - 1}) or the tolerance"
        )
    check_tangent("fit_curve", fitted.data)  # the path the kernels follow, everywhere
    step = 1e-4 * h
    dp_true = (
        _curve_points(curve, np.minimum(check + step, s_end))
        - _curve_points(curve, np.maximum(check - step, 0.0))
    ) / (2 * step)
    norms = np.linalg.norm(dp_true, axis=1) * np.linalg.norm(dp_fit, axis=1)
    if not np.all(norms >= MIN_TANGENT * MIN_TANGENT):
        raise ValueError(f"fit_curve: |p'(s)| must be >= {MIN_TANGENT} m per unit s everywhere")
    cosine = np.clip(np.einsum("ij,ij->i", dp_true, dp_fit) / norms, -1.0, 1.0)
    fitted.position_error = position_error
    fitted.tangent_error = float(np.arccos(cosine).max())
    return fitted
