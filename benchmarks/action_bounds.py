"""Alias of `benchmarks.analysis.action_bounds` under its former name: ``python -m
benchmarks.action_bounds`` and ``import benchmarks.action_bounds`` keep working."""

from __future__ import annotations

import sys

from benchmarks.analysis import action_bounds as _module

if __name__ == "__main__":
    _module.main()
else:
    sys.modules[__name__] = _module
