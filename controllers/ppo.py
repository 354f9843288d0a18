"""PPO baselines with stable-baselines3: configuration, training, checkpoints and the loaded agent.

Training (`train`, CLI `benchmarks/train_ppo.py`) reads an RL-Zoo hyper-parameter file
(`benchmarks/hyperparams/ppo.yml`, top-level key = the env id), normalises observations (and
rewards) with `VecNormalize`, evaluates on the paper scenario (helix, white noise ±35 N / N·m)
with fixed seeds, and writes, under the run directory::

    final/      model.zip, vecnormalize.pkl, vecnormalize.npz, metadata.json: the final agent
    best/       the same files for the best evaluation so far
    metadata.json                                                    copy of final/metadata.json
    checkpoints/step_<num_timesteps>/   the same files, every `checkpoint_freq` env steps
    evaluations.csv                     the learning curve (env steps, wall time, rms distance)
    tb/                                 TensorBoard logs

Every agent directory is complete on its own (model, normalisation statistics, metadata with the
command line, configuration, seed, package versions, wall time and the observation layout), and
each is written to a temporary directory first and renamed into place, so a killed run never
leaves a half-written agent. `resume=True` restarts from the newest checkpoint with
`reset_num_timesteps=False`, losing at most one checkpoint interval.

Loading (`load_policy`, or `controllers.make("ppo", path=...)`) returns a `PPOPolicy`, which
applies the saved observation normalisation itself and follows the Policy protocol of
DESIGN.md §3, so the evaluation code treats it exactly like FBSM. torch and SB3 are imported
lazily: `import controllers.ppo` works without the rl extra.
"""

from __future__ import annotations

import csv
import datetime as _dt
import json
import math
import os
import platform
import re
import shutil
import sys
import time
import zipfile
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from importlib import metadata as _metadata
from pathlib import Path
from typing import Any

import numpy as np

import auv_gym
from auv_gym.observation import OBS_DIM, OBS_NAMES

__all__ = [
    "EVAL_SEEDS",
    "HELD_OUT_SEEDS",
    "PPOPolicy",
    "TrainOptions",
    "ZooConfig",
    "evaluate_policy_on_seeds",
    "load_policy",
    "read_zoo_config",
    "train",
]

ENV_ID = "AUVPath3D-v0"
MODEL_FILE = "model.zip"
STATS_FILE = "vecnormalize.npz"  # obs mean/var/clip/epsilon: all a loaded agent needs
VECNORM_FILE = "vecnormalize.pkl"  # the full VecNormalize (for resuming and for RL Zoo)
METADATA_FILE = "metadata.json"
EVAL_FILE = "evaluations.csv"
HELD_OUT_FILE = "held_out_evaluation.json"  # written beside an exported agent
# Seeds: the evaluation callback uses EVAL_SEEDS; reported results use HELD_OUT_SEEDS (the
# seeds 0..9 of benchmarks/compare.py); training environments are seeded from
# TRAIN_SEED_BASE + 1000·seed upwards, so none of them is ever a training seed.
EVAL_SEEDS = (100, 101, 102, 103, 104)
HELD_OUT_SEEDS = tuple(range(10))
TRAIN_SEED_BASE = 1_000_000
TRANSIENT = 100.0  # [s] rms_distance is measured over t ≥ 100 s (MODEL.md §8)
# RL-Zoo keys this trainer understands; anything else in the YAML section is an error.
_ZOO_KEYS = {"n_envs", "n_timesteps", "policy", "normalize", "policy_kwargs", "env_kwargs"}
_PPO_KEYS = {
    "learning_rate", "n_steps", "batch_size", "n_epochs", "gamma", "gae_lambda", "clip_range",
    "clip_range_vf", "normalize_advantage", "ent_coef", "vf_coef", "max_grad_norm", "use_sde",
    "sde_sample_freq", "target_kl", "stats_window_size",
}  # fmt: skip


# --------------------------------------------------------------------------------------------
# Configuration (RL-Zoo format)


@dataclass(frozen=True)
class ZooConfig:
    """One env's section of an RL-Zoo hyper-parameter file, validated.

    `normalize` holds the `VecNormalize` keyword arguments ({} = no normalisation);
    `ppo_kwargs` the PPO constructor arguments, with "lin_<x>" schedules still as strings.
    """

    n_envs: int
    n_timesteps: int
    policy: str
    normalize: dict[str, Any]
    policy_kwargs: dict[str, Any]
    env_kwargs: dict[str, Any]
    ppo_kwargs: dict[str, Any]
    raw: dict[str, Any] = field(default_factory=dict)


