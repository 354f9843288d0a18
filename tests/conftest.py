from __future__ import annotations

import numpy as np
import pytest

from auv_gym.config import SimConfig
from auv_gym.simulator import Simulator


@pytest.fixture
def make_sim():
    """A seeded `Simulator` of n vehicles for the given env keyword arguments."""

    def _make(n: int = 1, seed: int = 0, **kwargs) -> Simulator:
        sim = Simulator(SimConfig.from_kwargs(**kwargs), n)
        for i in range(n):
            sim.reset_row(i, np.random.default_rng(seed + i))
        return sim

    return _make
