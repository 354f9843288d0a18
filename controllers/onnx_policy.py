"""An exported agent (`auv-gym export`) as a Policy that needs only numpy and onnxruntime.

The graph's inputs are ``observation`` (n, d) float32 and, when the agent has a memory (the
allocation's delivered command, a residual agent's previous action), ``state`` (n, s); its
outputs ``action`` (n, 3) float32 and ``next_state`` (n, s). The caller keeps the state, zeros
at each episode start. A residual agent's graph also takes ``base_action`` (n, 3), the command of
its classical base controller, which `OnnxPolicy` runs (numpy, `controllers.registry`). What the
files hold and how they are checked: `controllers.onnx_contract`.

`OnnxPolicy` adds the checks that need onnxruntime or the env: the session gets the checked
bytes (it reads no file) and its inputs and outputs must be the contract's; the env's actuator,
actuator settings, vehicle and control period must be those the graph was built for
(`check_env`); every call's outputs must be finite and the command within [-1, 1]. Each refusal
is one ValueError line naming the file. Every onnxruntime session of the project runs with
telemetry off and its memory capped (`onnxruntime_module`).

Nothing here imports torch or stable-baselines3 (a test runs `OnnxPolicy` with them blocked).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from controllers.onnx_contract import (
    ACTUATORS,
    CONTRACT_FORMAT,
    CONTRACT_VERSION,
    OnnxContract,
    allocation_settings,
    check_path,
    contract_path,
    graph_io,
    read_contract,
    sha256_of,
)

__all__ = [
    "ACTUATORS",
    "CONTRACT_FORMAT",
    "CONTRACT_VERSION",
    "MAX_RUN_BYTES",
    "TELEMETRY_VARIABLE",
    "OnnxContract",
    "OnnxPolicy",
    "check_env",
    "contract_path",
    "inference_session",
    "onnxruntime_module",
    "read_contract",
    "sha256_of",
]

# What onnxruntime may allocate while running the project's sessions, all of them together (its
# memory arena; constant folding at load has onnxruntime's own 1-GiB limit). The exports need
# about 1 KiB per vehicle of a batch.
MAX_RUN_BYTES = 512 * 2**20
ACTION_SLACK = 1e-6  # float32 rounding allowed beyond the action range [-1, 1]
# onnxruntime ≥ 1.29 writes a device id and an event queue under
# ~/.cache/Microsoft/DeveloperTools/.onnxruntime/ when imported unless this is set.
TELEMETRY_VARIABLE = "ORT_DISABLE_TELEMETRY"
_CAPPED_ARENA: list[bool] = []  # registered once per process (`onnxruntime_module`)


@dataclass
class OnnxState:
    """The agent's memory for a batch of ``n`` vehicles and its base controller's state."""

    memory: np.ndarray  # (n, s) float32
    base: Any
    n: int


def check_beside_agent(contract: OnnxContract) -> None:
    """ValueError, naming both files, when the graph sits in an agent's folder (beside its
    model.zip, or its ensemble.json) but was exported from other networks: the agent was
    retrained or replaced after the export, and the graph would fly the old one unnoticed. The
    contract's provenance records each exported model's SHA-256 (`controllers.onnx_export`). A
    graph away from any agent folder (deployed alone) is not checked."""
    from controllers.agent import MODEL_FILE
    from controllers.ensemble import ENSEMBLE_FILE, ensemble_members

    folder = contract.onnx.parent
    provenance = contract.raw.get("provenance", {})
    # an export named ensemble.onnx has its contract in ensemble.json: not a member list
    members = ensemble_members(folder) if contract.file.name != ENSEMBLE_FILE else None
    if members is not None:
        models = [m / MODEL_FILE if m.is_dir() else m for m in members]
    elif (folder / MODEL_FILE).is_file():
        models = [folder / MODEL_FILE]
    else:
        return
    exported = provenance.get("members") or [provenance]
    recorded = [
        entry.get("model_sha256") if isinstance(entry, Mapping) else None for entry in exported
    ]
    if len(recorded) != len(models):
        raise ValueError(
            f"{contract.onnx} was exported from {len(recorded)} network(s), the agent in its "
            f"folder has {len(models)}: re-export it (auv-gym export {folder} --out "
            f"{contract.onnx}) or move it out of the agent's folder"
        )
    for model, digest in zip(models, recorded, strict=True):
        actual = sha256_of(model)
        if digest != actual:
            raise ValueError(
                f"{contract.onnx} is stale: it was exported from a model with SHA-256 "
                f"{str(digest)[:12]}…, {model} beside it has {actual[:12]}… (retrained or "
                f"replaced after the export): re-export it (auv-gym export {folder} --out "
                f"{contract.onnx}) or move it out of the agent's folder"
            )


class OnnxPolicy:
    """An exported agent as a Policy (docs/design.md §3): ``predict`` feeds the ONNX graph and
    keeps its memory, reset at each episode start.

    ``actuator``, ``actuator_params``, ``control_dt``, ``params``, ``observation_names``: the
    env's, as `controllers.make("onnx", path=..., env=env)` passes them; given, they are checked
    against what the graph was built for (`check_env`). Without them the policy carries its env
    (``env_kwargs``: the contract's, its actuator and settings included), where `auv_gym.rollout`
    runs it. A residual agent's base controller is built with them and ``base_kwargs`` (the
    scenario's controller settings; a plain agent has no use for them, as in
    `controllers.loader.load_policy`). ``num_threads``: onnxruntime's intra-op threads.
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
        check_path(path, "controllers.make('onnx'): path")
        if isinstance(num_threads, bool) or not (isinstance(num_threads, int) and num_threads >= 1):
            raise ValueError(f"num_threads must be a positive integer, got {num_threads!r}")
        contract = read_contract(path)
        check_beside_agent(contract)
        where = contract.onnx
        if observation_names is not None and tuple(observation_names) != contract.obs_names:
            raise ValueError(
                f"{where} takes observations of {contract.obs_dim} values "
                f"({contract.env_id}, {contract.file}), the env gives "
                f"{len(observation_names)}: run it in the env its contract records"
            )
        env_given = control_dt is not None or params is not None
        check_env(contract, actuator, actuator_params, params, control_dt, env_given)
        self.contract = contract
        self.path = str(where)
        self.obs_dim = contract.obs_dim
        self.metadata = dict(contract.raw.get("provenance", {}))
        self.env_kwargs = dict(contract.env_kwargs)  # the env it was built for (`auv_gym.rollout`)
        self.base = None
        if contract.residual is not None:
            from controllers.agent import REALISTIC_ACTUATOR
            from controllers.registry import make_classical

            env_owned = {"actuator": actuator, "control_dt": control_dt, "params": params}
            env_owned["actuator_params"] = actuator_params
            kwargs = {k: v for k, v in env_owned.items() if v is not None}
            if contract.actuator == REALISTIC_ACTUATOR:  # its base commands them too, as in
                kwargs = {"actuator": REALISTIC_ACTUATOR, **kwargs}  # `load_policy`
            recorded = dict(contract.residual.get("base_kwargs") or {})
            base = contract.residual["base"]
            try:
                self.base = make_classical(
                    base, **{**recorded, **kwargs, **dict(base_kwargs or {})}
                )
            except (TypeError, ValueError) as error:
                raise type(error)(f"{where}: its residual base {base!r}: {error}") from None
        self.session = inference_session(contract.data, num_threads, where=where)
        _check_session(self.session, contract)

    def predict(
        self,
        observation: np.ndarray,
        state: OnnxState | None = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, OnnxState]:
        """Commands (float32, (3,) or (n, 3)) for raw observations (d,) or (n, d) (layout:
        the contract's observation names). The graph's outputs are checked at every call:
        shape, finite, the command within [-1, 1]."""
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
        try:
            outputs = self.session.run(None, feeds)
        except Exception as exc:  # onnxruntime's own error types, many lines each
            raise ValueError(f"ONNX graph {self.path} failed to run: {_first_line(exc)}") from None
        action = _checked_output(outputs[0], (n, 3), "action", self.path, 1.0 + ACTION_SLACK)
        if self.contract.state_size:
            size = (n, self.contract.state_size)
            state.memory = _checked_output(outputs[1], size, "next_state", self.path, math.inf)
        return (action[0] if single else action), state

    def __repr__(self) -> str:
        return f"OnnxPolicy(path={self.path!r})"


