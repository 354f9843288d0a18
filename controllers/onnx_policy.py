"""An exported agent (`auv-gym export`) as a Policy that needs only numpy and onnxruntime.

An export is two files side by side::

    policy.onnx   one graph: the raw observation (and the agent's memory) → the command the env
                  receives: normalisation, the network's deterministic action, the action scaling
                  and every stage (`controllers.onnx_export`, docs/design.md §3.18)
    policy.json   its contract: input and output layout with names and units, the memory's size
                  and when it resets, the control period, the env it was trained in, the
                  actuator its commands are for, and where it came from (`CONTRACT_FORMAT`)

The graph's inputs are ``observation`` (n, d) float32 and, when the agent has a memory (the
allocation's delivered command, a residual agent's previous action), ``state`` (n, s); its
outputs ``action`` (n, 3) float32 and ``next_state`` (n, s). The caller keeps the state, zeros
at each episode start. A residual agent's graph also takes ``base_action`` (n, 3), the command of
its classical base controller, which `OnnxPolicy` runs (numpy, `controllers.registry`).

Nothing here imports torch or stable-baselines3 (a test runs `OnnxPolicy` with them blocked).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "CONTRACT_FORMAT",
    "CONTRACT_VERSION",
    "OnnxContract",
    "OnnxPolicy",
    "contract_path",
    "inference_session",
    "read_contract",
]

CONTRACT_FORMAT = "auv-gym onnx policy"
CONTRACT_VERSION = 1
INPUT_NAMES = ("observation", "state", "base_action")
OUTPUT_NAMES = ("action", "next_state")


def contract_path(onnx_path: str | os.PathLike) -> Path:
    """The contract beside an ONNX file: ``policy.onnx`` → ``policy.json``."""
    return Path(onnx_path).with_suffix(".json")


def sha256_of(path: Path) -> str:
    """The SHA-256 of a file's bytes, hex."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


@dataclass(frozen=True)
class OnnxContract:
    """A checked contract (`read_contract`): what the graph takes and gives."""

    onnx: Path
    file: Path
    obs_names: tuple[str, ...]
    state_size: int
    actuator: str  # the env actuator its commands are for ("paper", "fins", "realistic")
    allocated: bool  # the agent lists the actuator allocation among its stages
    control_period_s: float
    env_id: str
    env_kwargs: dict[str, Any]  # the env the agent carries (`auv_gym.rollout` runs it there)
    residual: dict[str, Any] | None  # {"base", "base_kwargs"} of a residual agent
    raw: dict[str, Any]

    @property
    def obs_dim(self) -> int:
        return len(self.obs_names)


def _field(data: Mapping[str, Any], key: str, kind: type | tuple[type, ...], where: Path) -> Any:
    if key not in data:
        raise ValueError(f"ONNX contract {where}: missing {key!r}")
    value = data[key]
    if not isinstance(value, kind) or (isinstance(value, bool) and kind is not bool):
        raise ValueError(f"ONNX contract {where}: {key!r} is {value!r}")
    return value


