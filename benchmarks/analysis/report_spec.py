"""What the statistics of a suite evaluation compare, as data: references, the target ratio,
(policy, base) pairs and figure panels (`ReportSpec`), read from a TOML report table
(`DEFAULT_REPORT`: the shipped results' ``benchmarks/report.toml``). The statistics modules
(`benchmarks.analysis.suite_stats`, `benchmarks.analysis.smoothness_stats`) name no policy
themselves.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from auv_gym.support.files import read_toml

__all__ = ["DEFAULT_REPORT", "ReportSpec"]

DEFAULT_REPORT = Path(__file__).resolve().parents[1] / "report.toml"
_KEYS = {
    "": {"reference", "extra_references", "target", "smoothness"},
    "target": {"max_ratio", "references"},
    "smoothness": {"reference", "worse_ratio", "pairs", "tradeoff_scopes"},
}


@dataclass(frozen=True)
class ReportSpec:
    """A report table (module doc); every field as in ``benchmarks/report.toml``."""

    reference: str  # probability of improvement and the target ratio refer to it
    extra_references: tuple[str, ...] = ()  # probability of improvement also against these
    max_ratio: float = 2.0  # target: mean score at most this × the reference's
    # target: each set's reference is the best (lowest mean) of these; () → `reference`
    target_references: tuple[str, ...] = ()
    smoothness_reference: str = "fbsm"  # chattering ratios refer to it
    worse_ratio: float = 0.10  # a pair is "worse" above this relative difference
    pairs: tuple[tuple[str, str], ...] = ()  # (policy, base) paired differences
    tradeoff_scopes: tuple[str, ...] = ()  # panels of the accuracy-against-smoothness figure

    @classmethod
    def read(cls, path: str | os.PathLike = DEFAULT_REPORT) -> ReportSpec:
        """The report table of a TOML file; ValueError naming the file and the problem."""
        data = read_toml(path, "report table")
        try:
            return cls.from_dict(data)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"report table {path}: {exc}") from None

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ReportSpec:
        """From the TOML layout (module doc); ValueError naming the key."""
        target, smooth = data.get("target", {}), data.get("smoothness", {})
        for section, table in (("", data), ("target", target), ("smoothness", smooth)):
            if not isinstance(table, Mapping):
                raise ValueError(f"[{section}] must be a table, got {table!r}")
            unknown = sorted(set(table) - _KEYS[section])
            if unknown:
                where = f"[{section}] " if section else ""
                raise ValueError(f"{where}unknown keys {unknown}; valid: {sorted(_KEYS[section])}")
        reference = _name("reference", data.get("reference"))
        pairs = smooth.get("pairs", [])
        if not isinstance(pairs, list) or not all(
            isinstance(p, list) and len(p) == 2 for p in pairs
        ):
            raise ValueError(f"smoothness.pairs must be a list of [policy, base], got {pairs!r}")
        return cls(
            reference=reference,
            extra_references=_names("extra_references", data.get("extra_references", [])),
            max_ratio=_positive("target.max_ratio", target.get("max_ratio", 2.0)),
            target_references=_names("target.references", target.get("references", [])),
            smoothness_reference=_name("smoothness.reference", smooth.get("reference", reference)),
            worse_ratio=_positive("smoothness.worse_ratio", smooth.get("worse_ratio", 0.10)),
            pairs=tuple((_name("pair policy", p), _name("pair base", b)) for p, b in pairs),
            tradeoff_scopes=_names("smoothness.tradeoff_scopes", smooth.get("tradeoff_scopes", [])),
        )

    def with_reference(self, reference: str | None) -> ReportSpec:
        """This table with another reference (None: unchanged), the target's too; the
        smoothness reference stays."""
        if reference is None:
            return self
        return replace(self, reference=reference, target_references=())


def _name(key: str, value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise ValueError(f"{key} must be a policy name, got {value!r}")
    return value


def _names(key: str, value: Any) -> tuple[str, ...]:
    if not isinstance(value, list):
        raise ValueError(f"{key} must be a list of names, got {value!r}")
    return tuple(_name(key, v) for v in value)


def _positive(key: str, value: Any) -> float:
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not (math.isfinite(value) and value > 0)
    ):
        raise ValueError(f"{key} must be a positive number, got {value!r}")
    return float(value)
