"""Alias of `benchmarks.reports.tables` under its former name: ``import benchmarks.tables`` keeps
working."""

from __future__ import annotations

import sys

from benchmarks.reports import tables as _module

sys.modules[__name__] = _module
