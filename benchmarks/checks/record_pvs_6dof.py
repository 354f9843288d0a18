"""Record the 6-DOF accelerations of Fossen's PythonVehicleSimulator ``remus100`` on a grid of
states, commands and currents: the reference numbers tests/test_remus6dof.py holds
`auv_gym.vehicle.remus6dof.accelerations` to.

    python -m benchmarks.checks.record_pvs_6dof --pvs PATH/TO/PythonVehicleSimulator/src \
        --out tests/data/pvs_remus100_6dof.json

PATH is the ``src`` folder of a checkout of https://github.com/cybergalactic/PythonVehicleSimulator
(recorded from commit c717e07). ``remus100.dynamics`` integrates one Euler step of ``sampleTime``;
with sampleTime = 1 s the returned ν minus the given ν is ν̇ itself (an exact product, one
rounded subtraction). The actuator state is passed as the actual (δ_r, δ_s, n) the forces are
computed from; the reference clips it to its limits, and the grid goes beyond them.
"""

from __future__ import annotations

import importlib
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from auv_gym.support.files import write_json
from benchmarks.arguments import parse_options, program_name, usage_errors
from benchmarks.options import option

__all__ = ["GRID_POINTS", "RecordOptions", "grid", "main"]

GRID_POINTS = 400
NAMES = [
    *("x", "y", "z", "phi", "theta", "psi", "u", "v", "w", "p", "q", "r"),
    *("delta_r", "delta_s", "n", "current_speed", "current_direction"),
]
UNITS = [*["m"] * 3, *["rad"] * 3, *["m/s"] * 3, *["rad/s"] * 3, "rad", "rad", "rpm", "m/s", "rad"]
COLUMNS = tuple(zip(NAMES, UNITS, strict=True))  # the grid's inputs and their units


def grid(points: int = GRID_POINTS, seed: int = 0) -> np.ndarray:
    """(points, 17) inputs: poses, velocities, actuator states past their limits, currents."""
    rng = np.random.default_rng(seed)
    low = [-50, -50, 0, -0.8, -0.8, -math.pi, -0.5, -0.6, -0.6, -0.5, -0.5, -0.5]
    high = [50, 50, 100, 0.8, 0.8, math.pi, 2.5, 0.6, 0.6, 0.5, 0.5, 0.5]
    state = rng.uniform(low, high, (points, 12))
    fins = rng.uniform(-0.35, 0.35, (points, 2))  # beyond ±15°
    rpm = rng.uniform(-1700.0, 1700.0, (points, 1))  # beyond ±1525 rpm
    current = np.column_stack(
        [rng.uniform(0.0, 0.6, points), rng.uniform(-math.pi, math.pi, points)]
    )
    data = np.hstack([state, fins, rpm, current])
    data[:20, 6:12] = 0.0  # at rest: the restoring and propeller terms alone
    data[20:40, 15] = 0.0  # no current
    return data


@dataclass
class RecordOptions:
    """The command line of `python -m benchmarks.checks.record_pvs_6dof`."""

    pvs: Path = option(Path("PythonVehicleSimulator/src"), "the reference's src folder")  # noqa: RUF009
    out: Path = option(Path("tests/data/pvs_remus100_6dof.json"), "the JSON to write")  # noqa: RUF009
    points: int = option(GRID_POINTS, "grid points")


def main(argv: list[str] | None = None) -> Path:
    args, parser = parse_options(
        RecordOptions, argv, program_name("benchmarks.checks.record_pvs_6dof"), __doc__
    )
    with usage_errors(parser):
        if not (args.pvs / "python_vehicle_simulator" / "vehicles" / "remus100.py").is_file():
            raise FileNotFoundError(
                f"--pvs {args.pvs}: no python_vehicle_simulator/vehicles/remus100.py"
            )
        if args.points < 300:
            raise ValueError(f"--points must be at least 300, got {args.points}")
    sys.path.insert(0, str(args.pvs))
    remus100 = importlib.import_module("python_vehicle_simulator.vehicles.remus100").remus100
    rows = []
    for values in grid(args.points):
        eta, nu, actual = values[0:6], values[6:12], values[12:15]
        vehicle = remus100("stepInput", 0, 0, 0, 0, 0)
        vehicle.V_c, vehicle.beta_c = float(values[15]), float(values[16])
        nu_next, _ = vehicle.dynamics(eta.copy(), nu.copy(), actual.copy(), actual.copy(), 1.0)
        rows.append([*values.tolist(), *(np.asarray(nu_next) - nu).tolist()])
    record = {
        "source": "T. I. Fossen, PythonVehicleSimulator, src/python_vehicle_simulator/vehicles/"
        "remus100.py, remus100.dynamics (commit c717e07): nu_dot as (nu after one 1-s Euler step) "
        "- nu, actual = commanded actuator state",
        "columns": [c for c, _ in COLUMNS] + [f"{c}_dot" for c in ("u", "v", "w", "p", "q", "r")],
        "units": [u for _, u in COLUMNS] + ["m/s²"] * 3 + ["rad/s²"] * 3,
        "rows": rows,
    }
    write_json(args.out, record, indent=None)
    print(f"wrote {args.out}: {len(rows)} grid points")
    return args.out


if __name__ == "__main__":
    main()
