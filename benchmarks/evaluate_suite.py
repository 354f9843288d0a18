"""Alias of `benchmarks.runner.evaluate_suite` under its former name: ``python -m
benchmarks.evaluate_suite`` and ``import benchmarks.evaluate_suite`` keep working."""

from __future__ import annotations

import sys

from benchmarks.runner import evaluate_suite as _module

if __name__ == "__main__":
    _module.main()
else:
    sys.modules[__name__] = _module
