"""Warm start: a new run that begins from a saved agent's weights and observation statistics.

A curriculum's later phase (for instance a precision phase with less exploration noise on top of
a trained generalist) is a run of its own: its own configuration, budget, learning-rate schedule
and validation, starting from the earlier agent instead of random weights. `warm_start` loads
into a freshly built model and `VecNormalize`:

    model.zip          every parameter of the policy and its optimiser state (`set_parameters`,
                       exact match: the same network, observation and action shapes)
    vecnormalize.npz   the running observation and return statistics (plain arrays: nothing is
                       unpickled, docs/usage.md "Trusting agent files"); entries the new
                       configuration pins (`obs_scales`) stay pinned at its scales
    replay_transitions.npz   off-policy agents, where present (an off-policy jump start's
                       flights, `benchmarks.training.transitions`; plain arrays too): the new
                       replay buffer starts with them, and ``learning_starts`` counts them:
                       SAC waits only for the transitions the buffer still lacks (none after a
                       jump start of at least ``learning_starts`` steps), so it neither flies
                       a warm-up nor delays its updates when it already has the data

A run whose critic reads the true errors (`benchmarks.training.privileged`) starts from a saved
agent's actor and critic, the critic widened by zero weights on the true errors (so it values
every state as the saved one did) and their statistics those of the observed errors; its
optimiser restarts, as the moments of the widened layer have no saved counterpart.

The agent's stages (an envelope guard, an actuator allocation: `metadata.json`) are not training
state and are not carried over: a schedule's export stages add them to the new run's agents
(`benchmarks.training.schedule`). The agent must have been trained with the same algorithm on the
same observation layout; anything else is a ValueError naming the difference.
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.training.residual import privileged_extension
from benchmarks.training.transitions import TRANSITIONS_FILE, fill_buffer, read_transitions
from controllers.agent import (
    METADATA_FILE,
    MODEL_FILE,
    STATS_FILE,
    check_agent,
    first_difference,
    read_policy_state,
)
from controllers.algorithms import ALGORITHMS
from controllers.ensemble import ENSEMBLE_FILE, ensemble_members

__all__ = [
    "MAX_NETWORK_WEIGHTS",
    "SEED_FIELD",
    "agent_for_seed",
    "check_initial_agents",
    "check_network_size",
    "check_warm_start",
    "warm_start",
]

SEED_FIELD = "{seed}"  # replaced by each seed's number in a multi-seed run's --init-from
# Weights of the networks a configuration may build (estimated from net_arch: an actor and a
# critic, or each list of a dict): 40 MB of float32, which with the optimiser's moments and the
# gradients every seed's worker holds four times; the shipped configurations need 0.1 % of it.
MAX_NETWORK_WEIGHTS = 10_000_000


def check_network_size(
    policy_kwargs: dict[str, Any], obs_dim: int, action_dim: int, where: str
) -> None:
    """ValueError naming ``where`` (the config file) when ``policy_kwargs``' net_arch would build
    networks of more than `MAX_NETWORK_WEIGHTS` weights: refused before a worker fails to
    allocate them."""
    arch = policy_kwargs.get("net_arch")
    if arch is None:  # SB3's default, small
        return
    chains = list(arch.values()) if isinstance(arch, dict) else [arch, arch]
    total = 0
    for sizes in chains:
        widths = [obs_dim + action_dim, *(int(n) for n in sizes), 2 * action_dim]
        total += sum(a * b + b for a, b in itertools.pairwise(widths))
    if total > MAX_NETWORK_WEIGHTS:
        raise ValueError(
            f"{where}: policy_kwargs net_arch {arch!r:.80} builds about {total:.3g} weights "
            f"(observation {obs_dim}, actions {action_dim}), more than {MAX_NETWORK_WEIGHTS:.0e}:"
            " use smaller layers"
        )


def check_initial_agents(
    agents: Sequence[str | Path],
    algo: str,
    obs_names: Sequence[str],
    action_dim: int,
    policy_kwargs: dict[str, Any],
    where: str,
    use_sde: bool = False,
) -> None:
    """Every initial agent of a run, before any worker starts: its files, algorithm and
    observation (`check_warm_start`), an off-policy agent's transitions (`TRANSITIONS_FILE`),
    and its weights loaded into the network this run builds (``policy_kwargs`` and
    ``use_sde``, which SB3 gives the policy, from the config file ``where``), exactly as
    `warm_start` will; a ValueError naming the agent folder and the config otherwise."""
    if not agents:
        return
    for agent in agents:
        check_warm_start(agent, algo, obs_names)
        transitions = Path(agent) / TRANSITIONS_FILE
        if ALGORITHMS[algo].off_policy and transitions.is_file():
            read_transitions(transitions, obs_names, action_dim, f"init_from {str(agent)!r}")
    import zipfile

    from gymnasium import spaces

    policy_class = ALGORITHMS[algo].sb3_class().policy_aliases["MlpPolicy"]
    box = spaces.Box(-np.inf, np.inf, (len(obs_names),), np.float32)
    actions = spaces.Box(-1.0, 1.0, (action_dim,), np.float32)
    sde = {"use_sde": True} if use_sde else {}  # gSDE's layers (SB3 passes it to the policy)
    network = policy_class(box, actions, lambda _: 0.0, **sde, **policy_kwargs)
    for agent in agents:
        model = Path(agent) / MODEL_FILE
        try:
            network.load_state_dict(read_policy_state(model), strict=True)
        except (RuntimeError, ValueError, KeyError, OSError, zipfile.BadZipFile) as exc:
            problem = " ".join(str(exc).split())
            raise ValueError(
                f"init_from {str(agent)!r}: its weights ({model}) do not fit the network of "
                f"{where} (policy_kwargs {policy_kwargs!r:.80}): {problem:.300}"
            ) from None


def agent_for_seed(template: str, seed: int) -> str:
    """The agent directory of ``seed``: ``template`` with `SEED_FIELD` replaced."""
    return template.replace(SEED_FIELD, str(int(seed)))


def check_warm_start(agent: str | Path, algo: str, obs_names: Sequence[str] | None = None) -> dict:
    """The agent's metadata, checked to start a run of ``algo`` on ``obs_names`` (None: not
    compared); ValueError naming a missing file, another algorithm or another layout."""
    folder = Path(agent)
    if not folder.exists():
        raise ValueError(f"init_from {str(folder)!r} does not exist")
    if (folder / ENSEMBLE_FILE).is_file():
        # an ensemble's mean action is no network a run can continue from; one member is
        members = [str(member) for member in ensemble_members(folder)]
        raise ValueError(
            f"init_from {str(folder)!r}: an ensemble of {len(members)} agents (its "
            f"{ENSEMBLE_FILE}: {', '.join(members)}) is not one network to start from: pass one "
            f"member's folder, e.g. {members[0]!r}"
        )
    for name in (MODEL_FILE, STATS_FILE, METADATA_FILE):
        if not (folder / name).is_file():
            raise ValueError(
                f"init_from {str(folder)!r}: {name} is missing (a saved agent "
                f"directory holds {MODEL_FILE}, {STATS_FILE} and "
                f"{METADATA_FILE})"
            )
    try:
        meta = json.loads((folder / METADATA_FILE).read_text())
    except (OSError, json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(
            f"init_from {str(folder)!r}: {METADATA_FILE} is unreadable: {exc}"
        ) from None
    if not isinstance(meta, dict):
        raise ValueError(f"init_from {str(folder)!r}: {METADATA_FILE} is not a JSON object")
    if meta.get("algo") != algo:
        raise ValueError(
            f"init_from {str(folder)!r}: the agent was trained with "
            f"{meta.get('algo')!r}, this run uses {algo!r}"
        )
    try:  # its files intact (a damaged model.zip named as such, not as a network misfit)
        check_agent(folder)
    except (ValueError, OSError) as exc:
        raise ValueError(f"init_from {str(folder)!r}: {exc}") from None
    _statistics(folder)  # readable, with the return statistics, before any work
    saved = meta.get("obs_names")
    if obs_names is not None and list(saved or ()) != list(obs_names):
        theirs, ours = list(saved or ()), list(obs_names)
        k = first_difference(theirs, ours)
        differs = (
            f"entry {k}: {theirs[k] if k < len(theirs) else None!r} against "
            f"{ours[k] if k < len(ours) else None!r}"
        )
        raise ValueError(
            f"init_from {str(folder)!r}: the agent observes {len(theirs)} entries, this run's "
            f"observation has {len(ours)} (first difference at {differs}): start from an agent "
            "trained on this run's observation"
        )
    return meta


def warm_start(
    model: Any, vec_normalize: Any, agent: str | Path, algo: str, obs_names: Sequence[str]
) -> dict[str, Any]:
    """Load ``agent``'s weights into ``model`` and its statistics into ``vec_normalize`` (module
    doc); returns the record for the new run's metadata."""
    from benchmarks.training.privileged import is_privileged, widen_for_privileged_critic

    folder = Path(agent)
    meta = check_warm_start(folder, algo, obs_names)
    privileged = is_privileged(model)
    try:
        if privileged:
            widen_for_privileged_critic(model, read_policy_state(folder / MODEL_FILE))
        else:
            model.set_parameters(str(folder / MODEL_FILE), exact_match=True, device="cpu")
    except (RuntimeError, ValueError, KeyError) as exc:  # torch: size mismatch, missing keys
        raise ValueError(
            f"init_from {str(folder)!r}: its weights do not fit this run's network ({exc})"
        ) from None
    obs_mean, obs_var, obs_count, ret_mean, ret_var, ret_count = _statistics(folder)
    if privileged:  # the true errors start from the statistics of the observed ones
        obs_mean = privileged_extension(obs_mean, obs_names)
        obs_var = privileged_extension(obs_var, obs_names)
    target = vec_normalize.obs_rms
    if np.shape(obs_mean) != np.shape(target.mean):
        raise ValueError(
            f"init_from {str(folder)!r}: observation statistics of shape "
            f"{np.shape(obs_mean)}, this run's are "
            f"{np.shape(target.mean)}"
        )
    target.mean = np.array(obs_mean, dtype=np.float64)
    target.var = np.array(obs_var, dtype=np.float64)
    target.count = float(obs_count)
    if hasattr(target, "_pin"):  # this configuration's fixed scales win
        target._pin()
    vec_normalize.ret_rms.mean = np.array(ret_mean, dtype=np.float64)
    vec_normalize.ret_rms.var = np.array(ret_var, dtype=np.float64)
    vec_normalize.ret_rms.count = float(ret_count)
    record = {
        "init_from": str(folder),
        "num_timesteps": meta.get("num_timesteps"),
        "git_commit": meta.get("git_commit"),
        "config_file": meta.get("config_file"),
    }
    if privileged:
        record["optimizer"] = "restarted (the critic widened for the true errors)"
    transitions = folder / TRANSITIONS_FILE
    if getattr(model, "replay_buffer", None) is not None and transitions.is_file():
        record["replay_buffer"] = _load_transitions(model, transitions, obs_names, folder)
    return record


