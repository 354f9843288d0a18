"""A trained stable-baselines3 agent (PPO, SAC, any algorithm of `controllers.algorithms`) as a
Policy: the saved files, their checks and the actor.

An agent directory holds::

    model.zip          the SB3 model (`PPO.save`, `SAC.save`, ...)
    vecnormalize.npz   observation mean/var/clip/epsilon and obs_names: all a loaded agent needs
    vecnormalize.pkl   the full pickled `VecNormalize`, for SB3 and RL Zoo users (optional; never
                       unpickled here: a pickle can run code, docs/usage.md "Trusting agent files")
    metadata.json      how it was trained (optional; "algo" names the algorithm, default "ppo";
                       `obs_names` is checked when present)

`check_agent` validates the files without torch; `load_actor` returns an `AgentPolicy`, which
applies the saved observation normalisation itself and follows the Policy protocol
(`controllers.base`). An agent whose metadata holds a "residual" section was trained on the residual
observation (the env's, then its base's and its previous action:
`controllers.residual.residual_observation_names`); `controllers.loader.load_policy`
(``controllers.make("agent", path=...)``) wraps its actor in a
`controllers.residual.ResidualPolicy`. Training, checkpoints and export live on the benchmarks side
(`benchmarks.training`). Nothing here changes process-wide state: the torch thread count a policy
predicts with is set for each `predict` call and restored after it. torch and SB3 are imported
lazily: `import controllers.agent` works without the rl extra.
"""

from __future__ import annotations

import contextlib
import json
import os
import zipfile
import zlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym import __version__
from auv_gym.sim.observation import OBS_NAMES, ObservationConfig
from auv_gym.support.validation import ArgumentTypeError
from controllers.algorithms import ALGORITHMS, algorithm_of
from controllers.ensemble import ENSEMBLE_FILE, EnsembleActor, ensemble_members
from controllers.residual import (
    NO_STAGES,
    ResidualSettings,
    residual_observation_names,
)

ACTION_DIM = 3  # normalised (X, M, N) commands in [-1, 1]

__all__ = [
    "METADATA_FILE",
    "MODEL_FILE",
    "STATS_FILE",
    "VECNORM_FILE",
    "AgentFiles",
    "AgentPolicy",
    "check_actuator",
    "check_agent",
    "check_ensemble",
    "check_weights",
    "first_difference",
    "load_actor",
    "load_network",
    "read_policy_state",
]

MODEL_FILE = "model.zip"
STATS_FILE = "vecnormalize.npz"  # obs mean/var/clip/epsilon: all a loaded agent needs
VECNORM_FILE = "vecnormalize.pkl"  # the full VecNormalize, for SB3 and RL Zoo; never unpickled
METADATA_FILE = "metadata.json"
STATS_KEYS = ("mean", "var", "clip_obs", "epsilon")


