"""Alias of `benchmarks.speed.render` under its former name: ``python -m benchmarks.speed_render``
and ``import benchmarks.speed_render`` keep working."""

from __future__ import annotations

import sys

from benchmarks.speed import render as _module

if __name__ == "__main__":
    _module.main()
else:
    sys.modules[__name__] = _module
