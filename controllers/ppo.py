"""The agent loader under its former name: `controllers.agent` (files, checks, the actor) and
`controllers.loader.load_policy` (any saved agent, plain or residual)."""

from __future__ import annotations

from controllers.agent import (
    METADATA_FILE,
    MODEL_FILE,
    STATS_FILE,
    VECNORM_FILE,
    AgentFiles,
    AgentPolicy,
    PPOPolicy,
    check_agent,
)
from controllers.loader import load_policy

__all__ = [
    "METADATA_FILE",
    "MODEL_FILE",
    "STATS_FILE",
    "VECNORM_FILE",
    "AgentFiles",
    "AgentPolicy",
    "PPOPolicy",
    "check_agent",
    "load_policy",
]
