"""Alias of `benchmarks.speed.controllers` under its former name: ``python -m
benchmarks.speed_controllers`` and ``import benchmarks.speed_controllers`` keep working."""

from __future__ import annotations

import sys

from benchmarks.speed import controllers as _module

if __name__ == "__main__":
    _module.main()
else:
    sys.modules[__name__] = _module
