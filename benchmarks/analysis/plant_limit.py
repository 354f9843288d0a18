"""The paper's 5-DOF model against the 6-DOF REMUS 100 with roll held at zero: how far apart the
two plants are where the paper's assumptions hold (docs/model.md §15).

    python -m benchmarks.analysis.plant_limit

At a handful of states (cruise, turning, pitching, a mixed manoeuvre; φ = p = 0, no current) both
models get the same generalized forces τ = (X, M, N) — the 5-DOF model's actuation, applied to the
6-DOF hull as (X, 0, 0, 0, M, N) — and the table prints their accelerations (u̇, v̇, ẇ, q̇, ṙ) side by
side, with the roll acceleration ṗ the 5-DOF model drops. The difference is the two models'
hydrodynamics (the paper's Prestero coefficients against Fossen's spheroid, lift and cross-flow
forms), not numerical error: both are evaluated exactly.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit

from auv_gym.vehicle.dynamics import nu_dot
from auv_gym.vehicle.params import params_record, remus100
from auv_gym.vehicle.remus6dof import REMUS6DOF, hull_accelerations
from benchmarks.arguments import parse_options, program_name
from benchmarks.options import option

__all__ = ["STATES", "compare", "main"]

# name → (u, v, w, q, r [m/s, rad/s], θ [rad], X [N], M, N [N·m])
STATES: dict[str, tuple[float, ...]] = {
    "cruise 1 m/s": (1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 8.0, 0.0, 0.0),
    "turning": (1.0, 0.02, 0.0, 0.0, 0.05, 0.0, 8.0, 0.0, 1.0),
    "pitching": (1.0, 0.0, 0.02, 0.03, 0.0, 0.2, 8.0, -1.0, 0.0),
    "mixed 1.5 m/s": (1.5, 0.05, -0.03, 0.02, -0.04, -0.1, 15.0, 0.5, -0.5),
}


@njit(cache=True)
def _five_dof(nu, theta, tau, vector):
    return nu_dot(nu, theta, tau, (0.0, 0.0, 0.0, 0.0, 0.0), params_record(vector))


def compare(state: tuple[float, ...]) -> dict[str, Any]:
    """The 5-DOF ν̇ (u̇, v̇, ẇ, q̇, ṙ), the 6-DOF ν̇ at φ = p = 0 (the same five and ṗ)."""
    u, v, w, q, r, theta, x, m, n = state
    five = np.array(
        _five_dof((u, v, w, q, r), theta, (x, m, n), remus100().to_vector()), dtype=np.float64
    )
    eta = np.array([0.0, 0.0, 50.0, 0.0, theta, 0.0])
    six = hull_accelerations(
        REMUS6DOF, eta, np.array([u, v, w, 0.0, q, r]), np.array([x, 0.0, 0.0, 0.0, m, n])
    )
    return {"five_dof": five, "six_dof": six[[0, 1, 2, 4, 5]], "roll": float(six[3])}


@dataclass
class LimitOptions:
    """The command line of `python -m benchmarks.analysis.plant_limit` (no options yet)."""

    digits: int = option(3, "significant figures printed")


def main(argv: list[str] | None = None) -> dict[str, Any]:
    args, parser = parse_options(
        LimitOptions, argv, program_name("benchmarks.analysis.plant_limit"), __doc__
    )
    if not 1 <= args.digits <= 12:
        parser.error(f"--digits must be in [1, 12], got {args.digits}")
    names = ("u̇", "v̇", "ẇ", "q̇", "ṙ")
    print("accelerations [m/s², rad/s²]: 5-DOF (paper) | 6-DOF (Fossen 2021), φ = p = 0")
    results = {}
    for label, state in STATES.items():
        out = compare(state)
        results[label] = out
        pairs = "  ".join(
            f"{k} {a:+.{args.digits}g} | {b:+.{args.digits}g}"
            for k, a, b in zip(names, out["five_dof"], out["six_dof"], strict=True)
        )
        print(f"{label:<14} {pairs}  ṗ (6-DOF) {out['roll']:+.{args.digits}g}")
    return results


if __name__ == "__main__":
    main()
