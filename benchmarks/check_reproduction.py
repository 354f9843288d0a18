"""Alias of `benchmarks.checks.reproduction` under its former name: ``python -m
benchmarks.check_reproduction`` and ``import benchmarks.check_reproduction`` keep working."""

from __future__ import annotations

import sys

from benchmarks.checks import reproduction as _module

if __name__ == "__main__":
    sys.exit(_module.main())
else:
    sys.modules[__name__] = _module
