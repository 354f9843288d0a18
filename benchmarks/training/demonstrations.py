"""Demonstrations of a classical controller for an agent recipe, as a Minari dataset.

``auv-gym demos`` (`benchmarks.training.demos_cli`) flies a classical policy over the training
distribution of an agent recipe (the env id, env keyword arguments, observation, stages and
action box of a hyper-parameter file's phase: `DemoSource`) and writes what the agent would have
seen and done: the agent's observation (raw, before `VecNormalize`) and the expert's command in
the agent's action space (`benchmarks.training.expert.ExpertLabels`). The env steps with that
action through the agent's stages, so every transition (o, a, r, o′) is one of the agent's own
task. A jump start (`benchmarks.training.jump_start`) clones it; any offline-RL library that reads
Minari can use it too.

Layout (Minari 0.5, Farama's format for offline RL data, HDF5 storage)::

    OUT/data/main_data.hdf5   episode_<k>/{observations (T+1, d), actions (T, 3), rewards (T,),
                              terminations (T,), truncations (T,)}; attribute "seed"
    OUT/data/metadata.json    Minari's (dataset_id, spaces, env_spec with the env's keyword
                              arguments, minari_version, ...) and an "auv_gym" section: the
                              policy, env id and keyword arguments, observation names, the
                              agent's action interface (`action_interface`), the recipe, seeds,
                              versions and the SHA-256 of main_data.hdf5

``minari.MinariDataset("OUT/data")`` reads it; placed at
``$MINARI_DATASETS_PATH/<dataset_id>`` (``--out`` there), ``minari.load_dataset(dataset_id)``
finds it, and ``recover_environment()`` builds the env it was recorded on.

Episode k starts from ``AUVPath3DEnv(**env_kwargs).reset(seed=demo_seed(seed, k))``: reset seeds
in the [train] task set's range, apart from every training run's (`TRAIN_SEED_BASE` + 1000·seed
+ i), the validation and the test seeds. The file appears atomically when complete.

A dataset is checked before it is used (`check_dataset`): readable metadata with the "auv_gym"
section, the data file's SHA-256 as recorded (a damaged or edited file is refused), the
observation names and the action interface of the agent that will learn from it; every error is
one line naming the file and the mismatch.
"""

from __future__ import annotations

import glob
import hashlib
import json
import os
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym.support.files import process_alive

__all__ = [
    "DATA_FILE",
    "DEMO_SEED_BASE",
    "DemoSource",
    "Demonstrations",
    "action_interface",
    "check_dataset",
    "demo_seed",
    "read_dataset",
    "record_demonstrations",
]

FORMAT = 1  # the "auv_gym" section's layout
SECTION = "auv_gym"  # the metadata key of what auv-gym records beside Minari's own
DATA_FOLDER = "data"  # Minari's: <dataset folder>/data/{main_data.hdf5, metadata.json}
DATA_FILE = "main_data.hdf5"
META_FILE = "metadata.json"
# Reset seeds of the demonstrations: inside the [train] task set's range (1e6 to 1.001e9), above
# every training run's own (TRAIN_SEED_BASE + 1000·seed + i), below the range's end.
DEMO_SEED_BASE = 500_000_000
SEED_STRIDE = 1_000_000  # episodes per recording seed
MAX_DEMO_SEED = 499


def demo_seed(seed: int, episode: int) -> int:
    """The reset seed of episode ``episode`` of the recording seeded ``seed``."""
    return DEMO_SEED_BASE + SEED_STRIDE * int(seed) + int(episode)


def action_interface(
    env_kwargs: Mapping[str, Any],
    stages: Sequence[Mapping[str, Any]] = (),
    action_bounds: tuple[Sequence[float], Sequence[float]] | None = None,
) -> dict[str, Any]:
    """What an agent's actions mean: the actuator whose normalised commands they are (the
    paper's τ when the agent trains inside the actuator allocation onto fins or propeller and
    fins; else the env's actuator, "random" when drawn per episode) and the action box."""
    from auv_gym.sim.config import SimConfig
    from controllers.actuator_allocation import ALLOCATED_ACTUATORS, COMMANDED_ACTUATOR

    actuator = SimConfig.from_kwargs(**env_kwargs).actuator
    allocated = any(s.get("name") == "actuator_allocation" for s in stages)
    commands = COMMANDED_ACTUATOR if allocated and actuator in ALLOCATED_ACTUATORS else actuator
    low, high = ([-1.0] * 3, [1.0] * 3) if action_bounds is None else action_bounds
    return {
        "commands": commands,
        "low": [float(v) for v in low],
        "high": [float(v) for v in high],
    }