def read_contract(path: str | os.PathLike) -> OnnxContract:
    """The contract of an exported agent (the .onnx file or its .json), checked without
    onnxruntime: format and version, the layout, the ONNX file present with the recorded SHA-256
    (a damaged or swapped graph is refused). FileNotFoundError or a one-line ValueError naming
    the file otherwise."""
    given = Path(path)
    onnx_file = given if given.suffix == ".onnx" else given.with_suffix(".onnx")
    file = contract_path(onnx_file)
    for needed, what in ((onnx_file, "ONNX graph"), (file, "contract")):
        if not needed.is_file():
            raise FileNotFoundError(f"exported agent {given}: {what} {needed} does not exist")
    try:
        data = json.loads(file.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"ONNX contract {file} is unreadable: {exc}") from None
    if not isinstance(data, dict) or data.get("format") != CONTRACT_FORMAT:
        raise ValueError(f"ONNX contract {file}: not an {CONTRACT_FORMAT!r} contract")
    if data.get("format_version") != CONTRACT_VERSION:
        raise ValueError(
            f"ONNX contract {file}: format version {data.get('format_version')!r}, this "
            f"auv-gym reads {CONTRACT_VERSION}"
        )
    observation = _field(data, "observation", dict, file)
    names = _field(observation, "names", list, file)
    if not names or not all(isinstance(n, str) for n in names):
        raise ValueError(f"ONNX contract {file}: observation names must be a list of strings")
    state = _field(data, "state", dict, file)
    size = _field(state, "size", int, file)
    if size < 0:
        raise ValueError(f"ONNX contract {file}: state size {size} < 0")
    period = _field(data, "control_period_s", (int, float), file)
    if not (math.isfinite(period) and period > 0):
        raise ValueError(f"ONNX contract {file}: control_period_s {period!r} is not > 0")
    digest = _field(data, "onnx_sha256", str, file)
    if sha256_of(onnx_file) != digest:
        raise ValueError(
            f"ONNX graph {onnx_file} does not match its contract {file} (SHA-256 differs: "
            "damaged, or replaced without re-exporting)"
        )
    residual = data.get("residual")
    if residual is not None and not (isinstance(residual, dict) and "base" in residual):
        raise ValueError(f"ONNX contract {file}: residual must be {{'base': ..., ...}}")
    actuator = _field(data, "actuator", str, file)
    return OnnxContract(
        onnx=onnx_file,
        file=file,
        obs_names=tuple(names),
        state_size=size,
        actuator=actuator,
        allocated=bool(data.get("allocated", False)),
        control_period_s=float(period),
        env_id=_field(data, "env_id", str, file),
        env_kwargs=dict(_field(data, "env_kwargs", dict, file)),
        residual=residual,
        raw=data,
    )


@dataclass
class OnnxState:
    """The agent's memory for a batch of ``n`` vehicles and its base controller's state."""

    memory: np.ndarray  # (n, s) float32
    base: Any
    n: int


class OnnxPolicy:
    """An exported agent as a Policy (docs/design.md §3): ``predict`` feeds the ONNX graph and
    keeps its memory, reset at each episode start.

    ``actuator``, ``actuator_params``, ``control_dt``, ``params``, ``observation_names``: the
    env's, as `controllers.make("onnx", path=..., env=env)` passes them. An agent that allocates its
    commands was exported for one actuator: another is a ValueError naming the file and the
    export command that fits; so is another control period. A residual agent's base controller is
    built with them and ``base_kwargs`` (the scenario's controller settings; a plain agent has
    no use for them, as in `controllers.loader.load_policy`). ``num_threads``: onnxruntime's
    intra-op threads.
    """

    def __init__(
        self,
        path: str | os.PathLike,
        *,
        actuator: str | None = None,
        actuator_params: Any = None,
        control_dt: float | None = None,
        params: Any = None,
        num_threads: int = 1,
        observation_names: Any = None,
        base_kwargs: Mapping[str, Any] | None = None,
    ) -> None:
        contract = read_contract(path)
        where = contract.onnx
        if observation_names is not None and tuple(observation_names) != contract.obs_names:
            raise ValueError(
                f"{where} takes observations of {contract.obs_dim} values "
                f"({contract.env_id}, {contract.file}), the env gives "
                f"{len(observation_names)}: run it in the env its contract records"
            )
        own_actuator = contract.actuator == "realistic" and not contract.allocated
        if own_actuator and actuator is not None and actuator != contract.actuator:
            raise ValueError(
                f"{where} commands the propeller and fins (shaft speed and fin angles), the "
                f"env has actuator {actuator!r}: fly it with actuator='realistic'"
            )
        if contract.allocated and actuator is not None and actuator != contract.actuator:
            raise ValueError(
                f"{where} was exported for actuator {contract.actuator!r}, the env has "
                f"{actuator!r}: auv-gym export AGENT --actuator {actuator} --out FILE.onnx"
            )
        if control_dt is not None and not math.isclose(control_dt, contract.control_period_s):
            raise ValueError(
                f"{where} acts every {contract.control_period_s:g} s, the env every "
                f"{control_dt:g} s"
            )
        if not (isinstance(num_threads, int) and num_threads >= 1):
            raise ValueError(f"num_threads must be a positive integer, got {num_threads!r}")
        self.contract = contract
        self.path = str(where)
        self.obs_dim = contract.obs_dim
        self.metadata = dict(contract.raw.get("provenance", {}))
        self.env_kwargs = dict(contract.env_kwargs)  # the env it carries (`auv_gym.rollout`)
        self.base = None
        if contract.residual is not None:
            from controllers.registry import make_classical

            env_owned = {"actuator": actuator, "control_dt": control_dt, "params": params}
            env_owned["actuator_params"] = actuator_params
            kwargs = {k: v for k, v in env_owned.items() if v is not None}
            recorded = dict(contract.residual.get("base_kwargs") or {})
            self.base = make_classical(
                contract.residual["base"], **{**recorded, **kwargs, **dict(base_kwargs or {})}
            )
        self.session = inference_session(where, num_threads)
        _check_session(self.session, contract)

    def predict(
        self,
        observation: np.ndarray,
        state: OnnxState | None = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, OnnxState]:
        """Commands (float32, (3,) or (n, 3)) for raw observations (d,) or (n, d) (layout:
        the contract's observation names)."""
        obs = np.asarray(observation, dtype=np.float32)
        d = self.obs_dim
        if obs.ndim not in (1, 2) or obs.shape[-1] != d:
            raise ValueError(
                f"{self.path} takes observations of shape ({d},) or (n, {d}) "
                f"({self.contract.env_id}), got {obs.shape}"
            )
        single = obs.ndim == 1
        batch = obs.reshape(-1, d)
        if not np.all(np.isfinite(batch)):
            row = int(np.argwhere(~np.isfinite(batch))[0][0])
            raise ValueError(f"{self.path}: observation row {row} is not finite")
        n = batch.shape[0]
        if state is None or state.n != n:
            memory = np.zeros((n, self.contract.state_size), dtype=np.float32)
            state = OnnxState(memory, None, n)
        if episode_start is not None:
            state.memory[np.asarray(episode_start, dtype=bool).reshape(n)] = 0.0
        feeds = {"observation": batch}
        if self.contract.state_size:
            feeds["state"] = state.memory
        if self.base is not None:
            base_action, state.base = self.base.predict(
                batch, state.base, episode_start, deterministic
            )
            feeds["base_action"] = np.asarray(base_action, np.float32).reshape(n, 3)
        outputs = self.session.run(None, feeds)
        action = outputs[0]
        if self.contract.state_size:
            state.memory = outputs[1]
        return (action[0] if single else action), state

    def __repr__(self) -> str:
        return f"OnnxPolicy(path={self.path!r})"


