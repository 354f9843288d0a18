"""Policy specs of the benchmark CLIs: one parser for "fbsm", "ppo", "ppo:PATH", "module:attribute".

* a name of `controllers.CLASSICAL` ("fbsm", "backstepping", their presets): built with
  `controllers.make` for the scenario's control period and controller keyword arguments;
* a name of `SHIPPED_AGENTS` ("ppo", "ppo_helix_v1", "ppo_generalist", "sac_generalist",
  "ppo_residual", "ppo_preview", "ppo_preview_net256", "ppo_integral", "ppo_antiwindup",
  "ppo_paper_actuator", "ppo_paper_actuator_guard" (the same agent inside its envelope guard,
  `controllers.envelope_guard`), "ppo_paper_start_guard" (the same training for 8M env steps,
  guarded), "ppo_paper_start_guard_alloc" (that agent with its moments allocated to the
  scenario's actuator, `controllers.actuator_allocation`), "ppo_along_track_guard_alloc" (that
  agent trained on for 2M env steps with its along-track error at a finer scale, guarded and
  allocated likewise), "ppo_cross_track_guard_alloc" (that one trained on for 2M more with its
  cross-track and depth errors at a finer scale, likewise),
  "sac_paper_actuator_guard_alloc"
  (the SAC generalist trained inside the envelope guard, allocated likewise), "sac_helix"): the
  agent shipped under `benchmarks/agents/<folder>` (a name whose folder is not there yet is a
  one-line error saying so); "ppo:PATH": any saved agent directory or model zip
  (`controllers.loader.load_policy`, any algorithm of `controllers.algorithms`); a residual
  agent's base controller is built like a classical one, for the scenario;
* "module:attribute": an importable Policy object, or a class / factory called with the
  scenario's controller keyword arguments (`controllers.import_policy`).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import controllers
from auv_gym import ENV_ID, VARIANTS, ObservationConfig, resolve_env_id
from controllers import CLASSICAL

__all__ = [
    "AGENTS_DIR",
    "DEFAULT_AGENT",
    "SHIPPED_AGENTS",
    "MissingExtraError",
    "PolicySpec",
    "agent_run",
    "build_policy",
    "check_policy_spec",
    "policy_env_id",
    "policy_label",
    "policy_names",
]

AGENTS_DIR = Path(__file__).resolve().parents[1] / "agents"
# Policy name → folder of benchmarks/agents/ (README "Agents"; the realistic-speed
# retrained specialist and the generalists trained on the task distribution,
# AUVPath3DSpeedLimit-v0).
SHIPPED_AGENTS = {
    "ppo": "ppo_helix",
    "ppo_helix_v1": "ppo_helix_v1",
    "ppo_generalist": "ppo_generalist",
    "sac_generalist": "sac_generalist",
    "ppo_residual": "ppo_residual",
    "ppo_preview": "ppo_preview",
    "ppo_preview_net256": "ppo_preview_net256",
    "ppo_integral": "ppo_integral",
    "ppo_antiwindup": "ppo_antiwindup",
    "ppo_paper_actuator": "ppo_paper_actuator",
    "ppo_paper_actuator_guard": "ppo_paper_actuator_guard",
    "ppo_paper_start_guard": "ppo_paper_start_guard",
    "ppo_paper_start_guard_alloc": "ppo_paper_start_guard_alloc",
    "ppo_along_track_guard_alloc": "ppo_along_track_guard_alloc",
    "ppo_cross_track_guard_alloc": "ppo_cross_track_guard_alloc",
    "sac_paper_actuator_guard_alloc": "sac_paper_actuator_guard_alloc",
    "sac_helix": "sac_helix",
}
DEFAULT_AGENT = AGENTS_DIR / SHIPPED_AGENTS["ppo"]
AGENT_PREFIX = "ppo:"
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
    """A parsed spec: its text, its kind and, for "ppo" / "ppo:PATH", the agent's path."""

    text: str
    kind: Literal["classical", "agent", "import"]
    agent: Path | None = None

    @classmethod
    def parse(cls, spec: str) -> PolicySpec:
        """Classify ``spec`` without touching files or importing; ValueError if it names nothing."""
        if spec in CLASSICAL:
            return cls(spec, "classical")
        if spec in SHIPPED_AGENTS:
            return cls(spec, "agent", AGENTS_DIR / SHIPPED_AGENTS[spec])
        if spec.startswith(AGENT_PREFIX):
            return cls(spec, "agent", Path(spec[len(AGENT_PREFIX) :]))
        if ":" in spec:
            return cls(spec, "import")
        raise ValueError(
            f"unknown policy {spec!r}; valid: {policy_names()}, 'ppo:PATH' or 'module:attribute'"
        )


