"""Proven bounds on a spline path's tangent norm and turn rates (docs/model.md §3.1).

On a cubic segment p′ is a quadratic and p″ a line, so |p′|², the horizontal part h² = x′² + y′²
and the numerators of the turn rates are polynomials of degree ≤ 6 in the segment's parameter.
A polynomial on an interval lies between the smallest and the largest of its Bernstein
coefficients on that interval (the convex-hull property), and the enclosure shrinks as the
square of the interval's width. Each segment's rate is bounded above by those enclosures,

    |dψ_F/ds|/|p′| = |x′y″ − y′x″| / (h² |p′|)           ≤ max|N_ψ| / (min h² · √min|p′|²)
    |dθ_F/ds|/|p′| = |z″h² − z′(x′x″ + y′y″)| / (h |p′|³) ≤ max|N_θ| / (√min h² · min|p′|²^{3/2})
    |dθ_F/ds|/|p′| ≤ κ = |p′ × p″| / |p′|³                 ≤ √max|p′ × p″|² / min|p′|²^{3/2}

(the last because the unit tangent's derivative has the orthogonal components dθ_F/dℓ and
cos θ_F·dψ_F/dℓ, so κ² = (dθ_F/dℓ)² + cos²θ_F (dψ_F/dℓ)²); where h² <= 1e-12 the kernels hold
ψ_F and both rates are 0, so min h² enters as at least 1e-12. The pieces whose bound is not
yet within the tolerance of the largest rate evaluated so far are halved until it is. The
result is an upper bound of the rate the kernels compute (`guidance.path_angles`), never a
sample: a spike between two samples cannot hide.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["Bound", "min_tangent_squared", "spline_turn_rates"]

_MAX_DEPTH = 48  # halvings of one segment: pieces of 2⁻⁴⁸ of it
_MAX_PIECES = 1 << 16  # pieces refined at once; beyond, the (still proven) bound is returned
_HOLD = 1e-12  # [m² per unit s²] h² at or below which the kernels hold ψ_F (rates 0)


@dataclass(frozen=True)
class Bound:
    """A proven upper bound ``upper`` of a quantity over a spline, the largest value ``reached``
    at an evaluated point (so the true maximum lies in [reached, upper]), and where that point
    is: the segment index and the path parameter s [m]."""

    upper: float
    reached: float
    segment: int
    s: float


def _segments(data: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Knots (n_seg + 1,) and coefficients (n_seg, 3 axes, 4) of a SPLINE kernel vector."""
    n_seg = int(data[0])
    return data[1 : n_seg + 2], data[n_seg + 2 :].reshape(n_seg, 3, 4)


def _mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Product of batched polynomials (low degree first along the last axis)."""
    out = np.zeros((*a.shape[:-1], a.shape[-1] + b.shape[-1] - 1))
    for i in range(a.shape[-1]):
        out[..., i : i + b.shape[-1]] += a[..., i : i + 1] * b
    return out


def _pad(a: np.ndarray, n: int) -> np.ndarray:
    return np.concatenate([a, np.zeros((*a.shape[:-1], n - a.shape[-1]))], axis=-1)


def _polynomials(data: np.ndarray, tangent_only: bool = False) -> dict[str, np.ndarray]:
    """Per segment, in u = (s − knot)/h ∈ [0, 1]: |p′|², h², N_ψ, N_θ and |p′ × p″|² (only
    |p′|² and h² with ``tangent_only``)."""
    knots, a = _segments(data)
    h = np.diff(knots)[:, None]
    one = np.ones_like(h)
    # p′ = a1 + 2 a2 (h u) + 3 a3 (h u)², p″ = 2 a2 + 6 a3 (h u), each (n_seg, 3) polynomials
    d = [
        np.concatenate([a[:, k, 1:2], 2.0 * a[:, k, 2:3] * h, 3.0 * a[:, k, 3:4] * h * h], 1)
        for k in range(3)
    ]
    dd = [np.concatenate([2.0 * a[:, k, 2:3] * one, 6.0 * a[:, k, 3:4] * h], 1) for k in range(3)]
    dx, dy, dz = d
    ddx, ddy, ddz = dd
    horizontal = _mul(dx, dx) + _mul(dy, dy)
    speed2 = horizontal + _mul(dz, dz)
    if tangent_only:
        return {"speed2": speed2, "horizontal": horizontal}
    n_psi = _mul(dx, ddy) - _mul(dy, ddx)
    g = _mul(dx, ddx) + _mul(dy, ddy)
    n_theta = _mul(ddz, horizontal) - _pad(_mul(dz, g), 6)
    cx, cy = _mul(dy, ddz) - _mul(dz, ddy), _mul(dz, ddx) - _mul(dx, ddz)
    cross2 = _mul(cx, cx) + _mul(cy, cy) + _mul(n_psi, n_psi)
    return {
        "speed2": speed2,
        "horizontal": horizontal,
        "n_psi": n_psi,
        "n_theta": n_theta,
        "cross2": cross2,
    }


@functools.cache
def _basis_change(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For degree n: the exponents j − m (≥ 0) and the matrices C(j, m) [m, j] of the Taylor
    shift and C(i, m)/C(n, m) [i, m] from the power to the Bernstein basis on [0, 1]."""
    j = np.arange(n + 1)
    binom = np.array([[math.comb(r, c) for c in range(n + 1)] for r in range(n + 1)], float)
    shift = np.where(j[None, :] >= j[:, None], binom.T, 0.0)
    to_bernstein = np.where(j[:, None] >= j[None, :], binom / binom[n][None, :], 0.0)
    return np.clip(j[None, :] - j[:, None], 0, None), shift, to_bernstein


