"""Alias of `benchmarks.catalog.tasks` under its former name: ``python -m benchmarks.tasks`` and
``import benchmarks.tasks`` keep working."""

from __future__ import annotations

import sys

from benchmarks.catalog import tasks as _module

sys.modules[__name__] = _module
