"""Parametric 3D paths p(s) with analytic p'(s) and p''(s) (docs/model.md §3.1, §3.5).

Every path is described to the numba kernels by an integer ``kind`` and a float64 ``data``
vector, and evaluated by the single function `path_eval`; the Python classes only build those
vectors and offer numpy conveniences. Positions are NED [m]; s is the path parameter (for the
helix it is not arc length: |p'(s)| = sqrt(R²ω² + c²)).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numba import njit

__all__ = ["PATHS", "Helix", "Path", "Spline", "StraightLine", "make_path", "path_eval"]

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


@njit(cache=True, inline="always")  # inlined into the RK4 stages: ~7% faster kernel
def path_eval(kind, data, s):
    """(x, y, z, x', y', z', x'', y'', z'') of the path at parameter s [m, m/unit s, ...]."""
    if kind == HELIX:
        radius, omega, climb, x0, y0, z0 = data[0], data[1], data[2], data[3], data[4], data[5]
        c, sn = math.cos(omega * s), math.sin(omega * s)
        return (
            radius * c + x0, radius * sn + y0, z0 - climb * s,
            -radius * omega * sn, radius * omega * c, -climb,
            -radius * omega * omega * c, -radius * omega * omega * sn, 0.0,
        )  # fmt: skip
    if kind == LINE:
        return (
            data[0] + s * data[3], data[1] + s * data[4], data[2] + s * data[5],
            data[3], data[4], data[5], 0.0, 0.0, 0.0,
        )  # fmt: skip
    # SPLINE: data = [n_seg, knots[0..n_seg], coeffs[n_seg, 3 axes, 4]]; cubic in (s − knot_k)
    n_seg = int(data[0])
    lo, hi = 0, n_seg - 1
    while lo < hi:  # binary search for the segment, clamped to the end segments
        mid = (lo + hi + 1) // 2
        if data[1 + mid] <= s:
            lo = mid
        else:
            hi = mid - 1
    ds = s - data[1 + lo]
    base = 1 + (n_seg + 1) + lo * 12
    x, dx, ddx = _cubic(data, base, ds)
    y, dy, ddy = _cubic(data, base + 4, ds)
    z, dz, ddz = _cubic(data, base + 8, ds)
    return x, y, z, dx, dy, dz, ddx, ddy, ddz


class Path:
    """Base class: a path is a (kind, data) pair for the kernels plus a parameter range."""

    kind: int
    data: np.ndarray
    s_end: float = math.inf  # end of the path parameter; the episode ends there

    def evaluate(self, s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """p(s), p'(s), p''(s) as arrays of shape (..., 3)."""
        s_arr = np.asarray(s, dtype=np.float64)
        flat = np.array([path_eval(self.kind, self.data, float(x)) for x in s_arr.ravel()])
        flat = flat.reshape(*s_arr.shape, 9)
        return flat[..., 0:3], flat[..., 3:6], flat[..., 6:9]

    def default_start(self) -> tuple[np.ndarray, float]:
        """Initial position [m] and heading ψ [rad]: ε(0) = (−15, 5, 8) m as in the paper."""
        p, dp, _ = self.evaluate(0.0)
        psi = math.atan2(dp[1], dp[0])
        c, s = math.cos(psi), math.sin(psi)
        return p + np.array([-15.0 * c - 5.0 * s, -15.0 * s + 5.0 * c, 8.0]), psi

    def sample(self, n: int = 400, s_max: float | None = None) -> np.ndarray:
        """n points along the path for plotting, shape (n, 3) [m]."""
        end = self.s_end if math.isfinite(self.s_end) else (s_max if s_max is not None else 100.0)
        return self.evaluate(np.linspace(0.0, end, n))[0]


class Helix(Path):
    """The paper's helix (45): x = R cos(ωs) + x0, y = R sin(ωs) + y0, z = z0 − c s.

    Defaults R = 20 m, ω = π/20 rad per unit s, c = 1 m per unit s, (x0, y0, z0) = (10, 0, −8) m
    (docs/model.md §3.5: a 17.7° climb, one turn per Δs = 40).
    """

    kind = HELIX

    def __init__(
        self,
        radius: float = 20.0,
        omega: float = math.pi / 20.0,
        climb: float = 1.0,
        center: Sequence[float] = (10.0, 0.0, -8.0),
        s_end: float = math.inf,
    ) -> None:
        values = [radius, omega, climb, *center, s_end]
        if len(center) != 3 or not all(math.isfinite(x) for x in values[:-1]):
            raise ValueError("Helix: radius, omega, climb and a 3-vector center must be finite")
        if radius <= 0 or omega <= 0:
            raise ValueError(f"Helix: radius and omega must be positive, got {radius}, {omega}")
        if not s_end > 0:
            raise ValueError(f"Helix: s_end must be positive, got {s_end}")
        self.radius, self.omega, self.climb = float(radius), float(omega), float(climb)
        self.center = tuple(float(c) for c in center)
        self.s_end = float(s_end)
        self.data = np.array([radius, omega, climb, *center], dtype=np.float64)

    def default_start(self) -> tuple[np.ndarray, float]:
        """The paper's initial condition: (15, 5, 0) m, ψ = 0 (Section 6)."""
        if (self.radius, self.omega, self.climb, self.center) == (20.0, math.pi / 20, 1.0,
                                                                  (10.0, 0.0, -8.0)):  # fmt: skip
            return np.array([15.0, 5.0, 0.0]), 0.0
        return super().default_start()


class StraightLine(Path):
    """p(s) = p0 + s·d with d a unit direction, so s is arc length [m]."""

    kind = LINE

    def __init__(
        self,
        start: Sequence[float] = (0.0, 0.0, 0.0),
        direction: Sequence[float] = (1.0, 0.5, -0.2),
        length: float = math.inf,
    ) -> None:
        d = np.asarray(direction, dtype=np.float64)
        p0 = np.asarray(start, dtype=np.float64)
        if d.shape != (3,) or p0.shape != (3,) or not np.all(np.isfinite(np.r_[d, p0])):
            raise ValueError("StraightLine: start and direction must be finite 3-vectors")
        norm = float(np.linalg.norm(d))
        if norm == 0.0:
            raise ValueError("StraightLine: direction must be non-zero")
        if not length > 0:
            raise ValueError(f"StraightLine: length must be positive, got {length}")
        self.s_end = float(length)
        self.data = np.r_[p0, d / norm]


class Spline(Path):
    """A C²-smooth natural cubic spline through 3D waypoints, parameterised by chord length [m]."""

    kind = SPLINE

    def __init__(self, waypoints: Sequence[Sequence[float]]) -> None:
        pts = np.asarray(waypoints, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] < 2:
            raise ValueError(f"Spline: waypoints must have shape (n >= 2, 3), got {pts.shape}")
        if not np.all(np.isfinite(pts)):
            raise ValueError("Spline: waypoints must be finite")
        chords = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        if np.any(chords <= 1e-9):
            raise ValueError("Spline: consecutive waypoints must be distinct")
        knots = np.r_[0.0, np.cumsum(chords)]
        coeffs = _natural_cubic_coefficients(knots, pts)  # (n_seg, 3, 4)
        self.waypoints = pts
        self.s_end = float(knots[-1])
        self.data = np.r_[float(len(chords)), knots, coeffs.ravel()]


def _natural_cubic_coefficients(knots: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Per-segment cubic coefficients (a0..a3) of the natural spline, shape (n_seg, 3, 4)."""
    n = len(knots)
    h = np.diff(knots)
    # Second derivatives m_i solve a tridiagonal system; natural ends m_0 = m_{n−1} = 0.
    A = np.zeros((n, n))
    rhs = np.zeros((n, 3))
    A[0, 0] = A[-1, -1] = 1.0
    for i in range(1, n - 1):
        A[i, i - 1], A[i, i], A[i, i + 1] = h[i - 1], 2.0 * (h[i - 1] + h[i]), h[i]
        rhs[i] = 6.0 * ((pts[i + 1] - pts[i]) / h[i] - (pts[i] - pts[i - 1]) / h[i - 1])
    m = np.linalg.solve(A, rhs)
    a0 = pts[:-1]
    a1 = (pts[1:] - pts[:-1]) / h[:, None] - h[:, None] * (2.0 * m[:-1] + m[1:]) / 6.0
    a2 = m[:-1] / 2.0
    a3 = (m[1:] - m[:-1]) / (6.0 * h[:, None])
    return np.stack([a0, a1, a2, a3], axis=-1)


DEFAULT_WAYPOINTS = (
    (30.0, 0.0, -8.0), (60.0, 15.0, -14.0), (90.0, -10.0, -20.0), (120.0, 10.0, -16.0),
    (150.0, 0.0, -24.0), (180.0, 25.0, -30.0), (210.0, 5.0, -26.0), (240.0, -15.0, -34.0),
    (270.0, 5.0, -40.0), (300.0, 10.0, -36.0),
)  # fmt: skip

PATHS = {
    "helix": Helix,
    "line": StraightLine,
    "waypoints": lambda: Spline(DEFAULT_WAYPOINTS),
}


def make_path(path: str | Path) -> Path:
    """A path from its registry name or a `Path` instance; unknown names raise ValueError."""
    if isinstance(path, Path):
        return path
    if isinstance(path, str) and path in PATHS:
        return PATHS[path]()
    raise ValueError(f"unknown path {path!r}; valid names are {sorted(PATHS)} or a Path instance")
