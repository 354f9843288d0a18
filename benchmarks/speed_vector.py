"""Alias of `benchmarks.speed.vector` under its former name:
``python -m benchmarks.speed_vector`` and ``import benchmarks.speed_vector`` keep working."""

from __future__ import annotations

import sys

from benchmarks.speed import vector as _module

if __name__ == "__main__":
    _module.main()
else:
    sys.modules[__name__] = _module
