"""Alias of `benchmarks.reports.wave_depth` under its former name:
``python -m benchmarks.wave_depth`` and ``import benchmarks.wave_depth`` keep working."""

from __future__ import annotations

import sys

from benchmarks.reports import wave_depth as _module

if __name__ == "__main__":
    _module.main()
else:
    sys.modules[__name__] = _module
