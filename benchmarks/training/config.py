"""RL-Zoo hyper-parameter files and the SB3 algorithms the harness trains.

A file has one top-level section per env id, in rl_zoo3 2.x format::

    AUVPath3D-v0:
      n_envs: 32
      n_timesteps: !!float 2e7
      policy: MlpPolicy
      normalize: "dict(norm_obs=True, norm_reward=True)"
      learning_rate: lin_3e-4
      ...

The keys an algorithm accepts are listed in its `Algorithm` entry of
`controllers.algorithms.ALGORITHMS` (PPO, SAC; TQC, CrossQ from sb3-contrib), the table the
agent loader reads too; another algorithm is one more entry there, read with the same
`read_zoo_config`. Off-policy algorithms (`Algorithm.off_policy`) also save their replay buffer in
checkpoints, so a resumed run continues with the samples it had.

An optional ``residual`` section trains a residual agent (docs/design.md §3.10): the harness
wraps the training env in `benchmarks.training.residual_env.ResidualVectorEnv` with these
settings (`benchmarks.training.residual.ResidualTraining`)::

      residual:
        base: fbsm_colos            # a classical controller name (controllers.CLASSICAL)
        bound: [0.25, 0.5, 0.5]     # β per X, M, N, normalised actuator units
        tv_weight: 0.25             # chattering charge per unit TV of the applied action
        base_kwargs: {}             # base gains (actuator and control_dt come from the env)
        envelope_guard: {nose_up_command: -1.0}  # optional: guard the applied action

An optional ``jump_start`` mapping makes the run imitate a classical expert (or a dataset of
``auv-gym demos``) instead of running PPO: `benchmarks.training.jump_start`, checked here with
the rest of the file (the dataset against the agent's observation and actions).

An optional ``demo_regularization`` mapping (SAC) keeps the actor near the expert's labels of the
jump start it starts from while SAC fine-tunes it: a behaviour-cloning term in the actor loss,
an actor delay, a share of demonstrations in every batch
(`benchmarks.training.demo_regularization`).

An optional ``action_bounds`` key narrows the box the agent acts in, a sub-box of the env's
[−1, 1]³ given as ``[[low_X, low_M, low_N], [high_X, high_M, high_N]]``: the agent's action
space becomes that box (`benchmarks.training.train.ActionBox`), saved with the model, so a loaded
agent acts inside it too. For off-policy agents, whose squashed-Gaussian exploration covers the
whole box from the first step (`benchmarks.analysis.action_bounds` measures what that does).

An optional ``plant_share`` or ``actuator_share`` mapping puts a share of the ``n_envs``
training vehicles on another plant or actuator than the section's (``plant_share: {6dof: 0.25}``:
round(n_envs × 0.25) vehicles fly the 6-DOF plant, the others the ``env_kwargs``' plant;
``actuator_share: {fins: 0.2}`` likewise the fins): `benchmarks.training.vehicle_share`.
"""

from __future__ import annotations

import ast
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from auv_gym import ENV_ID
from benchmarks.training.residual import ResidualTraining
from benchmarks.training.selection_rule import DEFAULT_RULE, SelectionRule, parse_selection
from benchmarks.training.vehicle_share import VehicleShare, parse_vehicle_share
from controllers.algorithms import ALGORITHMS, Algorithm

__all__ = [
    "ALGORITHMS",
    "Algorithm",
    "ZooConfig",
    "check_algo_kwargs",
    "check_normalize",
    "read_zoo_config",
    "schedule",
]

# RL-Zoo keys of the harness itself (not constructor arguments of the algorithm).
ZOO_KEYS = frozenset(
    {
        "n_envs",
        "n_timesteps",
        "policy",
        "normalize",
        "policy_kwargs",
        "env_kwargs",
        "residual",
        "action_bounds",
        "obs_scales",
        "stages",
        "envelope_guard",  # refused with the stage that replaces it
        "jump_start",  # imitation of a classical expert instead of PPO (`jump_start`)
        "demo_regularization",  # SAC kept near the jump start's labels (`demo_regularization`)
        "plant_share",  # a share of the vehicles on another plant (`vehicle_share`)
        "actuator_share",  # a share of the vehicles on another actuator (`vehicle_share`)
        "selection",  # how evaluations rank to keep the best agent (`selection_rule`)
    }
)
# Keys of removed training features (no kept agent used them; their findings stay in
# docs/results.md): a file that still names one is refused with what the key did.
REMOVED_KEYS = {
    "action_increment": "incremental commands",
    "action_scale": "scaled commands",
    "action_std_schedule": "the exploration-noise schedule",
    "cost_penalty": "the safety cost as a training penalty",
}


