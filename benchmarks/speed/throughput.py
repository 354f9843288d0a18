"""Speed of the simulator, the vector env, the controllers, rendering and PPO training; prints
tables.

    auv-gym speed all [--sections env,vector,controllers,render,resets,training]
    python -m benchmarks.speed.throughput [--sections …]

Each section lives in its own module (env, vector, controllers, render, resets,
training: this tree against the default baseline ref; off-policy: SAC, TQC and CrossQ) and runs
alone with `auv-gym speed <name>` or `python -m benchmarks.speed.<module>`.
"""

from __future__ import annotations

import importlib
import platform
from dataclasses import dataclass

import numba
import numpy as np

from benchmarks.arguments import parse_options, program_name
from benchmarks.options import option

SECTIONS = {
    "env": "benchmarks.speed.env",
    "vector": "benchmarks.speed.vector",
    "controllers": "benchmarks.speed.controllers",
    "render": "benchmarks.speed.render",
    "resets": "benchmarks.speed.resets",
    "training": "benchmarks.speed.training",
    "off-policy": "benchmarks.speed.off_policy",
}


def machine() -> str:
    """One line describing this machine and the numeric stack."""
    import os

    return (
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
        f"Python {platform.python_version()}, numpy {np.__version__}, "
        f"numba {numba.__version__} ({numba.get_num_threads()} threads)"
    )


@dataclass
class Options:
    """The command line of `auv-gym speed all`."""

    sections: str = option(",".join(SECTIONS), f"comma-separated subset of {', '.join(SECTIONS)}")


def main(argv: list[str] | None = None) -> None:
    args, parser = parse_options(
        Options, argv, program_name("benchmarks.speed.throughput"), __doc__
    )
    names = [name.strip() for name in args.sections.split(",")]
    unknown = [name for name in names if name not in SECTIONS]
    if unknown or not names:
        parser.error(f"--sections: unknown {unknown}; valid: {', '.join(SECTIONS)}")
    print(machine())
    for name in names:
        importlib.import_module(SECTIONS[name]).main([])


if __name__ == "__main__":
    main()
