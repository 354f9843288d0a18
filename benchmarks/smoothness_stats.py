"""Alias of `benchmarks.analysis.smoothness_stats` under its former name: ``python -m
benchmarks.smoothness_stats`` and ``import benchmarks.smoothness_stats`` keep working."""

from __future__ import annotations

import sys

from benchmarks.analysis import smoothness_stats as _module

sys.modules[__name__] = _module