@dataclass(frozen=True)
class ZooConfig:
    """One env's section of an RL-Zoo hyper-parameter file, validated for one algorithm.

    `normalize` holds the `VecNormalize` keyword arguments; `algo_kwargs` the algorithm's
    constructor arguments, with "lin_<x>" schedules still as strings (`model_kwargs` resolves
    them). `residual` holds the residual settings when the file has a ``residual`` section.
    """

    algo: str
    n_envs: int
    n_timesteps: int
    policy: str
    normalize: dict[str, Any]
    policy_kwargs: dict[str, Any]
    env_kwargs: dict[str, Any]
    algo_kwargs: dict[str, Any]
    raw: dict[str, Any] = field(default_factory=dict)
    residual: ResidualTraining | None = None
    action_bounds: tuple[tuple[float, ...], tuple[float, ...]] | None = None  # (low, high)
    obs_scales: dict[str, float] | None = None  # entries at fixed scales (`training.normalization`)
    stages: tuple[dict[str, Any], ...] = ()  # trained inside and exported (`controllers.stages`)
    jump_start: Any = None  # `benchmarks.training.jump_start.JumpStart`: imitation, not PPO
    # `benchmarks.training.demo_regularization.DemoRegularization`: SAC near the expert's labels
    demo_regularization: Any = None
    vehicle_share: VehicleShare | None = None  # a share of the vehicles on another plant/actuator
    selection: SelectionRule = DEFAULT_RULE  # how its evaluations rank (`selection_rule`)

    def model_kwargs(self) -> dict[str, Any]:
        """`algo_kwargs` with the algorithm's schedule keys turned into SB3 schedules."""
        schedules = ALGORITHMS[self.algo].schedules
        return {k: schedule(v) if k in schedules else v for k, v in self.algo_kwargs.items()}


