"""Alias of `benchmarks.speed.residual` under its former name: ``python -m
benchmarks.speed_residual`` and ``import benchmarks.speed_residual`` keep working."""

from __future__ import annotations

import sys

from benchmarks.speed import residual as _module

if __name__ == "__main__":
    _module.main()
else:
    sys.modules[__name__] = _module
