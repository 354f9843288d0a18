"""Record the 6-DOF accelerations of Fossen's PythonVehicleSimulator ``torpedo`` (a REMUS-100
hull with four independently actuated fins in a cross, each with its own `fin` object) on a grid
of states, fin angles, shaft speeds and currents: the reference numbers tests/test_torpedo.py
holds the shipped ``torpedo`` vehicle file and `auv_gym.vehicle.fins` to.

    python -m benchmarks.checks.record_pvs_torpedo --pvs PATH/TO/PythonVehicleSimulator/src \
        --out tests/data/pvs_torpedo_6dof.json

PATH is the ``src`` folder of a checkout of https://github.com/cybergalactic/PythonVehicleSimulator
(recorded from commit c717e07). ``torpedo.dynamics`` integrates one Euler step of ``sampleTime``;
with sampleTime = 1 s the returned ν minus the given ν is ν̇ itself. Each fin's force is computed
from its own actual angle (``fin.u_actual_fin``) and the propeller's from its actual shaft speed
(``thruster.u_actual_n``), which the recorder sets before the call. The grid draws fin angles
past the ±15° limit; a fin's actual angle never exceeds it in the reference (``fin.actuate``
saturates it), so the reference is given the angle at its limit, as auv-gym's fins clip it. The
shaft speed goes to the reference as drawn (its thruster saturates it itself).
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
from benchmarks.checks.record_pvs_6dof import GRID_POINTS
from benchmarks.checks.record_pvs_6dof import grid as remus_grid
from benchmarks.options import option

__all__ = ["FINS", "FIN_LIMIT", "RecordOptions", "grid", "main"]

FINS = ("top_rudder", "bottom_rudder", "starboard_stern", "port_stern")  # the reference's order
FIN_LIMIT = math.radians(15.0)  # [rad] the reference fin's deltaMax
NAMES = [
    *("x", "y", "z", "phi", "theta", "psi", "u", "v", "w", "p", "q", "r"),
    *(f"delta_{fin}" for fin in FINS),
    *("n", "current_speed", "current_direction"),
]
UNITS = [*["m"] * 3, *["rad"] * 3, *["m/s"] * 3, *["rad/s"] * 3, *["rad"] * 4, "rpm", "m/s", "rad"]


def grid(points: int = GRID_POINTS, seed: int = 1) -> np.ndarray:
    """(points, 19) inputs: the REMUS 100 recorder's poses, velocities, shaft speeds and currents
    (seed ``seed``), and four independent fin angles past ±15°, a quarter of them in pairs (the
    rudders and the stern planes deflected together, as a stern-plane and rudder command)."""
    base = remus_grid(points, seed)
    rng = np.random.default_rng(seed + 1000)
    fins = rng.uniform(-0.35, 0.35, (points, 4))
    paired = slice(points // 2, points // 2 + points // 4)
    fins[paired, 1] = -fins[paired, 0]  # δ_top = δ_r, δ_bottom = −δ_r
    fins[paired, 2] = -fins[paired, 3]  # δ_port = δ_s, δ_starboard = −δ_s
    return np.hstack([base[:, :12], fins, base[:, 14:17]])


@dataclass
class RecordOptions:
    """The command line of `python -m benchmarks.checks.record_pvs_torpedo`."""

    pvs: Path = option(Path("PythonVehicleSimulator/src"), "the reference's src folder")  # noqa: RUF009
    out: Path = option(Path("tests/data/pvs_torpedo_6dof.json"), "the JSON to write")  # noqa: RUF009
    points: int = option(GRID_POINTS, "grid points")


def main(argv: list[str] | None = None) -> Path:
    args, parser = parse_options(
        RecordOptions, argv, program_name("benchmarks.checks.record_pvs_torpedo"), __doc__
    )
    with usage_errors(parser):
        if not (args.pvs / "python_vehicle_simulator" / "vehicles" / "torpedo.py").is_file():
            raise FileNotFoundError(
                f"--pvs {args.pvs}: no python_vehicle_simulator/vehicles/torpedo.py"
            )
        if args.points < 300:
            raise ValueError(f"--points must be at least 300, got {args.points}")
    sys.path.insert(0, str(args.pvs))
    torpedo = importlib.import_module("python_vehicle_simulator.vehicles.torpedo").torpedo
    rows = []
    for values in grid(args.points):
        eta, nu = values[0:6], values[6:12]
        vehicle = torpedo("stepInput", 0, 0, 0, 0, 0)
        vehicle.V_c, vehicle.beta_c = float(values[17]), float(values[18])
        *fins, propeller = vehicle.actuators
        for fin, angle in zip(fins, values[12:16], strict=True):
            fin.u_actual_fin = float(np.clip(angle, -FIN_LIMIT, FIN_LIMIT))
        propeller.u_actual_n = float(values[16])
        actual = values[12:17].copy()
        nu_next, _ = vehicle.dynamics(eta.copy(), nu.copy(), actual, actual.copy(), 1.0)
        rows.append([*values.tolist(), *(np.asarray(nu_next) - nu).tolist()])
    record = {
        "source": "T. I. Fossen, PythonVehicleSimulator, src/python_vehicle_simulator/vehicles/"
        "torpedo.py, torpedo.dynamics (commit c717e07): nu_dot as (nu after one 1-s Euler step) "
        "- nu; each fin's actual angle set to the drawn one clipped to its 15-degree limit, the "
        "shaft speed as drawn",
        "columns": [*NAMES, *(f"{c}_dot" for c in ("u", "v", "w", "p", "q", "r"))],
        "units": [*UNITS, *["m/s²"] * 3, *["rad/s²"] * 3],
        "rows": rows,
    }
    write_json(args.out, record, indent=None)
    print(f"wrote {args.out}: {len(rows)} grid points")
    return args.out


if __name__ == "__main__":
    main()
