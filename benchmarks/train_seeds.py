"""Alias of `benchmarks.training.seeds_cli` under its former name: ``python -m
benchmarks.train_seeds`` and ``import benchmarks.train_seeds`` keep working."""

from __future__ import annotations

import sys

from benchmarks.training import seeds_cli as _module

if __name__ == "__main__":
    sys.exit(_module.main())
else:
    sys.modules[__name__] = _module
