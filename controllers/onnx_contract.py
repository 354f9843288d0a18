"""The contract of an exported agent (`auv-gym export`): what its graph takes, gives and was
built for, read and checked before anything trusts it.

An export is two files side by side::

    policy.onnx   one graph: the raw observation (and the agent's memory) → the command the env
                  receives: normalisation, the network's deterministic action, the action scaling
                  and every stage (`controllers.onnx_export`, docs/design.md §3.18)
    policy.json   its contract: input and output layout with names and units, the memory's size
                  and when it resets, and everything the graph was built for: the env (id and
                  arguments, the actuator and its settings included), the control period, the
                  plant, the actuator its commands are for, the allocation's vehicle constants and
                  the stages; and where it came from (`CONTRACT_FORMAT`). The graph's metadata
                  properties repeat what it was built for.

`read_contract` trusts neither file: both sizes are capped before they are read; the graph's
bytes must have the contract's SHA-256 and are the bytes onnxruntime will load
(`controllers.onnx_policy`; external data, which the hash would not cover, is refused,
`controllers.onnx_file`); the contract must agree with itself (known actuator and plant, real
booleans, stages, memory size, inputs and outputs that fit each other), with the env it describes
and with the graph's metadata. Each refusal is one ValueError line naming the file. Nothing here
imports onnxruntime, onnx or torch.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from controllers.allocation import ALLOCATION_FIELDS

__all__ = [
    "ACTUATORS",
    "CONTRACT_FORMAT",
    "CONTRACT_VERSION",
    "MAX_CONTRACT_BYTES",
    "MAX_GRAPH_BYTES",
    "OnnxContract",
    "allocation_settings",
    "check_contract",
    "check_path",
    "contract_path",
    "graph_io",
    "read_contract",
    "sha256_of",
    "short",
]

CONTRACT_FORMAT = "auv-gym onnx policy"
# 2: the contract and the graph's metadata state the actuator settings, the plant and the
# allocation's vehicle constants the graph was built for, and the env arguments name them.
CONTRACT_VERSION = 2
ACTUATORS = ("paper", "fins", "realistic")  # what an export's commands may be for
MAX_GRAPH_BYTES = 256 * 2**20  # an .onnx file read at most (the shipped ones: 23–320 KiB)
MAX_CONTRACT_BYTES = 2**20  # a contract read at most (the shipped ones: 3–6 KiB)


def contract_path(onnx_path: str | os.PathLike) -> Path:
    """The contract beside an ONNX file: ``policy.onnx`` → ``policy.json``."""
    return Path(onnx_path).with_suffix(".json")


def sha256_of(path: Path) -> str:
    """The SHA-256 of a file's bytes, hex."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def graph_io(
    obs_dim: int, state_size: int, residual: bool
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """The inputs and outputs of an export's graph, as its contract lists them: name, shape
    (``"n"``: the batch) and type."""

    def tensor(name: str, size: int) -> dict[str, Any]:
        return {"name": name, "shape": ["n", size], "dtype": "float32"}

    inputs = [tensor("observation", obs_dim)]
    outputs = [tensor("action", 3)]
    if state_size:
        inputs.append(tensor("state", state_size))
        outputs.append(tensor("next_state", state_size))
    if residual:
        inputs.append(tensor("base_action", 3))
    return inputs, outputs


@dataclass(frozen=True)
class OnnxContract:
    """A checked contract (`read_contract`): what the graph takes and gives, what it was built
    for, and the graph's bytes as checked."""

    onnx: Path
    file: Path
    obs_names: tuple[str, ...]
    state_size: int
    actuator: str  # the env actuator its commands are for ("paper", "fins", "realistic")
    allocated: bool  # the agent lists the actuator allocation among its stages
    control_period_s: float
    env_id: str
    env_kwargs: dict[str, Any]  # the env the graph was built for (`auv_gym.rollout` runs it there)
    residual: dict[str, Any] | None  # {"base", "base_kwargs", ...} of a residual agent
    raw: dict[str, Any]
    plant: str = "5dof"  # the plant the agent was trained on (the graph models none)
    actuator_params: dict[str, Any] | None = None  # the realistic allocation's settings
    # The allocation stage's vehicle constants: {"fin_gain_kg": K·δ_max, "limits": [X, M, N]}
    allocation: dict[str, Any] | None = None
    stages: tuple[dict[str, Any], ...] = ()
    data: bytes = field(default=b"", repr=False)  # the graph's bytes, as hashed

    @property
    def obs_dim(self) -> int:
        return len(self.obs_names)

    @property
    def one_actuator(self) -> bool:
        """The commands mean something on `actuator` only: the graph allocates to it, or the
        agent commands the propeller and fins itself."""
        return self.allocation is not None or (self.actuator == "realistic" and not self.allocated)


