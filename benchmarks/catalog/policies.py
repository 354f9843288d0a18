"""Policy specs of the benchmark CLIs: one parser for "fbsm", "ppo_generalist", "agent:PATH" and
"module:attribute".

* a name of `controllers.CLASSICAL` ("fbsm", "backstepping", their presets): built with
  `controllers.make` for the scenario's control period and controller keyword arguments;
* a name of `REFERENCE_AGENTS`: the reference agent shipped under `benchmarks/agents/<name>`
  (benchmarks/agents/README.md);
* "agent:PATH": any saved agent directory or model zip (`controllers.loader.load_policy`, any
  algorithm of `controllers.algorithms`); a residual agent's base controller is built like a
  classical one, for the scenario;
* "onnx:FILE": an exported agent (`auv-gym export`), run by onnxruntime alone
  (`controllers.onnx_policy.OnnxPolicy`) in the env its contract records;
* "module:attribute": an importable Policy object, or a class / factory called with the
  scenario's controller keyword arguments (`controllers.import_policy`).

A name of an earlier release (`REMOVED_POLICIES`: "ppo", "ppo:PATH", agents no longer shipped)
is a one-line error naming what to type instead.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import controllers
from auv_gym import ENV_ID, VARIANTS, resolve_env_id
from controllers import CLASSICAL
from controllers.registry import NoFiveDofModelError, reads_ground_velocity

__all__ = [
    "AGENTS_DIR",
    "AGENT_PREFIX",
    "ONNX_PREFIX",
    "POLICY_SPEC_FORMS",
    "REFERENCE_AGENTS",
    "REMOVED_POLICIES",
    "MissingExtraError",
    "PolicySpec",
    "agent_run",
    "build_policy",
    "check_policy_for_env",
    "check_policy_spec",
    "policy_env",
    "policy_env_id",
    "policy_label",
    "policy_names",
]

AGENTS_DIR = Path(__file__).resolve().parents[1] / "agents"
# The reference agents: the name is the folder of benchmarks/agents/ (README there).
REFERENCE_AGENTS = (
    "ppo_generalist",
    "ppo_as_built",
    "ppo_residual",
    "sac_generalist",
    "ppo_residual_as_built",
)
AGENT_PREFIX = "agent:"
ONNX_PREFIX = "onnx:"
# The spec forms beyond names, for the CLIs' help: every one of them goes through `build_policy`.
POLICY_SPEC_FORMS = f"{AGENT_PREFIX}PATH, {ONNX_PREFIX}FILE or module:attribute"
_NOT_SHIPPED = "is no longer shipped (its results stay in docs/results.md); reference agents:"
# Names of earlier releases → what to type now (None: the agent left the tree).
REMOVED_POLICIES: dict[str, str | None] = {
    "ppo_cross_track_guard_alloc": "ppo_generalist",
    **dict.fromkeys(
        (
            "ppo",
            "ppo_helix",
            "ppo_helix_v1",
            "sac_helix",
            "ppo_preview",
            "ppo_preview_net256",
            "ppo_integral",
            "ppo_antiwindup",
            "ppo_paper_actuator",
            "ppo_paper_actuator_guard",
            "ppo_paper_start_guard",
            "ppo_paper_start_guard_alloc",
            "ppo_along_track_guard_alloc",
            "sac_paper_actuator_guard_alloc",
        )
    ),
}
FORMER_AGENT_PREFIX = "ppo:"
RL_MODULES = ("torch", "stable_baselines3")  # what loading an agent imports (the rl extra)


def _importable(module: str) -> bool:
    try:
        importlib.import_module(module)
    except ImportError:
        return False
    return True


class MissingExtraError(ValueError):
    """A policy needs an optional extra that is not installed (a usage error: exit code 2)."""


@dataclass(frozen=True)
class PolicySpec:
    """A parsed spec: its text, its kind and, for an agent, its path (an export: its file)."""

    text: str
    kind: Literal["classical", "agent", "onnx", "import"]
    agent: Path | None = None
    onnx: Path | None = None

    @property
    def files(self) -> Path | None:
        """The files the policy is read from (an agent folder, an .onnx file), or None."""
        return self.agent if self.agent is not None else self.onnx

    @classmethod
    def parse(cls, spec: str) -> PolicySpec:
        """Classify ``spec`` without touching files or importing; ValueError if it names nothing."""
        if spec in CLASSICAL:
            return cls(spec, "classical")
        if spec in REFERENCE_AGENTS:
            return cls(spec, "agent", AGENTS_DIR / spec)
        if spec.startswith(AGENT_PREFIX):
            return cls(spec, "agent", Path(spec[len(AGENT_PREFIX) :]))
        if spec.startswith(ONNX_PREFIX):
            return cls(spec, "onnx", onnx=Path(spec[len(ONNX_PREFIX) :]))
        if spec.startswith(FORMER_AGENT_PREFIX):
            path = spec[len(FORMER_AGENT_PREFIX) :]
            raise ValueError(f"policy {spec!r}: 'ppo:PATH' was renamed, use 'agent:{path}'")
        if spec in REMOVED_POLICIES:
            new = REMOVED_POLICIES[spec]
            if new is not None:
                raise ValueError(f"policy {spec!r} was renamed: use {new!r}")
            raise ValueError(f"policy {spec!r} {_NOT_SHIPPED} {list(REFERENCE_AGENTS)}")
        if ":" in spec:
            return cls(spec, "import")
        raise ValueError(
            f"unknown policy {spec!r}; valid: {policy_names()}, 'agent:PATH', 'onnx:FILE' or "
            "'module:attribute'"
        )


def policy_names() -> list[str]:
    """The policies known by name: the classical controllers and presets, the reference agents."""
    return [*CLASSICAL, *REFERENCE_AGENTS]


def check_policy_spec(spec: str) -> PolicySpec:
    """The parsed spec, after checking that its agent exists or its object imports.

    Raises ValueError (unknown name, import failure, an agent's damaged or inconsistent files,
    `controllers.agent.check_agent`) or FileNotFoundError (missing agent) with a message naming
    the spec: call it on every spec before any episode runs.
    """
    parsed = PolicySpec.parse(spec)
    if parsed.agent is not None:
        missing = [m for m in RL_MODULES if not _importable(m)]
        if missing:  # before any episode: a base install fails here, not after the others ran
            raise MissingExtraError(
                f"policy {spec!r}: running an agent needs {', '.join(missing)}, from the 'rl' "
                "extra: pip install 'auv-gym[rl]'"
            )
        if not parsed.agent.exists():
            raise FileNotFoundError(f"policy {spec!r}: agent {parsed.agent} does not exist")
        from controllers.agent import check_agent, check_weights

        try:
            check_weights(check_agent(parsed.agent))  # NaN weights too, before any episode
        except (OSError, ValueError) as error:
            raise type(error)(f"policy {spec!r}: {error}") from None
    if parsed.onnx is not None:
        check_onnx_spec(spec, parsed.onnx)
    if parsed.kind == "import":
        controllers.import_policy(spec, instantiate=False)
    return parsed


def check_onnx_spec(spec: str, path: Path) -> None:
    """An exported agent before any episode: onnxruntime installed, contract and graph intact and
    agreeing, and the graph's observation the one of the env its contract records."""
    from controllers.onnx_policy import onnxruntime_module

    try:  # imported with its telemetry off, as every onnxruntime import of the project
        onnxruntime_module(spec)
    except ImportError:
        raise MissingExtraError(
            f"policy {spec!r}: running an ONNX policy needs onnxruntime, from the 'onnx' extra: "
            "pip install 'auv-gym[onnx]'"
        ) from None
    from auv_gym.sim.config import SimConfig

    env_id, env_kwargs = policy_env(spec)
    try:
        names = SimConfig.from_kwargs(**{**VARIANTS[env_id], **env_kwargs}).observation.names
        controllers.make("onnx", path=str(path), observation_names=names)
    except (OSError, ValueError) as error:
        raise type(error)(f"policy {spec!r}: {error}") from None