def _bernstein(coeffs: np.ndarray, u0: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Bernstein coefficients on [u0, u0 + w] of the polynomials ``coeffs`` (P, n + 1)."""
    n = coeffs.shape[1] - 1
    exponents, shift, to_bernstein = _basis_change(n)
    # Taylor coefficients at u0, scaled to the piece: c'_m = w^m Σ_j C(j, m) c_j u0^(j − m).
    taylor = np.einsum("pmj,pj->pm", shift[None] * u0[:, None, None] ** exponents[None], coeffs)
    taylor *= w[:, None] ** np.arange(n + 1)[None, :]
    return taylor @ to_bernstein.T


def _enclosure(
    poly: np.ndarray, seg: np.ndarray, u0: np.ndarray, w: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    b = _bernstein(poly[seg], u0, w)
    return b.min(axis=1), b.max(axis=1)


def _abs_max(poly: np.ndarray, seg: np.ndarray, u0: np.ndarray, w: np.ndarray) -> np.ndarray:
    return np.abs(_bernstein(poly[seg], u0, w)).max(axis=1)


def _ratio(numerator: np.ndarray, denominator: np.ndarray) -> np.ndarray:
    """numerator/denominator with 0 for a zero numerator and inf for a non-positive denominator."""
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(denominator > 0.0, numerator / denominator, math.inf)
    return np.where(numerator == 0.0, 0.0, out)


def _kernel_rates(
    data: np.ndarray, seg: np.ndarray, u: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """|dψ_F/ds|/|p′|, |dθ_F/ds|/|p′| [rad/m] and |p′|² as `guidance.path_angles` computes them,
    at the points u of segments seg (inf where p′ = 0)."""
    knots, a = _segments(data)
    t = (u * np.diff(knots)[seg])[:, None]
    c = a[seg]
    dp = c[..., 1] + t * (2.0 * c[..., 2] + 3.0 * t * c[..., 3])
    ddp = 2.0 * c[..., 2] + 6.0 * t * c[..., 3]
    dx, dy, dz = dp.T
    ddx, ddy, ddz = ddp.T
    h2 = dx * dx + dy * dy
    speed2 = h2 + dz * dz
    with np.errstate(divide="ignore", invalid="ignore"):
        h = np.sqrt(h2)
        speed = np.sqrt(speed2)
        dpsi = (dx * ddy - dy * ddx) / h2
        dh = (dx * ddx + dy * ddy) / h
        dtheta = -(ddz * h - dz * dh) / speed2
        held = h2 <= _HOLD
        psi = np.where(held, 0.0, np.abs(dpsi)) / speed
        theta = np.where(held, 0.0, np.abs(dtheta)) / speed
    psi = np.where(np.isfinite(psi), psi, math.inf)
    theta = np.where(np.isfinite(theta), theta, math.inf)
    return psi, theta, speed2


def _maximise(
    data: np.ndarray,
    upper: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray],
    value: Callable[[np.ndarray, np.ndarray], np.ndarray],
    accept_below: float,
    rtol: float,
) -> Bound:
    """A proven bound of max value(s) over the spline: pieces are halved until their bound is at
    most ``accept_below`` while no value above it was reached, then to the largest value reached
    plus its tolerance ``rtol``."""
    n_seg = int(data[0])
    knots = data[1 : n_seg + 2]
    seg = np.arange(n_seg)
    u0, w = np.zeros(n_seg), np.ones(n_seg)
    reached, where = -math.inf, (0, 0.0)
    settled = -math.inf
    for _ in range(_MAX_DEPTH + 1):
        points_seg = np.r_[seg, seg, seg]
        points_u = np.r_[u0, u0 + 0.5 * w, u0 + w]
        values = value(points_seg, points_u)
        k = int(np.argmax(values))
        if values[k] > reached:
            reached = float(values[k])
            where = (
                int(points_seg[k]),
                float(
                    knots[points_seg[k]]
                    + points_u[k] * (knots[points_seg[k] + 1] - knots[points_seg[k]])
                ),
            )
        bound = upper(seg, u0, w)
        # Below the limit, refine to the limit (a yes/no answer); above it, to the tolerance.
        tolerance = reached + max(rtol * abs(reached), 1e-12)
        target = accept_below if reached <= accept_below else tolerance
        open_ = bound > target
        if np.any(~open_):
            settled = max(settled, float(bound[~open_].max()))
        if not np.any(open_) or 2 * int(open_.sum()) > _MAX_PIECES or math.isinf(reached):
            return Bound(max(settled, float(bound.max()), reached), reached, *where)
        seg, u0, w = seg[open_], u0[open_], w[open_] / 2.0
        seg, u0, w = np.r_[seg, seg], np.r_[u0, u0 + w], np.r_[w, w]
    return Bound(max(settled, float(upper(seg, u0, w).max()), reached), reached, *where)


def spline_turn_rates(
    data: np.ndarray, accept_below: float = -math.inf, rtol: float = 1e-3
) -> tuple[Bound, Bound]:
    """Proven upper bounds of |dψ_F/ds|/|p′| and |dθ_F/ds|/|p′| [rad/m] over a SPLINE kernel
    vector ``data``: each ``upper`` is at most ``rtol`` (relative) above the true maximum, or
    at most ``accept_below`` (refinement stops there: a yes/no check against a limit)."""
    polys = _polynomials(data)

    def psi_upper(seg: np.ndarray, u0: np.ndarray, w: np.ndarray) -> np.ndarray:
        h_lo = np.maximum(_enclosure(polys["horizontal"], seg, u0, w)[0], _HOLD)
        s_lo, _ = _enclosure(polys["speed2"], seg, u0, w)
        n = _abs_max(polys["n_psi"], seg, u0, w)
        return _ratio(n, np.where(s_lo > 0.0, h_lo * np.sqrt(np.maximum(s_lo, 0.0)), -1.0))

    def theta_upper(seg: np.ndarray, u0: np.ndarray, w: np.ndarray) -> np.ndarray:
        h_lo = np.maximum(_enclosure(polys["horizontal"], seg, u0, w)[0], _HOLD)
        s_lo, _ = _enclosure(polys["speed2"], seg, u0, w)
        n = _abs_max(polys["n_theta"], seg, u0, w)
        _, c_hi = _enclosure(polys["cross2"], seg, u0, w)
        s_pos = np.maximum(s_lo, 0.0)
        by_angle = _ratio(n, np.where(s_lo > 0.0, np.sqrt(h_lo) * s_pos**1.5, -1.0))
        curvature = _ratio(np.sqrt(np.maximum(c_hi, 0.0)), np.where(s_lo > 0.0, s_pos**1.5, -1.0))
        return np.minimum(by_angle, curvature)

    psi = _maximise(data, psi_upper, lambda s, u: _kernel_rates(data, s, u)[0], accept_below, rtol)
    theta = _maximise(
        data, theta_upper, lambda s, u: _kernel_rates(data, s, u)[1], accept_below, rtol
    )
    return psi, theta


def min_tangent_squared(
    data: np.ndarray, accept_above: float = math.inf, rtol: float = 1e-6
) -> Bound:
    """A proven LOWER bound of |p′(s)|² [m² per unit s²] over a SPLINE kernel vector, as a
    `Bound` of −|p′|² (``-upper`` is the lower bound, ``-reached`` the smallest value met and
    where): refined until within ``rtol`` of the minimum or at least ``accept_above``."""
    speed2 = _polynomials(data, tangent_only=True)["speed2"]

    def upper(seg: np.ndarray, u0: np.ndarray, w: np.ndarray) -> np.ndarray:
        return -_enclosure(speed2, seg, u0, w)[0]

    return _maximise(data, upper, lambda s, u: -_kernel_rates(data, s, u)[2], -accept_above, rtol)
