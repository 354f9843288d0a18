"""How a run's evaluations are ranked to keep its best agent (docs/design.md §3.20).

The default rule, the one every committed agent was selected by: fewer terminated validation
episodes first, then the lower mean rms distance [m] over all of them. A hyper-parameter file's
``selection`` section changes it for agents validated on several actuators or plants::

    selection: {failures_allowed: 1, across_variants: geometric}

- ``failures_allowed`` k: the first k terminated episodes do not outrank accuracy (the first
  component of the score is max(0, n_terminated − k)). On a set where some episodes of a hard
  variant fail for every agent now and then (the fins in 0.2 m/s currents, 1 of 16), failures
  first keeps whichever early agent happened to pass them all and discards every later, more
  accurate one.
- ``across_variants``: ``pooled`` (the mean over every episode) or ``geometric`` (the geometric
  mean of each variant's mean rms distance): each actuator on its own scale, so that 10 % gained
  on the paper's actuator (0.06 m) counts as much as 10 % on the fins (0.3 m) instead of a
  twentieth of it. A validation that varies nothing scores as ``pooled``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

__all__ = ["ACROSS_VARIANTS", "DEFAULT_RULE", "SelectionRule", "parse_selection", "rule_of"]

ACROSS_VARIANTS = ("pooled", "geometric")
MAX_FAILURES_ALLOWED = 1000


@dataclass(frozen=True)
class SelectionRule:
    """Ranks validation summaries (`benchmarks.training.evaluation.summarize`): lower is better."""

    failures_allowed: int = 0
    across_variants: str = "pooled"

    def score(
        self, summary: Mapping[str, Any], chattering_weight: float = 0.0
    ) -> tuple[int, float]:
        """(terminated episodes beyond the allowance, rms distance [m] as the rule combines it,
        plus ``chattering_weight`` λ [m·s] times the mean chattering [1/s] when λ > 0)."""
        mean = self._accuracy(summary)
        if chattering_weight > 0.0:
            mean = mean + chattering_weight * summary["chattering_mean"]
        failed = max(0, int(summary["n_terminated"]) - self.failures_allowed)
        return failed, (mean if math.isfinite(mean) else math.inf)

    def _accuracy(self, summary: Mapping[str, Any]) -> float:
        parts = summary.get("per_variant") or {}
        if self.across_variants == "pooled" or not parts:
            return float(summary["rms_distance_mean"])
        means = [float(part["rms_distance_mean"]) for part in parts.values()]
        if not all(math.isfinite(m) and m > 0.0 for m in means):
            return math.inf
        return math.exp(sum(math.log(m) for m in means) / len(means))

    def describe(self) -> str:
        """The rule in words, for the summaries a selection writes."""
        first = (
            "terminated episodes"
            if self.failures_allowed == 0
            else f"terminated episodes beyond {self.failures_allowed}"
        )
        second = (
            "mean rms distance"
            if self.across_variants == "pooled"
            else "geometric mean over the variants of their mean rms distance"
        )
        return f"{first}, then {second}"

    def to_dict(self) -> dict[str, Any]:
        """The file's form of the rule."""
        return {"failures_allowed": self.failures_allowed, "across_variants": self.across_variants}


DEFAULT_RULE = SelectionRule()


def parse_selection(value: Any, where: str) -> SelectionRule:
    """A ``selection`` section as a `SelectionRule`; ValueError (one line, naming ``where`` and
    the entry) for an unknown key, a count that is not a whole number in 0-1000, or an unknown
    way to combine the variants."""
    if not isinstance(value, Mapping):
        raise ValueError(f"{where}: selection must be a mapping, got {value!r}")
    unknown = sorted(set(value) - {"failures_allowed", "across_variants"})
    if unknown:
        raise ValueError(
            f"{where}: selection: unknown keys {unknown}; valid: "
            "['across_variants', 'failures_allowed']"
        )
    allowed = value.get("failures_allowed", 0)
    if isinstance(allowed, bool) or not isinstance(allowed, int):
        raise ValueError(
            f"{where}: selection.failures_allowed must be a whole number of episodes, "
            f"got {allowed!r}"
        )
    if not 0 <= allowed <= MAX_FAILURES_ALLOWED:
        raise ValueError(
            f"{where}: selection.failures_allowed must be 0-{MAX_FAILURES_ALLOWED} episodes, "
            f"got {allowed}"
        )
    across = value.get("across_variants", "pooled")
    if across not in ACROSS_VARIANTS:
        raise ValueError(
            f"{where}: selection.across_variants: unknown value {across!r}; "
            f"valid: {list(ACROSS_VARIANTS)}"
        )
    return SelectionRule(allowed, across)


def rule_of(metadata: Mapping[str, Any]) -> SelectionRule:
    """The rule a run was selected by, from its metadata's hyper-parameter section (the
    default for runs without a ``selection`` section)."""
    config = metadata.get("config") or {}
    section = config.get("selection") if isinstance(config, Mapping) else None
    if section is None:
        return DEFAULT_RULE
    return parse_selection(section, "agent metadata")
