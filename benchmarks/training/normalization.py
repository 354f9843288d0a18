"""Observation normalisation with some entries at fixed physical scales (`obs_scales`).

`VecNormalize` divides every observation entry by its running standard deviation over the whole
run. For the path errors that standard deviation is set by the first, clumsy episodes (x_e, y_e,
z_e: 3.9–5.1 m in the shipped 256-256 generalist), so the centimetre errors a trained agent
should resolve arrive at the network as a few hundredths: a 0.2-m depth offset moves its input
by 0.05 (docs/results.md, "Where the remaining error sits"). An ``obs_scales`` entry in a
hyper-parameter file pins named entries to mean 0 and a fixed scale instead, e.g.
``obs_scales: {x_e: 0.5, y_e: 0.5, z_e: 0.5}`` [the entry's unit]: the network sees e/0.5 m,
clipped at ±clip_obs (±5 m for the default clip of 10). Every other entry keeps its running
statistics. The saved ``vecnormalize.npz`` holds the pinned mean and variance, so a loaded agent
(`controllers.agent.AgentPolicy`) normalises exactly as in training with no extra file.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from stable_baselines3.common.running_mean_std import RunningMeanStd

__all__ = ["PinnedRunningMeanStd", "parse_obs_scales", "pin_observation_scales"]


class PinnedRunningMeanStd(RunningMeanStd):
    """Running mean and variance whose entries `index` stay at mean 0 and variance scale²."""

    def __init__(self, base: RunningMeanStd, index: np.ndarray, scale: np.ndarray) -> None:
        super().__init__(epsilon=base.count, shape=base.mean.shape)
        self.mean = base.mean.copy()
        self.var = base.var.copy()
        self.count = base.count
        self.index = np.asarray(index, dtype=np.intp)
        self.scale = np.asarray(scale, dtype=np.float64)
        self._pin()

    def _pin(self) -> None:
        self.mean[self.index] = 0.0
        self.var[self.index] = self.scale**2

    def update(self, arr: np.ndarray) -> None:
        super().update(arr)
        self._pin()

    def update_from_moments(
        self, batch_mean: np.ndarray, batch_var: np.ndarray, batch_count: float
    ) -> None:
        super().update_from_moments(batch_mean, batch_var, batch_count)
        self._pin()


def parse_obs_scales(value: Any, where: str) -> dict[str, float]:
    """{entry name: scale > 0, finite} from a hyper-parameter file, or a named error."""
    if not isinstance(value, Mapping) or not value:
        raise ValueError(
            f"{where}: obs_scales must be a non-empty mapping {{entry: scale}}, got {value!r}"
        )
    scales = {}
    for name, scale in value.items():
        number = isinstance(scale, (int, float)) and not isinstance(scale, bool)
        if not isinstance(name, str) or not number or not (math.isfinite(scale) and scale > 0):
            raise ValueError(
                f"{where}: obs_scales[{name!r}] must be a finite number > 0 (the "
                f"entry's unit), got {scale!r}"
            )
        scales[name] = float(scale)
    return scales


def pin_observation_scales(
    vec_normalize: Any, obs_names: Sequence[str], scales: Mapping[str, float]
) -> None:
    """Replace `vec_normalize.obs_rms` by one that keeps the entries named in `scales` at mean 0
    and standard deviation `scales[name]`; unknown names are an error naming the valid ones."""
    names = list(obs_names)
    unknown = sorted(set(scales) - set(names))
    if unknown:
        raise ValueError(
            f"obs_scales: unknown observation entries {unknown}; this env's entries are {names}"
        )
    index = np.array([names.index(n) for n in scales], dtype=np.intp)
    scale = np.array(list(scales.values()), dtype=np.float64)
    vec_normalize.obs_rms = PinnedRunningMeanStd(vec_normalize.obs_rms, index, scale)