def read_zoo_config(path: str | os.PathLike, env_id: str = ENV_ID) -> ZooConfig:
    """Parse the `env_id` section of an RL-Zoo YAML file (rl_zoo3 2.x semantics).

    `normalize` may be a bool, a dict or a string evaluating to a dict, as in RL Zoo; the
    discount `gamma` is copied into it like RL Zoo does. `policy_kwargs` may be a dict or a
    string such as "dict(net_arch=[64, 64])" (evaluated with only `dict` and `torch.nn`).
    """
    import yaml

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"hyper-parameter file {path} does not exist")
    with path.open() as f:
        data = yaml.safe_load(f)
    if not isinstance(data, dict) or env_id not in data:
        raise ValueError(f"{path}: no top-level key {env_id!r}")
    section = dict(data[env_id])
    unknown = set(section) - _ZOO_KEYS - _PPO_KEYS
    if unknown:
        raise ValueError(f"{path}: unsupported keys for {env_id}: {sorted(unknown)}")
    for key in ("n_timesteps", "policy"):
        if key not in section:
            raise ValueError(f"{path}: {env_id} needs {key!r}")
    n_envs = int(section.get("n_envs", 1))
    n_timesteps = int(float(section["n_timesteps"]))
    if n_envs < 1 or n_timesteps < 1:
        raise ValueError(f"{path}: n_envs and n_timesteps must be positive")
    ppo_kwargs = {k: section[k] for k in _PPO_KEYS if k in section}
    normalize = section.get("normalize", False)
    if isinstance(normalize, str):
        normalize = _eval_kwargs(normalize, path, "normalize")
    if normalize is True:
        normalize = {}
        norm_enabled = True
    elif normalize is False:
        norm_enabled = False
        normalize = {}
    elif isinstance(normalize, dict):
        norm_enabled = True
    else:
        raise ValueError(f"{path}: normalize must be a bool, a dict or a dict expression")
    if norm_enabled:
        normalize = {"norm_obs": True, "norm_reward": True, **normalize}
        if "gamma" in ppo_kwargs:
            normalize["gamma"] = float(ppo_kwargs["gamma"])
        if not normalize["norm_obs"]:
            raise ValueError(f"{path}: this project requires observation normalisation")
    else:
        raise ValueError(f"{path}: normalize must be enabled (VecNormalize, DESIGN.md §3)")
    policy_kwargs = section.get("policy_kwargs", {})
    if isinstance(policy_kwargs, str):
        policy_kwargs = _eval_kwargs(policy_kwargs, path, "policy_kwargs")
    env_kwargs = dict(section.get("env_kwargs") or {})
    return ZooConfig(
        n_envs=n_envs, n_timesteps=n_timesteps, policy=str(section["policy"]),
        normalize=normalize, policy_kwargs=dict(policy_kwargs), env_kwargs=env_kwargs,
        ppo_kwargs=ppo_kwargs, raw=section,
    )  # fmt: skip


def _eval_kwargs(text: str, path: Path, key: str) -> dict[str, Any]:
    import torch

    try:
        value = eval(text, {"__builtins__": {}}, {"dict": dict, "nn": torch.nn})
    except Exception as exc:
        raise ValueError(f"{path}: cannot evaluate {key} {text!r}: {exc}") from exc
    if not isinstance(value, dict):
        raise ValueError(f"{path}: {key} must evaluate to a dict, got {type(value).__name__}")
    return value


def _schedule(value: Any) -> Any:
    """RL-Zoo schedules: "lin_<x>" decays linearly from x to 0; numbers stay constant."""
    if isinstance(value, str):
        match = re.fullmatch(r"lin_([0-9.eE+-]+)", value)
        if not match:
            raise ValueError(f"schedule {value!r} is not a number or 'lin_<x>'")
        from stable_baselines3.common.utils import LinearSchedule

        return LinearSchedule(float(match.group(1)), 0.0, 1.0)
    return float(value)


# --------------------------------------------------------------------------------------------
# The loaded agent


