"""Alias of `benchmarks.runner.jobs` under its former name: ``python -m benchmarks.jobs`` and
``import benchmarks.jobs`` keep working."""

from __future__ import annotations

import sys

from benchmarks.runner import jobs as _module

sys.modules[__name__] = _module
