"""Alias of `benchmarks.checks.fuzz` under its former name: ``python -m benchmarks.fuzz`` and
``import benchmarks.fuzz`` keep working."""

from __future__ import annotations

import sys

from benchmarks.checks import fuzz as _module

if __name__ == "__main__":
    _module.main()
else:
    sys.modules[__name__] = _module
