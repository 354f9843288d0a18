"""Saved agents as policies: the one loader, dispatching plain vs residual agents.

`load_policy` checks an agent's files (`controllers.agent.check_agent`), loads its actor with the
algorithm its metadata names (`controllers.algorithms`) and, for a residual agent (metadata
"residual"), puts the actor on top of its base controller (`controllers.residual`). It is what
``controllers.make("agent", path=...)`` and ``controllers.make("residual", agent=PATH)`` call.
"""

from __future__ import annotations

import os
from typing import Any

from controllers.actuator_allocation import (
    ALLOCATED_ACTUATORS,
    AllocatedPolicy,
    check_actuator_allocation,
)
from controllers.agent import AgentPolicy, check_agent, load_actor, observation_layout
from controllers.envelope_guard import GuardedPolicy, check_envelope_guard
from controllers.residual import ResidualPolicy, check_bound
from controllers.residual import make_residual as residual_of_policy

__all__ = ["REMOVED_STAGES", "load_policy", "make_residual"]

# Metadata keys of agent stages that were removed (no shipped agent used them; what they measured
# stays in docs/results.md): an agent that names one is refused, not loaded without it.
REMOVED_STAGES = {
    "action_increment": "incremental commands",
    "action_scale": "scaled commands",
}


def load_policy(
    path: str | os.PathLike,
    *,
    device: str = "cpu",
    num_threads: int | None = 1,
    base_kwargs: dict[str, Any] | None = None,
    algo: str | None = None,
) -> AgentPolicy | ResidualPolicy | GuardedPolicy | AllocatedPolicy:
    """A saved agent (a directory with model.zip + vecnormalize.npz + metadata.json, or a zip)
    as a Policy: its actor (`controllers.agent.AgentPolicy`), or for a residual agent a
    `ResidualPolicy` of its base controller, built with the recorded settings and
    ``base_kwargs`` (the scenario's, e.g. ``actuator``, ``control_dt``; ignored for other
    agents), and its actor; with metadata "envelope_guard", that policy inside a
    `GuardedPolicy` (`controllers.envelope_guard`); with metadata "actuator_allocation" and a
    ``base_kwargs`` actuator "fins" or "realistic", the whole inside an `AllocatedPolicy`
    (`controllers.actuator_allocation`) for that actuator.

    ``algo``: the algorithm the caller expects (None: any); ValueError naming the one found
    otherwise. The files are validated first, before torch is imported (FileNotFoundError when
    the model or its statistics are missing, ValueError naming the file and the problem
    otherwise; a metadata key of a removed stage, `REMOVED_STAGES`, is such a ValueError).
    `num_threads`: torch's intra-op threads while the policy predicts (None: torch's setting);
    loading itself leaves torch's settings alone.
    """
    files = check_agent(path)
    if algo is not None and files.algo != algo:
        raise ValueError(f"agent {files.model} was trained with {files.algo!r}, not {algo!r}")
    for key, stage in REMOVED_STAGES.items():  # checked before torch loads anything
        if key in files.metadata:
            raise ValueError(
                f"{files.metadata_file}: {key!r} ({stage}) was removed from auv-gym; this agent "
                "cannot be loaded"
            )
    guard = files.metadata.get("envelope_guard")
    if guard is not None:
        guard = check_envelope_guard(guard, f"{files.metadata_file}")
        if files.residual is not None:
            raise ValueError(f"{files.metadata_file}: envelope_guard excludes residual")
    allocation = files.metadata.get("actuator_allocation")
    if allocation is not None:
        check_actuator_allocation(allocation, f"{files.metadata_file}")
        if files.residual is not None:
            raise ValueError(f"{files.metadata_file}: actuator_allocation excludes residual")
    policy = _unguarded(
        files, load_actor(files, device=device, num_threads=num_threads), base_kwargs
    )
    names = observation_layout(files.metadata)
    if guard is not None:
        policy = GuardedPolicy(policy, guard, names)
    settings = base_kwargs or {}
    if allocation is None or settings.get("actuator") not in ALLOCATED_ACTUATORS:
        return policy
    return AllocatedPolicy(
        policy, names, settings["actuator"], settings.get("params"), settings.get("actuator_params")
    )


def _unguarded(files: Any, actor: AgentPolicy, base_kwargs: dict[str, Any] | None) -> Any:
    if files.residual is None:
        return actor
    base = files.residual.make_base(**(base_kwargs or {}))
    return ResidualPolicy(base, actor, files.residual.bound, files.residual)


def make_residual(
    agent: Any = None,
    base: str | None = None,
    bound: Any = None,
    filter_max: float | None = None,
    **base_kwargs: Any,
) -> ResidualPolicy:
    """``controllers.make("residual", ...)``: a `ResidualPolicy`.

    ``agent`` is a Policy of the 21-value observation (`controllers.residual.make_residual`),
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
