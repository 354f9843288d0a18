"""`ActorWrapper`: the base of policies that transform a loaded actor's output (the envelope guard,
`controllers.envelope_guard`, and actuator allocation, `controllers.actuator_allocation`). It holds
the actor and its path and forwards every other attribute (metadata, label, num_threads...) to it,
so a wrapped agent reads like its actor everywhere but in `predict`."""

from __future__ import annotations

from typing import Any

__all__ = ["ActorWrapper"]


class ActorWrapper:
    """A Policy built on ``actor``; subclasses define `predict`."""

    def __init__(self, actor: Any) -> None:
        self.actor = actor
        self.path = getattr(actor, "path", None)

    def __getattr__(self, name: str) -> Any:  # metadata, label, num_threads... of the actor
        if name == "actor":  # not set yet (e.g. while unpickling): no recursion
            raise AttributeError(name)
        return getattr(self.actor, name)