def read_zoo_config(path: str | os.PathLike, env_id: str = ENV_ID, algo: str = "ppo") -> ZooConfig:
    """Parse the `env_id` section of an RL-Zoo YAML file for `algo` (rl_zoo3 2.x semantics).

    `normalize` may be a bool, a dict or a string evaluating to a dict, as in RL Zoo; the
    discount `gamma` is copied into it like RL Zoo does. `policy_kwargs` may be a dict or a
    string such as "dict(net_arch=[64, 64])" (parsed as a literal, never evaluated:
    `_literal`).
    """
    import yaml

    if algo not in ALGORITHMS:
        raise ValueError(f"unknown algorithm {algo!r}; valid: {sorted(ALGORITHMS)}")
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"hyper-parameter file {path} does not exist")
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as error:
        problem = " ".join(str(error).split())
        raise ValueError(f"{path}: cannot be read as YAML: {problem}") from None
    if not isinstance(data, dict) or env_id not in data:
        found = data if isinstance(data, dict) else {}
        keys = [k for k in found if re.fullmatch(r"\w+-v\d+", str(k))]
        hint = f" (its env ids: {keys}; pass --env-id {keys[0]})" if keys else ""
        raise ValueError(f"{path}: no top-level key {env_id!r}{hint}")
    if not isinstance(data[env_id], dict):
        raise ValueError(
            f"{path}: {env_id} must be a mapping of hyper-parameters, got "
            f"{type(data[env_id]).__name__} {data[env_id]!r:.60}"
        )
    section = dict(data[env_id])
    removed = sorted(set(section) & set(REMOVED_KEYS))
    if removed:
        key = removed[0]
        raise ValueError(
            f"{path}: {env_id}: key {key!r} ({REMOVED_KEYS[key]}) was removed from auv-gym; "
            "delete it from the file"
        )
    accepted = ALGORITHMS[algo].hyperparameters
    unknown = set(section) - ZOO_KEYS - accepted
    if unknown:
        raise ValueError(f"{path}: unsupported keys for {env_id}: {sorted(unknown)}")
    for key in ("n_timesteps", "policy"):
        if key not in section:
            raise ValueError(f"{path}: {env_id} needs {key!r}")
    n_envs = section.get("n_envs", 1)
    if isinstance(n_envs, bool) or not isinstance(n_envs, int) or n_envs < 1:
        raise ValueError(f"{path}: {env_id}: n_envs must be an integer >= 1, got {n_envs!r}")
    try:
        n_timesteps = float(section["n_timesteps"])
    except (TypeError, ValueError):
        n_timesteps = math.nan
    if not (math.isfinite(n_timesteps) and n_timesteps >= 1 and n_timesteps == int(n_timesteps)):
        raise ValueError(
            f"{path}: {env_id}: n_timesteps must be a whole number >= 1, got "
            f"{section['n_timesteps']!r}"
        )
    n_timesteps = int(n_timesteps)
    algo_kwargs = {k: section[k] for k in accepted if k in section}
    normalize = section.get("normalize", False)
    if isinstance(normalize, str):
        normalize = _eval_kwargs(normalize, path, "normalize")
    if normalize is True:
        normalize = {}
    elif normalize is False:
        raise ValueError(f"{path}: normalize must be enabled (VecNormalize, docs/design.md §3)")
    elif not isinstance(normalize, dict):
        raise ValueError(f"{path}: normalize must be a bool, a dict or a dict expression")
    normalize = {"norm_obs": True, "norm_reward": True, **normalize}
    if "gamma" in algo_kwargs:
        normalize["gamma"] = float(algo_kwargs["gamma"])
    if not normalize["norm_obs"]:
        raise ValueError(f"{path}: this project requires observation normalisation")
    policy_kwargs = section.get("policy_kwargs", {})
    if isinstance(policy_kwargs, str):
        policy_kwargs = _eval_kwargs(policy_kwargs, path, "policy_kwargs")
    env_kwargs = dict(section.get("env_kwargs") or {})
    residual = None
    if "residual" in section:
        residual = ResidualTraining.from_dict(section["residual"], f"{path}: residual")
        if residual.privileged_critic and ALGORITHMS[algo].off_policy:
            raise ValueError(
                f"{path}: residual privileged_critic gives PPO's value network the true errors; "
                f"{algo} has no such critic here: train it with --algo ppo or leave it out"
            )
    action_bounds = None
    if "action_bounds" in section:
        if residual is not None:
            raise ValueError(f"{path}: action_bounds and residual exclude each other")
        from benchmarks.training.action_box import parse_action_bounds

        action_bounds = parse_action_bounds(section["action_bounds"], path)
    from benchmarks.training.agent_interface import parse_interface

    interface = parse_interface(section, path, env_id, residual)
    # Every value SB3 would refuse, or accept and train nonsense with, is refused here: before
    # the first training step, not at the model's construction or in its first update.
    where = f"{path}: {env_id}"
    check_algo_kwargs(algo, algo_kwargs, n_envs, where)
    check_normalize(normalize, where)
    _check_policy(section["policy"], policy_kwargs, algo, where)
    _check_env_kwargs(env_id, env_kwargs, where)
    vehicle_share = parse_vehicle_share(section, n_envs, env_id, env_kwargs, where)
    selection = DEFAULT_RULE
    if "selection" in section:
        selection = parse_selection(section["selection"], where)
    jump_start = None
    if "jump_start" in section:
        from benchmarks.training.jump_start import parse_jump_start

        jump_start = parse_jump_start(section["jump_start"], where)
    demo_regularization = None
    if "demo_regularization" in section:
        from benchmarks.training.demo_regularization import parse_demo_regularization

        demo_regularization = parse_demo_regularization(section["demo_regularization"], algo, where)
    cfg = ZooConfig(
        algo=algo,
        n_envs=n_envs,
        n_timesteps=n_timesteps,
        policy=str(section["policy"]),
        normalize=normalize,
        policy_kwargs=dict(policy_kwargs),
        env_kwargs=env_kwargs,
        algo_kwargs=algo_kwargs,
        raw=section,
        residual=residual,
        action_bounds=action_bounds,
        jump_start=jump_start,
        demo_regularization=demo_regularization,
        vehicle_share=vehicle_share,
        selection=selection,
        **interface,
    )
    if jump_start is not None:
        from benchmarks.training.jump_start import check_jump_start

        check_jump_start(cfg, env_id, where)
    return cfg


