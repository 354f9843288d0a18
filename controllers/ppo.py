"""A trained stable-baselines3 PPO agent as a Policy: the saved files and their loader.

An agent directory holds::

    model.zip          the SB3 model (`PPO.save`)
    vecnormalize.npz   observation mean/var/clip/epsilon and obs_names: all a loaded agent needs
    vecnormalize.pkl   the full pickled `VecNormalize` (optional: for resuming and for RL Zoo)
    metadata.json      how it was trained (optional; `obs_names` is checked when present)

`load_policy` (or ``controllers.make("ppo", path=...)``) returns a `PPOPolicy`, which applies the
saved observation normalisation itself and follows the Policy protocol (`controllers.base`), so
the rollouts treat it exactly like FBSM. Training, checkpoints and export live on the benchmarks
side (`benchmarks.training`). Nothing here changes process-wide state: the torch thread count a
policy predicts with is set for each `predict` call and restored after it. torch and SB3 are
imported lazily: `import controllers.ppo` works without the rl extra.
"""

from __future__ import annotations

import contextlib
import json
import os
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym.observation import OBS_DIM, OBS_NAMES

__all__ = [
    "METADATA_FILE",
    "MODEL_FILE",
    "STATS_FILE",
    "VECNORM_FILE",
    "PPOPolicy",
    "load_policy",
]

MODEL_FILE = "model.zip"
STATS_FILE = "vecnormalize.npz"  # obs mean/var/clip/epsilon: all a loaded agent needs
VECNORM_FILE = "vecnormalize.pkl"  # the full VecNormalize (for resuming and for RL Zoo)
METADATA_FILE = "metadata.json"
ALGORITHM_CLASSES = {"ppo": "PPO", "sac": "SAC"}  # metadata "algo" → stable_baselines3 class


class PPOPolicy:
    """A trained PPO actor with its observation normalisation: the Policy protocol
    (docs/design.md §3).

    `predict` normalises like `VecNormalize` — clip((o − μ)/√(σ² + ε), −c, c) — then runs the
    SB3 actor with torch on `num_threads` intra-op threads (set for the call, then restored;
    None: torch's current setting). Stateless: `state` is returned unchanged, `episode_start`
    is ignored.
    """

    def __init__(
        self,
        sb3_policy: Any,
        obs_mean: np.ndarray,
        obs_var: np.ndarray,
        clip_obs: float,
        epsilon: float,
        metadata: dict[str, Any] | None = None,
        path: str | None = None,
        num_threads: int | None = None,
    ) -> None:
        if num_threads is not None and not (isinstance(num_threads, int) and num_threads >= 1):
            raise ValueError(f"num_threads must be a positive integer or None, got {num_threads!r}")
        self.sb3_policy = sb3_policy
        self.obs_mean = np.asarray(obs_mean, dtype=np.float64)
        self.obs_var = np.asarray(obs_var, dtype=np.float64)
        self.clip_obs = float(clip_obs)
        self.epsilon = float(epsilon)
        self.metadata = dict(metadata or {})
        self.path = path
        self.num_threads = num_threads
        self.observation_space = sb3_policy.observation_space
        self.action_space = sb3_policy.action_space
        sb3_policy.set_training_mode(False)

    def normalize(self, observation: np.ndarray) -> np.ndarray:
        """VecNormalize's observation transform with the saved statistics."""
        return np.clip(
            (observation - self.obs_mean) / np.sqrt(self.obs_var + self.epsilon),
            -self.clip_obs,
            self.clip_obs,
        )

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """Actions in [−1, 1]³ for observations (15,) or (n, 15) (layout `auv_gym.OBS_NAMES`)."""
        obs = np.asarray(observation, dtype=np.float32)
        if obs.ndim not in (1, 2) or obs.shape[-1] != OBS_DIM:
            raise ValueError(
                f"observation must have shape ({OBS_DIM},) or (n, {OBS_DIM}), got {obs.shape}"
            )
        single = obs.ndim == 1
        normed = self.normalize(obs.reshape(-1, OBS_DIM)).astype(np.float32)
        with _torch_threads(self.num_threads):
            action, _ = self.sb3_policy.predict(normed, deterministic=deterministic)
        return (action[0] if single else action), state

    def __repr__(self) -> str:
        return f"PPOPolicy(path={self.path!r})"


@contextlib.contextmanager
def _torch_threads(n: int | None) -> Iterator[None]:
    """torch on ``n`` intra-op threads inside the block, its previous setting after it."""
    if n is None:
        yield
        return
    import torch

    previous = torch.get_num_threads()
    if previous != n:
        torch.set_num_threads(n)
    try:
        yield
    finally:
        if previous != n:
            torch.set_num_threads(previous)


