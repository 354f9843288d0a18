"""Export a saved agent to one ONNX graph and its contract (`auv-gym export`, docs/design.md §3.18).

The graph maps the raw observation, as the env (or the vehicle's navigation) gives it, to the
command the env receives: the agent's observation normalisation, its network's deterministic
action, SB3's action scaling and every stage its metadata lists, built for the actuator the
export names (`controllers.stages.build_stages`: the allocation is the identity on the paper's
actuator and left out there). A residual agent's graph ends in its bounded correction and
learned filter on top of its base controller's command, an input (the base is a classical
controller with adaptive laws, run beside the graph by `controllers.onnx_policy.OnnxPolicy`).
An ensemble (`controllers.ensemble`) is one graph too: every member's normalisation and network
side by side, their actions averaged before the stages or the residual's bound, as the Python
ensemble flies; its contract's provenance names each member.

The contract and the graph's metadata state everything the graph was built for: the env (id and
arguments, with the actuator and its settings, so that a run from the contract flies the actuator
the graph commands), the control period, the plant the agent was trained on, the actuator, the
allocation's vehicle constants and settings, and the stages. An option that would not change the
graph is refused, not ignored: ``actuator`` other than the default for an agent without an
allocation stage (its commands would only be relabelled), ``actuator_params`` for any graph
without an allocation to the realistic actuator.

Before anything is written the agent's files are checked (`controllers.agent.check_agent`), the
output folder must exist, and the graph is run by onnxruntime against the Python agent on
observations drawn from the agent's own normalisation statistics: an export whose commands
differ by more than `PARITY_TOLERANCE` is refused. The contract and the graph then pass the
runtime's own checks (`controllers.onnx_contract.check_contract`), and both files are written or
neither (`write_export`). Export needs torch (to read the network) and onnx; running the result
needs only onnxruntime and numpy.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from auv_gym import __version__
from auv_gym.support.files import json_default, temporary_prefix
from controllers.agent import (
    AgentFiles,
    check_agent,
    commands_realistic_actuators,
    load_network,
    observation_layout,
)
from controllers.envelope_guard import ENV_GUARD_INDEX, guard_env_commands
from controllers.mirror import ACTION_MIRROR, MIRROR_STAGE, MirroredNetwork, mirrored
from controllers.onnx_contract import (
    ACTUATORS,
    CONTRACT_FORMAT,
    CONTRACT_VERSION,
    check_contract,
    contract_path,
    graph_io,
    sha256_of,
)
from controllers.onnx_graph import (
    OPSET,
    Graph,
    action_head,
    allocation_graph,
    guard_graph,
    network_graph,
    normalisation_graph,
    residual_graph,
)
from controllers.onnx_policy import inference_session
from controllers.residual import RESIDUAL_FEATURES
from controllers.stages import AllocationStage, GuardStage, build_stages

__all__ = ["ACTUATORS", "PARITY_TOLERANCE", "export_onnx", "mlp_layers", "write_export"]

_REPOSITORY = Path(__file__).resolve().parents[1]  # holds controllers/ and benchmarks/
PARITY_TOLERANCE = 1e-5  # max |ONNX − Python| over the check's commands, normalised units
PARITY_SAMPLES = 2048  # observations the export checks itself on
# A residual agent observes the env's observation, then its base's and its previous action.
RESIDUAL_EXTRA = len(RESIDUAL_FEATURES)
# The env's command for each actuator (docs/model.md §2.3, §2.6): names and what 1 means.
ACTION_LAYOUT = {
    "paper": (["X", "M", "N"], "τ / τ_max, τ_max = (50 N, 10 N·m, 10 N·m)"),
    "fins": (["X", "delta_s", "delta_r"], "X / 50 N; fin angles / δ_max"),
    "realistic": (["rpm", "delta_s", "delta_r"], "shaft speed / n_max; fin angles / δ_max"),
}


def mlp_layers(module: Any, where: str) -> list[tuple[str, Any]]:
    """The layers of a torch MLP (Linear, Tanh, ReLU, Hardtanh, Identity, Flatten; nested
    Sequential) as ("linear", (W, b)), ("tanh", None), ... in order; a one-line ValueError
    naming ``where`` and the module for anything else."""
    import torch

    out: list[tuple[str, Any]] = []
    children = list(module.children()) if isinstance(module, torch.nn.Sequential) else [module]
    for child in children:
        if isinstance(child, torch.nn.Sequential):
            out.extend(mlp_layers(child, where))
        elif isinstance(child, torch.nn.Linear):
            weight = child.weight.detach().cpu().numpy().astype(np.float32)
            bias = (
                child.bias.detach().cpu().numpy().astype(np.float32)
                if child.bias is not None
                else np.zeros(weight.shape[0], np.float32)
            )
            out.append(("linear", (weight, bias)))
        elif isinstance(child, torch.nn.Tanh):
            out.append(("tanh", None))
        elif isinstance(child, torch.nn.ReLU):
            out.append(("relu", None))
        elif isinstance(child, torch.nn.Hardtanh):
            out.append(("hardtanh", (float(child.min_val), float(child.max_val))))
        elif not isinstance(child, (torch.nn.Identity, torch.nn.Flatten)):
            raise ValueError(f"{where}: layer {child!r} has no ONNX export here")
    return out


def actor_layers(sb3_policy: Any, where: str) -> tuple[list[tuple[str, Any]], bool]:
    """(the layers from normalised observation to the action's mean, squashed?) of an SB3
    policy: PPO's `mlp_extractor.policy_net` + `action_net`, or SAC's (and TQC's, CrossQ's)
    `actor.latent_pi` + `actor.mu` followed by tanh."""
    import torch

    if hasattr(sb3_policy, "mlp_extractor"):  # ActorCriticPolicy (PPO)
        extractor = sb3_policy.pi_features_extractor
        if not isinstance(extractor, torch.nn.Flatten) and type(extractor).__name__ != (
            "FlattenExtractor"
        ):
            raise ValueError(f"{where}: features extractor {extractor!r} has no ONNX export here")
        if getattr(sb3_policy, "use_sde", False):
            raise ValueError(f"{where}: gSDE on an on-policy agent has no ONNX export here")
        body = mlp_layers(sb3_policy.mlp_extractor.policy_net, where)
        return body + mlp_layers(sb3_policy.action_net, where), bool(sb3_policy.squash_output)
    actor = getattr(sb3_policy, "actor", None)
    if actor is None or not hasattr(actor, "latent_pi"):
        raise ValueError(f"{where}: policy {type(sb3_policy).__name__} has no ONNX export here")
    return mlp_layers(actor.latent_pi, where) + mlp_layers(actor.mu, where), True


def _check_out(out: str | os.PathLike) -> Path:
    target = Path(out)
    if target.suffix != ".onnx":
        raise ValueError(f"--out {target}: the file name must end in .onnx")
    if target.parent.exists() and not target.parent.is_dir():
        raise FileNotFoundError(f"--out {target}: {target.parent} is a file, not a folder")
    if not target.parent.is_dir():
        raise FileNotFoundError(f"--out {target}: folder {target.parent} does not exist")
    if target.is_dir():
        raise IsADirectoryError(f"--out {target} is a folder, not a file")
    return target


def export_onnx(
    agent: str | os.PathLike,
    out: str | os.PathLike,
    *,
    actuator: str | None = None,
    actuator_params: Mapping[str, Any] | None = None,
) -> tuple[Path, Path, dict[str, Any]]:
    """Export the saved agent ``agent`` to ``out`` (.onnx) and its contract beside it (.json),
    its commands for the env actuator ``actuator`` (`ACTUATORS`; None: "paper", or "realistic"
    for an agent trained on the propeller and fins, whose commands no other actuator reads;
    another is refused for an agent without an allocation stage) and ``actuator_params`` (the
    realistic actuators' settings its allocation is built for; refused where there is none).
    Returns (onnx file, contract file, the parity check's figures). Every check runs before a
    file is written (module doc)."""
    target = _check_out(out)
    files = check_agent(agent)
    actuator, params = _export_settings(files, actuator, actuator_params)
    layout = observation_layout(files.metadata)
    settings: dict[str, Any] = {"actuator": actuator, "actuator_params": params}
    stages = build_stages(files.stages, layout, settings, str(files.model))
    actor = mirrored(load_network(files, num_threads=1), files.stages, layout, str(files.model))
    model, state_size = _build_model(files, actor, stages, layout)
    parity = _parity(model, files, actor, stages, state_size)
    if parity["max_abs_error"] > PARITY_TOLERANCE:
        raise ValueError(
            f"{files.ensemble or files.model}: the exported graph differs from the agent by "
            f"{parity['max_abs_error']:.3g} > {PARITY_TOLERANCE:g}; nothing written"
        )
    contract = _contract(files, target, layout, state_size, actuator, params, stages, parity)
    _annotate(model, contract)
    data = model.SerializeToString()
    contract["onnx_sha256"] = hashlib.sha256(data).hexdigest()
    check_contract(contract, data, target, contract_path(target))  # what a load will check
    contract_file = write_export(target, data, contract)
    return target, contract_file, parity


def _export_settings(
    files: AgentFiles, actuator: str | None, actuator_params: Any
) -> tuple[str, Any]:
    """(the actuator, the `ActuatorParams` or None) an export is built for, after refusing
    what would not change the graph (module doc)."""
    from auv_gym.vehicle.actuators import ActuatorParams, actuator_params_from_spec

    own = "realistic" if commands_realistic_actuators(files.metadata) else None
    default = own or "paper"
    if actuator is None:
        actuator = default
    if actuator not in ACTUATORS:
        raise ValueError(f"actuator {actuator!r:.40} is not one of {list(ACTUATORS)}")
    if own is not None and actuator != own:
        raise ValueError(
            f"{files.model}: the agent commands the propeller and fins (actuator='realistic'); "
            f"it cannot be exported for actuator {actuator!r}"
        )
    allocating = any(spec["name"] == "actuator_allocation" for spec in files.stages)
    if actuator != default and not allocating:
        raise ValueError(
            f"--actuator {actuator}: {files.metadata_file} lists no actuator_allocation stage, so "
            f"the graph would be its {default!r} graph with the commands relabelled, not "
            f"allocated; export it without --actuator (it flies any actuator as the agent does)"
        )
    if actuator_params is None:
        return actuator, None
    if actuator != "realistic" or not allocating:
        why = (
            f"with --actuator {actuator} there is no propeller to configure"
            if actuator != "realistic"
            else f"{files.metadata_file} lists no actuator_allocation stage for them to change"
        )
        raise ValueError(
            f"--actuator-params configure the realistic actuator's allocation, and {why}: they "
            "would not change the graph; drop them (give them to the env instead)"
        )
    try:
        params = actuator_params_from_spec(actuator_params)
    except (TypeError, ValueError) as error:
        raise ValueError(f"--actuator-params: {error}") from None
    changed = allocation_params(params)
    unread = sorted(
        name
        for name, value in dataclasses.asdict(params).items()
        if value != getattr(ActuatorParams(), name) and name not in changed
    )
    if unread:
        raise ValueError(
            f"--actuator-params {unread}: the allocation does not read them (the torque curve, "
            "the motor's and servos' lags, the servo rate limit), so they would not change the "
            "graph; drop them (give them to the env instead)"
        )
    return actuator, (params if changed else None)


def allocation_params(params: Any) -> dict[str, Any]:
    """The fields of `ActuatorParams` ``params`` that the allocation reads
    (`controllers.allocation.ALLOCATION_FIELDS`) where they differ from the defaults."""
    from auv_gym.vehicle.actuators import ActuatorParams
    from controllers.allocation import ALLOCATION_FIELDS

    default = ActuatorParams()
    return {
        name: getattr(params, name)
        for name in ALLOCATION_FIELDS
        if getattr(params, name) != getattr(default, name)
    }


def write_export(target: Path, data: bytes, contract: Mapping[str, Any]) -> Path:
    """Write the graph ``data`` to ``target`` and ``contract`` beside it: both or neither.

    Both are written to temporary files first (a failure there leaves the folder as it was),
    then renamed into place, the graph first; if the contract's rename fails, the previous
    graph is put back (or the new one removed). A process killed between the two renames leaves
    a graph its old contract refuses (SHA-256), never a pair that loads wrongly. Returns the
    contract's path."""
    contract_file = contract_path(target)
    text = (json.dumps(contract, indent=1, default=json_default) + "\n").encode("utf-8")
    mask = os.umask(0)
    os.umask(mask)
    temporaries: list[str] = []
    try:
        for path, payload in ((target, data), (contract_file, text)):
            fd, tmp = tempfile.mkstemp(
                prefix=temporary_prefix(path), suffix=".tmp", dir=path.parent
            )
            temporaries.append(tmp)
            with os.fdopen(fd, "wb") as fh:
                fh.write(payload)
            os.chmod(tmp, 0o666 & ~mask)
        backup = None
        if target.exists():  # kept until the contract is in place
            fd, backup = tempfile.mkstemp(
                prefix=temporary_prefix(target), suffix=".tmp", dir=target.parent
            )
            os.close(fd)
            temporaries.append(backup)
            shutil.copy2(target, backup)
        os.replace(temporaries[0], target)
        try:
            os.replace(temporaries[1], contract_file)
        except BaseException:
            if backup is not None:
                os.replace(backup, target)
            else:
                target.unlink(missing_ok=True)
            raise
    finally:
        for tmp in temporaries:
            if os.path.exists(tmp):
                os.unlink(tmp)
    return contract_file


def _build_model(
    files: AgentFiles, actor: Any, stages: list[Any], layout: tuple[str, ...]
) -> tuple[Any, int]:
    """The ONNX model of the agent and the size of its memory."""
    from onnx import TensorProto, checker, helper

    where = str(files.model)
    g = Graph()
    n = "n"
    inputs = []
    env_names = layout if files.residual is None else layout[:-RESIDUAL_EXTRA]
    observation = "observation"
    inputs.append(
        helper.make_tensor_value_info(observation, TensorProto.FLOAT, [n, len(env_names)])
    )
    networks = [
        (member, *actor_layers(policy, str(member.model)), policy.action_space)
        for member, policy in _networks(files, actor)
    ]
    seen = observation
    state_outputs: list[str] = []
    if files.residual is not None:
        state_size = 4  # previous applied action (3), started (1)
        inputs.append(helper.make_tensor_value_info("state", TensorProto.FLOAT, [n, state_size]))
        inputs.append(helper.make_tensor_value_info("base_action", TensorProto.FLOAT, [n, 3]))
        previous = g.op("Slice", "state", *(g.const([v], np.int64) for v in (0, 3, 1)))
        started = g.op("Slice", "state", *(g.const([v], np.int64) for v in (3, 4, 1)))
        seen = g.op("Concat", observation, "base_action", previous, axis=1)
    else:
        allocation = next((s for s in stages if isinstance(s, AllocationStage)), None)
        state_size = 3 if allocation is not None else 0
        if allocation is not None:  # the network sees the delivered command (`Stage.observe`)
            inputs.append(helper.make_tensor_value_info("state", TensorProto.FLOAT, [n, 3]))
            keep = np.ones(len(layout), np.float32)
            keep[allocation.allocation.previous_index] = 0.0
            if allocation.factors is not None:  # the entries it scales on this actuator
                keep[allocation.factors.index] = allocation.factors.values
            place = np.zeros((3, len(layout)), np.float32)
            place[np.arange(3), allocation.allocation.previous_index] = 1.0
            seen = g.op(
                "Add",
                g.op("Mul", observation, g.const(keep, np.float32)),
                g.op("MatMul", "state", g.const(place, np.float32)),
            )

    def network_commands(observed: str) -> str:
        """Each network's action on ``observed`` through its own normalisation; their mean."""
        actions = []
        for member, layers, squash, space in networks:
            normed = normalisation_graph(
                g, observed, member.obs_mean, member.obs_var, member.clip_obs, member.epsilon
            )
            net = network_graph(g, normed, layers)
            actions.append(action_head(g, net, space.low, space.high, squash))
        if len(actions) == 1:
            return actions[0]
        total = g.op("Sum", *actions)  # as `EnsembleActor`: the sum over K, then / K
        return g.op("Div", total, g.const(np.float32(len(actions)), np.float32))

    commands = network_commands(seen)
    if isinstance(actor, MirroredNetwork):  # ½·(π(o) + M_a·π(M_o·o)), `controllers.mirror`
        image = network_commands(g.op("Mul", seen, g.const(actor.signs, np.float32)))
        image = g.op("Mul", image, g.const(ACTION_MIRROR, np.float32))
        commands = g.op("Mul", g.const(0.5, np.float32), g.op("Add", commands, image))
    if files.residual is not None:
        settings = files.residual
        commands = residual_graph(
            g,
            "base_action",
            commands,
            previous,
            started,
            settings.bound,
            settings.filter_max,
            settings.bound_below,
            settings.brake_fin_margin,
        )
        if settings.envelope_guard is not None:  # before it becomes the previous action
            commands = guard_graph(
                g, commands, observation, ENV_GUARD_INDEX, settings.envelope_guard
            )
        ones = g.op("ConstantOfShape", g.op("Shape", started), value=_one_float32())
        state_outputs = [g.op("Concat", commands, ones, axis=1)]  # (applied, started = 1)
    for stage in stages:
        if isinstance(stage, GuardStage):
            commands = guard_graph(g, commands, seen, stage.index, stage.guard)
        elif isinstance(stage, AllocationStage):
            commands, delivered = allocation_graph(g, commands, seen, stage.allocation)
            state_outputs = [delivered]
        else:
            raise ValueError(f"{where}: stage {stage.name!r} has no ONNX export here")
    g.op("Identity", commands, output="action")
    outputs = [helper.make_tensor_value_info("action", TensorProto.FLOAT, [n, 3])]
    if state_size:
        g.op("Identity", state_outputs[0], output="next_state")
        outputs.append(
            helper.make_tensor_value_info("next_state", TensorProto.FLOAT, [n, state_size])
        )
    graph = helper.make_graph(g.nodes, "auv_gym_agent", inputs, outputs, g.initializers)
    model = helper.make_model(
        graph, opset_imports=[helper.make_opsetid("", OPSET)], producer_name="auv-gym"
    )
    model.producer_version = __version__
    model.ir_version = 8  # onnxruntime ≥ 1.12 reads it
    checker.check_model(model, full_check=True)
    return model, state_size


def _networks(files: AgentFiles, actor: Any) -> list[tuple[AgentFiles, Any]]:
    """(files, SB3 policy) of each network the graph holds: the agent's, or every member's of
    an ensemble (whose actions the graph averages), inside the mirror stage or not."""
    network = actor.network if isinstance(actor, MirroredNetwork) else actor
    if files.members:
        return [
            (member, policy.sb3_policy)
            for member, policy in zip(files.members, network.members, strict=True)
        ]
    return [(files, network.sb3_policy)]


def _one_float32() -> Any:
    from onnx import numpy_helper

    return numpy_helper.from_array(np.ones(1, np.float32))


def _parity(
    model: Any, files: AgentFiles, actor: Any, stages: list[Any], state_size: int
) -> dict[str, Any]:
    """The graph against the Python agent on `PARITY_SAMPLES` observations drawn from the
    agent's normalisation statistics (μ ± σ per entry; a residual agent: base commands, previous
    actions and episode starts drawn too, its commands through its envelope guard if it has
    one): the largest |difference| of the commands and of the memory it passes on."""
    from controllers.residual import agent_observation, residual_action
    from controllers.stages import PipelineState, StagedPolicy

    rng = np.random.default_rng(0)
    k = PARITY_SAMPLES
    draw = files.obs_mean + np.sqrt(files.obs_var) * rng.standard_normal((k, files.obs_mean.size))
    session = inference_session(model.SerializeToString(), where=files.model)
    if files.residual is not None:
        obs = draw[:, :-RESIDUAL_EXTRA].astype(np.float32)  # the env's; then b, a_{k−1}
        base = rng.uniform(-1.0, 1.0, (k, 3)).astype(np.float32)
        previous = rng.uniform(-1.0, 1.0, (k, 3)).astype(np.float32)
        started = rng.integers(0, 2, k).astype(bool)
        state = np.column_stack([previous, started]).astype(np.float32)
        got, got_state = session.run(
            None, {"observation": obs, "state": state, "base_action": base}
        )
        correction, _ = actor.predict(agent_observation(obs, base, previous))
        want = residual_action(
            base,
            correction,
            files.residual.bound,
            files.residual.filter_max,
            previous,
            started,
            files.residual.bound_below,
            brake_fin_margin=files.residual.brake_fin_margin,
        )
        want = guard_env_commands(want, obs, files.residual.envelope_guard)
        want_state = np.column_stack([want, np.ones(k)])
    else:
        obs = draw.astype(np.float32)
        policy = StagedPolicy(actor, stages)
        memories = [stage.start(k) for stage in stages]
        feeds = {"observation": obs}
        if state_size:
            delivered = rng.uniform(-1.0, 1.0, (k, 3)).astype(np.float32)
            memories = [delivered.copy() if m is not None else m for m in memories]
            feeds["state"] = delivered
        reference_state = PipelineState(None, memories, k)
        want, reference_state = policy.predict(obs, reference_state)
        got, *rest = session.run(None, feeds)
        got_state = rest[0] if rest else np.zeros((k, 0))
        kept = [m for m in reference_state.memories if m is not None]
        want_state = kept[0] if kept else np.zeros((k, 0))
    errors = [np.abs(np.asarray(got, np.float64) - want)]
    errors.append(np.abs(np.asarray(got_state, np.float64) - want_state))
    worst = max(float(e.max()) if e.size else 0.0 for e in errors)
    return {"observations": k, "max_abs_error": worst, "seed": 0}


def _contract(
    files: AgentFiles,
    target: Path,
    layout: tuple[str, ...],
    state_size: int,
    actuator: str,
    actuator_params: Any,
    stages: list[Any],
    parity: dict[str, Any],
) -> dict[str, Any]:
    """The contract JSON of an export (`controllers.onnx_contract.read_contract` reads it)."""
    from auv_gym import resolve_env_id
    from auv_gym.sim.config import SimConfig
    from auv_gym.sim.observation import ObservationConfig
    from controllers.agent import agent_env_kwargs

    metadata = files.metadata
    env_id = resolve_env_id(metadata.get("env_id", "AUVPath3D-v0"))
    trained = metadata.get("env_kwargs") or {}
    plant = trained.get("plant", "5dof")
    # The env the graph was built for: the agent's, flown on the export's actuator and plant.
    env_kwargs = agent_env_kwargs(metadata)
    if actuator != "paper":
        env_kwargs["actuator"] = actuator
    params = None
    if actuator_params is not None:
        params = allocation_params(actuator_params)
        env_kwargs["actuator_params"] = params
    for key in ("plant", "plant_params"):
        if key in trained and plant != "5dof":
            env_kwargs[key] = trained[key]
    config = SimConfig.from_kwargs(**env_kwargs)
    names = layout if files.residual is None else layout[:-RESIDUAL_EXTRA]
    units = ObservationConfig.from_spec(env_kwargs.get("observation")).units
    action_names, action_meaning = ACTION_LAYOUT[actuator]
    inputs, outputs = graph_io(len(names), state_size, files.residual is not None)
    allocation = next((s.allocation for s in stages if isinstance(s, AllocationStage)), None)
    residual = None
    if files.residual is not None:
        # β⁻, the fin margin and the guard are in the graph; stated, not re-applied
        residual = files.residual.with_optional(
            {
                "base": files.residual.base,
                "base_kwargs": files.residual.base_kwargs,
                "bound": list(files.residual.bound),
                "filter_max": files.residual.filter_max,
            }
        )
    return {
        "format": CONTRACT_FORMAT,
        "format_version": CONTRACT_VERSION,
        "onnx_file": target.name,
        "onnx_sha256": None,  # of the serialised graph, set by `export_onnx`
        "opset": OPSET,
        "env_id": env_id,
        "env_kwargs": env_kwargs,
        "control_period_s": config.control_dt,
        "plant": plant,  # the agent's training plant; the graph holds no plant model
        "observation": {"names": list(names), "units": [units.get(x, "") for x in names]},
        "action": {"names": action_names, "units": action_meaning, "range": [-1.0, 1.0]},
        "actuator": actuator,
        "actuator_params": params,  # the realistic allocation's, where not the defaults
        # the agent allocates its commands: the graph is for this actuator only
        "allocated": any(spec["name"] == "actuator_allocation" for spec in files.stages),
        # the vehicle constants the allocation stage holds (K·δ_max [kg]; X [N], M, N [N·m])
        "allocation": None
        if allocation is None
        else {"fin_gain_kg": float(allocation.fin_gain), "limits": allocation.limits.tolist()},
        "state": {
            "size": state_size,
            "reset": "zeros at every episode start; pass next_state back as state",
        },
        "inputs": inputs,
        "outputs": outputs,
        "stages": [
            *({"name": MIRROR_STAGE} for spec in files.stages if spec["name"] == MIRROR_STAGE),
            *(stage.to_dict() for stage in stages),
        ],
        "residual": residual,
        "parity": parity,
        "provenance": _provenance(files),
    }


def _provenance(files: AgentFiles) -> dict[str, Any]:
    """Where the export came from, without the exporting machine's paths: the agent's
    (`_model_provenance`), or for an ensemble its folder's name and each member's, in the order
    of its ensemble.json; then the exporting version."""
    if files.ensemble is not None:
        out: dict[str, Any] = {
            "agent": files.ensemble.parent.name,
            "members": [_model_provenance(member) for member in files.members],
        }
    else:
        out = _model_provenance(files)
    out["exported_with"] = f"auv-gym {__version__}"
    return out


def _model_provenance(files: AgentFiles) -> dict[str, Any]:
    """One saved agent: its folder's name, its model's SHA-256, how it was trained, and its
    training file only where it is a file of this repository (a path relative to it)."""
    metadata = files.metadata
    out: dict[str, Any] = {
        "agent": Path(files.model).parent.name,
        "model_sha256": sha256_of(Path(files.model)),
    }
    for key in ("algo", "seed", "num_timesteps", "git_commit", "auv_gym_version"):
        if key in metadata:
            out[key] = metadata[key]
    config = metadata.get("config_file")
    if isinstance(config, str) and _repository_file(config):
        out["config_file"] = Path(config).as_posix()
    return out


# The repository's scratch folders (git-ignored): a training file there is the run's copy,
# absent from every other checkout.
SCRATCH_FOLDERS = ("runs", "out")


def _repository_file(path: str) -> bool:
    """``path`` is relative, stays inside the repository, outside its scratch folders, and names
    one of its files."""
    relative = Path(path)
    if relative.is_absolute() or ".." in relative.parts:
        return False
    if relative.parts and relative.parts[0] in SCRATCH_FOLDERS:
        return False
    return (_REPOSITORY / relative).is_file()


def _annotate(model: Any, contract: Mapping[str, Any]) -> None:
    """The model's metadata properties: what a runtime must know without the contract and what
    the graph was built for (env id and arguments, observation and action names and units,
    actuator and its settings, allocation constants, plant, control period, memory size,
    stages, residual base). `controllers.onnx_contract` checks the contract against them."""
    from onnx import helper

    props = {
        "format": f"{CONTRACT_FORMAT} {CONTRACT_VERSION}",
        "env_id": contract["env_id"],
        "env_kwargs": json.dumps(contract["env_kwargs"]),
        "observation_names": json.dumps(contract["observation"]["names"]),
        "observation_units": json.dumps(contract["observation"]["units"], ensure_ascii=False),
        "action_names": json.dumps(contract["action"]["names"]),
        "action_units": contract["action"]["units"],
        "actuator": contract["actuator"],
        "actuator_params": json.dumps(contract["actuator_params"]),
        "allocated": json.dumps(contract["allocated"]),
        "allocation": json.dumps(contract["allocation"]),
        "plant": contract["plant"],
        "control_period_s": repr(contract["control_period_s"]),
        "state_size": str(contract["state"]["size"]),
        "stages": json.dumps([stage["name"] for stage in contract["stages"]]),
        "stage_settings": json.dumps(contract["stages"]),
        "residual": json.dumps(contract["residual"]),
    }
    helper.set_model_props(model, props)
