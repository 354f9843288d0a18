"""Alias of `benchmarks.reports.figures` under its former name: ``import benchmarks.figures`` keeps
working."""

from __future__ import annotations

import sys

from benchmarks.reports import figures as _module

sys.modules[__name__] = _module