def _load_transitions(model: Any, path: Path, obs_names: Sequence[str], folder: Path) -> dict:
    """Fill ``model``'s replay buffer from ``path`` and count it in ``learning_starts`` (module
    doc); the record for the run's metadata."""
    where = f"init_from {str(folder)!r}"
    stream = read_transitions(path, obs_names, int(model.action_space.shape[0]), where)
    added = fill_buffer(model.replay_buffer, stream)
    configured = int(model.learning_starts)
    model.learning_starts = max(0, configured - added)
    return {
        "transitions": added,
        "configured_learning_starts": configured,
        "learning_starts": model.learning_starts,
    }


RETURN_KEYS = ("ret_mean", "ret_var", "ret_count")


def _statistics(folder: Path) -> tuple[Any, ...]:
    """(obs mean, var, count, return mean, var, count) from the agent's vecnormalize.npz, read
    without unpickling; a ValueError naming the file when it is unreadable or lacks the return
    statistics (agents saved before they were recorded there)."""
    path = folder / STATS_FILE
    try:
        with np.load(path, allow_pickle=False) as data:
            values = {key: np.asarray(data[key]) for key in data.files}
    except Exception as exc:
        raise ValueError(f"init_from {str(folder)!r}: {STATS_FILE} is unreadable: {exc}") from None
    missing = [k for k in ("mean", "var", "count", *RETURN_KEYS) if k not in values]
    if missing:
        raise ValueError(
            f"init_from {str(folder)!r}: {STATS_FILE} lacks {missing} (saved before auv-gym "
            "recorded the return statistics there); in a session you trust, rewrite it from the "
            "agent's vecnormalize.pkl with benchmarks.training.checkpoints.stats_from_vecnormalize"
        )
    for key, value in values.items():
        if key != "obs_names" and not np.all(np.isfinite(value)):
            raise ValueError(f"init_from {str(folder)!r}: {STATS_FILE} {key} is not finite")
    return tuple(values[k] for k in ("mean", "var", "count", *RETURN_KEYS))