@dataclass(frozen=True)
class DemoSource:
    """The training distribution of an agent recipe: env id, the file's env keyword arguments,
    training stages (checked specs), action box, and where it came from (for metadata and
    errors)."""

    env_id: str
    env_kwargs: dict[str, Any]
    stages: tuple[dict[str, Any], ...] = ()
    action_bounds: tuple[tuple[float, ...], tuple[float, ...]] | None = None
    recipe: dict[str, Any] = field(default_factory=dict)

    @property
    def full_kwargs(self) -> dict[str, Any]:
        """The env keyword arguments: the id's fixed ones (`auv_gym.VARIANTS`), then the file's."""
        from auv_gym import VARIANTS

        return {**VARIANTS[self.env_id], **self.env_kwargs}

    @property
    def obs_names(self) -> tuple[str, ...]:
        from auv_gym.sim.observation import ObservationConfig

        return ObservationConfig.from_spec(self.full_kwargs.get("observation")).names

    @property
    def interface(self) -> dict[str, Any]:
        return action_interface(self.full_kwargs, self.stages, self.action_bounds)

    @classmethod
    def from_config(cls, cfg: Any, env_id: str, recipe: dict[str, Any]) -> DemoSource:
        """The source of a checked `benchmarks.training.config.ZooConfig` of ``env_id``; a
        residual agent's file is refused (its actions are corrections of its base)."""
        if cfg.residual is not None:
            raise ValueError(
                f"{recipe.get('config_file')}: a residual agent learns corrections of its base "
                "controller, not commands: demonstrations are for plain agents"
            )
        return cls(env_id, dict(cfg.env_kwargs), tuple(cfg.stages), cfg.action_bounds, recipe)


@dataclass
class Demonstrations:
    """A dataset read back (`read_dataset`): one dict per episode with ``observations`` (T+1,
    d), ``actions`` (T, 3), ``rewards`` (T,), ``terminations`` and ``truncations`` (T,) and
    ``seed``; ``meta`` is its "auv_gym" metadata section, ``path`` its folder."""

    path: Path
    meta: dict[str, Any]
    episodes: list[dict[str, Any]]

    @property
    def steps(self) -> int:
        return int(sum(len(e["rewards"]) for e in self.episodes))


