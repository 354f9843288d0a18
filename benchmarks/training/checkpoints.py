"""Agent directories of a training run: saving, checkpoints, resuming and export.

Every agent directory (`final/`, `best/`, `checkpoints/step_<num_timesteps>/`, an exported agent)
is complete on its own — model, normalisation statistics, metadata — in the layout
`controllers.loader.load_policy` reads, and each is written through `auv_gym.support.files.
write_folder_atomic`, so a killed run never leaves a half-written agent.

A checkpoint also holds the training state (`TRAINING_STATE_FILE`, `capture_training_state`)
that model.zip and vecnormalize.pkl leave out: the random generators (python, numpy, torch, the
action space's, the gSDE noise and action noise), the training env mid-episode (every vehicle's
state, task draws, generators and step counters; the episode counters of VecMonitor and the
discounted returns of VecNormalize) and the last observation the algorithm holds, and the
evaluation and checkpoint schedules. Checkpoints are taken where SB3 starts collecting a rollout
(nothing half-collected), so a run resumed from one continues bit for bit as if it had never
stopped (single thread, same machine and versions); with the replay buffer for SAC.
"""

from __future__ import annotations

import copy
import os
import pickle
import random
import re
import shutil
from collections import deque
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym.sim.observation import OBS_NAMES
from auv_gym.support.files import write_atomic, write_folder_atomic, write_json, zip_is_whole
from benchmarks.training.evaluation import HELD_OUT_FILE
from benchmarks.training.transitions import TRANSITIONS_FILE
from controllers.agent import METADATA_FILE, MODEL_FILE, STATS_FILE, VECNORM_FILE

__all__ = [
    "CHECKPOINTS",
    "REPLAY_FILE",
    "SEED_AGENT_PREFIX",
    "TRAINING_STATE_FILE",
    "capture_training_state",
    "export_agent",
    "latest_checkpoint",
    "list_checkpoints",
    "prune_checkpoints",
    "read_training_state",
    "restore_env_state",
    "restore_random_state",
    "save_agent",
    "write_metadata",
    "write_vecnormalize_from_stats",
]

CHECKPOINTS = "checkpoints"  # folder of a run holding step_<num_timesteps>/ agent directories
REPLAY_FILE = "replay_buffer.pkl"  # off-policy checkpoints (SAC): the replay buffer, for resuming
TRAINING_STATE_FILE = "training_state.pkl"  # checkpoints: what resuming exactly needs besides
SEED_AGENT_PREFIX = "agent_seed_"  # multi-seed results: <prefix><k>/ is training seed k's agent


def write_metadata(path: Path, metadata: dict[str, Any]) -> None:
    """An agent's or a run's metadata.json (sorted keys, 2-space indent), atomically."""
    write_json(path, metadata, indent=2, sort_keys=True)


def write_stats(path: Any, vec_normalize: Any, obs_names: Any) -> None:
    """vecnormalize.npz of a `VecNormalize`: the observation statistics a loaded agent needs
    (mean, var, count, clip_obs, epsilon, obs_names) and the return statistics a warm start
    continues from (ret_mean, ret_var, ret_count, clip_reward, gamma), plain arrays that load
    without unpickling anything; ``obs_names`` names each observation entry."""
    obs, ret = vec_normalize.obs_rms, vec_normalize.ret_rms
    if len(obs_names) != obs.mean.shape[0]:
        raise ValueError(
            f"{len(obs_names)} observation names for statistics of {obs.mean.shape[0]} "
            f"entries: {list(obs_names)}"
        )
    np.savez(
        path,
        mean=obs.mean,
        var=obs.var,
        count=np.float64(obs.count),
        clip_obs=np.float64(vec_normalize.clip_obs),
        epsilon=np.float64(vec_normalize.epsilon),
        obs_names=np.array(obs_names),
        ret_mean=np.float64(ret.mean),
        ret_var=np.float64(ret.var),
        ret_count=np.float64(ret.count),
        clip_reward=np.float64(vec_normalize.clip_reward),
        gamma=np.float64(vec_normalize.gamma),
    )


def stats_from_vecnormalize(pickled: Path, obs_names: Any = None) -> Path:
    """Write vecnormalize.npz beside a pickled VecNormalize (an RL Zoo or SB3 agent's
    vecnormalize.pkl), so that auv-gym can load the agent without unpickling anything.

    This function itself unpickles ``pickled``, which runs any code the file holds: call it
    only on files you trust (your own training runs), once; docs/usage.md "Trusting agent
    files"."""
    pickled = Path(pickled)
    with pickled.open("rb") as f:
        vec_normalize = pickle.load(f)  # trusted by the caller, as documented
    names = OBS_NAMES if obs_names is None else obs_names
    target = pickled.with_name(STATS_FILE)
    write_atomic(target, lambda fh: write_stats(fh, vec_normalize, names))
    return target


