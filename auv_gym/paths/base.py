"""The kernel-facing base of every path: the `Path` class, the documented ranges of the path
arguments, the proven |p'(s)| check and, per kernel kind (`KERNEL_KINDS`), its data check,
turn-rate bounds and translation (docs/model.md §3.1, §3.5).

`auv_gym.paths` builds the helix, line and spline on it and `auv_gym.paths.fit` a user's curve;
both re-export what they use from here, so ``auv_gym.paths.Path`` etc. stay where they were.
"""

from __future__ import annotations

import math

import numpy as np

from auv_gym.paths.bounds import Bound, min_tangent_squared, spline_turn_rates
from auv_gym.paths.guidance import path_angles
from auv_gym.paths.kernels import HELIX, LINE, SPLINE, path_eval

__all__ = [
    "KERNEL_KINDS",
    "MAX_OMEGA",
    "MAX_WAYPOINTS",
    "MIN_CHORD",
    "MIN_TANGENT",
    "POSITION_BOUND",
    "SCALE_BOUND",
    "KernelKind",
    "Path",
    "SplineKind",
    "check_tangent",
    "path_turn_rates",
]

# Documented ranges of the path arguments: they keep every evaluation of p, p', p'' finite.
POSITION_BOUND = 1e6  # [m] |coordinate| of centres, starts and waypoints (1000 km)
SCALE_BOUND = 1e5  # [m] helix radius, |climb| per unit s
MAX_OMEGA = 1e3  # [rad per unit s] helix ω
MIN_TANGENT = 1e-6  # [m per unit s] smallest |p'(s)|: ṡ = u_p/|p'| stays finite
MAX_WAYPOINTS = 1000  # the natural spline solves a dense (n × n) system
MIN_CHORD = 1e-9  # [m] distance between consecutive waypoints


class Path:
    """Base class: a path is a (kind, data) pair for the kernels plus a parameter range."""

    kind: int
    data: np.ndarray
    s_end: float = math.inf  # end of the path parameter; the episode ends there
    knots_are_waypoints: bool = False  # a `Spline`: error messages name its waypoints

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

    def check_kernel_data(self) -> None:
        """The kernel description is complete and finite (the kernels do not bounds-check)."""
        data = getattr(self, "data", None)
        ok = (
            isinstance(data, np.ndarray)
            and data.dtype == np.float64
            and data.ndim == 1
            and self.kind in KERNEL_KINDS
            and data.size >= 6
            and np.all(np.isfinite(data))
        )
        if not (ok and KERNEL_KINDS[self.kind].fits(data)):
            raise ValueError(
                f"path {type(self).__name__} has no valid kernel data (kind, data); "
                "build paths with Helix, StraightLine, Spline or make_path"
            )

    def turn_rate_bounds(self, accept_below: float = -math.inf) -> tuple[Bound, Bound]:
        """`path_turn_rates` with where each maximum lies (`path_bounds.Bound`)."""
        return KERNEL_KINDS[self.kind].turn_rate_bounds(self, accept_below)

    def turn_location(self, bound: Bound) -> str:
        """Where a turn-rate maximum lies, for an error message: "" or " (near s = …)"."""
        return KERNEL_KINDS[self.kind].location(self, bound)


def check_tangent(owner: str, data: np.ndarray, knots: np.ndarray | None = None) -> None:
    """Raise ValueError if |p′(s)| of a SPLINE kernel vector falls below `MIN_TANGENT`
    anywhere (a proven lower bound, not samples), naming the waypoint nearest to where it does
    (``knots``: the waypoints' s) or its s."""
    low = min_tangent_squared(data, accept_above=MIN_TANGENT * MIN_TANGENT)
    if -low.upper >= MIN_TANGENT * MIN_TANGENT:
        return
    speed = math.sqrt(max(-low.reached, 0.0))
    where = f"s = {low.s:.6g}"
    if knots is not None:
        k = low.segment + int(low.s - knots[low.segment] > knots[low.segment + 1] - low.s)
        raise ValueError(
            f"{owner}: the path doubles back at waypoint {k} ({where} m: |p'(s)| = {speed:.3g} < "
            f"{MIN_TANGENT:g}); add a turn waypoint beside waypoint {k} (or split the path there)"
        )
    raise ValueError(
        f"{owner}: |p'(s)| must be >= {MIN_TANGENT:g} m per unit s everywhere, got {speed:.3g} "
        f"at {where}; the curve must not stop or double back"
    )