def inference_session(source: Path | bytes, num_threads: int = 1, where: Any = None) -> Any:
    """An onnxruntime session on the CPU of an ONNX file or serialised model, on
    ``num_threads`` intra-op threads; errors name ``where`` (default: the file)."""
    where = source if where is None else where
    try:
        import onnxruntime
    except ImportError as exc:
        raise ImportError(
            f"running {where} needs onnxruntime (pip install 'auv-gym[onnx]'): {exc}"
        ) from exc
    options = onnxruntime.SessionOptions()
    options.intra_op_num_threads = num_threads
    options.inter_op_num_threads = 1
    options.log_severity_level = 3
    model = str(source) if isinstance(source, Path) else source
    try:
        return onnxruntime.InferenceSession(model, options, providers=["CPUExecutionProvider"])
    except Exception as exc:  # onnxruntime raises its own error types for a bad graph
        raise ValueError(f"ONNX graph {where} cannot be loaded: {exc}") from None


def _check_session(session: Any, contract: OnnxContract) -> None:
    """The graph's inputs and outputs are the contract's: names, and the observation size."""
    inputs = {i.name: i.shape for i in session.get_inputs()}
    expected = {"observation"}
    if contract.state_size:
        expected.add("state")
    if contract.residual is not None:
        expected.add("base_action")
    if set(inputs) != expected:
        raise ValueError(
            f"ONNX graph {contract.onnx} takes {sorted(inputs)}, its contract {contract.file} "
            f"says {sorted(expected)}"
        )
    size = inputs["observation"][-1]
    if size != contract.obs_dim:
        raise ValueError(
            f"ONNX graph {contract.onnx} takes observations of {size} values, its contract "
            f"{contract.file} names {contract.obs_dim}"
        )
    outputs = [o.name for o in session.get_outputs()]
    wanted = list(OUTPUT_NAMES[: 2 if contract.state_size else 1])
    if outputs != wanted:
        raise ValueError(f"ONNX graph {contract.onnx} gives {outputs}, expected {wanted}")
