"""Arithmetic whose bits do not depend on the CPU it runs on.

NumPy hands a dot product, and so the norm of a 1-D vector, to OpenBLAS, whose kernel is chosen
for the CPU at run time: on an AVX-512 machine the SkylakeX kernel fuses the multiply-adds, on an
AVX2 machine the Haswell kernel rounds each product, and the last bit of about one norm in ten
differs. A norm that places an episode's path, start or depth envelope must round alike on every
machine, or the same seed flies another episode elsewhere (docs/design.md §4, the bullet on
OpenBLAS kernels). Elementwise IEEE operations in a fixed order do; the order here is the one the
committed results were computed with (NumPy on AVX2: left to right, each product rounded).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

__all__ = ["norm3"]


def norm3(vector: Sequence[float]) -> float:
    """Euclidean norm of a 3-vector, ((x² + y²) + z²)^½, the same bits on every CPU."""
    x, y, z = (float(c) for c in vector)
    return math.sqrt(x * x + y * y + z * z)