def check_policy_for_env(
    spec: str, env: Any, controller_kwargs: dict[str, Any] | None = None
) -> None:
    """What building the policy ``spec`` for a scenario's ``env`` would refuse, without running
    anything or loading torch: a classical controller or an export is built; an agent's stages
    are built for the env's plant (an allocation whose observation lacks its inputs, say) and a
    residual agent's base controller too. Call it for every policy and scenario before any
    episode. An imported policy's factory is called and must return a Policy. Errors name the
    policy (and an agent's file)."""
    parsed = PolicySpec.parse(spec)
    try:
        _check_for_env(parsed, env, controller_kwargs)
    except (TypeError, ValueError) as error:
        if not str(error).startswith(f"policy {spec!r}"):
            error.args = (f"policy {spec!r}: {error}",)  # its type and fields kept
        raise error.with_traceback(None) from None


def _check_for_env(parsed: PolicySpec, env: Any, controller_kwargs: dict[str, Any] | None) -> None:
    spec = parsed.text
    if parsed.kind in ("classical", "onnx"):
        build_policy(spec, env, controller_kwargs)
        return
    if parsed.kind == "import":
        policy = build_policy(spec, env, controller_kwargs)
        if not callable(getattr(policy, "predict", None)):
            raise ValueError(
                f"policy {spec!r} gave {type(policy).__name__} {policy!r:.40}, not a Policy (an "
                "object with predict(observation, state, episode_start, deterministic))"
            )
        return
    if parsed.agent is None:
        return
    from controllers.agent import check_actuator, check_agent, observation_layout
    from controllers.env_settings import policy_settings
    from controllers.stages import build_stages

    files = check_agent(parsed.agent)
    settings = {**policy_settings(env), **(controller_kwargs or {})}
    check_actuator(files, settings.get("actuator", "paper"))
    build_stages(files.stages, observation_layout(files.metadata), settings, str(files.model))
    if files.residual is not None:
        residual = files.residual
        try:
            base = residual.make_base(**settings)
        except (TypeError, ValueError) as error:
            # a base that needs a 5-DOF model the vehicle lacks: the pair is not applicable
            kind = NoFiveDofModelError if isinstance(error, NoFiveDofModelError) else ValueError
            raise kind(
                f"policy {spec!r}: its residual base {residual.base!r} with base_kwargs "
                f"{residual.base_kwargs!r:.120} ({files.metadata_file}) cannot be built: {error}"
            ) from None
        if not callable(getattr(base, "predict", None)):
            raise ValueError(
                f"policy {spec!r}: its residual base {residual.base!r} "
                f"({files.metadata_file}) gave {type(base).__name__}, not a Policy"
            )


