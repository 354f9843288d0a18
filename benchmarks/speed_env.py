"""Alias of `benchmarks.speed.env` under its former name: ``python -m benchmarks.speed_env`` and
``import benchmarks.speed_env`` keep working."""

from __future__ import annotations

import sys

from benchmarks.speed import env as _module

if __name__ == "__main__":
    _module.main()
else:
    sys.modules[__name__] = _module