def _locate(path: Path) -> tuple[Path, Path | None, Path | None]:
    """(model zip, statistics file, metadata file) for an agent directory or a model zip.

    Directories hold `model.zip`; a zip is looked up with its statistics beside it
    (`vecnormalize.npz`, else `vecnormalize.pkl`, else RL Zoo's `<stem>/vecnormalize.pkl`).
    """
    if path.is_dir():
        model = path / MODEL_FILE
        if not model.is_file():
            raise FileNotFoundError(f"agent directory {path} has no {MODEL_FILE}")
    elif path.is_file():
        model = path
    else:
        raise FileNotFoundError(f"PPO agent {path} does not exist")
    folder = model.parent
    stats = None
    for candidate in (
        folder / STATS_FILE,
        folder / VECNORM_FILE,
        folder / model.stem / VECNORM_FILE,
    ):
        if candidate.is_file():
            stats = candidate
            break
    meta = folder / METADATA_FILE
    return model, stats, (meta if meta.is_file() else None)


def _read_stats(stats: Path) -> tuple[np.ndarray, np.ndarray, float, float, tuple[str, ...] | None]:
    """(mean, var, clip_obs, epsilon, obs_names or None) from a .npz or a pickled VecNormalize."""
    try:
        if stats.suffix == ".npz":
            with np.load(stats, allow_pickle=False) as data:
                names = tuple(str(n) for n in data["obs_names"]) if "obs_names" in data else None
                return (data["mean"], data["var"], float(data["clip_obs"]),
                        float(data["epsilon"]), names)  # fmt: skip
        import pickle

        with stats.open("rb") as f:
            vec_normalize = pickle.load(f)
        rms = vec_normalize.obs_rms
        return rms.mean, rms.var, float(vec_normalize.clip_obs), float(vec_normalize.epsilon), None
    except Exception as exc:
        raise ValueError(f"normalisation statistics {stats} are unreadable: {exc}") from exc


def load_policy(
    path: str | os.PathLike, *, device: str = "cpu", num_threads: int | None = 1
) -> PPOPolicy:
    """Load a PPO agent (directory with model.zip + vecnormalize.npz + metadata.json, or a zip);
    a SAC agent of the same layout when its metadata says ``"algo": "sac"``.

    Raises FileNotFoundError when the model or its normalisation statistics are missing, and
    ValueError naming the file when the zip is corrupt or the agent was trained for another
    observation layout (its `obs_names` differ from `auv_gym.OBS_NAMES`, or its observation
    space is not (15,)). `num_threads`: torch's intra-op threads while the policy predicts (1 is
    fastest for these small networks on this machine, docs/design.md §4; None: torch's setting);
    loading itself leaves torch's settings alone.
    """
    import stable_baselines3

    model_path, stats_path, meta_path = _locate(Path(path))
    if stats_path is None:
        raise FileNotFoundError(
            f"PPO agent {model_path}: normalisation statistics missing (expected "
            f"{model_path.parent / STATS_FILE} or {model_path.parent / VECNORM_FILE})"
        )
    metadata: dict[str, Any] = {}
    if meta_path is not None:
        try:
            metadata = json.loads(meta_path.read_text())
        except (OSError, json.JSONDecodeError) as exc:
            raise ValueError(f"agent metadata {meta_path} is unreadable: {exc}") from exc
    names = metadata.get("obs_names")
    if names is not None and tuple(names) != OBS_NAMES:
        raise ValueError(
            f"{meta_path}: agent trained for observation layout {list(names)}, this auv_gym has "
            f"{list(OBS_NAMES)}"
        )
    if not zipfile.is_zipfile(model_path):
        raise ValueError(f"PPO model {model_path} is not a valid zip file (corrupt or truncated)")
    # The harness trains PPO and SAC (benchmarks.training.config); metadata names the algorithm.
    algo = str(metadata.get("algo", "ppo"))
    if algo not in ALGORITHM_CLASSES:
        raise ValueError(f"{meta_path}: algo {algo!r} is not one of {sorted(ALGORITHM_CLASSES)}")
    algorithm = getattr(stable_baselines3, ALGORITHM_CLASSES[algo])
    # Schedules are not needed for inference; replacing them avoids unpickling closures.
    custom = {"learning_rate": 0.0, "lr_schedule": lambda _: 0.0, "clip_range": lambda _: 0.0}
    try:
        model = algorithm.load(model_path, device=device, custom_objects=custom)
    except Exception as exc:
        raise ValueError(f"PPO model {model_path} cannot be loaded: {exc}") from exc
    shape = tuple(model.observation_space.shape or ())
    if shape != (OBS_DIM,):
        raise ValueError(
            f"PPO model {model_path}: observation space shape {shape}, expected ({OBS_DIM},) "
            f"(layout {list(OBS_NAMES)})"
        )
    mean, var, clip_obs, epsilon, stat_names = _read_stats(stats_path)
    if stat_names is not None and stat_names != OBS_NAMES:
        raise ValueError(f"{stats_path}: statistics for observation layout {list(stat_names)}")
    if np.shape(mean) != (OBS_DIM,) or np.shape(var) != (OBS_DIM,):
        raise ValueError(
            f"{stats_path}: statistics of shape {np.shape(mean)}, expected ({OBS_DIM},)"
        )
    if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(var)) and np.all(var >= 0)):
        raise ValueError(f"{stats_path}: non-finite or negative normalisation statistics")
    return PPOPolicy(
        model.policy, mean, var, clip_obs, epsilon, metadata, str(model_path), num_threads
    )
