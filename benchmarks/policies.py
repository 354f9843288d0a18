"""Alias of `benchmarks.catalog.policies` under its former name: ``python -m benchmarks.policies``
and ``import benchmarks.policies`` keep working."""

from __future__ import annotations

import sys

from benchmarks.catalog import policies as _module

sys.modules[__name__] = _module