class PPOPolicy:
    """A trained PPO actor with its observation normalisation: the Policy protocol (DESIGN.md §3).

    `predict` normalises like `VecNormalize` — clip((o − μ)/√(σ² + ε), −c, c) — then runs the
    SB3 actor. Stateless: `state` is returned unchanged, `episode_start` is ignored.
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
    ) -> None:
        self.sb3_policy = sb3_policy
        self.obs_mean = np.asarray(obs_mean, dtype=np.float64)
        self.obs_var = np.asarray(obs_var, dtype=np.float64)
        self.clip_obs = float(clip_obs)
        self.epsilon = float(epsilon)
        self.metadata = dict(metadata or {})
        self.path = path
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
        action, _ = self.sb3_policy.predict(normed, deterministic=deterministic)
        return (action[0] if single else action), state

    def __repr__(self) -> str:
        return f"PPOPolicy(path={self.path!r})"


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
    """Load a PPO agent (directory with model.zip + vecnormalize.npz + metadata.json, or a zip).

    Raises FileNotFoundError when the model or its normalisation statistics are missing, and
    ValueError naming the file when the zip is corrupt or the agent was trained for another
    observation layout (its `obs_names` differ from `auv_gym.OBS_NAMES`, or its observation
    space is not (15,)). `num_threads` sets torch's intra-op threads (1 is fastest for
    these small networks on this machine, DESIGN.md §4; None leaves torch alone).
    """
    import torch
    from stable_baselines3 import PPO

    if num_threads is not None:
        torch.set_num_threads(int(num_threads))
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
    # Schedules are not needed for inference; replacing them avoids unpickling closures.
    custom = {"learning_rate": 0.0, "lr_schedule": lambda _: 0.0, "clip_range": lambda _: 0.0}
    try:
        model = PPO.load(model_path, device=device, custom_objects=custom)
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
    return PPOPolicy(model.policy, mean, var, clip_obs, epsilon, metadata, str(model_path))


# --------------------------------------------------------------------------------------------
# Evaluation


def evaluate_policy_on_seeds(
    policy: Any,
    seeds: Sequence[int] = HELD_OUT_SEEDS,
    transient: float = TRANSIENT,
    **env_kwargs: Any,
) -> list[dict[str, Any]]:
    """Seeded episodes of `policy` through `auv_gym.evaluation.evaluate` (batched rows).

    Returns one dict per seed with seed, rms_distance and rms_x_e, rms_y_e, rms_z_e [m] over
    t ≥ transient (NaN if the episode ended earlier), max_distance [m] over that window,
    duration [s] and termination_reason ("" when the episode ran to max_time).
    """
    from auv_gym import evaluation

    results = evaluation.evaluate(policy, list(seeds), transient=transient, **env_kwargs)
    return [
        {"seed": int(r["seed"]), "rms_distance": float(r["rms_distance"]),
         "rms_x_e": float(r["rms_x_e"]), "rms_y_e": float(r["rms_y_e"]),
         "rms_z_e": float(r["rms_z_e"]),
         "max_distance": float(r["max_distance_window"]), "duration": float(r["duration"]),
         "termination_reason": "" if r["termination_reason"] == "time_limit"
         else str(r["termination_reason"])}
        for r in results
    ]  # fmt: skip


def summarize(results: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Mean ± std of rms_distance over seeds and the number of terminated episodes."""
    rms = np.array([r["rms_distance"] for r in results], dtype=float)
    terminated = [r["termination_reason"] for r in results if r["termination_reason"]]
    finite = rms[np.isfinite(rms)]
    per_axis = {}
    for key in ("rms_x_e", "rms_y_e", "rms_z_e"):
        values = np.array([r.get(key, math.nan) for r in results], dtype=float)
        values = values[np.isfinite(values)]
        per_axis[f"{key}_mean"] = float(values.mean()) if values.size else math.nan
    return {
        **per_axis,
        "rms_distance_mean": float(finite.mean()) if finite.size else math.nan,
        "rms_distance_std": float(finite.std()) if finite.size else math.nan,
        "rms_distance_max": float(finite.max()) if finite.size else math.nan,
        "n_episodes": len(results),
        "n_terminated": len(terminated),
        "terminations": sorted(set(terminated)),
    }


