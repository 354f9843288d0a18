"""One way to print a result in a table: units, significant figures, and failures.

Every markdown table the project writes (the paper figures' `metrics.md`, a benchmark run's
`summary.md`, the suite's tables) goes through this module, so a reader learns one convention:

- Numbers carry ``SIGNIFICANT_FIGURES`` significant figures, positional from 0.001 to 10⁶
  (``0.0173``, ``988``) and scientific outside (``5.63e-06``), never float noise
  (``0.01728 ± 3.5e-18``). A spread is printed to the same decimal place as its mean
  (``988 ± 110``, ``0.0173 ± 0``).
- Units live in the header. A row or column in metres whose largest value is below 1 cm is
  shown in millimetres (``0.42 mm`` instead of ``0.000``), and the same for m/s.
- A failed episode (an end in `auv_gym.sim.trajectory.FAILURE_REASONS`) contributes no metric: the
  metric is over the episodes that ran to the end, the failures are counted beside it, a cell
  with no finished episode is "—", and a policy with a failed episode is never marked best.
  A mean over fewer than all the episodes of a cell shows its sample size: ``0.300 (n = 1/3)``.
  `inf` is never printed as a number; a settling threshold never reached is "never" ("never in
  3/10" when 3 of 10 episodes never reached it: their mean is unbounded).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

__all__ = [
    "EMPTY",
    "FAILURE_CONVENTION",
    "METRIC_INFO",
    "NEVER_METRICS",
    "SIGNIFICANT_FIGURES",
    "Cell",
    "display_scale",
    "format_mean_std",
    "format_number",
    "mark_best",
    "markdown_table",
]

SIGNIFICANT_FIGURES = 3
EMPTY = "—"  # no value: every episode failed, or the metric is undefined

FAILURE_CONVENTION = (
    "Metrics are over the episodes that ran to the end; failed episodes (an early end: corridor, "
    "envelope, overspeed, non-finite state, broached, grounded) are counted in the *failed* "
    "column and excluded, "
    f"“{EMPTY}” marks a cell with no finished episode, “(n = 1/3)” a mean over 1 of its 3 "
    "episodes, and a policy with a failed episode is never marked best (**bold**). “never”: the "
    "threshold was not reached (“never in 3/10”: in 3 of 10 episodes)."
)

# name → (label, unit, better: "min" / "max" / "" for no ranking).
METRIC_INFO: dict[str, tuple[str, str, str]] = {
    "rms_distance": ("RMS distance, t ≥ transient", "m", "min"),
    "rms_x_e": ("RMS x_e, t ≥ transient", "m", "min"),
    "rms_y_e": ("RMS y_e, t ≥ transient", "m", "min"),
    "rms_z_e": ("RMS z_e, t ≥ transient", "m", "min"),
    "max_distance_window": ("max distance, t ≥ transient", "m", "min"),
    "iae_distance": ("IAE distance (whole episode)", "m·s", "min"),
    "settling_time_0p5": ("settling time to 0.5 m", "s", "min"),
    "settling_time_0p1": ("settling time to 0.1 m", "s", "min"),
    "surge_overshoot": ("surge overshoot max(u − u_D)", "m/s", "min"),
    "rms_speed_error": ("RMS(u − u_D), t ≥ transient", "m/s", "min"),
    # not ranked: the pace is a condition of the comparison (u_D asked), not a score
    "mean_path_speed": ("pace: mean virtual-point speed u_p, t ≥ transient", "m/s", ""),
    "max_surge": ("max surge u", "m/s", "min"),
    # above the vehicle's own top speed (`AUVParams.max_surge`: REMUS 100 2.0, torpedo 2.5)
    "overspeed_fraction": ("time with u > max_surge (the vehicle's top speed)", "-", "min"),
    "control_effort": ("control effort ∫Σ(τ/τ_max)² dt", "s", "min"),
    "chattering": ("chattering TV(τ/τ_max) per s", "1/s", "min"),
    "saturation_fraction": ("saturated control steps", "-", "min"),
    "episode_cost": ("episode safety cost Σc (auv_gym.sim.safety_cost)", "-", "min"),
    "fin_rate_saturation": ("time a fin moves at its rate limit", "-", "min"),
    "mean_shaft_power": ("mean propeller shaft power, t ≥ transient", "W", "min"),
    "energy_per_km": ("shaft energy per km travelled, t ≥ transient", "kJ/km", "min"),
    "final_distance": ("final distance", "m", "min"),
    "success": ("success", "-", "max"),
    "termination_reason": ("episode end", "-", ""),
}

# Metrics whose +inf means "the threshold was never reached" rather than "undefined" (an episode
# record stores it as null: `benchmarks.reports.tables.aggregate` reads it back as +inf).
NEVER_METRICS = frozenset({"settling_time_0p5", "settling_time_0p1"})
_SMALLER_UNITS = {"m": ("mm", 1e3), "m/s": ("mm/s", 1e3)}
_SMALL = 0.01  # below 1 cm (1 cm/s), metres print as millimetres


def _decimals(value: float, significant: int) -> int:
    """Decimal places that give ``significant`` figures for ``value`` (≥ 0)."""
    if value == 0 or not math.isfinite(value):
        return 0
    return max(significant - 1 - math.floor(math.log10(abs(value))), 0)


def format_number(value: object, significant: int = SIGNIFICANT_FIGURES, metric: str = "") -> str:
    """``value`` with ``significant`` figures in positional notation; "—" for None/NaN/-inf.

    +inf prints "never" for the settling times (`METRIC_INFO`) and "—" for anything else.
    Booleans print "yes"/"no", strings as they are.
    """
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, str):
        return value or EMPTY
    if value is None:
        return EMPTY
    x = float(value)  # type: ignore[arg-type]
    if math.isnan(x) or x == -math.inf:
        return EMPTY
    if x == math.inf:
        return "never" if metric in NEVER_METRICS else EMPTY
    if x == 0:
        return "0"
    # Round to the significant figures first: 9.996 with 3 figures is "10.0", not "10.00".
    rounded = float(f"{x:.{significant - 1}e}")
    if not 1e-3 <= abs(rounded) < 1e6:
        return f"{rounded:.{significant - 1}e}"
    return f"{rounded:.{_decimals(rounded, significant)}f}"


def format_mean_std(
    mean: float, std: float, significant: int = SIGNIFICANT_FIGURES, metric: str = ""
) -> str:
    """ "mean ± std", the spread to the mean's last decimal place ("988 ± 110", "0.0173 ± 0")."""
    text = format_number(mean, significant, metric)
    if not (math.isfinite(mean) and math.isfinite(std)):
        return text
    if "e" in text:  # a mean in scientific notation: its spread too ("6.77e-04 ± 6.8e-05"),
        # zero below the mean's last significant digit, as in positional notation
        last_digit = 10.0 ** (math.floor(math.log10(abs(mean))) - (significant - 1))
        return f"{text} ± {format_number(std, 2)}" if std >= 0.5 * last_digit else f"{text} ± 0"
    decimals = _decimals(float(f"{mean:.{significant - 1}e}"), significant) if mean else 0
    spread = round(std, decimals)
    if spread == 0:
        return f"{text} ± 0"
    if decimals == 0 and abs(spread) >= 10**significant:
        return f"{text} ± {format_number(spread, 2)}"
    return f"{text} ± {spread:.{decimals}f}"


