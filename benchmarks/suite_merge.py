"""Alias of `benchmarks.analysis.suite_merge` under its former name: ``python -m
benchmarks.suite_merge`` and ``import benchmarks.suite_merge`` keep working."""

from __future__ import annotations

import sys

from benchmarks.analysis import suite_merge as _module

if __name__ == "__main__":
    raise SystemExit(_module.main())
else:
    sys.modules[__name__] = _module
