"""Alias of `benchmarks.runner.compare` under its former name: ``python -m benchmarks.compare`` and
``import benchmarks.compare`` keep working."""

from __future__ import annotations

import sys

from benchmarks.runner import compare as _module

if __name__ == "__main__":
    _module.main()
else:
    sys.modules[__name__] = _module
