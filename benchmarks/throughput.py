"""Alias of `benchmarks.speed.throughput` under its former name: ``python -m
benchmarks.throughput`` and ``import benchmarks.throughput`` keep working."""

from __future__ import annotations

import sys

from benchmarks.speed import throughput as _module

if __name__ == "__main__":
    _module.main()
else:
    sys.modules[__name__] = _module