def display_scale(unit: str, values: Iterable[float]) -> tuple[str, float]:
    """(unit shown, factor): metres below 1 cm become millimetres; anything else stays."""
    finite = [abs(float(v)) for v in values if v is not None and math.isfinite(float(v))]
    if unit in _SMALLER_UNITS and finite and 0 < max(finite) < _SMALL:
        return _SMALLER_UNITS[unit]
    return unit, 1.0


@dataclass(frozen=True)
class Cell:
    """One policy's values of one metric in one setting, with its failed-episode count.

    ``values`` are the metric of the episodes that ran to the end (non-finite entries are
    kept: a settling time of +inf is "never", NaN is undefined and left out of the mean);
    ``failed`` of ``episodes`` ended early.
    """

    values: tuple[float, ...]
    failed: int = 0

    @property
    def episodes(self) -> int:
        return len(self.values) + self.failed

    @property
    def counted(self) -> int:
        """How many episodes the mean is over: the finished ones with a defined value."""
        return int(np.count_nonzero(~np.isnan(np.asarray(self.values, dtype=float))))

    def sample_size(self) -> str:
        """ "n = k/N" when the mean is over k of the cell's N episodes (some failed, or their
        metric is undefined); "" when it is over all of them or over none."""
        counted = self.counted
        return f"n = {counted}/{self.episodes}" if 0 < counted < self.episodes else ""

    def mean(self) -> float:
        """Mean over finished episodes; +inf when any is +inf (never settled); NaN if none."""
        data = np.asarray(self.values, dtype=float)
        data = data[~np.isnan(data)]
        if data.size == 0:
            return math.nan
        if np.isposinf(data).any():
            return math.inf
        return float(data.mean())

    def text(self, metric: str = "", scale: float = 1.0) -> str:
        """ "mean ± std" or "—", with "(n = k/N)" after it when the mean is over fewer than
        all the episodes; for a settling time not reached in j of the N episodes, "never in
        j/N" ("never" when j = N)."""
        data = np.asarray(self.values, dtype=float)
        data = data[~np.isnan(data)]
        if data.size == 0:
            return EMPTY
        mean = self.mean()
        if mean == math.inf and metric in NEVER_METRICS:  # how many never reached it
            never = int(np.count_nonzero(np.isposinf(data)))
            return "never" if never == self.episodes else f"never in {never}/{self.episodes}"
        if not math.isfinite(mean) or data.size == 1:
            text = format_number(mean * scale, metric=metric)
        else:
            text = format_mean_std(mean * scale, float(data.std()) * scale, metric=metric)
        size = self.sample_size()
        return f"{text} ({size})" if size else text


def mark_best(
    texts: Sequence[str], scores: Sequence[float], eligible: Sequence[bool], better: str
) -> list[str]:
    """Bold the best score among eligible entries (ties all bold).

    NaN scores take no part; +inf ranks last for "min" (a threshold never reached). Nothing is
    bold when fewer than two entries have a score, when the best is not finite, or when every
    entry ties.
    """
    if better not in ("min", "max"):
        return list(texts)
    compared = [s for s in scores if not math.isnan(s)]
    candidates = [s for s, e in zip(scores, eligible, strict=True) if e and not math.isnan(s)]
    if len(compared) < 2 or not candidates:
        return list(texts)
    best = min(candidates) if better == "min" else max(candidates)
    if not math.isfinite(best) or compared.count(best) == len(compared):
        return list(texts)
    return [
        f"**{t}**" if e and s == best else t
        for t, s, e in zip(texts, scores, eligible, strict=True)
    ]


def markdown_table(
    header: Sequence[str], rows: Sequence[Sequence[str]], align: Sequence[str] | None = None
) -> str:
    """A GitHub markdown table; ``align`` per column: "l" (default for the first) or "r"."""
    if any(len(r) != len(header) for r in rows):
        raise ValueError(f"every row needs {len(header)} cells, got {[len(r) for r in rows]}")
    align = align or ["l", *["r"] * (len(header) - 1)]
    rule = ["---:" if a == "r" else "---" for a in align]
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join(rule) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines) + "\n"