class AgentPolicy:
    """A trained actor (PPO, SAC, ...) with its observation normalisation: the Policy protocol
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
        # 15 (the paper's), more with a preview; a residual agent's actor: 6 more (b, a_{k−1})
        self.obs_dim = int(self.obs_mean.shape[0])
        # The env the agent carries: `auv_gym.rollout` runs it there unless told otherwise.
        self.env_kwargs = agent_env_kwargs(self.metadata)
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
        """Actions in [−1, 1]³ for observations (d,) or (n, d), d = `obs_dim` (the layout of
        `observation_layout`: `auv_gym.OBS_NAMES` for the paper's; a residual agent's actor:
        `controllers.residual.residual_observation_names`)."""
        obs = np.asarray(observation, dtype=np.float32)
        dim = self.obs_dim
        if obs.ndim not in (1, 2) or obs.shape[-1] != dim:
            raise ValueError(f"observation must have shape ({dim},) or (n, {dim}), got {obs.shape}")
        single = obs.ndim == 1
        normed = self.normalize(obs.reshape(-1, dim)).astype(np.float32)
        with _torch_threads(self.num_threads):
            action, _ = self.sb3_policy.predict(normed, deterministic=deterministic)
        return (action[0] if single else action), state

    def __repr__(self) -> str:
        return f"AgentPolicy(path={self.path!r})"


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
        if path.suffix != ".zip":  # an ONNX export, a metadata file, ...: not a model
            kind = "an ONNX export (fly it as onnx:FILE)" if path.suffix == ".onnx" else "a file"
            raise ValueError(
                f"agent {path} is {kind}, not a saved agent: give its folder (model.zip, "
                f"{STATS_FILE}, {METADATA_FILE}) or its model .zip"
            )
        model = path
    else:
        raise FileNotFoundError(f"agent {path} does not exist")
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


@dataclass(frozen=True)
class AgentFiles:
    """An agent's files, checked (`check_agent`): where they are and what they hold."""

    model: Path
    stats: Path
    metadata_file: Path | None
    obs_mean: np.ndarray  # (d,) finite, d = len(observation_layout(metadata))
    obs_var: np.ndarray  # (d,) finite, >= 0
    clip_obs: float  # finite, > 0
    epsilon: float  # finite, > 0
    metadata: dict[str, Any]
    residual: ResidualSettings | None = None  # metadata "residual": a residual agent
    algo: str = "ppo"  # the key of `controllers.algorithms.ALGORITHMS` it was trained with
    stages: tuple[dict[str, Any], ...] = ()  # metadata "stages", checked (`controllers.stages`)
    # An ensemble (`controllers.ensemble`): its ensemble.json and every member's files, the
    # first of which the fields above are.
    ensemble: Path | None = None
    members: tuple[AgentFiles, ...] = ()

    @property
    def label(self) -> str:
        """How errors name the model: its algorithm's class ("PPO model", "SAC model")."""
        return f"{ALGORITHMS[self.algo].class_name} model"


def agent_env_kwargs(metadata: dict[str, Any], env_id: str | None = None) -> dict[str, Any]:
    """The env an agent carries, as `AUVPath3DEnv` keyword arguments: the fixed arguments of
    ``env_id`` (None: the id its metadata records; `auv_gym.VARIANTS`; none recorded: the
    paper's `AUVPath3D-v0`) and
    the observation it was trained on where that id's differs (a residual agent's env
    observation; recorded before residual agents had a choice: the paper's). Trained on the
    propeller and fins, an agent (and a residual agent's base) commands them too."""
    from auv_gym import ENV_ID, VARIANTS, resolve_env_id

    recorded = metadata.get("env_id", ENV_ID) if env_id is None else env_id
    fixed = dict(VARIANTS[resolve_env_id(recorded)])
    if commands_realistic_actuators(metadata):  # its actions are shaft speed and fin angles
        fixed["actuator"] = REALISTIC_ACTUATOR
    trained = ObservationConfig.from_spec(metadata.get("observation"))
    if trained != ObservationConfig.from_spec(fixed.get("observation")):
        fixed["observation"] = trained.to_dict()
    return fixed


REALISTIC_ACTUATOR = "realistic"


def commands_realistic_actuators(metadata: dict[str, Any]) -> bool:
    """True for an agent trained on the propeller and fins (``actuator="realistic"``): its
    actions are normalised shaft speed and fin angles, which no other actuator interprets, so
    it carries that actuator like its observation (docs/model.md §2.6)."""
    return (metadata.get("env_kwargs") or {}).get("actuator") == REALISTIC_ACTUATOR


def check_actuator(files: AgentFiles, actuator: str) -> None:
    """ValueError naming the agent when it commands the propeller and fins
    (`commands_realistic_actuators`) and is to fly ``actuator``, another actuator model: its
    actions mean shaft speed and fin angles nowhere else."""
    if commands_realistic_actuators(files.metadata) and actuator != REALISTIC_ACTUATOR:
        agent = files.ensemble.parent if files.ensemble is not None else files.model.parent
        raise ValueError(
            f"agent {agent} commands the propeller and fins (shaft speed and fin angles, "
            f"actuator={REALISTIC_ACTUATOR!r}); this env's actuator is {actuator!r}: fly it on "
            f"an env with actuator={REALISTIC_ACTUATOR!r}"
        )


def observation_layout(metadata: dict[str, Any]) -> tuple[str, ...]:
    """The observation names an agent was trained on: the env's 15, the agent observation of
    its "observation" section (`auv_gym.ObservationConfig`), or for a residual agent that
    observation with the base and previous actions after it (21 values on the paper's)."""
    if "residual" in metadata:
        return residual_observation_names(metadata.get("observation"))
    return ObservationConfig.from_spec(metadata.get("observation")).names


