"""The reference: parametric 3-D paths p(s) and the path-following geometry.

- `shapes`: the path families (`Helix`, `StraightLine`, `Spline`, `FittedCurve`) and
  `make_path`; re-exports the names of `base` and `fit`;
- `base`: the `Path` base class, the arguments' ranges and, per kernel kind (`KERNEL_KINDS`),
  its data check, turn-rate bounds and translation;
- `kernels`: each kind's compiled evaluation `path_eval` (p, p′, p″) and p‴;
- `cubic`: the cubic-spline coefficients a spline stores (a tridiagonal solve, linear in n);
- `fit`: `fit_curve`, a user's curve p(s) as a clamped spline in the same s;
- `bounds`: proven bounds on a spline's |p′| and turn rates;
- `offset`: a path translated by a fixed offset (`shift_path`);
- `guidance`: Serret–Frenet path angles, body-frame errors, the virtual-point speed.

The lowest room of the model: it imports only `auv_gym.support`.
"""

from __future__ import annotations

from auv_gym.paths.offset import ShiftedPath, shift_path
from auv_gym.paths.shapes import (
    FIT_TOLERANCE,
    KERNEL_KINDS,
    MIN_FIT_SEGMENTS,
    PATHS,
    FittedCurve,
    Helix,
    KernelKind,
    Path,
    Spline,
    SplineKind,
    StraightLine,
    fit_curve,
    make_path,
    path_eval,
    path_third_derivative,
    path_turn_rates,
)

__all__ = [
    "FIT_TOLERANCE",
    "KERNEL_KINDS",
    "MIN_FIT_SEGMENTS",
    "PATHS",
    "FittedCurve",
    "Helix",
    "KernelKind",
    "Path",
    "ShiftedPath",
    "Spline",
    "SplineKind",
    "StraightLine",
    "fit_curve",
    "make_path",
    "path_eval",
    "path_third_derivative",
    "path_turn_rates",
    "shift_path",
]