def save_agent(
    model: Any,
    vec_normalize: Any,
    folder: Path,
    metadata: dict[str, Any],
    replay_buffer: bool = False,
    training_state: dict[str, Any] | None = None,
    obs_names: Sequence[str] | None = None,
) -> None:
    """Write model.zip, vecnormalize.pkl/.npz and metadata.json as the folder ``folder``
    (and, with ``replay_buffer``, the off-policy replay buffer as replay_buffer.pkl; with
    ``training_state``, `TRAINING_STATE_FILE`). The .npz names the model's input entries
    ``obs_names`` (default: the agent's observation, ``metadata["obs_names"]``, else the
    paper's; a privileged critic's checkpoint passes its longer list, `privileged_names`).

    The folder is filled beside its place and then swapped in (`write_folder_atomic`), so
    readers see either the previous complete agent or the new one.
    """

    def fill(tmp: Path) -> None:
        model.save(tmp / MODEL_FILE)
        vec_normalize.save(str(tmp / VECNORM_FILE))
        names = list(metadata.get("obs_names", OBS_NAMES) if obs_names is None else obs_names)
        write_stats(tmp / STATS_FILE, vec_normalize, names)
        write_metadata(tmp / METADATA_FILE, metadata)
        if replay_buffer:
            model.save_replay_buffer(tmp / REPLAY_FILE)
        if training_state is not None:
            with (tmp / TRAINING_STATE_FILE).open("wb") as f:
                pickle.dump(training_state, f, protocol=pickle.HIGHEST_PROTOCOL)

    write_folder_atomic(folder, fill)


# What an exported agent's folder holds besides ONNX exports (NAME.onnx, its NAME.json
# contract): replacing the folder replaces these, and a folder holding anything else is refused.
EXPORTED_FILES = frozenset(
    {
        MODEL_FILE,
        STATS_FILE,
        VECNORM_FILE,
        METADATA_FILE,
        HELD_OUT_FILE,
        TRANSITIONS_FILE,
    }
)


def check_export_folder(
    target: str | os.PathLike, flag: str, out: str | os.PathLike | None
) -> None:
    """ValueError naming ``flag`` when exporting an agent to ``target`` would delete what is not
    an exported agent: the run's own folder ``out`` (target is it or holds it; a folder inside
    it is fine), or entries other than `EXPORTED_FILES` and ONNX exports. An export replaces the
    folder whole (`export_agent`)."""
    path = Path(target)
    if out is not None:
        run = Path(out).resolve()
        if run == path.resolve() or run.is_relative_to(path.resolve()):
            raise ValueError(
                f"{flag} {str(target)!r} holds the run's own folder --out {str(out)!r}, which "
                "exporting would delete (the export replaces its folder whole): choose a "
                "folder outside --out, or one inside it"
            )
    if not path.is_dir():
        return
    names = os.listdir(path)
    onnx = {n[: -len(".onnx")] for n in names if n.endswith(".onnx")}
    foreign = sorted(
        n
        for n in names
        if n not in EXPORTED_FILES and not n.endswith(".onnx") and n[: -len(".json")] not in onnx
    )
    if foreign:
        more = f" and {len(foreign) - 5} more" if len(foreign) > 5 else ""
        raise ValueError(
            f"{flag} {str(target)!r} holds {', '.join(foreign[:5])}{more}, which are not an "
            "exported agent's files: the export replaces the folder whole; choose an empty "
            "folder (or an agent's) or move them"
        )


def export_agent(source: Path, target: Path, metadata: dict[str, Any] | None = None) -> None:
    """Copy an agent directory (model.zip, vecnormalize.npz, metadata.json and, when the run
    wrote it, vecnormalize.pkl) atomically; with ``metadata``, that is written as the copy's
    metadata.json instead of the source's (e.g. an agent given an envelope guard). The copy
    replaces ``target`` whole; ValueError, before anything is written, when that folder holds
    more than an exported agent (`check_export_folder`).

    `controllers.loader.load_policy` needs only the .npz statistics; the pickled VecNormalize is
    what SB3's `VecNormalize.load` and RL Zoo's `enjoy` read, so the exported folder works with
    them as it is.
    """
    check_export_folder(target, "export", None)

    def fill(tmp: Path) -> None:
        for name in (MODEL_FILE, STATS_FILE):
            shutil.copy2(source / name, tmp / name)
        if metadata is None:
            shutil.copy2(source / METADATA_FILE, tmp / METADATA_FILE)
        else:
            write_metadata(tmp / METADATA_FILE, metadata)
        if (source / VECNORM_FILE).is_file():
            shutil.copy2(source / VECNORM_FILE, tmp / VECNORM_FILE)

    write_folder_atomic(target, fill)


