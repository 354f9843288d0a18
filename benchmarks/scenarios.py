"""Alias of `benchmarks.catalog.scenarios` under its former name: ``python -m
benchmarks.scenarios`` and ``import benchmarks.scenarios`` keep working."""

from __future__ import annotations

import sys

from benchmarks.catalog import scenarios as _module

sys.modules[__name__] = _module