def check_env(
    contract: OnnxContract,
    actuator: str | None,
    actuator_params: Any,
    params: Any,
    control_dt: float | None,
    env_given: bool,
) -> None:
    """An env's actuator, its settings, its vehicle and control period against what the graph
    was built for: a one-line ValueError naming the file and the mismatch (and the export
    command that fits, where one does). ``env_given``: the caller passed an env's settings, so
    ``actuator=None`` means the env draws its actuator per episode ("random")."""
    from auv_gym.vehicle.actuators import actuator_params_from_spec
    from controllers.base import actuator_vector

    where = contract.onnx
    own = contract.actuator
    if contract.one_actuator and actuator is None and env_given:
        raise ValueError(
            f"{where} commands actuator {own!r} only; the env draws its actuator per episode "
            f"(actuator='random'): fly it with actuator={own!r}"
        )
    if actuator is not None and actuator != own:
        if contract.actuator == "realistic" and not contract.allocated:
            raise ValueError(
                f"{where} commands the propeller and fins (shaft speed and fin angles), the "
                f"env has actuator {actuator!r}: fly it with actuator='realistic'"
            )
        if contract.allocated:
            raise ValueError(
                f"{where} was exported for actuator {own!r}, the env has {actuator!r}: "
                f"auv-gym export AGENT --actuator {actuator} --out FILE.onnx"
            )
    if contract.allocation is not None and actuator == own:
        env_params = actuator_params_from_spec(actuator_params)
        if own == "realistic":
            built = allocation_settings(actuator_params_from_spec(contract.actuator_params))
            env_settings = allocation_settings(env_params)
            if env_settings != built:
                differ = sorted(k for k in built if built[k] != env_settings[k])
                default = allocation_settings(type(env_params)())
                wanted = {k: v for k, v in env_settings.items() if v != default[k]}
                raise ValueError(
                    f"{where}'s allocation was built for other actuator_params than the env's "
                    f"(they differ in {differ}): auv-gym export AGENT --actuator realistic "
                    f"--actuator-params '{json.dumps(wanted)}' --out FILE.onnx"
                )
        if params is not None:
            _, gain, *limits = actuator_vector(own, params, env_params)
            stated = contract.allocation
            same = math.isclose(gain, stated["fin_gain_kg"], rel_tol=1e-12) and all(
                math.isclose(a, b, rel_tol=1e-12)
                for a, b in zip(limits, stated["limits"], strict=True)
            )
            if not same:
                raise ValueError(
                    f"{where}'s allocation was built for the fin gain K·δ_max "
                    f"{stated['fin_gain_kg']:.4g} kg and limits {stated['limits']} N, N·m; the "
                    f"env's vehicle gives {gain:.4g} kg and {[float(v) for v in limits]}"
                )
    if control_dt is not None and not math.isclose(control_dt, contract.control_period_s):
        raise ValueError(
            f"{where} acts every {contract.control_period_s:g} s, the env every {control_dt:g} s"
        )


