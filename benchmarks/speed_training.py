"""Alias of `benchmarks.speed.training` under its former name: ``python -m
benchmarks.speed_training`` and ``import benchmarks.speed_training`` keep working."""

from __future__ import annotations

import sys

from benchmarks.speed import training as _module

if __name__ == "__main__":
    _module.main()
else:
    sys.modules[__name__] = _module
