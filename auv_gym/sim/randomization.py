"""Per-episode draws of the task distribution: path, current, noise amplitude and actuator.

`draw_task` turns one episode's generator into an `EpisodeTask`. It first takes four 63-bit seeds
from that generator and draws each part from its own child generator, so the path of a seed does
not depend on whether the current or the noise is randomised too, and every part is a function of
the reset seed only (docs/model.md §3.8, §11.6). `task_for_seed` gives the task of the first
episode after ``reset(seed=k)`` without building an env, which is how task sets check that their
training and test episodes differ.

Domain randomisation (env arguments, documented ranges):

- ``random_current`` V [m/s] in [0, `MAX_RANDOM_CURRENT`]: a constant horizontal current of
  direction U[−π, π) and speed U[0, V] is added to the mean of ``current``;
- ``random_noise`` ε in [0, `MAX_RANDOM_NOISE`]: the white-noise amplitudes are scaled by
  1 + U[−ε, ε] (ε = 1: from none to twice the ``disturbance`` amplitude);
- ``actuator="random"``: "paper" or "fins", each with probability ½;
- ``param_uncertainty`` (already per episode, `vehicle.AUVParams.perturbed`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from gymnasium.utils import seeding

from auv_gym.paths.shapes import Path
from auv_gym.sim.path_depths import draw_path
from auv_gym.sim.path_generator import PathDistribution

if TYPE_CHECKING:
    from auv_gym.sim.config import SimConfig

__all__ = ["MAX_RANDOM_CURRENT", "MAX_RANDOM_NOISE", "EpisodeTask", "draw_task", "task_for_seed"]

# A REMUS 100 following at u_D = 1 m/s makes no headway against a current near 1 m/s.
MAX_RANDOM_CURRENT = 1.0  # [m/s]
MAX_RANDOM_NOISE = 1.0  # relative spread ε of the noise amplitude
RANDOM_ACTUATORS = ("paper", "fins")


@dataclass(frozen=True)
class EpisodeTask:
    """What one episode draws: its path, the current added to the configured mean [m/s] (NED),
    the factor on the white-noise amplitudes and the actuator model."""

    path: Path
    current: tuple[float, float, float]
    noise_scale: float
    actuator: str


def draw_task(config: SimConfig, rng: np.random.Generator) -> EpisodeTask:
    """The episode's task from its generator (consumes one draw of four 63-bit seeds)."""
    seeds = rng.integers(0, 2**63, size=4, dtype=np.int64)
    path_rng, current_rng, noise_rng, actuator_rng = (np.random.default_rng(int(s)) for s in seeds)
    path = config.path
    if isinstance(path, PathDistribution):  # a fixed path carries its offset already
        path = draw_path(config, path_rng)  # inside a depth envelope's band
    current = (0.0, 0.0, 0.0)
    if config.random_current > 0.0:
        direction = current_rng.uniform(-math.pi, math.pi)
        speed = current_rng.uniform(0.0, config.random_current)
        current = (speed * math.cos(direction), speed * math.sin(direction), 0.0)
    noise_scale = 1.0
    if config.random_noise > 0.0:
        noise_scale = 1.0 + noise_rng.uniform(-config.random_noise, config.random_noise)
    actuator = config.actuator
    if actuator == "random":
        actuator = RANDOM_ACTUATORS[int(actuator_rng.integers(len(RANDOM_ACTUATORS)))]
    return EpisodeTask(path, current, noise_scale, actuator)


def task_for_seed(config: SimConfig, seed: int) -> EpisodeTask:
    """The task of the first episode after ``reset(seed=seed)`` of an env with this config."""
    return draw_task(config, seeding.np_random(seed)[0])
