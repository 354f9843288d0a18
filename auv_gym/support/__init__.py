"""Plumbing every room shares; nothing here knows the vehicle or the task.

- `numba_cache`: where the compiled kernels are cached and how staleness is detected;
- `records`: named access to the packed float64 rows the kernels share;
- `validation`: the argument checks behind every one-line error (`ArgumentTypeError`);
- `files`: atomic writes of files and folders, JSON with non-finite numbers, the environment
  record of a run.
"""

from __future__ import annotations

# First: the kernel cache locator must be in place before any kernel is defined.
from auv_gym.support.numba_cache import NumbaCacheWarning

# isort: split
from auv_gym.support.files import FolderInUseError
from auv_gym.support.validation import ArgumentTypeError

__all__ = ["ArgumentTypeError", "FolderInUseError", "NumbaCacheWarning"]