def _score(summary: dict[str, Any]) -> tuple[int, float]:
    """Lower is better: first fewer terminated episodes, then lower mean rms distance."""
    mean = summary["rms_distance_mean"]
    return summary["n_terminated"], (mean if math.isfinite(mean) else math.inf)


# --------------------------------------------------------------------------------------------
# Training


@dataclass
class TrainOptions:
    """Arguments of `train` (and of the CLI `benchmarks/train_ppo.py`)."""

    config: str = "benchmarks/hyperparams/ppo.yml"  # RL-Zoo hyper-parameter file
    env_id: str = ENV_ID  # top-level key of the config and Gymnasium id
    out: str = "runs/ppo_helix"  # run directory
    seed: int = 0  # seeds torch, numpy and the training environments
    n_timesteps: int | None = None  # override the config's n_timesteps
    resume: bool = False  # continue from the newest checkpoint in `out`
    checkpoint_freq: int = 100_000  # [env steps] between checkpoints
    keep_checkpoints: int = 3  # newest checkpoints kept on disk
    eval_freq: int = 100_000  # [env steps] between evaluations; 0 disables
    eval_seeds: tuple[int, ...] = EVAL_SEEDS  # seeds of the evaluation episodes
    eval_duration: float = 300.0  # [s] evaluation episode length (paper scenario)
    vec_env: str = "auto"  # "auto" (native batched if available), "native" or "dummy"
    threads: int = 1  # torch intra-op and numba threads
    progress_bar: bool = True
    export: str | None = None  # copy the best agent here at the end (e.g. benchmarks/agents/x)
    verbose: int = 0


def package_versions() -> dict[str, str]:
    """Versions of Python and the packages that determine a training run."""
    versions = {"python": platform.python_version()}
    for name in ("auv-gym", "numpy", "numba", "gymnasium", "stable-baselines3", "torch"):
        try:
            versions[name] = _metadata.version(name)
        except _metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions


def _git_commit() -> str | None:
    head = Path(__file__).resolve().parent.parent / ".git"
    try:
        ref = (head / "HEAD").read_text().strip()
        if ref.startswith("ref: "):
            return (head / ref[5:]).read_text().strip()
        return ref
    except OSError:
        return None


def write_json_atomic(path: Path, data: dict[str, Any]) -> None:
    """Write JSON through a temporary file in the same directory, then rename."""
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    tmp.write_text(json.dumps(data, indent=2, sort_keys=True, default=str) + "\n")
    os.replace(tmp, path)


def save_agent(model: Any, vec_normalize: Any, folder: Path, metadata: dict[str, Any]) -> None:
    """Write model.zip, vecnormalize.pkl/.npz and metadata.json into `folder`, atomically.

    Files go to a sibling temporary directory which then replaces `folder` (rename), so readers
    see either the previous complete agent or the new one.
    """
    folder = Path(folder)
    folder.parent.mkdir(parents=True, exist_ok=True)
    tmp = folder.with_name(f".{folder.name}.tmp{os.getpid()}")
    if tmp.exists():
        shutil.rmtree(tmp)
    tmp.mkdir()
    model.save(tmp / MODEL_FILE)
    vec_normalize.save(str(tmp / VECNORM_FILE))
    rms = vec_normalize.obs_rms
    np.savez(
        tmp / STATS_FILE, mean=rms.mean, var=rms.var, count=np.float64(rms.count),
        clip_obs=np.float64(vec_normalize.clip_obs), epsilon=np.float64(vec_normalize.epsilon),
        obs_names=np.array(OBS_NAMES),
    )  # fmt: skip
    write_json_atomic(tmp / METADATA_FILE, metadata)
    _swap_folder(tmp, folder)


def policy_from_model(model: Any, vec_normalize: Any) -> PPOPolicy:
    """The Policy of a model in training, with a snapshot of the current statistics."""
    rms = vec_normalize.obs_rms
    return PPOPolicy(model.policy, rms.mean.copy(), rms.var.copy(), vec_normalize.clip_obs,
                     vec_normalize.epsilon)  # fmt: skip