# ------------------------------------------------------------------------------------ writing
def record_demonstrations(
    source: DemoSource,
    policy: str,
    out: str | os.PathLike,
    episodes: int,
    seed: int = 0,
    vehicles: int = 32,
    progress: bool = False,
) -> dict[str, Any]:
    """Fly ``policy`` (a classical name) on ``episodes`` episodes of ``source`` and write them to
    the dataset folder ``out`` (module doc); ``vehicles`` episodes run at once (one batched
    simulator). Returns what was written (episodes, steps, returns, terminations, bytes, wall
    time)."""
    from gymnasium.vector import AutoresetMode

    from auv_gym.envs.vector_env import AUVPath3DVectorEnv
    from benchmarks.training.expert import ExpertLabels
    from controllers.stages import observe_stages

    began = time.perf_counter()
    out = Path(out)
    if not 1 <= episodes <= SEED_STRIDE:
        raise ValueError(f"episodes must be 1-{SEED_STRIDE}, got {episodes}")
    if not 0 <= seed <= MAX_DEMO_SEED:
        raise ValueError(f"seed must be 0-{MAX_DEMO_SEED}, got {seed}")
    kwargs = source.full_kwargs
    names = source.obs_names
    expert = ExpertLabels(
        policy, kwargs, names, source.stages, source.action_bounds, f"demos {policy}"
    )
    n = max(1, min(int(vehicles), episodes))
    env = AUVPath3DVectorEnv(n, autoreset_mode=AutoresetMode.DISABLED, threads=1, **kwargs)
    stages = expert.stages
    try:
        writer = _DatasetWriter(
            out,
            env.single_observation_space,
            _action_space(expert.low, expert.high),
            source,
            policy,
            seed,
        )
    except BaseException:
        env.close()
        raise
    buffers: list[dict[str, list]] = [_empty() for _ in range(n)]
    slot = list(range(n))  # the episode each vehicle flies; -1: none left (its data dropped)
    started = n
    raw, _ = env.reset(seed=[demo_seed(seed, k) for k in range(n)])
    memories = [stage.start(n) for stage in stages]
    starts = np.ones(n, dtype=bool)
    finished: list[dict[str, Any]] = []
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=episodes, unit="episode", desc=f"demos {policy}")
    try:
        while len(finished) < episodes:
            seen = observe_stages(stages, raw, memories)
            action = expert.label(seen, starts)
            command = _apply(stages, action, seen, memories)
            raw, reward, terminated, truncated, _ = env.step(command)
            ended = terminated | truncated
            final = observe_stages(stages, raw, memories) if ended.any() else None
            for i in range(n):
                if slot[i] < 0:
                    continue
                buf = buffers[i]
                buf["observations"].append(seen[i])
                buf["actions"].append(action[i])
                buf["rewards"].append(float(reward[i]))
                buf["terminations"].append(bool(terminated[i]))
                buf["truncations"].append(bool(truncated[i]))
            starts = ended.copy()
            if not ended.any():
                continue
            rows = np.flatnonzero(ended)
            seeds: list[int | None] = [None] * n
            for i in rows:
                if slot[i] >= 0:
                    buf = buffers[i]
                    buf["observations"].append(final[i])
                    episode = {"index": slot[i], "seed": demo_seed(seed, slot[i]), **buf}
                    finished.append(_summary(episode))
                    writer.add(episode)
                    if bar is not None:
                        bar.update(1)
                buffers[i] = _empty()
                if started < episodes:
                    slot[i], started = started, started + 1
                else:
                    slot[i] = -1  # flown on a spare episode, not recorded
                seeds[i] = demo_seed(seed, started if slot[i] < 0 else slot[i])
            mask = np.zeros(n, dtype=bool)
            mask[rows] = True
            raw, _ = env.reset(seed=seeds, options={"reset_mask": mask})
            for stage, memory in zip(stages, memories, strict=True):
                stage.restart(memory, mask)
        result = writer.close(finished)
    except BaseException:
        writer.abort()
        raise
    finally:
        env.close()
        if bar is not None:
            bar.close()
    returns = np.array([e["return"] for e in finished])
    return {
        **result,
        "episodes": len(finished),
        "steps": int(sum(e["steps"] for e in finished)),
        "return_mean": float(returns.mean()),
        "terminated": int(sum(e["terminated"] for e in finished)),
        "wall_s": time.perf_counter() - began,
    }


def _apply(stages: Sequence[Any], action: np.ndarray, seen: np.ndarray, memories: list) -> Any:
    from controllers.stages import apply_stages

    return apply_stages(stages, action, seen, memories) if stages else action


def _empty() -> dict[str, list]:
    return {k: [] for k in ("observations", "actions", "rewards", "terminations", "truncations")}


def _summary(episode: dict[str, Any]) -> dict[str, Any]:
    return {
        "index": episode["index"],
        "seed": episode["seed"],
        "steps": len(episode["rewards"]),
        "return": float(np.sum(episode["rewards"])),
        "terminated": bool(episode["terminations"][-1]),
    }


def _action_space(low: np.ndarray, high: np.ndarray) -> Any:
    from gymnasium import spaces

    return spaces.Box(np.asarray(low, np.float32), np.asarray(high, np.float32), dtype=np.float32)


def dataset_id(source: DemoSource, policy: str) -> str:
    """The Minari id: ``auv_gym/<recipe file stem>-<policy>-v0`` (``task-<set>`` for a task
    set)."""
    recipe = source.recipe
    stem = (
        Path(str(recipe["config_file"])).stem
        if recipe.get("config_file")
        else f"task-{recipe.get('task_set', 'env')}"
    )
    name = "".join(c if c.isalnum() or c in "_-" else "_" for c in f"{stem}-{policy}")
    return f"auv_gym/{name}-v0"


