"""The env API: `AUVPath3D-v0` and its variants as Gymnasium envs.

- `env`: `AUVPath3DEnv`, the single env; `vector_env`: `AUVPath3DVectorEnv`, the native vector
  env (one `Simulator` for all vehicles), with its reset arguments in `vector_reset`;
- `checks`: the boundary checks both envs share; `info`: the ``info`` of both envs;
- `rendering`: ``render_mode="rgb_array"`` frames (`EpisodeRenderer`), drawing the depth
  envelope with `envelope_drawing`;
- `sb3`: the vector env as a stable-baselines3 ``VecEnv`` (imports stable-baselines3, so it is
  not imported here: ``from auv_gym.envs.sb3 import make_sb3_vec_env``).

Imports the simulation core and the rooms below it.
"""

from __future__ import annotations

from auv_gym.envs.env import AUVPath3DEnv
from auv_gym.envs.rendering import EpisodeRenderer
from auv_gym.envs.vector_env import AUVPath3DVectorEnv

__all__ = ["AUVPath3DEnv", "AUVPath3DVectorEnv", "EpisodeRenderer"]
