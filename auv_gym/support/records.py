"""Named access to the packed float64 rows the numba kernels share, at no run-time cost.

The kernels keep their inputs in plain float64 arrays (cheap to pass from Python, one row per
vehicle) and their working values in registers. Two tools give both names:

- `field_indices` turns a tuple of field names into a named tuple of their positions. numba
  freezes it as a constant, so ``st[STATE.theta]`` compiles to ``st[3]``.
- `record_type` + `fixed_tuple` view the first n entries of an array as a named tuple held in
  registers, so that ``p.X_uu * u * abs(u)`` reads like its equation: no heap array and no
  reference count (each array reference costs two atomic updates in a hot loop).
"""

from __future__ import annotations

from collections import namedtuple
from collections.abc import Sequence

from numba import types
from numba.core.errors import TypingError
from numba.extending import overload
from numba.np.unsafe.ndarray import to_fixed_tuple

__all__ = ["field_indices", "fixed_tuple", "record_type"]


def record_type(type_name: str, names: Sequence[str], module: str) -> type:
    """A named-tuple type with the given fields; ``module`` is the defining module's __name__
    (the type must be a global there under ``type_name``, so that pickle can find it)."""
    return namedtuple(type_name, names, module=module)


def field_indices(type_name: str, names: Sequence[str], module: str) -> tuple:
    """A named tuple of the names' positions: ``field_indices(t, ("a", "b"), m).b == 1``."""
    return record_type(type_name, names, module)(*range(len(names)))


def fixed_tuple(array, length):
    """``array[:length]`` as a tuple; compiled, a register copy (numba's `to_fixed_tuple`).

    The plain-Python body keeps the kernels runnable with ``NUMBA_DISABLE_JIT=1`` (debugging).
    """
    return tuple(array[:length])


@overload(fixed_tuple, prefer_literal=True)
def _fixed_tuple_compiled(array, length):
    if not isinstance(length, types.IntegerLiteral):
        raise TypingError("fixed_tuple needs a compile-time constant length")
    n = length.literal_value

    def impl(array, length):
        return to_fixed_tuple(array, n)

    return impl