# (low, high, low_open, high_open) of the numeric hyper-parameters; None: unbounded.
_RANGES: dict[str, tuple[float, float, bool, bool]] = {
    "learning_rate": (0.0, math.inf, True, True),
    "gamma": (0.0, 1.0, False, False),
    "gae_lambda": (0.0, 1.0, False, False),
    "clip_range": (0.0, math.inf, True, True),
    "clip_range_vf": (0.0, math.inf, True, True),
    "vf_coef": (0.0, math.inf, False, True),
    "max_grad_norm": (0.0, math.inf, True, True),
    "target_kl": (0.0, math.inf, True, True),
    "tau": (0.0, 1.0, True, False),
    "ent_coef": (0.0, math.inf, False, True),
}
# Integer hyper-parameters and their smallest value.
_INTEGERS = {
    "n_epochs": 1,
    "stats_window_size": 1,
    "sde_sample_freq": -1,
    "buffer_size": 1,
    "learning_starts": 0,
    "target_update_interval": 1,
    "n_steps": 1,
    "policy_delay": 1,
    "top_quantiles_to_drop_per_net": 0,
}
_BOOLEANS = ("normalize_advantage", "use_sde", "optimize_memory_usage", "use_sde_at_warmup")
_OPTIONAL = ("clip_range_vf", "target_kl")  # None (null) switches them off
# VecNormalize keyword arguments a config may set, with their checks.
_NORMALIZE = {
    "norm_obs": bool,
    "norm_reward": bool,
    "clip_obs": "positive",
    "clip_reward": "positive",
    "gamma": "unit",
    "epsilon": "positive",
}


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _text_hint(value: Any) -> str:
    """For a number YAML 1.1 read as text ("3e-4": no dot before the exponent), how to write it."""
    if isinstance(value, str):
        try:
            number = float(value)
        except ValueError:
            return ""
        if math.isfinite(number) and "e" in value.lower() and "." not in value:
            mantissa, exponent = value.lower().split("e")
            return f" (YAML reads {value} as text: write {mantissa}.0e{exponent})"
    return ""


def _number(key: str, value: Any, where: str) -> None:
    """A finite number inside the key's range (`_RANGES`); ValueError naming key and range."""
    low, high, low_open, high_open = _RANGES[key]
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if ok:
        ok = (value > low if low_open else value >= low) and (
            value < high if high_open else value <= high
        )
    if not ok:
        left, right = "(" if low_open else "[", ")" if high_open else "]"
        top = "inf" if high == math.inf else f"{high:g}"
        raise ValueError(
            f"{where}: {key} must be a number in {left}{low:g}, {top}{right}, got {value!r}"
            + _text_hint(value)
        )