def write_vecnormalize_from_stats(agent: Path, gamma: float = 0.99) -> Path:
    """Write AGENT/vecnormalize.pkl from AGENT/vecnormalize.npz, for agents exported before the
    pickle was: SB3's `VecNormalize.load` and RL Zoo then normalise observations exactly as
    `controllers.agent` does (mean, var, count, clip_obs, epsilon). The reward statistics, which
    inference never uses, start fresh (``norm_reward`` off, ``training`` off)."""
    import gymnasium as gym
    from stable_baselines3.common.running_mean_std import RunningMeanStd
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    with np.load(Path(agent) / STATS_FILE, allow_pickle=False) as stats:
        mean, var = stats["mean"], stats["var"]
        clip_obs, epsilon, count = (float(stats[key]) for key in ("clip_obs", "epsilon", "count"))

    class _Shape(gym.Env):  # only the observation shape matters to VecNormalize
        observation_space = gym.spaces.Box(-np.inf, np.inf, mean.shape, np.float32)
        action_space = gym.spaces.Box(-1.0, 1.0, (3,), np.float32)

    venv = VecNormalize(
        DummyVecEnv([_Shape]),
        training=False,
        norm_obs=True,
        norm_reward=False,
        clip_obs=clip_obs,
        gamma=gamma,
        epsilon=epsilon,
    )
    venv.obs_rms = RunningMeanStd(shape=mean.shape)
    venv.obs_rms.mean, venv.obs_rms.var = mean.astype(np.float64), var.astype(np.float64)
    venv.obs_rms.count = count
    target = Path(agent) / VECNORM_FILE
    # VecNormalize.save is this pickle.dump, written in place; here the file appears whole
    write_atomic(target, lambda fh: pickle.dump(venv, fh))
    venv.close()
    return target


def list_checkpoints(out: Path) -> list[tuple[int, Path]]:
    """(num_timesteps, folder) of the complete checkpoints of a run, oldest first."""
    found = []
    folder = out / CHECKPOINTS
    if folder.is_dir():
        for p in folder.iterdir():
            m = re.fullmatch(r"step_(\d+)", p.name)
            # whole: its model an SB3 zip to the last byte (cut short: the checkpoint before)
            if m and (p / VECNORM_FILE).is_file() and zip_is_whole(p / MODEL_FILE, ["data"]):
                found.append((int(m.group(1)), p))
    return sorted(found)


def latest_checkpoint(out: str | os.PathLike) -> Path | None:
    """The newest complete checkpoint directory of a run, or None."""
    found = list_checkpoints(Path(out))
    return found[-1][1] if found else None


def checkpoint_folder(out: Path, num_timesteps: int) -> Path:
    """Where the checkpoint at ``num_timesteps`` env steps goes."""
    return out / CHECKPOINTS / f"step_{num_timesteps:010d}"


def prune_checkpoints(out: Path, keep: int) -> None:
    """Delete all but the newest ``keep`` (at least one) checkpoints."""
    for _, old in list_checkpoints(out)[: -max(1, keep)]:
        shutil.rmtree(old, ignore_errors=True)


# ------------------------------------------------------------------------------ training state
# Attributes of an SB3 algorithm that model.zip keeps but `load(env=...)` discards (the last
# observation) or `learn` resets; restored before `learn` so it does not reset the env.
_MODEL_ATTRIBUTES = (
    "_last_obs",
    "_last_episode_starts",
    "_last_original_obs",
    "_episode_num",
    "ep_info_buffer",
    "ep_success_buffer",
)
# Per-wrapper state VecNormalize.save and VecMonitor leave out (the running discounted return of
# reward normalisation restarts at 0 on load; episode returns and lengths of the log).
_WRAPPER_ATTRIBUTES = {
    "VecNormalize": ("returns", "old_obs", "old_reward", "obs_rms", "ret_rms"),
    "VecMonitor": ("episode_returns", "episode_lengths", "episode_count"),
    "StagedActions": ("last_obs", "memories"),
}


def _env_chain(venv: Any) -> list[Any]:
    """The VecEnv wrappers of ``venv``, outermost first, down to the base VecEnv."""
    chain = []
    while venv is not None:
        chain.append(venv)
        venv = getattr(venv, "venv", None)
    return chain


def _action_distributions(model: Any) -> list[Any]:
    """The policy's action distributions (PPO's ``policy.action_dist``, SAC's actor's)."""
    return [m.action_dist for m in model.policy.modules() if hasattr(m, "action_dist")]


def _tensors(obj: Any) -> dict[str, Any]:
    """The tensor attributes of a distribution (the gSDE exploration matrices), detached."""
    import torch

    return {k: v.detach().clone() for k, v in vars(obj).items() if isinstance(v, torch.Tensor)}


