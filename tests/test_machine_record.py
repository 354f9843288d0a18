"""A result records the CPU choices its last digits depend on (NumPy's SIMD level, OpenBLAS's
kernel): the same seed reproduces bit for bit on the machine class that made it."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import auv_gym
from auv_gym.support.files import environment, git_commit, machine

_RECORD = "import json; from auv_gym.support.files import machine; print(json.dumps(machine()))"


def _machine_under(**settings: str) -> dict:
    run = subprocess.run(
        [sys.executable, "-c", _RECORD],
        env={**os.environ, **settings},
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    return json.loads(run.stdout)


def test_the_machine_record_follows_numpy_and_openblas_choices() -> None:
    """Held to its baseline loops, NumPy reports no dispatched level; on the Nehalem kernels
    (SSE4.2, older than any AVX machine) OpenBLAS reports them; every result carries the record."""
    pytest.importorskip("threadpoolctl")  # the rl extra's: without it "blas" is None
    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__

    available = [name for name in __cpu_dispatch__ if __cpu_features__.get(name)]
    own = machine()
    assert own["numpy_simd"] == available
    assert own["blas"] is not None and own["blas"].startswith("openblas ")
    held = _machine_under(NPY_DISABLE_CPU_FEATURES=" ".join(available), OPENBLAS_CORETYPE="Nehalem")
    assert held == {"numpy_simd": [], "blas": "openblas Nehalem"}
    assert environment()["machine"] == own


def test_a_result_records_the_commit_of_the_checkout_it_ran_from() -> None:
    """The environment record names the checkout's HEAD (378 committed results recorded null
    after `files.py` moved one folder down and looked for `.git` inside the package)."""
    checkout = Path(auv_gym.__file__).resolve().parents[1]
    if not (checkout / ".git").exists():
        pytest.skip("an installed copy, not a git checkout")
    head = subprocess.run(
        ["git", "-C", str(checkout), "rev-parse", "HEAD"], capture_output=True, text=True
    ).stdout.strip()
    assert len(head) == 40 and git_commit() == head == environment()["git_commit"]
