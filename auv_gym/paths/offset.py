"""A path moved as a whole: `ShiftedPath`, the `path_offset` argument of the envs.

The paths are defined around a reference origin (the paper's helix starts at z = −8 m and climbs
about 97 m in an episode, docs/model.md §2.0). With a sea surface at z = 0
(`auv_gym.ocean.depth_envelope`) a path must lie at real depth: ``path_offset = (0, 0, 110)`` moves
it, and its default start, 110 m down. The kernels see only the translated (kind, data) vector;
turn rates, curvature and every error are translation invariant, so nothing else changes.
"""

from __future__ import annotations

import numpy as np

from auv_gym.paths.shapes import KERNEL_KINDS, Path

__all__ = ["ShiftedPath", "shift_path"]


def _shifted_data(kind: int, data: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """The kernel vector of p(s) + offset (`paths.KernelKind.shifted`)."""
    if kind not in KERNEL_KINDS:
        raise ValueError(f"path kind {kind} cannot be shifted")
    return KERNEL_KINDS[kind].shifted(data, offset)


class ShiftedPath(Path):
    """``base`` moved by ``offset`` [m] (NED): p(s) = p_base(s) + offset, same s and s_end; the
    default start moves with it (the paper's helix keeps its start (15, 5, 0) m + offset)."""

    def __init__(self, base: Path, offset: tuple[float, float, float]) -> None:
        if isinstance(base, ShiftedPath):  # one level: offsets add up
            offset = tuple(np.add(base.offset, offset).tolist())  # type: ignore[assignment]
            base = base.base
        self.base = base
        self.offset = tuple(float(v) for v in offset)
        self.kind = base.kind
        self.s_end = base.s_end
        self.data = _shifted_data(base.kind, base.data, np.asarray(self.offset))
        if hasattr(base, "family"):  # drawn paths name their family (path_generator)
            self.family = base.family

    def default_start(self) -> tuple[np.ndarray, float]:
        position, heading = self.base.default_start()
        return position + np.asarray(self.offset), heading

    def __repr__(self) -> str:
        return f"ShiftedPath({type(self.base).__name__}, offset={self.offset} m)"


def shift_path(path: Path, offset: tuple[float, float, float]) -> Path:
    """``path`` moved by ``offset`` [m]; the path itself when the offset is zero, so that a
    configuration without an offset keeps its path object (and every result) unchanged."""
    if not any(offset):
        return path
    return ShiftedPath(path, offset)
