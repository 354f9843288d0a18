"""Speed of the simulator, the vector env, the controllers, rendering and PPO training; prints
tables.

    auv-gym speed all [--sections env,vector,controllers,render,training]
    python -m benchmarks.throughput [--sections …]

Each section lives in its own module (env, vector, controllers, render,
training: this tree against the default baseline ref) and runs alone with
`auv-gym speed <name>` or `python -m benchmarks.speed_<name>`.
"""

from __future__ import annotations

import argparse
import importlib
import platform

import numba
import numpy as np

from benchmarks.cli import HelpFormatter

SECTIONS = {"env": "benchmarks.speed.env", "vector": "benchmarks.speed.vector",
            "controllers": "benchmarks.speed.controllers",
            "render": "benchmarks.speed.render",
            "training": "benchmarks.speed.training"}  # fmt: skip


def machine() -> str:
    """One line describing this machine and the numeric stack."""
    import os

    return (
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
        f"Python {platform.python_version()}, numpy {np.__version__}, "
        f"numba {numba.__version__} ({numba.get_num_threads()} threads)"
    )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=HelpFormatter)
    parser.add_argument("--sections", default=",".join(SECTIONS),
                        help=f"comma-separated subset of {', '.join(SECTIONS)}")  # fmt: skip
    args = parser.parse_args(argv)
    names = [name.strip() for name in args.sections.split(",")]
    unknown = [name for name in names if name not in SECTIONS]
    if unknown or not names:
        parser.error(f"--sections: unknown {unknown}; valid: {', '.join(SECTIONS)}")
    print(machine())
    for name in names:
        importlib.import_module(SECTIONS[name]).main([])


if __name__ == "__main__":
    main()