def check_algo_kwargs(algo: str, kwargs: Mapping[str, Any], n_envs: int, where: str) -> None:
    """Refuse hyper-parameter values SB3 would reject or train nonsense with (a negative
    learning rate, a batch of one, γ > 1, ...): ValueError naming ``where``, the key, the
    allowed range and the value."""
    for key, value in kwargs.items():
        if key in _OPTIONAL and value is None:
            continue
        if key in ALGORITHMS[algo].schedules and isinstance(value, str):
            match = re.fullmatch(r"lin_([0-9.eE+-]+)", value)
            try:
                start = float(match.group(1)) if match else math.nan
            except ValueError:
                start = math.nan
            if not (math.isfinite(start) and start > 0):
                raise ValueError(
                    f"{where}: {key} {value!r} must be a positive number or 'lin_<x>' with x > 0"
                    + _text_hint(value)
                )
        elif key == "ent_coef" and ALGORITHMS[algo].off_policy and isinstance(value, str):
            match = re.fullmatch(r"auto(?:_([0-9.eE+-]+))?", value)
            try:
                ok = bool(match) and (match.group(1) is None or float(match.group(1)) > 0)
            except ValueError:
                ok = False
            if not ok:
                raise ValueError(
                    f"{where}: ent_coef {value!r} must be a number >= 0, 'auto' "
                    "or 'auto_<x>' with x > 0"
                )
        elif key in _RANGES:
            _number(key, value, where)
        elif key in _INTEGERS:
            if not _is_int(value) or value < _INTEGERS[key]:
                raise ValueError(
                    f"{where}: {key} must be an integer >= {_INTEGERS[key]}, got {value!r}"
                )
        elif key in _BOOLEANS:
            if not isinstance(value, bool):
                raise ValueError(f"{where}: {key} must be true or false, got {value!r}")
        elif key == "batch_size":
            smallest = 2 if algo == "ppo" else 1  # PPO normalises advantages over a batch
            if not _is_int(value) or value < smallest:
                raise ValueError(
                    f"{where}: batch_size must be an integer >= {smallest}, got {value!r}"
                )
        elif key == "gradient_steps":
            if not _is_int(value) or not (value >= 1 or value == -1):
                raise ValueError(
                    f"{where}: gradient_steps must be an integer >= 1 or -1 (as "
                    f"many as env steps), got {value!r}"
                )
        elif key == "train_freq":
            unit_ok = (
                isinstance(value, (list, tuple))
                and len(value) == 2
                and value[1] in ("step", "episode")
            )
            count = value[0] if unit_ok else value
            if not _is_int(count) or count < 1:
                raise ValueError(
                    f"{where}: train_freq must be an integer >= 1 or [n, 'step' | "
                    f"'episode'], got {value!r}"
                )
        elif key == "target_entropy":
            finite = isinstance(value, (int, float)) and math.isfinite(value)
            if value != "auto" and (isinstance(value, bool) or not finite):
                raise ValueError(
                    f"{where}: target_entropy must be 'auto' or a finite number, got {value!r}"
                )
    rollout = kwargs.get("n_steps", 2048) * n_envs
    if algo == "ppo" and rollout < 2:
        raise ValueError(
            f"{where}: n_steps × n_envs must be at least 2 (PPO's rollout), got "
            f"{kwargs.get('n_steps', 2048)} × {n_envs}"
        )
    if algo == "ppo" and kwargs.get("batch_size", 64) > rollout:
        raise ValueError(
            f"{where}: batch_size {kwargs['batch_size']} exceeds the rollout n_steps × n_envs = "
            f"{kwargs.get('n_steps', 2048)} × {n_envs} = {rollout}: PPO would train on batches "
            f"of {rollout}; use batch_size <= {rollout}"
        )


def check_normalize(normalize: Mapping[str, Any], where: str) -> None:
    """VecNormalize keyword arguments: known keys, booleans, positive clips and ε, γ in [0, 1]."""
    unknown = sorted(set(normalize) - set(_NORMALIZE))
    if unknown:
        raise ValueError(
            f"{where}: normalize has unknown keys {unknown}; valid: {sorted(_NORMALIZE)}"
        )
    for key, value in normalize.items():
        kind = _NORMALIZE[key]
        number = isinstance(value, (int, float)) and not isinstance(value, bool)
        if kind is bool:
            ok = isinstance(value, bool)
        elif kind == "positive":
            ok = number and math.isfinite(value) and value > 0
        else:
            ok = number and 0.0 <= value <= 1.0
        if not ok:
            wanted = {
                bool: "true or false",
                "positive": "a finite number > 0",
                "unit": "a number in [0, 1]",
            }[kind]
            raise ValueError(f"{where}: normalize {key} must be {wanted}, got {value!r}")


def _check_policy(policy: Any, policy_kwargs: Mapping[str, Any], algo: str, where: str) -> None:
    """MlpPolicy (the observation is a vector) and keyword arguments its constructor takes."""
    if policy != "MlpPolicy":
        raise ValueError(
            f"{where}: policy must be 'MlpPolicy' (the observation is a vector), got {policy!r}"
        )
    import inspect

    policy_class = ALGORITHMS[algo].sb3_class().policy_aliases["MlpPolicy"]
    accepted = set(inspect.signature(policy_class.__init__).parameters) - {
        "self",
        "observation_space",
        "action_space",
        "lr_schedule",
    }
    unknown = sorted(set(policy_kwargs) - accepted)
    if unknown:
        raise ValueError(
            f"{where}: policy_kwargs has keys {policy_class.__name__} does not take: {unknown}"
        )
    arch = policy_kwargs.get("net_arch")
    layers = list(arch.values()) if isinstance(arch, dict) else [arch] if arch is not None else []
    for sizes in layers:
        if not isinstance(sizes, (list, tuple)) or not all(_is_int(n) and n >= 1 for n in sizes):
            raise ValueError(
                f"{where}: policy_kwargs net_arch must be a list of layer sizes "
                f">= 1 (or a dict of such lists), got {arch!r}"
            )
    log_std = policy_kwargs.get("log_std_init", 0.0)
    number = isinstance(log_std, (int, float)) and not isinstance(log_std, bool)
    if not (number and math.isfinite(log_std)):
        raise ValueError(
            f"{where}: policy_kwargs log_std_init must be a finite number, got {log_std!r}"
        )