def _env_state(venv: Any) -> dict[str, Any]:
    names = next(
        (names for cls in type(venv).__mro__ if (names := _WRAPPER_ATTRIBUTES.get(cls.__name__))),
        (),
    )
    if names:
        return {name: copy.deepcopy(getattr(venv, name)) for name in names}
    if hasattr(venv, "snapshot"):  # auv_gym.envs.sb3.SB3VecEnv
        return {"snapshot": venv.snapshot()}
    if getattr(venv, "venv", None) is None:  # another base VecEnv (DummyVecEnv): all of it
        return {"vars": copy.deepcopy(vars(venv))}
    return {}  # a stateless wrapper (ActionBox)


def capture_training_state(model: Any, phase: str, schedules: dict[str, Any]) -> dict[str, Any]:
    """Everything a resumed run needs besides model.zip, vecnormalize.pkl and the replay buffer
    to continue bit for bit (module doc); ``phase`` says where it was taken: "rollout_start"
    (SB3 starts collecting a rollout; the gSDE noise of that rollout is drawn) or
    "training_end" (`learn` returned). ``schedules``: the callbacks' next evaluation and next
    checkpoint [env steps]."""
    import torch

    if phase not in ("rollout_start", "training_end"):
        raise ValueError(f"phase must be 'rollout_start' or 'training_end', got {phase!r}")
    chain = _env_chain(model.get_env())
    return {
        "phase": phase,
        "num_timesteps": int(model.num_timesteps),
        "random": {
            "python": random.getstate(),
            "numpy": np.random.get_state(),  # noqa: NPY002 - SB3 samples minibatches from it
            "torch": torch.get_rng_state(),
            "action_space": copy.deepcopy(model.action_space._np_random),
            "action_dists": [_tensors(d) for d in _action_distributions(model)],
            "action_noise": copy.deepcopy(model.action_noise),
        },
        "model": {name: copy.deepcopy(getattr(model, name)) for name in _MODEL_ATTRIBUTES},
        "envs": [(type(v).__name__, _env_state(v)) for v in chain],
        "schedules": dict(schedules),
    }


def read_training_state(folder: Path) -> dict[str, Any] | None:
    """The training state of a checkpoint directory (None: written before it was kept)."""
    path = folder / TRAINING_STATE_FILE
    if not path.is_file():
        return None
    try:
        with path.open("rb") as f:
            state = pickle.load(f)
    except (OSError, EOFError, pickle.UnpicklingError, ValueError, TypeError) as error:
        raise ValueError(f"{path} cannot be read ({error}): a damaged checkpoint") from None
    if not isinstance(state, dict):
        raise ValueError(f"{path} holds {type(state).__name__}, not a training state")
    return state


def restore_env_state(model: Any, state: dict[str, Any]) -> None:
    """Put the training env and the algorithm's last observation back (before `learn`, which
    then does not reset the env); ValueError if the env chain differs from the saved one."""
    chain = _env_chain(model.get_env())
    names = [type(v).__name__ for v in chain]
    saved = [name for name, _ in state["envs"]]
    if names != saved:
        raise ValueError(
            f"the training env {'<'.join(names)} differs from the checkpoint's {'<'.join(saved)}"
        )
    for venv, (_, values) in zip(chain, state["envs"], strict=True):
        if "snapshot" in values:
            venv.restore(values["snapshot"])
        elif "vars" in values:
            vars(venv).update(copy.deepcopy(values["vars"]))
        else:
            for name, value in values.items():
                setattr(venv, name, copy.deepcopy(value))
    for name, value in state["model"].items():
        value = copy.deepcopy(value)
        if isinstance(value, deque) and getattr(model, name, None) is not None:
            value = deque(value, maxlen=getattr(model, name).maxlen)
        setattr(model, name, value)
    model.num_timesteps = int(state["num_timesteps"])


def restore_random_state(model: Any, state: dict[str, Any]) -> None:
    """Put the random generators, the gSDE noise and the action noise back: where the state
    was taken (`capture_training_state`'s ``phase``), after SB3 drew what it draws there."""
    import torch

    saved = state["random"]
    random.setstate(saved["python"])
    np.random.set_state(saved["numpy"])  # noqa: NPY002 - the generator SB3 seeds and uses
    torch.set_rng_state(saved["torch"])
    model.action_space._np_random = copy.deepcopy(saved["action_space"])
    dists = _action_distributions(model)
    if len(dists) != len(saved["action_dists"]):
        raise ValueError("the policy's action distributions differ from the checkpoint's")
    for dist, tensors in zip(dists, saved["action_dists"], strict=True):
        for name, value in tensors.items():
            setattr(dist, name, value.clone())
    model.action_noise = copy.deepcopy(saved["action_noise"])
