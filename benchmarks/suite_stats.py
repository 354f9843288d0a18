"""Alias of `benchmarks.analysis.suite_stats` under its former name: ``python -m
benchmarks.suite_stats`` and ``import benchmarks.suite_stats`` keep working."""

from __future__ import annotations

import sys

from benchmarks.analysis import suite_stats as _module

sys.modules[__name__] = _module
