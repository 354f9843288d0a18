"""Alias of `benchmarks.reports.paper_figures` under its former name: ``python -m
benchmarks.paper_figures`` and ``import benchmarks.paper_figures`` keep working."""

from __future__ import annotations

import sys

from benchmarks.reports import paper_figures as _module

if __name__ == "__main__":
    _module.main(sys.argv[1:])
else:
    sys.modules[__name__] = _module