def make_training_env(n_envs: int, seed: int, env_kwargs: dict[str, Any], kind: str = "auto",
                      env_id: str = ENV_ID) -> Any:  # fmt: skip
    """An SB3 VecEnv of `n_envs` training environments.

    "native": `auv_gym.sb3` over the batched `AUVPath3DVectorEnv` (one compiled call per step);
    "dummy": SB3's DummyVecEnv over `gym.make`; "auto": native when available.
    """
    if kind not in ("auto", "native", "dummy"):
        raise ValueError(f"vec_env must be 'auto', 'native' or 'dummy', got {kind!r}")
    env_seed = TRAIN_SEED_BASE + 1000 * int(seed)
    if kind in ("auto", "native") and env_id == ENV_ID:
        from stable_baselines3.common.vec_env import VecMonitor

        from auv_gym.sb3 import make_sb3_vec_env

        return VecMonitor(make_sb3_vec_env(n_envs, seed=env_seed, **env_kwargs))
    if kind == "native":
        raise ValueError(f"the native vector env simulates {ENV_ID} only, not {env_id}")
    from stable_baselines3.common.env_util import make_vec_env

    return make_vec_env(env_id, n_envs=n_envs, seed=env_seed, env_kwargs=env_kwargs)


def _describe(venv: Any) -> str:
    """The chain of VecEnv wrappers, outermost first ("VecNormalize<VecMonitor<SB3VecEnv>>")."""
    names = []
    while venv is not None:
        names.append(type(venv).__name__)
        venv = getattr(venv, "venv", None)
    return "<".join(names) + ">" * (len(names) - 1)


def _checkpoints(out: Path) -> list[tuple[int, Path]]:
    found = []
    folder = out / "checkpoints"
    if folder.is_dir():
        for p in folder.iterdir():
            m = re.fullmatch(r"step_(\d+)", p.name)
            if m and (p / MODEL_FILE).is_file() and (p / VECNORM_FILE).is_file():
                found.append((int(m.group(1)), p))
    return sorted(found)


def latest_checkpoint(out: str | os.PathLike) -> Path | None:
    """The newest complete checkpoint directory of a run, or None."""
    found = _checkpoints(Path(out))
    return found[-1][1] if found else None