def policy_names() -> list[str]:
    """The policies known by name: the classical controllers and presets, the shipped agents."""
    return [*CLASSICAL, *SHIPPED_AGENTS]


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
        if not parsed.agent.exists() and spec in SHIPPED_AGENTS:
            raise FileNotFoundError(
                f"policy {spec!r}: the agent is not shipped (yet): {parsed.agent} does not exist"
            )
        if not parsed.agent.exists():
            raise FileNotFoundError(f"policy {spec!r}: agent {parsed.agent} does not exist")
        from controllers.agent import check_agent

        try:
            check_agent(parsed.agent)
        except (OSError, ValueError) as error:
            raise type(error)(f"policy {spec!r}: {error}") from None
    if parsed.kind == "import":
        controllers.import_policy(spec, instantiate=False)
    return parsed


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
    return controllers.import_policy(spec, **kwargs)


def policy_label(text: str) -> str:
    """A file-system-safe label of a spec or policy name ("ppo:runs/x" → "ppo-runs_x")."""
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in text.replace(":", "-", 1))
    return safe.strip("_") or "policy"


def agent_run(where: str, agent: Path, default_env_id: str | None = None) -> tuple[int, str]:
    """(training seed, env id) that a checked agent's metadata.json records; the env id must be
    a key of `auv_gym.VARIANTS` or an earlier id that `auv_gym.resolve_env_id` maps to one (an
    agent is evaluated under the env it was trained on, e.g. AUVPath3DSpeedLimit-v0's surge
    limit); ``default_env_id`` stands in for a missing one (None: an error). Errors name
    ``where``."""
    from controllers.agent import check_agent

    try:
        files = check_agent(agent)
    except (OSError, ValueError) as error:
        raise type(error)(f"{where}: {error}") from None
    recorded = files.metadata.get("env_id", default_env_id)
    try:  # an id of an earlier release (AUVPath3D-v1) runs under today's name for that env
        env_id = resolve_env_id(recorded)
    except ValueError as error:
        raise ValueError(
            f"{where}: {agent}/metadata.json records env_id {recorded!r}; an agent runs under "
            f"its training env: {error}"
        ) from None
    trained = ObservationConfig.from_spec(files.metadata.get("observation"))
    registered = ObservationConfig.from_spec(VARIANTS[env_id].get("observation"))
    if trained != registered:  # the benchmark builds an agent's env from its id alone
        raise ValueError(
            f"{where}: {agent} was trained on the observation {trained.to_dict()}, but its env "
            f"{env_id} gives {registered.to_dict()}; benchmarks run an agent under its env id's "
            "registered arguments (evaluate it with auv_gym.rollout and that observation)"
        )
    seed = files.metadata.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"{where}: {agent}/metadata.json records seed {seed!r}, not an int >= 0")
    return seed, env_id


def policy_env_id(spec: str) -> str:
    """The env id a policy runs under: an agent's training env (`agent_run`), else the
    benchmark's `auv_gym.ENV_ID` (the classical controllers, imported policies and agents
    whose files record no env id, e.g. an RL Zoo model zip)."""
    parsed = PolicySpec.parse(spec)
    if parsed.kind != "agent" or parsed.agent is None:
        return ENV_ID
    return agent_run(f"policy {spec!r}", parsed.agent, default_env_id=ENV_ID)[1]
