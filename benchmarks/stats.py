"""Alias of `benchmarks.analysis.stats` under its former name: ``python -m benchmarks.stats`` and
``import benchmarks.stats`` keep working."""

from __future__ import annotations

import sys

from benchmarks.analysis import stats as _module

sys.modules[__name__] = _module