def _first_line(exc: BaseException) -> str:
    lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
    text = lines[0] if lines else type(exc).__name__
    return text if len(text) <= 300 else text[:297] + "..."


def _checked_output(
    value: Any, shape: tuple[int, int], name: str, where: str, bound: float
) -> np.ndarray:
    """An output of the graph: float32 of ``shape``, finite and within ±``bound``; a one-line
    ValueError naming ``where`` otherwise."""
    out = np.asarray(value)
    if out.shape != shape or out.dtype != np.float32:
        raise ValueError(
            f"ONNX graph {where} gave {name} of shape {out.shape} {out.dtype}, expected "
            f"{shape} float32"
        )
    bad = ~np.isfinite(out) | (np.abs(out) > bound)
    if bad.any():
        row = int(np.argwhere(bad)[0][0])
        what = "not finite" if not np.isfinite(out[row]).all() else "outside [-1, 1]"
        raise ValueError(f"ONNX graph {where} gave {name} row {row} {out[row].tolist()}: {what}")
    return out


def onnxruntime_module(where: Any = "an ONNX policy") -> Any:
    """onnxruntime, imported with its telemetry off and the project's sessions' memory capped.

    `TELEMETRY_VARIABLE` is set before the import (onnxruntime reads it then: without it, the
    import alone writes a device id and an event queue under
    ~/.cache/Microsoft/DeveloperTools/.onnxruntime/), and the telemetry events are switched off
    after it, for an onnxruntime that something else imported first. The memory arena the
    sessions share is registered once, capped at `MAX_RUN_BYTES`. ImportError naming ``where``
    and the extra if onnxruntime is missing."""
    os.environ[TELEMETRY_VARIABLE] = "1"
    try:
        import onnxruntime
    except ImportError as exc:
        raise ImportError(
            f"running {where} needs onnxruntime (pip install 'auv-gym[onnx]'): {exc}"
        ) from exc
    disable = getattr(onnxruntime, "disable_telemetry_events", None)
    if disable is not None:
        disable()
    if not _CAPPED_ARENA:
        memory = onnxruntime.OrtMemoryInfo(
            "Cpu",
            onnxruntime.OrtAllocatorType.ORT_ARENA_ALLOCATOR,
            0,
            onnxruntime.OrtMemType.DEFAULT,
        )
        onnxruntime.create_and_register_allocator(
            memory, onnxruntime.OrtArenaCfg(MAX_RUN_BYTES, -1, -1, -1)
        )
        _CAPPED_ARENA.append(True)
    return onnxruntime