def _field(data: Mapping[str, Any], key: str, kind: type | tuple[type, ...], where: Path) -> Any:
    if key not in data:
        raise ValueError(f"ONNX contract {where}: missing {key!r}")
    value = data[key]
    kinds = kind if isinstance(kind, tuple) else (kind,)
    if not isinstance(value, kinds) or (isinstance(value, bool) and bool not in kinds):
        names = " or ".join("true/false" if k is bool else k.__name__ for k in kinds)
        raise ValueError(f"ONNX contract {where}: {key!r} is {value!r:.80}, not {names}")
    return value


def _read_capped(path: Path, limit: int, what: str) -> bytes:
    """The bytes of ``path``, refused in one line when larger than ``limit``."""
    size = path.stat().st_size
    if size > limit:
        raise ValueError(
            f"{what} {path} is {size:,} bytes, more than the {limit:,} auv-gym reads; refused"
        )
    with path.open("rb") as fh:
        data = fh.read(limit + 1)
    if len(data) > limit:  # grew since the stat
        raise ValueError(f"{what} {path} is more than the {limit:,} bytes auv-gym reads; refused")
    return data


def check_path(path: Any, what: str) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        from auv_gym.support.validation import ArgumentTypeError

        raise ArgumentTypeError(
            f"{what} must be the path of an exported agent's .onnx file (a str or "
            f"os.PathLike), got {type(path).__name__} {path!r:.60}"
        )
    return Path(path)