def build_policy(spec: str, env: Any, controller_kwargs: dict[str, Any] | None = None) -> Any:
    """The Policy named by ``spec``, configured for a scenario: its env (a `SimConfig` or env
    keyword arguments: control period, vehicle and actuator model reach a classical controller
    and a residual agent's base, `controllers.env_settings`) and its controller keyword
    arguments (they win; an imported policy's factory takes only these)."""
    parsed = PolicySpec.parse(spec)
    kwargs = dict(controller_kwargs or {})
    if parsed.kind == "classical":
        return controllers.make(spec, env=env, **kwargs)
    if parsed.kind == "agent":  # a residual agent's base is configured like a classical one
        return controllers.make("agent", env=env, path=str(parsed.agent), base_kwargs=kwargs)
    if parsed.kind == "onnx":  # so is an exported residual agent's
        return controllers.make("onnx", env=env, path=str(parsed.onnx), base_kwargs=kwargs)
    return controllers.import_policy(spec, **kwargs)


def policy_label(text: str) -> str:
    """A file-system-safe label of a spec or policy name ("agent:runs/x" → "agent-runs_x")."""
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in text.replace(":", "-", 1))
    return safe.strip("_") or "policy"


def agent_run(
    where: str, agent: Path, default_env_id: str | None = None
) -> tuple[int, str, dict[str, Any]]:
    """(training seed, env id, env arguments) of a checked agent: an agent carries its env.

    The env id is the one its metadata.json records, a key of `auv_gym.VARIANTS`; the env
    arguments hold the
    observation it was trained on where the id's registered one differs (e.g.
    ``observation="preview_integral"``). ``default_env_id`` stands in for a
    missing id (None: an error). Errors name ``where``."""
    from controllers.agent import check_agent

    try:
        files = check_agent(agent)
    except (OSError, ValueError) as error:
        raise type(error)(f"{where}: {error}") from None
    recorded = files.metadata.get("env_id", default_env_id)
    try:
        env_id = resolve_env_id(recorded)
    except ValueError as error:
        raise ValueError(
            f"{where}: {files.metadata_file or agent / 'metadata.json'} records env_id "
            f"{recorded!r}; an agent runs under "
            f"its training env: {error}"
        ) from None
    from controllers.agent import agent_env_kwargs

    fixed = VARIANTS[env_id]  # what the id gives; the rest is the agent's own (its observation)
    own = agent_env_kwargs(files.metadata)
    env_kwargs = {k: v for k, v in own.items() if k not in fixed or fixed[k] != v}
    seed = files.metadata.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"{where}: {agent}/metadata.json records seed {seed!r}, not an int >= 0")
    return seed, env_id, env_kwargs


def policy_env(spec: str) -> tuple[str, dict[str, Any]]:
    """(env id, env arguments) a policy runs under: an agent's training env (`agent_run`), else
    the benchmark's `auv_gym.ENV_ID` with no arguments (the classical controllers, imported
    policies and agents whose files record no env id, e.g. an RL Zoo model zip), or with the
    agents' observation for a classical controller that reads the DVL's velocity over ground
    (`controllers.registry.reads_ground_velocity`)."""
    parsed = PolicySpec.parse(spec)
    if parsed.onnx is not None:
        return onnx_env(spec, parsed.onnx)
    if parsed.kind == "classical" and reads_ground_velocity(spec):
        return ENV_ID, {"observation": "preview"}  # the DVL's velocity over ground, same env
    if parsed.kind != "agent" or parsed.agent is None:
        return ENV_ID, {}
    _, env_id, env_kwargs = agent_run(f"policy {spec!r}", parsed.agent, default_env_id=ENV_ID)
    return env_id, env_kwargs


def policy_env_id(spec: str) -> str:
    """The env id a policy runs under (`policy_env`)."""
    return policy_env(spec)[0]


def onnx_env(spec: str, path: Path) -> tuple[str, dict[str, Any]]:
    """(env id, env arguments) an exported agent's contract records (the env its graph was
    built for: an export for the fins or the propeller and fins names that actuator and its
    settings), as `agent_run` gives them for its saved agent; the contract is checked in full
    (`controllers.onnx_contract.read_contract`); errors name the spec."""
    from controllers.onnx_contract import read_contract

    try:
        contract = read_contract(path)
        env_id = resolve_env_id(contract.env_id)
    except (OSError, ValueError) as error:
        raise type(error)(f"policy {spec!r}: {error}") from None
    fixed = VARIANTS[env_id]
    own = contract.env_kwargs
    return env_id, {k: v for k, v in own.items() if k not in fixed or fixed[k] != v}
