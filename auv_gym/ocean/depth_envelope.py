"""The water column: a sea surface at z = 0 (NED, z down) and an optional seabed (`DepthEnvelope`).

Opt-in through the envs' `depth_envelope` argument (docs/model.md §12); without it the ocean is
unbounded, as in the paper, and nothing depends on depth. With it:

- the episode ends as "broached" when the vehicle's origin rises above the surface (z < 0) and
  as "grounded" when it sinks below the seabed (z > seabed_depth), failures like "corridor";
- the safety ``margin`` m below the surface and above the seabed is where the safety cost's
  depth term grows (`auv_gym.sim.safety_cost`): REMUS 100's hull radius (0.095 m) lies well inside
  the default 2 m, so a vehicle near the boundary is charged before it breaks the surface;
- the path must lie between the margins wherever an episode following it on schedule goes
  (`check_path_depths`): checked when the env is built for a fixed path, at each reset for a
  drawn one, a ValueError naming `path_offset` (`auv_gym.paths.offset`) or `depth_envelope`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields

import numpy as np

from auv_gym.paths.shapes import SPLINE, Path
from auv_gym.support.validation import ArgumentTypeError, keys_within, real

__all__ = ["DepthEnvelope", "check_path_depths", "path_depth_range"]

SURFACE_Z = 0.0  # [m] the sea surface (NED origin at sea level)
MAX_DEPTH = 11_000.0  # [m] Challenger Deep, about 10.9 km
MAX_MARGIN = 1_000.0  # [m]
RANDOM_START_RISE = 8.0  # [m] largest |Δz| of a random start from its path point (Simulator)


@dataclass(frozen=True)
class DepthEnvelope:
    """A sea surface at z = 0 and, if ``seabed_depth`` [m] is given, a flat seabed there;
    ``margin`` [m]: the safety band inside both (the cost's depth term, the path check)."""

    seabed_depth: float | None = None  # [m] below the surface; None: deep water, no seabed
    margin: float = 2.0  # [m]

    def __post_init__(self) -> None:
        margin = real(
            "depth_envelope margin", self.margin, 0.0, MAX_MARGIN, low_open=True, unit="m"
        )
        object.__setattr__(self, "margin", margin)
        if self.seabed_depth is not None:
            # Both margins must leave water between them: a seabed above the surface or within
            # twice the margin of it leaves no depth a vehicle could hold at zero cost.
            depth = real(
                "depth_envelope seabed_depth",
                self.seabed_depth,
                2.0 * margin,
                MAX_DEPTH,
                low_open=True,
                unit=f"m (below the surface z = 0 by more than twice the margin {margin:g} m)",
            )
            object.__setattr__(self, "seabed_depth", depth)

    @classmethod
    def from_spec(cls, spec: DepthEnvelope | Mapping | bool | None) -> DepthEnvelope | None:
        """None or False: no envelope (the paper's unbounded ocean); True: the surface with the
        default margin; a dict of fields (e.g. ``{"seabed_depth": 30.0}``) or itself."""
        if spec is None or spec is False:
            return None
        if spec is True:
            return cls()
        if isinstance(spec, DepthEnvelope):
            return spec
        if isinstance(spec, Mapping):
            return cls(**keys_within("depth_envelope", spec, [f.name for f in fields(cls)]))
        raise ArgumentTypeError(
            "depth_envelope must be None, True, a dict with keys among ['margin', "
            f"'seabed_depth'] or a DepthEnvelope, got {spec!r:.80}"
        )

    @property
    def seabed_z(self) -> float:
        """z of the seabed [m]; inf without one."""
        return math.inf if self.seabed_depth is None else self.seabed_depth

    @property
    def safe_band(self) -> tuple[float, float]:
        """(shallowest, deepest) z [m] a vehicle may hold without a depth cost."""
        return SURFACE_Z + self.margin, self.seabed_z - self.margin


def path_depth_range(path: Path, s_max: float) -> tuple[float, float]:
    """(min z, max z) [m] of p(s) over s in [0, min(s_max, s_end)]: exact — z is linear in s
    on a helix or a line, and a cubic per segment on a spline (its end points and the roots of
    its derivative)."""
    s_hi = min(s_max, path.s_end)
    if path.kind != SPLINE:
        z = path.evaluate(np.array([0.0, s_hi]))[0][:, 2]
        return float(z.min()), float(z.max())
    n_seg = int(path.data[0])
    knots = path.data[1 : n_seg + 2]
    a0, a1, a2, a3 = path.data[n_seg + 2 :].reshape(n_seg, 3, 4)[:, 2, :].T  # z coefficients
    used = knots[:-1] < s_hi
    used[0] = True
    h = np.minimum(knots[1:], s_hi) - knots[:-1]
    a0, a1, a2, a3, h = a0[used], a1[used], a2[used], a3[used], h[used]
    disc = np.maximum((2.0 * a2) ** 2 - 12.0 * a3 * a1, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        roots = [(-2.0 * a2 + sign * np.sqrt(disc)) / (6.0 * a3) for sign in (-1.0, 1.0)]
        roots.append(-a1 / (2.0 * a2))  # the quadratic's extremum where a3 = 0
    candidates = [np.zeros_like(h), h] + [
        np.clip(np.nan_to_num(r, nan=0.0, posinf=0.0, neginf=0.0), 0.0, h) for r in roots
    ]
    z = np.concatenate([a0 + ds * (a1 + ds * (a2 + ds * a3)) for ds in candidates])
    return float(z.min()), float(z.max())


def check_path_depths(
    path: Path,
    envelope: DepthEnvelope,
    *,
    start_z: float,
    u_desired: float,
    max_time: float,
    randomize_start: bool,
    drawn: bool,
) -> None:
    """ValueError naming the argument to change if the path, over the arc length
    u_desired·max_time an episode on schedule covers, or the start (±`RANDOM_START_RISE` with
    ``randomize_start``) leaves the envelope's safe band. A vehicle that runs ahead of schedule
    can still reach the boundary further on; the episode then ends as "broached" or
    "grounded"."""
    tangent = float(np.linalg.norm(path.evaluate(0.0)[1]))
    s_max = u_desired * max_time / tangent  # helix and line: |p'| is constant
    z_min, z_max = path_depth_range(path, s_max)
    rise = RANDOM_START_RISE if randomize_start else 0.0
    z_min, z_max = min(z_min, start_z) - rise, max(z_max, start_z) + rise
    top, bottom = envelope.safe_band
    what = "the path drawn at this reset" if drawn else "the path"
    reach = f"over the {u_desired * max_time:g} m it covers in max_time at u_desired"
    start = " and the start" + (" (± 8 m with randomize_start)" if randomize_start else "")
    if z_min < top:
        raise ValueError(
            f"{what}{start} reach z = {z_min:.4g} m {reach}, above the depth_envelope's safe "
            f"band z >= {top:g} m (the surface z = 0 plus the margin): move the path at "
            f"least {math.ceil(top - z_min)} m down: add (0, 0, {math.ceil(top - z_min)}) to "
            "path_offset"
        )
    if z_max > bottom:
        raise ValueError(
            f"{what}{start} reach z = {z_max:.4g} m {reach}, below the depth_envelope's safe "
            f"band z <= {bottom:g} m (seabed_depth {envelope.seabed_depth:g} m less the "
            "margin): raise the path with path_offset or give a deeper seabed_depth"
        )
