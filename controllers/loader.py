"""Saved agents as policies: the one loader, dispatching plain vs residual agents.

`load_policy` checks an agent's files (`controllers.agent.check_agent`), loads its actor with the
algorithm its metadata names (`controllers.algorithms`) and, for a residual agent (metadata
"residual"), puts the actor on top of its base controller (`controllers.residual`). It is what
``controllers.make("agent", path=...)`` and ``controllers.make("residual", agent=PATH)`` call.
"""

from __future__ import annotations

import os
from typing import Any

from controllers.agent import (
    REALISTIC_ACTUATOR,
    AgentPolicy,
    check_actuator,
    check_agent,
    commands_realistic_actuators,
    load_network,
    observation_layout,
)
from controllers.mirror import mirrored
from controllers.residual import NO_STAGES, ResidualPolicy, check_bound
from controllers.residual import make_residual as residual_of_policy
from controllers.stages import StagedPolicy, build_stages, check_stage_specs

__all__ = ["load_policy", "make_residual"]


def load_policy(
    path: str | os.PathLike,
    *,
    device: str = "cpu",
    num_threads: int | None = 1,
    base_kwargs: dict[str, Any] | None = None,
    algo: str | None = None,
    stages: Any = None,
) -> AgentPolicy | ResidualPolicy | StagedPolicy:
    """A saved agent (a directory with model.zip + vecnormalize.npz + metadata.json, or a zip;
    or an ensemble's folder, `controllers.ensemble`: its members' mean action in place of one
    network) as a Policy: its network (`controllers.agent.AgentPolicy`), inside the stages its
    metadata lists (`controllers.stages.StagedPolicy`, built for the plant of ``base_kwargs``: the
    scenario's ``actuator``, ``params``, ``actuator_params``, ``control_dt``); for a residual
    agent a `ResidualPolicy` of its base controller, built with the recorded settings and
    ``base_kwargs`` (the propeller and fins by default for one trained on them), and its
    network.

    ``stages``: None for the agent's own; a list of stage specs replaces them (``[]``: the bare
    network; ``["envelope_guard"]``: guard an agent trained without it), checked like the
    metadata's. ``algo``: the algorithm the caller expects (None: any); ValueError naming the one
    found otherwise. The files are validated first, before torch is imported
    (`controllers.agent.check_agent`: FileNotFoundError when the model or its statistics are
    missing, ValueError naming the file and the problem otherwise). `num_threads`: torch's
    intra-op threads while the policy predicts (None: torch's setting); loading itself leaves
    torch's settings alone.
    """
    files = check_agent(path)
    if algo is not None and files.algo != algo:
        raise ValueError(f"agent {files.model} was trained with {files.algo!r}, not {algo!r}")
    specs = files.stages if stages is None else check_stage_specs(stages, "stages")
    if specs and files.residual is not None:
        raise ValueError(f"{files.model}: {NO_STAGES}")
    settings = base_kwargs or {}
    if "actuator" in settings:  # the plant it is built for: its actions must mean the same there
        check_actuator(files, settings["actuator"])
    built = build_stages(specs, observation_layout(files.metadata), settings, str(files.model))
    actor = load_network(files, device=device, num_threads=num_threads)
    actor = mirrored(actor, specs, observation_layout(files.metadata), str(files.model))
    if files.residual is not None:
        if commands_realistic_actuators(files.metadata):  # its base commands them too
            settings = {"actuator": REALISTIC_ACTUATOR, **settings}
        base = files.residual.make_base(**settings)
        policy = ResidualPolicy(base, actor, files.residual.bound, files.residual)
        policy.env_kwargs = actor.env_kwargs  # the env it carries (`auv_gym.rollout`)
        return policy
    return StagedPolicy(actor, built) if built else actor


def make_residual(
    agent: Any = None,
    base: str | None = None,
    bound: Any = None,
    filter_max: float | None = None,
    **base_kwargs: Any,
) -> ResidualPolicy:
    """``controllers.make("residual", ...)``: a `ResidualPolicy`.

    ``agent`` is a Policy of the residual observation (`controllers.residual.make_residual`),
    or the directory of a saved residual agent (its recorded base and β are used; a ``base``,
    ``bound`` or ``filter_max`` given here must equal them).
    """
    if agent is None:
        raise ValueError(
            "controllers.make('residual') needs agent=<Policy or saved residual agent directory>"
        )
    if callable(getattr(agent, "predict", None)):
        return residual_of_policy(agent, base, bound, filter_max, **base_kwargs)
    policy = load_policy(agent, base_kwargs=base_kwargs)
    if not isinstance(policy, ResidualPolicy):
        raise ValueError(
            f"agent {agent!r} is not a residual agent (its metadata.json has no 'residual' section)"
        )
    recorded = policy.settings
    assert recorded is not None
    if base is not None and base != recorded.base:
        raise ValueError(f"agent {agent!r} was trained on base {recorded.base!r}, not {base!r}")
    if bound is not None and check_bound(bound) != recorded.bound:
        raise ValueError(
            f"agent {agent!r} was trained with bound {list(recorded.bound)}, "
            f"not {list(check_bound(bound))}"
        )
    if filter_max is not None and filter_max != recorded.filter_max:
        raise ValueError(
            f"agent {agent!r} was trained with filter_max {recorded.filter_max}, not {filter_max!r}"
        )
    return policy
