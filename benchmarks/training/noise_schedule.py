"""Annealing a PPO agent's exploration noise late in training (``action_std_schedule``).

PPO's Gaussian policy learns its standard deviation; with no entropy bonus the shipped 256-256
generalist still explores with σ = 0.21–0.26 (normalised commands) after 5M steps, and it
learns the mean action that is best under that much noise of its own. Starting with less noise
fails (`log_std_init` −2: most episodes still fail at 2.5M steps, docs/results.md), because
exploration is what the first millions of steps need. The schedule leaves the first part of
training alone and then caps σ geometrically, from the initial σ₀ = exp(log_std_init) at the
fraction `start` of the run to `final` at its end:

    σ ≤ σ₀·(final/σ₀)^((p − start)/(1 − start)),   p = steps done / steps planned ≥ start

applied to the policy's log σ before every rollout (the update may raise it again; the next
rollout caps it). The cap depends on the step count only, so a resumed run continues exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from stable_baselines3.common.callbacks import BaseCallback

__all__ = ["AnnealActionStd", "StdSchedule", "parse_std_schedule"]


@dataclass(frozen=True)
class StdSchedule:
    """Where annealing starts (fraction of the run, [0, 1)) and the final σ (normalised)."""

    start: float
    final: float

    def cap(self, progress: float, initial: float) -> float:
        """The largest σ allowed at ``progress`` ∈ [0, 1] of the run (inf before `start`)."""
        if progress < self.start:
            return math.inf
        fraction = min((progress - self.start) / (1.0 - self.start), 1.0)
        return initial * (self.final / initial) ** fraction


def parse_std_schedule(value: Any, where: str) -> StdSchedule:
    """``{start: 0 ≤ s < 1, final: 0 < σ ≤ 1}`` from a hyper-parameter file, or a named error."""
    ok = isinstance(value, dict) and set(value) == {"start", "final"}
    if ok:
        start, final = value["start"], value["final"]
        real = [isinstance(v, (int, float)) and not isinstance(v, bool) for v in (start, final)]
        ok = all(real) and 0.0 <= start < 1.0 and 0.0 < final <= 1.0
    if not ok:
        raise ValueError(
            f"{where}: action_std_schedule must be {{start: s in [0, 1), final: σ in "
            f"(0, 1]}}, got {value!r}"
        )
    return StdSchedule(float(value["start"]), float(value["final"]))


class AnnealActionStd(BaseCallback):
    """Caps the policy's σ before each rollout by `StdSchedule.cap` of the run's progress."""

    def __init__(self, schedule: StdSchedule, total_timesteps: int, initial_std: float) -> None:
        super().__init__()
        self.schedule, self.total, self.initial = schedule, total_timesteps, initial_std

    def _on_training_start(self) -> None:
        if not hasattr(self.model.policy, "log_std") or getattr(self.model, "use_sde", False):
            raise ValueError(
                "action_std_schedule needs a Gaussian policy with a learned log σ "
                "(PPO or A2C without gSDE)"
            )

    def _on_rollout_start(self) -> None:
        import torch

        cap = self.schedule.cap(self.num_timesteps / self.total, self.initial)
        if math.isfinite(cap):
            with torch.no_grad():
                self.model.policy.log_std.clamp_(max=math.log(cap))

    def _on_step(self) -> bool:
        return True
