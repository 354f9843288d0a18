"""Alias of `benchmarks.analysis.stats_figures` under its former name: ``python -m
benchmarks.stats_figures`` and ``import benchmarks.stats_figures`` keep working."""

from __future__ import annotations

import sys

from benchmarks.analysis import stats_figures as _module

sys.modules[__name__] = _module
