"""One seeded episode of one scenario for one policy: the options and checks that `auv-gym record`
and `auv-gym video` share.

Both take a policy spec (`benchmarks.catalog.policies`), one scenario of a scenarios file
(`benchmarks/scenarios.toml`), a reset seed and a duration, and fly them as `auv-gym compare`
does: an agent under the env id and observation its metadata records, the scenario's env and
controller settings on top.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from auv_gym import VARIANTS
from auv_gym.sim.config import SimConfig
from benchmarks.catalog.policies import (
    POLICY_SPEC_FORMS,
    build_policy,
    check_policy_spec,
    policy_env,
)
from benchmarks.catalog.scenarios import SCENARIOS_FILE, load_scenarios, select
from benchmarks.options import option

__all__ = ["OneEpisodeOptions", "resolve_episode"]


@dataclass
class OneEpisodeOptions:
    """The options of a one-episode command, inherited by its option dataclass (its own
    options follow these)."""

    policy: str = option(
        "fbsm",
        f"policy spec: a controllers.make name, a reference agent name, {POLICY_SPEC_FORMS}",
    )
    scenario: str = option("paper", "scenario name in --scenario-file")
    # A Path is immutable: one shared default is safe.
    scenario_file: Path = option(SCENARIOS_FILE, "TOML file of named scenarios")  # noqa: RUF009
    seed: int = option(0, "reset seed of the episode")
    duration: float = option(300.0, "episode length [s]")


def resolve_episode(args: argparse.Namespace) -> dict[str, Any]:
    """Check ``args``' seed, scenario and policy (``--duration`` is the command's to bound) and
    set ``args.scenario`` to the one scenario named, ``args.env_id`` to the env the policy runs
    under and ``args.policy_object`` to the policy built for the scenario. Returns the env
    arguments the episode adds to that id's fixed ones (`auv_gym.VARIANTS`): the agent's
    recorded env, the scenario's and ``max_time``; ``args.config`` is the `SimConfig` of both.
    ValueError / OSError naming the argument, before any episode."""
    if args.seed < 0:
        raise ValueError(f"--seed must be non-negative, got {args.seed}")
    try:
        scenarios = load_scenarios(args.scenario_file)
    except OSError as error:
        raise OSError(f"--scenario-file {str(args.scenario_file)!r}: {error.strerror}") from None
    names = select(args.scenario, list(scenarios), "scenario")
    if len(names) != 1:
        raise ValueError(f"--scenario must name one scenario, got {args.scenario!r}")
    args.scenario = names[0]
    scenario = scenarios[names[0]]
    check_policy_spec(args.policy)
    # An agent runs under the env id it records, as in `compare` and the suite.
    args.env_id, agent_env = policy_env(args.policy)
    env_kwargs = {**agent_env, **scenario.env, "max_time": float(args.duration)}
    try:
        args.config = SimConfig.from_kwargs(**{**VARIANTS[args.env_id], **env_kwargs})
    except (TypeError, ValueError) as error:
        raise ValueError(f"scenario {names[0]!r}: {error}") from None
    args.policy_object = build_policy(args.policy, args.config, scenario.controller)
    return env_kwargs
