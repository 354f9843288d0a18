"""The simulation core: settings, the batched compiled step, the task and the observation.

- `config`, `config_args`: `SimConfig`, the envs' keyword arguments as validated settings and the
  packed row the compiled step reads;
- `simulator`: `Simulator`, the batched state both envs drive, its step kernels and episode
  table; `integrator`: RK4 and the control-period loop of one vehicle;
- `task`: reward terms and episode end; `safety_cost`: the constraint cost c ≥ 0;
- `observation`: the one definition of the observation; `preview`: the agent observation's
  extra entries; `navigation`: the estimate the observation is computed from when sensors are
  modelled;
- `episode_start`, `randomization`, `path_generator`: what a reset draws (the start, the task,
  a random path: `PathDistribution`);
- `trajectory`: a recorded episode (`Trajectory`) and its file.

Imports the rooms below it (`auv_gym.support`, `auv_gym.paths`, `auv_gym.vehicle`,
`auv_gym.ocean`); never the env API above it.
"""

from __future__ import annotations

from auv_gym.sim.config import SimConfig
from auv_gym.sim.observation import (
    OBS_HIGH,
    OBS_INDEX,
    OBS_LOW,
    OBS_NAMES,
    OBS_UNITS,
    ObservationConfig,
)
from auv_gym.sim.path_generator import PathDistribution
from auv_gym.sim.safety_cost import SafetyCost
from auv_gym.sim.simulator import Simulator
from auv_gym.sim.task import REWARD_TERMS, TERMINATION_REASONS, RewardWeights
from auv_gym.sim.trajectory import Trajectory

__all__ = [
    "OBS_HIGH",
    "OBS_INDEX",
    "OBS_LOW",
    "OBS_NAMES",
    "OBS_UNITS",
    "REWARD_TERMS",
    "TERMINATION_REASONS",
    "ObservationConfig",
    "PathDistribution",
    "RewardWeights",
    "SafetyCost",
    "SimConfig",
    "Simulator",
    "Trajectory",
]