def _check_env_kwargs(env_id: str, env_kwargs: Mapping[str, Any], where: str) -> None:
    """The training env's keyword arguments, as the env would check them at its creation."""
    from auv_gym import VARIANTS
    from auv_gym.sim.config import SimConfig

    if env_id not in VARIANTS:  # another registered env checks its own arguments
        import gymnasium

        try:
            gymnasium.spec(env_id)
        except gymnasium.error.Error as error:
            raise ValueError(f"{where}: {error}") from None
        return
    try:
        SimConfig.from_kwargs(**{**VARIANTS[env_id], **env_kwargs})
    except (TypeError, ValueError) as error:
        raise ValueError(f"{where}: env_kwargs: {error}") from None


# The activation functions a hyper-parameter string may name (`nn.<name>`): torch classes.
ACTIVATIONS = ("ReLU", "Tanh", "ELU", "LeakyReLU", "SiLU", "GELU", "Sigmoid", "Softplus", "Mish")


def _literal(node: ast.AST, where: str) -> Any:
    """The value of a literal expression node: numbers, strings, booleans, None, lists, tuples,
    dicts, ``dict(key=...)`` and ``nn.<activation>`` (`ACTIVATIONS`); a one-line ValueError
    naming ``where`` and the construct for anything else (no call, name or attribute runs)."""
    if isinstance(node, ast.Constant) and isinstance(
        node.value, (int, float, str, bool, type(None))
    ):
        return node.value
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        value = _literal(node.operand, where)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return -value if isinstance(node.op, ast.USub) else value
    if isinstance(node, ast.List):
        return [_literal(e, where) for e in node.elts]
    if isinstance(node, ast.Tuple):
        return tuple(_literal(e, where) for e in node.elts)
    if isinstance(node, ast.Dict) and None not in node.keys:
        return {
            _literal(k, where): _literal(v, where)
            for k, v in zip(node.keys, node.values, strict=True)
        }
    if (
        isinstance(node, ast.Call)
        and isinstance(node.func, ast.Name)
        and node.func.id == "dict"
        and not node.args
        and all(k.arg is not None for k in node.keywords)
    ):
        return {k.arg: _literal(k.value, where) for k in node.keywords}
    if (
        isinstance(node, ast.Attribute)
        and isinstance(node.value, ast.Name)
        and node.value.id == "nn"
        and node.attr in ACTIVATIONS
    ):
        import torch

        return getattr(torch.nn, node.attr)
    raise ValueError(
        f"{where}: {ast.unparse(node)!r} is not a literal (numbers, strings, lists, dict(...), "
        f"nn.<activation> with activation in {list(ACTIVATIONS)})"
    )


def _eval_kwargs(text: str, path: Path, key: str) -> dict[str, Any]:
    """A dict from a hyper-parameter string such as "dict(net_arch=[64, 64],
    activation_fn=nn.ReLU)", parsed as a literal (`_literal`), never evaluated."""
    where = f"{path}: {key}"
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError as exc:
        raise ValueError(f"{where} {text!r} is not an expression: {exc.msg}") from None
    value = _literal(tree.body, where)
    if not isinstance(value, dict):
        raise ValueError(f"{where} must be a dict, got {type(value).__name__}")
    return value


def schedule(value: Any) -> Any:
    """RL-Zoo schedules: "lin_<x>" decays linearly from x to 0; numbers stay constant."""
    if isinstance(value, str):
        match = re.fullmatch(r"lin_([0-9.eE+-]+)", value)
        if not match:
            raise ValueError(f"schedule {value!r} is not a number or 'lin_<x>'")
        from stable_baselines3.common.utils import LinearSchedule

        return LinearSchedule(float(match.group(1)), 0.0, 1.0)
    return float(value)
