"""Argument checks at the package boundary, with one message format for every bad input.

Each checker returns the value in its canonical type or raises: `ArgumentTypeError` for the wrong
kind of value (a string, a bool or a complex number where a real number belongs, …) and
`ValueError` for the right kind outside its documented range. Every message names the argument,
the value it got and what is allowed, e.g.
``control_dt must be a real number in (0, 1000] s, got 'fast'``.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

__all__ = [
    "ArgumentTypeError",
    "choice",
    "flag",
    "integer",
    "is_real",
    "keys_within",
    "real",
    "vector",
    "whole_steps",
]

# Relative slack of `whole_steps`: a decimal interval divided by a decimal step is a whole
# number only up to the rounding of both (0.3 / 0.1 = 2.9999999999999996).
WHOLE_STEP_TOLERANCE = 1e-9


class ArgumentTypeError(TypeError, ValueError):
    """A wrong kind of value. A `TypeError`, and a `ValueError` for callers that caught the
    ValueErrors this package raised for such input before it had a type check."""


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _interval(low: float, high: float, low_open: bool, high_open: bool, unit: str) -> str:
    def bound(x: float) -> str:
        return "∞" if x == math.inf else "−∞" if x == -math.inf else f"{x:g}"

    left = "(" if low_open or low == -math.inf else "["
    right = ")" if high_open or high == math.inf else "]"
    text = f"{left}{bound(low)}, {bound(high)}{right}"
    return f"{text} {unit}" if unit else text


def is_real(value: Any) -> bool:
    """True for int, float and numpy real scalars; False for bool, complex, str and containers."""
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def real(
    name: str,
    value: Any,
    low: float = -math.inf,
    high: float = math.inf,
    *,
    low_open: bool = False,
    high_open: bool = False,
    unit: str = "",
) -> float:
    """``value`` as a float if it is a finite real number in the interval; else a named error."""
    allowed = _interval(low, high, low_open, high_open, unit)
    if not is_real(value):
        raise ArgumentTypeError(
            f"{name} must be a real number in {allowed}, got {_show(value)} "
            f"({type(value).__name__})"
        )
    try:
        x = float(value)
    except OverflowError:  # an int beyond the float range
        x = math.inf if value > 0 else -math.inf
    below = x <= low if low_open else x < low
    above = x >= high if high_open else x > high
    if not math.isfinite(x) or below or above:
        raise ValueError(f"{name} must be a finite number in {allowed}, got {_show(value)}")
    return x


def integer(name: str, value: Any, low: int, high: int | None = None) -> int:
    """``value`` as an int if it is an integer (not a bool) in [low, high]; else a named error."""
    allowed = f"[{low}, {'∞' if high is None else high}]"
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise ArgumentTypeError(f"{name} must be an integer in {allowed}, got {_show(value)}")
    if value < low or (high is not None and value > high):
        raise ValueError(f"{name} must be an integer in {allowed}, got {_show(value)}")
    return int(value)


def flag(name: str, value: Any) -> bool:
    """``value`` if it is a bool (or numpy bool); strings such as "False" are refused."""
    if not isinstance(value, (bool, np.bool_)):
        raise ArgumentTypeError(f"{name} must be True or False, got {_show(value)}")
    return bool(value)


def choice(name: str, value: Any, options: Iterable[str]) -> str:
    """``value`` if it is one of the strings ``options``; else a named error listing them."""
    valid = sorted(options)
    if not isinstance(value, str):
        raise ArgumentTypeError(f"{name} must be one of {valid}, got {_show(value)}")
    if value not in valid:
        raise ValueError(f"unknown {name} {value!r}; valid: {valid}")
    return value


def vector(
    name: str,
    value: Any,
    length: int,
    low: float = -math.inf,
    high: float = math.inf,
    unit: str = "",
) -> tuple[float, ...]:
    """``value`` as a tuple of ``length`` finite reals in [low, high]; else a named error."""
    allowed = f"{length} real numbers in {_interval(low, high, False, False, unit)}"
    if isinstance(value, np.ndarray):
        items = value.tolist() if value.ndim == 1 and value.dtype.kind in "iuf" else [value]
    elif isinstance(value, (str, bytes, Mapping)) or not isinstance(value, Iterable):
        items = [value, None]  # not a sequence: a type error whatever it holds
    else:
        items = list(value)
    if not all(map(is_real, items)):
        raise ArgumentTypeError(f"{name} must be {allowed}, got {_show(value)}")
    try:
        out = tuple(float(x) for x in items)
    except OverflowError:  # an int beyond the float range
        raise ValueError(f"{name} must be {allowed}, got {_show(value)}") from None
    if len(out) != length or not all(math.isfinite(x) and low <= x <= high for x in out):
        raise ValueError(f"{name} must be {allowed}, got {_show(value)}")
    return out


def keys_within(name: str, value: Any, allowed: Iterable[str]) -> dict[str, Any]:
    """``value`` as a dict if it is a mapping whose keys are among ``allowed``."""
    valid = sorted(allowed)
    if not isinstance(value, Mapping):
        raise ArgumentTypeError(
            f"{name} must be a mapping with keys among {valid}, got {_show(value)}"
        )
    unknown = sorted(map(str, set(value) - set(valid)))
    if unknown:
        raise ValueError(f"{name} has unknown key(s) {unknown}; valid: {valid}")
    return dict(value)


def whole_steps(name: str, interval: float, step: float, step_name: str) -> int:
    """``interval`` [s] as a whole number (at least 1) of ``step`` [s]; ValueError naming both
    (``step_name`` is the step's own name, e.g. "control_dt") when it is not one."""
    ratio = interval / step
    if abs(ratio - round(ratio)) > WHOLE_STEP_TOLERANCE * ratio or round(ratio) < 1:
        raise ValueError(
            f"{name} = {interval} s must be a whole multiple of {step_name} = {step} s"
        )
    return round(ratio)
