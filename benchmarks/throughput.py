"""Speed of the simulator, the vector env and the controllers; prints tables.

    python -m benchmarks.throughput [--sections env,vector,controllers]

Each section lives in its own module (speed_env, speed_vector, speed_controllers) and can be run
alone with `python -m benchmarks.speed_<name>`.
"""

from __future__ import annotations

import argparse
import importlib
import platform

import numba
import numpy as np

SECTIONS = {"env": "benchmarks.speed_env", "vector": "benchmarks.speed_vector",
            "controllers": "benchmarks.speed_controllers"}  # fmt: skip


def machine() -> str:
    """One line describing this machine and the numeric stack."""
    import os

    return (
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
        f"Python {platform.python_version()}, numpy {np.__version__}, "
        f"numba {numba.__version__} ({numba.get_num_threads()} threads)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sections", default=",".join(SECTIONS),
                        help=f"comma-separated subset of {list(SECTIONS)}")  # fmt: skip
    args = parser.parse_args()
    print(machine())
    for name in args.sections.split(","):
        if name not in SECTIONS:
            raise SystemExit(f"unknown section {name!r}; valid: {list(SECTIONS)}")
        importlib.import_module(SECTIONS[name]).main([])


if __name__ == "__main__":
    main()