class KernelKind:
    """The Python side of a kernel path kind whose p' and p'' have constant norms and turn
    rates (helix, line): a data vector of 6 floats, turn rates from samples (exact), and the
    point a translation moves at ``data[origin : origin + 3]`` (helix centre, line start)."""

    def __init__(self, origin: int) -> None:
        self.origin = origin

    def fits(self, data: np.ndarray) -> bool:
        return data.size == 6

    def shifted(self, data: np.ndarray, offset: np.ndarray) -> np.ndarray:
        """The data vector of p(s) + offset [m]."""
        out = data.copy()
        out[self.origin : self.origin + 3] += offset
        return out

    def turn_rate_bounds(self, path: Path, accept_below: float) -> tuple[Bound, Bound]:
        samples = np.linspace(0.0, 100.0, 9)
        rates = np.empty((len(samples), 2))
        for k, s in enumerate(samples):
            _, _, _, dx, dy, dz, ddx, ddy, ddz = path_eval(path.kind, path.data, float(s))
            _, _, dpsi_ds, dtheta_ds, speed = path_angles(dx, dy, dz, ddx, ddy, ddz)
            rates[k] = abs(dpsi_ds) / speed, abs(dtheta_ds) / speed
        if not np.all(np.isfinite(rates)):
            raise ValueError(f"path {type(path).__name__}: p'(s) or p''(s) is not finite or zero")
        psi_rate, theta_rate = rates.max(axis=0)
        return Bound(float(psi_rate), float(psi_rate), 0, 0.0), Bound(
            float(theta_rate), float(theta_rate), 0, 0.0
        )

    def location(self, path: Path, bound: Bound) -> str:
        return ""


class SplineKind(KernelKind):
    """The cubic-spline kind: [n_seg, knots (n_seg + 1), 12 coefficients per segment]; proven
    turn-rate bounds per segment (`path_bounds.spline_turn_rates`); no single origin (a
    translation moves every segment's a0)."""

    def fits(self, data: np.ndarray) -> bool:
        n_seg = data[0]
        return bool(n_seg >= 1 and n_seg == int(n_seg) and data.size == 2 + 13 * int(n_seg))

    def shifted(self, data: np.ndarray, offset: np.ndarray) -> np.ndarray:
        """The constant coefficient a0 of every segment's x, y, z cubic moves (`path_eval`)."""
        out = data.copy()
        n_seg = int(data[0])
        base = 1 + (n_seg + 1) + 12 * np.arange(n_seg)
        for axis in range(3):
            out[base + 4 * axis] += offset[axis]
        return out

    def turn_rate_bounds(self, path: Path, accept_below: float) -> tuple[Bound, Bound]:
        bounds = spline_turn_rates(path.data, accept_below)
        if not all(math.isfinite(b.upper) for b in bounds):
            raise ValueError(
                f"path {type(path).__name__}: p'(s) is zero at s = "
                f"{bounds[0].s:.6g}, where its heading is undefined"
            )
        return bounds

    def location(self, path: Path, bound: Bound) -> str:
        knots = path.data[1 : int(path.data[0]) + 2]
        k = bound.segment + int(bound.s - knots[bound.segment] > knots[bound.segment + 1] - bound.s)
        if path.knots_are_waypoints:
            return f" (near s = {bound.s:.6g}, waypoint {k})"
        return f" (near s = {bound.s:.6g})"


# One entry per kernel path kind (`path_eval`): what the checks know of its data vector.
KERNEL_KINDS: dict[int, KernelKind] = {
    HELIX: KernelKind(origin=3),
    LINE: KernelKind(origin=0),
    SPLINE: SplineKind(origin=0),
}


def path_turn_rates(path: Path, accept_below: float = -math.inf) -> tuple[float, float]:
    """Largest |dψ_F/ds|/|p'(s)| and |dθ_F/ds|/|p'(s)| along the path [rad/m].

    ψ̇_F = dψ_F/ds · ṡ with ṡ = u_p/|p'| (docs/model.md §3.1, §3.3), so ψ̇_F = this rate × u_p.
    Exact for the helix (constant in s) and the line (0); for a spline a proven upper bound at
    most 0.1 % above the maximum (`path_bounds.spline_turn_rates`), or, with ``accept_below``,
    a bound at most that limit whenever the maximum is. A path whose p'(s) vanishes raises.
    """
    return tuple(b.upper for b in path.turn_rate_bounds(accept_below))  # type: ignore[return-value]