class _DatasetWriter:
    """A Minari HDF5 dataset filled episode by episode in a temporary folder beside ``out``,
    moved into place by `close` (atomic: a killed recording leaves no dataset)."""

    def __init__(
        self,
        out: Path,
        obs_space: Any,
        action_space: Any,
        source: DemoSource,
        policy: str,
        seed: int,
    ) -> None:
        import gymnasium
        import minari
        from minari.dataset.minari_storage import MinariStorage

        from auv_gym import __version__

        if out.exists() and (not out.is_dir() or any(out.iterdir())):
            raise ValueError(f"--out {str(out)!r} exists and is not an empty folder")
        out.parent.mkdir(parents=True, exist_ok=True)
        self.out = out
        _claim_temporaries(out)
        self.tmp = out.with_name(f".{out.name}.tmp{os.getpid()}")
        self.tmp.mkdir()
        spec = gymnasium.spec(source.env_id)
        spec = _replace_kwargs(spec, source.full_kwargs)
        self.storage = MinariStorage.new(
            self.tmp / DATA_FOLDER, obs_space, action_space, env_spec=spec, data_format="hdf5"
        )
        self.id = dataset_id(source, policy)
        self.storage.update_metadata(
            {
                "dataset_id": self.id,
                "minari_version": minari.__version__,
                "algorithm_name": f"classical controller {policy} (controllers.make)",
                "author": {"auv-gym"},
                "code_permalink": "auv-gym demos (benchmarks/training/demonstrations.py)",
                "description": (
                    f"{policy} flying the training distribution of "
                    f"{source.recipe.get('config_file') or source.recipe.get('task_set')}: the "
                    "agent's observation (raw) and the controller's command in the agent's "
                    "action space"
                ),
                "auv_gym_version": __version__,
            }
        )
        self.section = {
            "format": FORMAT,
            "policy": policy,
            "env_id": source.env_id,
            "env_kwargs": source.full_kwargs,
            "obs_names": list(source.obs_names),
            "action_interface": source.interface,
            "stages": [dict(s) for s in source.stages],
            "recipe": source.recipe,
            "seed": int(seed),
            "seed_rule": f"{DEMO_SEED_BASE} + {SEED_STRIDE}·seed + episode index",
        }

    def add(self, episode: dict[str, Any]) -> None:
        from minari.data_collector.episode_buffer import EpisodeBuffer

        self.storage.update_episodes(
            [
                EpisodeBuffer(
                    seed=int(episode["seed"]),
                    observations=np.asarray(episode["observations"], dtype=np.float32),
                    actions=np.asarray(episode["actions"], dtype=np.float32),
                    rewards=np.asarray(episode["rewards"], dtype=np.float64),
                    terminations=np.asarray(episode["terminations"], dtype=bool),
                    truncations=np.asarray(episode["truncations"], dtype=bool),
                )
            ]
        )

    def close(self, finished: Sequence[dict[str, Any]]) -> dict[str, Any]:
        from auv_gym.support.files import git_commit, versions

        data = self.tmp / DATA_FOLDER / DATA_FILE
        self.storage.update_metadata(
            {
                SECTION: {
                    **self.section,
                    "episodes": [
                        {k: e[k] for k in ("seed", "steps", "return", "terminated")}
                        for e in finished
                    ],
                    "versions": versions(),
                    "git_commit": git_commit(),
                    "data_sha256": _sha256(data),
                }
            }
        )
        size = data.stat().st_size
        if self.out.exists():  # an empty folder (checked): replaced
            self.out.rmdir()
        os.replace(self.tmp, self.out)
        return {"dataset_id": self.id, "path": str(self.out), "bytes": size}

    def abort(self) -> None:
        import shutil

        shutil.rmtree(self.tmp, ignore_errors=True)


