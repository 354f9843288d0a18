"""Alias of `benchmarks.reports.video` under its former name: ``python -m benchmarks.video`` and
``import benchmarks.video`` keep working."""

from __future__ import annotations

import sys

from benchmarks.reports import video as _module

if __name__ == "__main__":
    _module.main()
else:
    sys.modules[__name__] = _module