def _make_callbacks(
    opts: TrainOptions,
    out: Path,
    metadata_fn: Callable[[Any], dict[str, Any]],
    eval_kwargs: dict[str, Any],
    start_wall: float,
    best: dict[str, Any],
) -> list:
    from stable_baselines3.common.callbacks import BaseCallback

    class CheckpointAndEval(BaseCallback):
        """Checkpoints (model + statistics + metadata) and paper-scenario evaluations."""

        def __init__(self) -> None:
            super().__init__()
            self.t0 = time.monotonic()
            self.next_ckpt = 0
            self.next_eval = 0

        def _on_training_start(self) -> None:
            n = self.num_timesteps
            self.next_ckpt = (n // opts.checkpoint_freq + 1) * opts.checkpoint_freq
            if opts.eval_freq > 0:
                self.next_eval = (n // opts.eval_freq + 1) * opts.eval_freq
                if n == 0:
                    self.evaluate()  # the untrained agent: the curve starts at step 0

        def _on_step(self) -> bool:
            if opts.eval_freq > 0 and self.num_timesteps >= self.next_eval:
                self.next_eval += opts.eval_freq
                self.evaluate()
            if self.num_timesteps >= self.next_ckpt:
                self.next_ckpt += opts.checkpoint_freq
                self.checkpoint()
            return True

        def evaluate(self) -> None:
            vec_normalize = self.model.get_vec_normalize_env()
            policy = policy_from_model(self.model, vec_normalize)
            results = evaluate_policy_on_seeds(policy, opts.eval_seeds, **eval_kwargs)
            summary = summarize(results)
            self.model.policy.set_training_mode(False)
            wall = start_wall + (time.monotonic() - self.t0)
            self.logger.record("eval/rms_distance_mean", summary["rms_distance_mean"])
            self.logger.record("eval/n_terminated", summary["n_terminated"])
            row = [self.num_timesteps, f"{wall:.1f}", f"{summary['rms_distance_mean']:.6g}",
                   f"{summary['rms_distance_std']:.6g}", f"{summary['rms_distance_max']:.6g}",
                   summary["n_terminated"]]  # fmt: skip
            _append_eval_row(out / EVAL_FILE, row)
            if best.get("score") is None or _score(summary) < tuple(best["score"]):
                best["score"] = list(_score(summary))
                best["num_timesteps"] = self.num_timesteps
                best["summary"] = summary
                meta = metadata_fn({"evaluation": summary, "eval_results": results})
                save_agent(self.model, vec_normalize, out / "best", meta)
            if opts.verbose:
                print(f"[eval] steps={self.num_timesteps} wall={wall:.0f}s {summary}", flush=True)

        def checkpoint(self) -> None:
            folder = out / "checkpoints" / f"step_{self.num_timesteps:010d}"
            save_agent(self.model, self.model.get_vec_normalize_env(), folder, metadata_fn({}))
            for _, old in _checkpoints(out)[: -max(1, opts.keep_checkpoints)]:
                shutil.rmtree(old, ignore_errors=True)

    return [CheckpointAndEval()]


EVAL_HEADER = ["num_timesteps", "wall_time_s", "rms_distance_mean", "rms_distance_std",
               "rms_distance_max", "n_terminated"]  # fmt: skip


def _append_eval_row(path: Path, row: list) -> None:
    new = not path.exists()
    with path.open("a", newline="") as f:
        writer = csv.writer(f)
        if new:
            writer.writerow(EVAL_HEADER)
        writer.writerow(row)
        f.flush()
        os.fsync(f.fileno())


def _truncate_eval_rows(path: Path, max_steps: int) -> None:
    """Drop learning-curve rows past the checkpoint a resumed run restarts from."""
    if not path.exists():
        return
    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    kept = [rows[0]] + [r for r in rows[1:] if r and int(r[0]) <= max_steps]
    tmp = path.with_name(f".{path.name}.tmp")
    with tmp.open("w", newline="") as f:
        csv.writer(f).writerows(kept)
    os.replace(tmp, path)


def train(opts: TrainOptions, argv: Sequence[str] | None = None) -> Path:
    """Train (or resume) PPO as configured; returns the run directory. See the module docstring."""
    import numba
    import stable_baselines3
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.utils import set_random_seed
    from stable_baselines3.common.vec_env import VecNormalize

    # One thread for torch and for the numba simulator kernel: on this 2-core machine shared
    # with other jobs, two-threaded kernels stall at their barriers (DESIGN.md §4).
    torch.set_num_threads(int(opts.threads))
    numba.set_num_threads(min(int(opts.threads), numba.config.NUMBA_NUM_THREADS))
    cfg = read_zoo_config(opts.config, opts.env_id)
    n_timesteps = int(opts.n_timesteps or cfg.n_timesteps)
    if opts.checkpoint_freq < 1:
        raise ValueError("checkpoint_freq must be a positive number of env steps")
    out = Path(opts.out)
    if out.exists() and any(out.iterdir()) and not opts.resume:
        raise ValueError(f"run directory {out} is not empty; pass --resume or another --out")
    out.mkdir(parents=True, exist_ok=True)
    eval_kwargs = {"max_time": float(opts.eval_duration)}  # the paper scenario: defaults
    set_random_seed(opts.seed)
    venv = make_training_env(cfg.n_envs, opts.seed, cfg.env_kwargs, opts.vec_env, opts.env_id)

    previous: dict[str, Any] = {}
    checkpoint = latest_checkpoint(out) if opts.resume else None
    if opts.resume and checkpoint is None:
        raise FileNotFoundError(f"--resume: no complete checkpoint under {out / 'checkpoints'}")
    if checkpoint is not None:
        previous = json.loads((checkpoint / METADATA_FILE).read_text())
        venv = VecNormalize.load(str(checkpoint / VECNORM_FILE), venv)
        venv.training = True
        model = PPO.load(checkpoint / MODEL_FILE, env=venv, device="cpu",
                         tensorboard_log=str(out / "tb"), verbose=opts.verbose)  # fmt: skip
        _truncate_eval_rows(out / EVAL_FILE, model.num_timesteps)
    else:
        venv = VecNormalize(venv, **cfg.normalize)
        kwargs = dict(cfg.ppo_kwargs)
        for key in ("learning_rate", "clip_range"):
            if key in kwargs:
                kwargs[key] = _schedule(kwargs[key])
        model = PPO(cfg.policy, venv, policy_kwargs=cfg.policy_kwargs, seed=opts.seed,
                    device="cpu", tensorboard_log=str(out / "tb"), verbose=opts.verbose,
                    **kwargs)  # fmt: skip
    start_wall = float(previous.get("wall_time_s", 0.0))
    best: dict[str, Any] = dict(previous.get("best", {}))
    sessions = [*previous.get("sessions", []), {
        "argv": list(argv if argv is not None else sys.argv),
        "started": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "resumed_from": None if checkpoint is None else str(checkpoint),
        "start_timesteps": int(model.num_timesteps),
    }]  # fmt: skip
    t0 = time.monotonic()
    commit = _git_commit()  # the code this session started from

    def metadata(extra: dict[str, Any]) -> dict[str, Any]:
        return {
            "algo": "ppo", "env_id": opts.env_id, "seed": opts.seed,
            "num_timesteps": int(model.num_timesteps), "n_timesteps": n_timesteps,
            "wall_time_s": start_wall + (time.monotonic() - t0),
            "command": " ".join(sessions[0]["argv"]), "sessions": sessions,
            "options": asdict(opts), "config_file": str(opts.config), "config": cfg.raw,
            "env_kwargs": cfg.env_kwargs, "eval_env_kwargs": eval_kwargs,
            "eval_seeds": list(opts.eval_seeds), "obs_names": list(OBS_NAMES),
            "observation_shape": [OBS_DIM], "action_shape": [3],
            "versions": package_versions(), "sb3_version": stable_baselines3.__version__,
            "git_commit": commit, "vec_env": _describe(venv),
            "torch_threads": torch.get_num_threads(), "cpu_count": os.cpu_count(),
            "best": best, "auv_gym_version": auv_gym.__version__, **extra,
        }  # fmt: skip

    callbacks = _make_callbacks(opts, out, metadata, eval_kwargs, start_wall, best)
    remaining = n_timesteps - int(model.num_timesteps)
    if remaining > 0:
        model.learn(remaining, callback=callbacks, progress_bar=opts.progress_bar,
                    reset_num_timesteps=checkpoint is None, tb_log_name="PPO")  # fmt: skip
    final_meta = metadata({})
    _save_final(model, venv, out, final_meta)
    venv.close()
    if opts.export:
        source = out / "best" if (out / "best" / MODEL_FILE).is_file() else out / "final"
        export_agent(source, Path(opts.export))
        write_json_atomic(Path(opts.export) / HELD_OUT_FILE,
                          held_out_evaluation(Path(opts.export), opts.eval_duration))  # fmt: skip
    return out


def held_out_evaluation(agent: str | os.PathLike, duration: float = 300.0) -> dict[str, Any]:
    """An agent on the paper scenario over the held-out seeds 0-9: summary and per-seed results."""
    policy = load_policy(agent)
    results = evaluate_policy_on_seeds(policy, HELD_OUT_SEEDS, max_time=float(duration))
    return {
        "scenario": "paper (helix, white noise ±35 N / N·m, defaults of AUVPath3D-v0)",
        "seeds": list(HELD_OUT_SEEDS), "duration_s": float(duration), "transient_s": TRANSIENT,
        "summary": summarize(results), "results": results,
        "agent_num_timesteps": policy.metadata.get("num_timesteps"),
        "agent_wall_time_s": policy.metadata.get("wall_time_s"),
    }  # fmt: skip


def _save_final(model: Any, venv: Any, out: Path, meta: dict[str, Any]) -> None:
    """The final agent in `out/final` (a complete agent directory, written atomically)."""
    save_agent(model, venv, out / "final", meta)
    write_json_atomic(out / METADATA_FILE, meta)


def export_agent(source: Path, target: Path) -> None:
    """Copy an agent directory (model.zip, vecnormalize.npz, metadata.json) atomically.

    The pickled VecNormalize is left out: a shipped agent needs only the .npz statistics.
    """
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = target.with_name(f".{target.name}.tmp{os.getpid()}")
    if tmp.exists():
        shutil.rmtree(tmp)
    tmp.mkdir()
    for name in (MODEL_FILE, STATS_FILE, METADATA_FILE):
        shutil.copy2(source / name, tmp / name)
    _swap_folder(tmp, target)


def _swap_folder(tmp: Path, target: Path) -> None:
    """Put the complete folder ``tmp`` in place of ``target`` with renames only (atomic swap)."""
    old = target.with_name(f".{target.name}.old{os.getpid()}")
    if target.exists():
        os.replace(target, old)
    os.replace(tmp, target)
    if old.exists():
        shutil.rmtree(old)
