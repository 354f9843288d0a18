"""Parametric 3D paths p(s) with analytic p'(s) and p''(s) (docs/model.md §3.1, §3.5).

Every path is described to the numba kernels by an integer ``kind`` and a float64 ``data``
vector, and evaluated by the single function `path_eval`; the Python classes only build those
vectors and offer numpy conveniences. Positions are NED [m]; s is the path parameter (for the
helix it is not arc length: |p'(s)| = sqrt(R²ω² + c²)).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numba import njit

from auv_gym.validation import ArgumentTypeError, choice, is_real, real, vector

__all__ = ["PATHS", "Helix", "Path", "Spline", "StraightLine", "make_path", "path_eval"]

HELIX, LINE, SPLINE = 0, 1, 2
# Documented ranges of the path arguments: they keep every evaluation of p, p', p'' finite.
POSITION_BOUND = 1e6  # [m] |coordinate| of centres, starts and waypoints (1000 km)
SCALE_BOUND = 1e5  # [m] helix radius, |climb| per unit s
MAX_OMEGA = 1e3  # [rad per unit s] helix ω
MIN_TANGENT = 1e-6  # [m per unit s] smallest |p'(s)|: ṡ = u_p/|p'| stays finite
MAX_WAYPOINTS = 1000  # the natural spline solves a dense (n × n) system
MIN_CHORD = 1e-9  # [m] distance between consecutive waypoints


def _s_end(owner: str, value: float) -> float:
    """A path's end parameter: a positive real or math.inf (endless)."""
    if not is_real(value):
        raise ArgumentTypeError(f"{owner} must be a positive real number or inf, got {value!r}")
    if not float(value) > 0:
        raise ValueError(f"{owner} must be a positive real number or inf, got {value!r}")
    return float(value)


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
        radius = real("Helix radius", radius, 0.0, SCALE_BOUND, low_open=True, unit="m")
        omega = real("Helix omega", omega, 0.0, MAX_OMEGA, low_open=True, unit="rad per unit s")
        climb = real("Helix climb", climb, -SCALE_BOUND, SCALE_BOUND, unit="m per unit s")
        center = vector("Helix center", center, 3, -POSITION_BOUND, POSITION_BOUND, "m")
        if math.hypot(radius * omega, climb) < MIN_TANGENT:
            raise ValueError(
                f"Helix: |p'(s)| = sqrt((radius·omega)² + climb²) must be >= {MIN_TANGENT} m per "
                f"unit s, got radius = {radius}, omega = {omega}, climb = {climb}"
            )
        self.radius, self.omega, self.climb = radius, omega, climb
        self.center = center
        self.s_end = _s_end("Helix s_end", s_end)
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
        p0 = np.array(vector("StraightLine start", start, 3, -POSITION_BOUND, POSITION_BOUND, "m"))
        d = np.array(vector("StraightLine direction", direction, 3, -SCALE_BOUND, SCALE_BOUND))
        norm = float(np.linalg.norm(d))
        if norm < MIN_TANGENT:
            raise ValueError(f"StraightLine: direction must be non-zero (norm >= {MIN_TANGENT}), "
                             f"got {tuple(d)}")  # fmt: skip
        self.s_end = _s_end("StraightLine length", length)
        self.data = np.r_[p0, d / norm]


class Spline(Path):
    """A C²-smooth natural cubic spline through 3D waypoints, parameterised by chord length [m]."""

    kind = SPLINE

    def __init__(self, waypoints: Sequence[Sequence[float]]) -> None:
        shape = f"(n, 3) with 2 <= n <= {MAX_WAYPOINTS}, coordinates in [-{POSITION_BOUND:g}, " \
            f"{POSITION_BOUND:g}] m"  # fmt: skip
        try:
            pts = np.asarray(waypoints)
        except (TypeError, ValueError):  # ragged nesting
            pts = np.asarray(None)
        if pts.dtype.kind not in "iuf":
            raise ArgumentTypeError(f"Spline waypoints must be real numbers of shape {shape}, "
                                    f"got {waypoints!r:.80}")  # fmt: skip
        pts = pts.astype(np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3 or not 2 <= pts.shape[0] <= MAX_WAYPOINTS:
            raise ValueError(f"Spline: waypoints must have shape {shape}, got {pts.shape}")
        if not np.all(np.isfinite(pts)) or np.abs(pts).max() > POSITION_BOUND:
            raise ValueError(f"Spline: waypoints must be finite, in [-{POSITION_BOUND:g}, "
                             f"{POSITION_BOUND:g}] m")  # fmt: skip
        chords = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        if np.any(chords <= MIN_CHORD):
            raise ValueError("Spline: consecutive waypoints must be distinct")
        knots = np.r_[0.0, np.cumsum(chords)]
        coeffs = _natural_cubic_coefficients(knots, pts)  # (n_seg, 3, 4)
        if not np.all(np.isfinite(coeffs)):
            raise ValueError("Spline: the waypoints give a spline with non-finite coefficients")
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


def make_path(path: str | Path | Mapping[str, Any]) -> Path:
    """A path from its registry name, a `Path` instance, or a mapping {"kind": name, **arguments}
    (e.g. ``{"kind": "line", "direction": [1, 0, 0.25]}``, as a TOML scenario writes it);
    unknown names or arguments raise ValueError."""
    if isinstance(path, Path):
        return path
    if isinstance(path, Mapping):
        arguments = dict(path)
        kind = choice("path kind", arguments.pop("kind", None), PATHS)
        try:
            return PATHS[kind](**arguments)
        except ArgumentTypeError:
            raise
        except TypeError as exc:  # an argument the path does not take
            raise ValueError(f"path {path!r:.80}: {exc}") from exc
    if not isinstance(path, str):
        raise ArgumentTypeError(f"path must be one of {sorted(PATHS)}, a Path instance or a "
                                "mapping with 'kind' one of them, "
                                f"got {path!r:.80}")  # fmt: skip
    if path in PATHS:
        return PATHS[path]()
    raise ValueError(f"unknown path {path!r}; valid names are {sorted(PATHS)} or a Path instance")