def read_contract(path: str | os.PathLike) -> OnnxContract:
    """The contract of an exported agent (the .onnx file or its .json), checked without
    onnxruntime (module doc): sizes, format and version, the graph's SHA-256, the graph's
    content (`controllers.onnx_file.scan_model`), the contract against itself and against the
    graph's metadata. FileNotFoundError or a one-line ValueError naming the file otherwise."""
    given = check_path(path, "an exported agent's path")
    onnx_file = given if given.suffix == ".onnx" else given.with_suffix(".onnx")
    file = contract_path(onnx_file)
    for needed, what in ((onnx_file, "ONNX graph"), (file, "contract")):
        if not needed.is_file():
            raise FileNotFoundError(f"exported agent {given}: {what} {needed} does not exist")
    try:
        data = json.loads(_read_capped(file, MAX_CONTRACT_BYTES, "ONNX contract"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise ValueError(f"ONNX contract {file} is unreadable: {exc}") from None
    graph = _read_capped(onnx_file, MAX_GRAPH_BYTES, "ONNX graph")
    return check_contract(data, graph, onnx_file, file)


def check_contract(data: Any, graph: bytes, onnx_file: Path, file: Path) -> OnnxContract:
    """The `OnnxContract` of the contract JSON ``data`` (``file``) and the graph's bytes
    ``graph`` (``onnx_file``), after every check of `read_contract` but the files' sizes (the
    export runs it on what it is about to write)."""
    from controllers.onnx_file import scan_model

    if not isinstance(data, dict) or data.get("format") != CONTRACT_FORMAT:
        raise ValueError(f"ONNX contract {file}: not an {CONTRACT_FORMAT!r} contract")
    if data.get("format_version") != CONTRACT_VERSION:
        raise ValueError(
            f"ONNX contract {file}: format version {data.get('format_version')!r:.20}, this "
            f"auv-gym reads {CONTRACT_VERSION}: re-export the agent with auv-gym export"
        )
    digest = _field(data, "onnx_sha256", str, file)
    if hashlib.sha256(graph).hexdigest() != digest:
        raise ValueError(
            f"ONNX graph {onnx_file} does not match its contract {file} (SHA-256 differs: "
            "damaged, or replaced without re-exporting)"
        )
    if len(graph) > MAX_GRAPH_BYTES:
        raise ValueError(f"ONNX graph {onnx_file}: more than {MAX_GRAPH_BYTES:,} bytes")
    properties = scan_model(graph, onnx_file)
    contract = _contract_of(data, onnx_file, file, graph)
    _check_against_graph(contract, properties)
    return contract


def _contract_of(data: dict[str, Any], onnx_file: Path, file: Path, graph: bytes) -> OnnxContract:
    """The `OnnxContract` of the contract JSON ``data``, each field checked and the fields
    checked against each other and against the env they describe."""
    from auv_gym import VARIANTS, resolve_env_id
    from auv_gym.sim.config import PLANTS, SimConfig
    from auv_gym.vehicle.actuators import actuator_params_from_spec
    from controllers.stages import check_stage_specs

    observation = _field(data, "observation", dict, file)
    names = _field(observation, "names", list, file)
    if not names or not all(isinstance(n, str) for n in names):
        raise ValueError(f"ONNX contract {file}: observation names must be a list of strings")
    state = _field(data, "state", dict, file)
    size = _field(state, "size", int, file)
    period = _field(data, "control_period_s", (int, float), file)
    if not (math.isfinite(period) and period > 0):
        raise ValueError(f"ONNX contract {file}: control_period_s {period!r} is not > 0")
    actuator = _field(data, "actuator", str, file)
    if actuator not in ACTUATORS:
        raise ValueError(
            f"ONNX contract {file}: actuator {actuator!r:.40} is not one of {list(ACTUATORS)}"
        )
    allocated = _field(data, "allocated", bool, file)
    plant = _field(data, "plant", str, file)
    if plant not in PLANTS:
        raise ValueError(f"ONNX contract {file}: plant {plant!r:.40} is not one of {list(PLANTS)}")
    stages = _field(data, "stages", list, file)
    try:
        stages = [dict(s) for s in check_stage_specs(stages, f"ONNX contract {file}")]
    except TypeError as error:
        raise ValueError(f"ONNX contract {file}: stages: {error}") from None
    allocates = any(s["name"] == "actuator_allocation" for s in stages)
    if allocates != (allocated and actuator != "paper"):
        raise ValueError(
            f"ONNX contract {file}: the stages {[s['name'] for s in stages]} do not fit "
            f"allocated={allocated} and actuator {actuator!r} (the allocation stage is in the "
            "graph exactly when an allocating agent is exported for fins or realistic)"
        )
    allocation = _allocation_constants(data, file, allocates)
    params = data.get("actuator_params")
    if params is not None and not (allocates and actuator == "realistic"):
        raise ValueError(
            f"ONNX contract {file}: actuator_params without an allocation for the realistic "
            "actuator change nothing in the graph"
        )
    if params is not None and not isinstance(params, dict):
        raise ValueError(f"ONNX contract {file}: actuator_params is {params!r:.60}, not a mapping")
    unread = sorted(set(params or {}) - set(ALLOCATION_FIELDS))
    if unread:
        raise ValueError(
            f"ONNX contract {file}: actuator_params {unread} are not read by the allocation"
        )
    residual = data.get("residual")
    if residual is not None:
        _check_residual(residual, file)
    wanted = 4 if residual is not None else 3 if allocates else 0
    if size != wanted:
        raise ValueError(
            f"ONNX contract {file}: state size {size}, the graph it describes keeps {wanted} "
            "(3: the allocation's delivered command, 4: a residual agent's previous action)"
        )
    inputs, outputs = graph_io(len(names), size, residual is not None)
    for key, expected in (("inputs", inputs), ("outputs", outputs)):
        if data.get(key) != expected:
            raise ValueError(
                f"ONNX contract {file}: {key} {data.get(key)!r:.120} do not fit its observation "
                f"({len(names)} values) and state size {size}: expected {expected}"
            )
    env_id = _field(data, "env_id", str, file)
    env_kwargs = dict(_field(data, "env_kwargs", dict, file))
    try:
        env_id = resolve_env_id(env_id)
        config = SimConfig.from_kwargs(**{**VARIANTS[env_id], **env_kwargs})
        own_params = actuator_params_from_spec(params)
    except (TypeError, ValueError) as error:
        raise ValueError(f"ONNX contract {file}: its env: {error}") from None
    built = {
        "actuator": (config.actuator, actuator),
        "plant": (config.plant, plant),
        "observation": (list(config.observation.names), names),
    }
    if allocates and actuator == "realistic":
        built["actuator_params"] = (
            allocation_settings(config.actuator_params),
            allocation_settings(own_params),
        )
    if not math.isclose(config.control_dt, period):
        built["control period"] = (config.control_dt, period)
    for what, (env_value, own) in built.items():
        if env_value != own:
            raise ValueError(
                f"ONNX contract {file}: its env ({env_id}, env_kwargs) has {what} "
                f"{short(env_value)}, the contract says {short(own)}"
            )
    return OnnxContract(
        onnx=onnx_file,
        file=file,
        obs_names=tuple(names),
        state_size=size,
        actuator=actuator,
        allocated=allocated,
        control_period_s=float(period),
        env_id=env_id,
        env_kwargs=env_kwargs,
        residual=residual,
        raw=data,
        plant=plant,
        actuator_params=params,
        allocation=allocation,
        stages=tuple(stages),
        data=graph,
    )


def allocation_settings(params: Any) -> dict[str, Any]:
    """The fields of `ActuatorParams` ``params`` the allocation reads
    (`controllers.allocation.ALLOCATION_FIELDS`): what an allocation to the realistic actuator
    depends on."""
    return {name: getattr(params, name) for name in ALLOCATION_FIELDS}


def short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 100 else text[:97] + "..."


def _allocation_constants(
    data: Mapping[str, Any], file: Path, allocates: bool
) -> dict[str, Any] | None:
    """The contract's ``allocation`` (K·δ_max [kg], (X_max [N], M_max, N_max [N·m])), present
    exactly when the graph allocates."""
    allocation = data.get("allocation")
    if allocation is None and not allocates:
        return None
    if not allocates:
        raise ValueError(f"ONNX contract {file}: allocation constants without an allocation stage")
    if not isinstance(allocation, dict):
        raise ValueError(
            f"ONNX contract {file}: the allocation stage needs 'allocation': "
            "{'fin_gain_kg': ..., 'limits': [X_max, M_max, N_max]}"
        )
    gain = allocation.get("fin_gain_kg")
    limits = allocation.get("limits")
    numbers = [gain, *(limits if isinstance(limits, list) else [None])]
    if not (
        isinstance(limits, list)
        and len(limits) == 3
        and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0
            for v in numbers
        )
    ):
        raise ValueError(
            f"ONNX contract {file}: allocation {allocation!r:.80} is not "
            "{'fin_gain_kg': K > 0, 'limits': [X_max, M_max, N_max] > 0}"
        )
    return {"fin_gain_kg": float(gain), "limits": [float(v) for v in limits]}


def _check_residual(residual: Any, file: Path) -> None:
    from controllers.registry import CLASSICAL

    if not isinstance(residual, dict) or "base" not in residual:
        raise ValueError(f"ONNX contract {file}: residual must be {{'base': ..., ...}}")
    if residual["base"] not in CLASSICAL:
        raise ValueError(
            f"ONNX contract {file}: residual base {residual['base']!r:.40} is not a classical "
            f"controller; valid: {list(CLASSICAL)}"
        )
    if not isinstance(residual.get("base_kwargs") or {}, dict):
        raise ValueError(f"ONNX contract {file}: residual base_kwargs must be a mapping")


# What the graph's metadata properties state (`controllers.onnx_export`), and how to read them.
_STATED: dict[str, Any] = {
    "env_id": str,
    "env_kwargs": json.loads,
    "observation_names": json.loads,
    "actuator": str,
    "actuator_params": json.loads,
    "allocated": json.loads,
    "allocation": json.loads,
    "plant": str,
    "control_period_s": float,
    "state_size": int,
    "stage_settings": json.loads,
    "residual": json.loads,
}


def _check_against_graph(contract: OnnxContract, properties: Mapping[str, str]) -> None:
    """The contract says what the graph's metadata says it was built for (the SHA-256 covers
    the graph, not the contract: an edited contract is caught here)."""
    fmt = f"{CONTRACT_FORMAT} {CONTRACT_VERSION}"
    if properties.get("format") != fmt:
        raise ValueError(
            f"ONNX graph {contract.onnx}: metadata format {properties.get('format')!r:.60}, "
            f"expected {fmt!r}: not an auv-gym export of this version"
        )
    raw = contract.raw
    says = {
        "env_id": raw["env_id"],
        "env_kwargs": contract.env_kwargs,
        "observation_names": list(contract.obs_names),
        "actuator": contract.actuator,
        "actuator_params": contract.actuator_params,
        "allocated": contract.allocated,
        "allocation": contract.allocation,
        "plant": contract.plant,
        "control_period_s": contract.control_period_s,
        "state_size": contract.state_size,
        "stage_settings": list(contract.stages),
        "residual": contract.residual,
    }
    for key, read in _STATED.items():
        if key not in properties:
            raise ValueError(f"ONNX graph {contract.onnx}: metadata lacks {key!r}")
        try:
            stated = read(properties[key])
        except ValueError:
            raise ValueError(
                f"ONNX graph {contract.onnx}: metadata {key} {properties[key]!r:.60} unreadable"
            ) from None
        if stated != says[key]:
            raise ValueError(
                f"ONNX contract {contract.file} says {key} {short(says[key])}, its graph "
                f"{contract.onnx} was built for {short(stated)}"
            )
