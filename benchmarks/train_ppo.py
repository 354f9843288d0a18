"""Alias of `benchmarks.training.train_cli` under its former name: ``python -m
benchmarks.train_ppo`` and ``import benchmarks.train_ppo`` keep working."""

from __future__ import annotations

import sys

from benchmarks.training import train_cli as _module

if __name__ == "__main__":
    _module.main()
else:
    sys.modules[__name__] = _module