def inference_session(source: bytes, num_threads: int = 1, where: Any = None) -> Any:
    """An onnxruntime session on the CPU of a serialised model (the bytes that were checked:
    the session reads no file), on ``num_threads`` intra-op threads, telemetry off and its
    memory in the capped arena (`onnxruntime_module`); errors name ``where``."""
    onnxruntime = onnxruntime_module(where)
    options = onnxruntime.SessionOptions()
    options.intra_op_num_threads = num_threads
    options.inter_op_num_threads = 1
    options.log_severity_level = 3
    options.add_session_config_entry("session.use_env_allocators", "1")
    try:
        return onnxruntime.InferenceSession(source, options, providers=["CPUExecutionProvider"])
    except Exception as exc:  # onnxruntime raises its own error types for a bad graph
        raise ValueError(f"ONNX graph {where} cannot be loaded: {_first_line(exc)}") from None


_ONNX_FLOAT = "tensor(float)"


def _check_session(session: Any, contract: OnnxContract) -> None:
    """The graph's inputs and outputs are the contract's: names, order, rank, sizes (the first
    dimension free: the batch) and type; the first that differs is named."""
    inputs, outputs = graph_io(contract.obs_dim, contract.state_size, contract.residual is not None)
    for kind, declared, wanted in (
        ("takes", session.get_inputs(), inputs),
        ("gives", session.get_outputs(), outputs),
    ):
        got = [(a.name, _shape(a.shape), a.type) for a in declared]
        want = [(t["name"], ["n", t["shape"][1]], _ONNX_FLOAT) for t in wanted]
        if len(got) != len(want):
            raise ValueError(
                f"ONNX graph {contract.onnx} {kind} {[g[0] for g in got]}, its contract "
                f"{contract.file} says {[w[0] for w in want]}"
            )
        for mine, theirs in zip(got, want, strict=True):
            if mine != theirs:
                raise ValueError(
                    f"ONNX graph {contract.onnx} {kind} {mine}, its contract {contract.file} "
                    f"says {theirs}"
                )


def _shape(shape: Any) -> list[Any]:
    """A declared shape with a free first dimension (the batch: a name or None) written "n"."""
    return [
        ("n" if k == 0 else d) if not isinstance(d, int) or d is None else d
        for k, d in enumerate(shape)
    ]