def _claim_temporaries(out: Path) -> None:
    """Before writing ``out``: a temporary folder of a live run for the same ``out``
    (``.OUT.tmp<pid>``) refuses this one in one line; one a killed run left is removed (they
    hold up to the whole dataset and would pile up, one per run)."""
    import shutil

    for tmp in out.parent.glob(f".{glob.escape(out.name)}.tmp*"):
        pid = tmp.name.rpartition(".tmp")[2]
        if not pid.isdigit():
            continue
        if int(pid) != os.getpid() and process_alive(int(pid)):
            raise ValueError(
                f"--out {str(out)!r} is being written by another run (process {pid}, {tmp})"
            )
        shutil.rmtree(tmp, ignore_errors=True)

    return True


def _replace_kwargs(spec: Any, kwargs: dict[str, Any]) -> Any:
    import dataclasses

    return dataclasses.replace(spec, kwargs=dict(kwargs))


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with path.open("rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


# ------------------------------------------------------------------------------------ reading
def _folder(path: str | os.PathLike) -> Path:
    """The folder holding metadata.json and main_data.hdf5: ``path``/data or ``path`` itself."""
    path = Path(path)
    return path / DATA_FOLDER if (path / DATA_FOLDER / META_FILE).exists() else path


_CHECKED: dict[tuple[str, int, int], str] = {}  # (data file, size, mtime_ns) → its SHA-256


def read_metadata(path: str | os.PathLike, where: str = "dataset") -> dict[str, Any]:
    """The "auv_gym" metadata section of the dataset at ``path``, with the data file's
    integrity checked against its recorded SHA-256; one-line ValueError naming the file."""
    folder = _folder(path)
    meta_file = folder / META_FILE
    data_file = folder / DATA_FILE
    if not Path(path).exists():
        raise ValueError(f"{where} {str(path)!r} does not exist")
    if not meta_file.is_file():
        raise ValueError(
            f"{where} {str(path)!r}: no {DATA_FOLDER}/{META_FILE} (an auv-gym demos dataset "
            "folder, written by auv-gym demos, holds data/metadata.json and data/main_data.hdf5)"
        )
    try:
        metadata = json.loads(meta_file.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        problem = " ".join(str(error).split())
        raise ValueError(f"{where} {meta_file}: unreadable ({problem})") from None
    section = metadata.get(SECTION) if isinstance(metadata, dict) else None
    if not isinstance(section, dict) or section.get("format") != FORMAT:
        raise ValueError(
            f"{where} {meta_file}: no {SECTION!r} section of format {FORMAT} (not a dataset "
            "of auv-gym demos, or one of another version)"
        )
    if not data_file.is_file():
        raise ValueError(f"{where} {data_file}: missing")
    stat = data_file.stat()
    key = (str(data_file.resolve()), stat.st_size, stat.st_mtime_ns)
    digest = _CHECKED.get(key) or _sha256(data_file)
    if digest != section.get("data_sha256"):
        raise ValueError(
            f"{where} {data_file}: damaged or changed since it was recorded (SHA-256 "
            f"{digest[:12]}…, recorded {str(section.get('data_sha256'))[:12]}…)"
        )
    if key not in _CHECKED:
        _check_hdf5(data_file, where)
    _CHECKED[key] = digest
    return section


def _check_hdf5(data_file: Path, where: str) -> None:
    """ValueError naming ``data_file`` when HDF5 cannot open it: a file whose recorded hash was
    rewritten to match a damaged copy would otherwise fail only when a training worker reads it,
    after the run has started."""
    import h5py

    try:
        with h5py.File(data_file, "r") as data:
            data.visit(lambda name: None)  # every group's index is read, not only the header
    except Exception as error:  # h5py raises OSError, KeyError, RuntimeError by the damage
        problem = " ".join(str(error).split())
        raise ValueError(
            f"{where} {data_file}: cannot be read as HDF5 ({type(error).__name__}: {problem})"
        ) from None


def check_dataset(
    path: str | os.PathLike,
    obs_names: Sequence[str],
    interface: Mapping[str, Any],
    where: str = "dataset",
) -> dict[str, Any]:
    """The dataset's "auv_gym" section (`read_metadata`), checked for an agent observing
    ``obs_names`` whose actions mean ``interface`` (`action_interface`); a one-line
    ValueError naming the file and the first mismatch."""
    section = read_metadata(path, where)
    meta_file = _folder(path) / META_FILE
    recorded = list(section.get("obs_names") or ())
    if recorded != list(obs_names):
        extra = sorted(set(recorded) - set(obs_names))
        missing = sorted(set(obs_names) - set(recorded))
        raise ValueError(
            f"{where} {meta_file}: its observation ({len(recorded)} values) is not the agent's "
            f"({len(obs_names)}): entries only in the dataset {extra[:6]}, only in the agent's "
            f"{missing[:6]}" + ("" if extra or missing else " (another order)")
        )
    theirs = section.get("action_interface") or {}
    if dict(theirs) != dict(interface):
        raise ValueError(
            f"{where} {meta_file}: its actions are {_said(theirs)}, the agent's are "
            f"{_said(interface)}"
        )
    return section


def _said(interface: Mapping[str, Any]) -> str:
    return (
        f"{interface.get('commands')!r} commands in [{interface.get('low')}, "
        f"{interface.get('high')}]"
    )


def read_dataset(
    path: str | os.PathLike,
    obs_names: Sequence[str] | None = None,
    interface: Mapping[str, Any] | None = None,
    where: str = "dataset",
) -> Demonstrations:
    """Every episode of the dataset at ``path`` (checked with `check_dataset` when
    ``obs_names`` and ``interface`` are given, else `read_metadata`), read with Minari; each
    episode's shapes and values are checked (T+1 observations, finite values, actions inside
    the recorded action space). One-line ValueError naming the file otherwise."""
    import minari

    if obs_names is not None and interface is not None:
        section = check_dataset(path, obs_names, interface, where)
    else:
        section = read_metadata(path, where)
    folder = _folder(path)
    data_file = folder / DATA_FILE
    try:
        dataset = minari.MinariDataset(folder)
        raw = list(dataset.iterate_episodes())
        obs_dim = dataset.observation_space.shape
        low, high = dataset.action_space.low, dataset.action_space.high
    except Exception as error:  # h5py / Minari: a file that passed its hash but does not parse
        problem = " ".join(str(error).split())
        raise ValueError(
            f"{where} {data_file}: cannot be read by Minari ({type(error).__name__}: {problem})"
        ) from None
    names = section.get("obs_names") or []
    if obs_dim != (len(names),):
        raise ValueError(
            f"{where} {folder / META_FILE}: observation space {obs_dim}, its names "
            f"{len(names)} values"
        )
    episodes = []
    for episode in raw:
        at = f"{where} {data_file}: episode {episode.id}"
        obs = np.asarray(episode.observations)
        act = np.asarray(episode.actions)
        steps = len(episode.rewards)
        if steps < 1 or obs.shape != (steps + 1, len(names)) or act.shape != (steps, 3):
            raise ValueError(
                f"{at}: {steps} steps with observations {obs.shape} and actions {act.shape} "
                f"(expected ({steps + 1}, {len(names)}) and ({steps}, 3))"
            )
        rewards = np.asarray(episode.rewards, dtype=np.float64)
        if not (np.isfinite(obs).all() and np.isfinite(act).all() and np.isfinite(rewards).all()):
            raise ValueError(f"{at}: values that are not finite")
        if np.any(act < low - 1e-6) or np.any(act > high + 1e-6):
            raise ValueError(f"{at}: actions outside the action space [{low}, {high}]")
        episodes.append(
            {
                "observations": obs,
                "actions": act,
                "rewards": rewards,
                "terminations": np.asarray(episode.terminations, dtype=bool),
                "truncations": np.asarray(episode.truncations, dtype=bool),
                "seed": _episode_seed(dataset, episode.id),
            }
        )
    if not episodes:
        raise ValueError(f"{where} {data_file}: holds no episode")
    return Demonstrations(
        folder.parent if folder.name == DATA_FOLDER else folder, section, episodes
    )


def _episode_seed(dataset: Any, index: int) -> int | None:
    meta = next(iter(dataset.storage.get_episode_metadata([index])), {})
    seed = meta.get("seed")
    return None if seed is None else int(seed)