def check_agent(path: str | os.PathLike) -> AgentFiles:
    """Validate a saved agent completely, without torch and without unpickling anything: every
    problem raises an error naming the file.

    FileNotFoundError: the agent, its model.zip or its statistics are missing. ValueError:
    model.zip is not a zip, fails its CRC check, lacks SB3's ``data``/``policy.pth`` or was saved
    for another observation/action shape; the statistics are unreadable, lack a key, have the
    wrong shape, or are not finite with var >= 0, clip_obs > 0, epsilon > 0; metadata.json is not
    a JSON object or names another algorithm, observation layout or shape, action shape, or
    auv-gym major version, or has an invalid "residual" section. The expected observation is
    `observation_layout` of the metadata (the env's 15 values by default; a residual agent's
    6 more). A folder holding ensemble.json (`controllers.ensemble`) is an ensemble: every
    member is checked so, and must fly like the first but for its network (ValueError naming
    what differs); the first member's files are returned with ``members`` and ``ensemble`` set.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise ArgumentTypeError(
            f"agent path must be a folder or model zip path (str or os.PathLike), got "
            f"{type(path).__name__} {path!r:.60}"
        )
    members = ensemble_members(Path(path)) if Path(path).is_dir() else None
    if members is not None:
        return check_ensemble(Path(path) / ENSEMBLE_FILE, members)
    model, stats, meta = _locate(Path(path))
    metadata = _read_metadata(meta) if meta is not None else {}
    algo = algorithm_of(metadata, str(meta))
    if stats is None:
        raise FileNotFoundError(
            f"{algo.class_name} agent {model}: normalisation statistics missing (expected "
            f"{model.parent / STATS_FILE} or {model.parent / VECNORM_FILE})"
        )
    residual = None
    if "residual" in metadata:  # the training keys it also records are the training side's
        residual = ResidualSettings.from_dict(
            metadata["residual"], f"{meta}: residual", strict=False
        )
    action_dim = ACTION_DIM if residual is None else residual.action_dim
    if "action_shape" in metadata and metadata["action_shape"] != [action_dim]:
        raise ValueError(
            f"{meta}: action_shape is {metadata['action_shape']!r}, expected {[action_dim]!r}"
        )
    names = observation_layout(metadata)
    _check_model_zip(model, names, action_dim, f"{algo.class_name} model", meta)
    mean, var, clip_obs, epsilon = _read_stats(stats, names)
    stages = agent_stages(metadata, str(meta))
    if stages and residual is not None:
        raise ValueError(f"{meta}: {NO_STAGES}")
    return AgentFiles(
        model, stats, meta, mean, var, clip_obs, epsilon, metadata, residual, algo.name, stages
    )


def check_ensemble(spec: Path, paths: Sequence[Path]) -> AgentFiles:
    """The checked files of an ensemble ``spec`` (its ensemble.json) of the agents at ``paths``:
    the first member's with ``members`` and ``ensemble`` set, after checking every member
    (`check_agent`) and that each flies like the first but for its network (ValueError naming
    what differs)."""
    members = [check_agent(path) for path in paths]
    first = members[0]
    models = [files.model.resolve() for files in members]
    for k, model in enumerate(models):  # a folder and its model.zip are one agent
        if model in models[:k]:
            raise ValueError(
                f"ensemble {spec}: members {str(paths[models.index(model)])!r} and "
                f"{str(paths[k])!r} are one agent ({model}); list each agent once"
            )

    def flies_as(files: AgentFiles) -> dict[str, Any]:
        return {
            "algorithm": files.algo,
            "observation layout": observation_layout(files.metadata),
            "residual section": files.residual,
            "stages": files.stages,
            "env id": files.metadata.get("env_id"),
            "env": agent_env_kwargs(files.metadata),
        }

    reference = flies_as(first)
    for files in members[1:]:
        for key, value in flies_as(files).items():
            if value != reference[key]:
                raise ValueError(
                    f"ensemble {spec}: member {files.model.parent} differs from "
                    f"{first.model.parent} in its {key} ({_difference(value, reference[key])})"
                )
    return replace(first, ensemble=spec, members=tuple(members))


def first_difference(a: Sequence[Any], b: Sequence[Any]) -> int:
    """The first index where sequences ``a`` and ``b`` differ (the shorter one's length when one
    is the other's head)."""
    return next(
        (i for i, (x, y) in enumerate(zip(a, b, strict=False)) if x != y), min(len(a), len(b))
    )


def _difference(value: Any, reference: Any) -> str:
    """Where ``value`` differs from ``reference``, short enough for one line: for two sequences
    their lengths and the first entry that differs (a long layout's shared head would hide it),
    else both values."""
    if isinstance(value, (list, tuple)) and isinstance(reference, (list, tuple)):
        k = first_difference(value, reference)
        first, other = (f"{v[k]!r:.60}" if k < len(v) else "no entry" for v in (value, reference))
        return (
            f"{len(value)} entries vs {len(reference)}, first difference at entry {k}: "
            f"{first} vs {other}"
        )
    return f"{value!r:.120} vs {reference!r:.120}"


# Metadata keys of earlier releases: the stages an agent now lists under "stages".
FORMER_STAGE_KEYS = ("envelope_guard", "actuator_allocation")
# Metadata keys of agent stages that were removed (no shipped agent used them; what they measured
# stays in docs/results.md): an agent that names one is refused, not loaded without it.
REMOVED_STAGES = {
    "action_increment": "incremental commands",
    "action_scale": "scaled commands",
}


def agent_stages(metadata: dict[str, Any], where: str) -> tuple[dict[str, Any], ...]:
    """The checked stage list of an agent's metadata (`controllers.stages.check_stage_specs`);
    a one-line ValueError naming ``where`` for a former key or a removed stage."""
    from controllers.stages import check_stage_specs

    for key in FORMER_STAGE_KEYS:
        if key in metadata:
            raise ValueError(
                f"{where}: {key!r} is now a stage: list it as {{'name': {key!r}, ...}} "
                "under 'stages'"
            )
    for key, stage in REMOVED_STAGES.items():
        if key in metadata:
            raise ValueError(
                f"{where}: {key!r} ({stage}) was removed from auv-gym; this agent cannot be loaded"
            )
    return check_stage_specs(metadata.get("stages"), where)


def _read_metadata(meta: Path) -> dict[str, Any]:
    try:
        metadata = json.loads(meta.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"agent metadata {meta} is unreadable: {exc}") from exc
    if not isinstance(metadata, dict):
        kind = type(metadata).__name__
        raise ValueError(f"agent metadata {meta} must be a JSON object, got a {kind}")
    try:
        layout = observation_layout(metadata)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{meta}: invalid observation section: {exc}") from None
    names = metadata.get("obs_names")
    if names is not None and (not isinstance(names, list) or tuple(names) != layout):
        raise ValueError(
            f"{meta}: agent trained for observation layout {names!r}, this auv_gym has "
            f"{list(layout)}"
        )
    algorithm_of(metadata, str(meta))
    expected = [len(layout)]  # the action shape depends on the residual section (check_agent)
    if "observation_shape" in metadata and metadata["observation_shape"] != expected:
        raise ValueError(
            f"{meta}: observation_shape is {metadata['observation_shape']!r}, expected {expected!r}"
        )
    version = metadata.get("auv_gym_version")
    if version is not None:
        major = str(version).split(".")[0]
        if not (isinstance(version, str) and major.isdigit()):
            raise ValueError(f"{meta}: auv_gym_version {version!r} is not a version number")
        if major != __version__.split(".")[0]:
            raise ValueError(
                f"{meta}: agent trained with auv-gym {version}, this is auv-gym {__version__} "
                "(another major version: its observations may differ)"
            )
    return metadata


def _check_model_zip(
    model: Path,
    names: tuple[str, ...] = OBS_NAMES,
    action_dim: int = ACTION_DIM,
    label: str = "PPO model",
    metadata_file: Path | None = None,
) -> None:
    """SB3's zip: intact (CRC), with its parameters and a (len(names),) → (action_dim,) Box
    policy (3 actions; a residual agent with a learned filter: 6). Errors begin with ``label``
    (the algorithm's model, e.g. "SAC model"); ``metadata_file`` is where ``names`` came from
    (None: no metadata, the paper's layout)."""
    if not zipfile.is_zipfile(model):
        raise ValueError(f"{label} {model} is not a valid zip file (corrupt or truncated)")
    try:
        with zipfile.ZipFile(model) as archive:
            members = archive.namelist()
            for name in members:  # reading a member checks its CRC-32
                try:
                    archive.read(name)
                except (zipfile.BadZipFile, zlib.error, EOFError) as exc:
                    problem = f"member {name!r}: {exc}"
                    raise ValueError(f"{label} {model} is damaged: {problem}") from exc
            missing = sorted({"data", "policy.pth"} - set(members))
            if missing:
                raise ValueError(
                    f"{label} {model} is damaged (truncated, or not an SB3 model): no {missing}"
                )
            data = json.loads(archive.read("data"))
    except (zipfile.BadZipFile, OSError, json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{label} {model} cannot be read (corrupt or truncated): {exc}") from exc
    for key, expected in (("observation_space", (len(names),)), ("action_space", (action_dim,))):
        space = data.get(key) if isinstance(data, dict) else None
        shape = space.get("_shape") if isinstance(space, dict) else None
        if shape is not None and tuple(shape) != expected:
            what = key.replace("_", " ")
            raise ValueError(
                f"{label} {model}: {what} shape {tuple(shape)}, expected {expected}"
                + (
                    f" (layout {list(names)}){_layout_source(metadata_file)}"
                    if key == "observation_space"
                    else ""
                )
            )


def _layout_source(metadata_file: Path | None) -> str:
    """What an observation-shape error adds about where the expected layout came from: without
    metadata.json an agent is read as the paper's observation, and a lost metadata file is the
    likelier cause of a mismatch than a wrong network."""
    if metadata_file is not None:
        return ""
    return f"; there is no {METADATA_FILE} beside it, so it is read as the paper's observation"


def _read_stats(
    stats: Path, names: tuple[str, ...] = OBS_NAMES
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """(mean, var, clip_obs, epsilon) from a .npz (a pickle is refused, never loaded), checked:
    shapes
    (d,), (d,), (), () for the d = len(names) observation values; all finite; var >= 0;
    clip_obs > 0; epsilon > 0."""
    shapes = {"mean": (len(names),), "var": (len(names),), "clip_obs": (), "epsilon": ()}
    if stats.suffix != ".npz":
        raise ValueError(
            f"normalisation statistics {stats}: auv-gym reads {STATS_FILE} only and never "
            f"unpickles {stats.name} (a pickle can run code); in a session you trust, write "
            f"{STATS_FILE} beside it with benchmarks.training.checkpoints.stats_from_vecnormalize"
        )
    try:
        with np.load(stats, allow_pickle=False) as data:
            values = {key: data[key] for key in data.files}
    except Exception as exc:
        raise ValueError(f"normalisation statistics {stats} are unreadable: {exc}") from exc
    missing = [key for key in STATS_KEYS if key not in values]
    if missing:
        raise ValueError(f"{stats}: missing statistics {missing}")
    if "obs_names" in values:
        saved = tuple(str(n) for n in np.atleast_1d(values["obs_names"]))
        if saved != names:
            raise ValueError(
                f"{stats}: statistics for observation layout {list(saved)}, this auv_gym has "
                f"{list(names)}"
            )
    arrays = {key: np.asarray(values[key]) for key in STATS_KEYS}
    for key, shape in shapes.items():
        a = arrays[key]
        if a.dtype.kind not in "iuf":
            raise ValueError(f"{stats}: {key} must hold real numbers, got dtype {a.dtype}")
        if a.shape != shape:
            raise ValueError(f"{stats}: statistics of shape {a.shape} for {key}, expected {shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{stats}: {key} is not finite: {a.tolist()}")
    mean, var = arrays["mean"].astype(np.float64), arrays["var"].astype(np.float64)
    clip_obs, epsilon = float(arrays["clip_obs"]), float(arrays["epsilon"])
    if np.any(var < 0):
        raise ValueError(f"{stats}: var must be >= 0, got {var.tolist()}")
    if clip_obs <= 0:
        raise ValueError(f"{stats}: clip_obs must be > 0, got {clip_obs}")
    if epsilon <= 0:
        raise ValueError(f"{stats}: epsilon must be > 0, got {epsilon}")
    return mean, var, clip_obs, epsilon


def read_policy_state(model: str | os.PathLike) -> Any:
    """The state dict of a model.zip's policy (its policy.pth), read as tensors only (torch's
    ``weights_only``: nothing else is unpickled); the zip's and torch's own errors propagate."""
    import io

    import torch

    with zipfile.ZipFile(model) as archive:
        data = archive.read("policy.pth")
    return torch.load(io.BytesIO(data), map_location="cpu", weights_only=True)


def check_weights(files: AgentFiles) -> None:
    """Every weight of a checked agent's policy (model.zip's policy.pth; every member's for an
    ensemble) finite, as `load_actor` requires, read as tensors only (torch's ``weights_only``:
    nothing else is unpickled) and without building the model: for the checks before any
    episode. ValueError naming the file."""
    if files.members:
        for member in files.members:
            check_weights(member)
        return

    import torch

    try:
        state = read_policy_state(files.model)
    except Exception as exc:
        raise ValueError(f"{files.label} {files.model}: policy.pth cannot be read: {exc}") from None
    if not isinstance(state, dict):
        raise ValueError(f"{files.label} {files.model}: policy.pth holds no state dict")
    bad = [
        str(name)
        for name, value in state.items()
        if torch.is_tensor(value) and value.is_floating_point() and not value.isfinite().all()
    ]
    if bad:
        raise ValueError(
            f"{files.label} {files.model}: non-finite weights in {bad[:3]}"
            + (f" and {len(bad) - 3} more" if len(bad) > 3 else "")
            + " (a diverged or damaged model)"
        )


def load_network(
    files: AgentFiles, *, device: str = "cpu", num_threads: int | None = 1
) -> AgentPolicy | EnsembleActor:
    """What a checked agent's network stage flies: its actor (`load_actor`), or for an ensemble
    the mean of its members' actors (`controllers.ensemble.EnsembleActor`)."""
    if files.members:
        return EnsembleActor(
            [load_actor(m, device=device, num_threads=num_threads) for m in files.members]
        )
    return load_actor(files, device=device, num_threads=num_threads)


def load_actor(
    files: AgentFiles, *, device: str = "cpu", num_threads: int | None = 1
) -> AgentPolicy:
    """The actor of checked agent files (`check_agent`) with its normalisation, loaded with the
    algorithm its metadata names (`controllers.algorithms`). A residual agent's actor takes
    the residual observation (`observation_layout`); `controllers.loader.load_policy` adds its
    base.

    `num_threads`: torch's intra-op threads while the policy predicts (1 suits these small
    networks, docs/design.md §4; None: torch's setting); loading itself leaves torch's
    settings alone. ValueError naming the model when SB3 cannot load it.
    """
    algorithm = ALGORITHMS[files.algo].sb3_class()
    # Schedules are not needed for inference; replacing them avoids unpickling closures.
    # An off-policy model saved with n-step returns names SB3's NStepReplayBuffer, which SB3
    # then warns makes `n_steps` "ignored"; no buffer is built for inference, so drop the name.
    custom = {
        "learning_rate": 0.0,
        "lr_schedule": lambda _: 0.0,
        "clip_range": lambda _: 0.0,
        "replay_buffer_class": None,
        "replay_buffer_kwargs": {},
    }
    try:
        model = algorithm.load(files.model, device=device, custom_objects=custom)
    except Exception as exc:
        raise ValueError(f"{files.label} {files.model} cannot be loaded: {exc}") from exc
    bad = [name for name, value in model.policy.state_dict().items() if not value.isfinite().all()]
    if bad:
        raise ValueError(
            f"{files.label} {files.model}: non-finite weights in {bad[:3]}"
            + (f" and {len(bad) - 3} more" if len(bad) > 3 else "")
            + " (a diverged or damaged model)"
        )
    layout = observation_layout(files.metadata)
    shape = tuple(model.observation_space.shape or ())
    if shape != (len(layout),):
        raise ValueError(
            f"{files.label} {files.model}: observation space shape {shape}, expected "
            f"({len(layout)},) (layout {list(layout)}){_layout_source(files.metadata_file)}"
        )
    return AgentPolicy(
        model.policy,
        files.obs_mean,
        files.obs_var,
        files.clip_obs,
        files.epsilon,
        files.metadata,
        str(files.model),
        num_threads,
    )
