"""SAC fine-tuning that keeps a jump start: a behaviour-cloning term on the expert's labels.

SAC's actor update follows the critic's action gradient alone; started from a jump-started
actor (`benchmarks.training.dagger_sac`), it pushes the actions out of the data the critic was
fitted on, where the critic is unreliable, and the policy that flew is lost within a few
thousand updates. The remedies of RL from demonstrations keep the actor near the data while the
critic catches up; a ``demo_regularization`` mapping in a SAC hyper-parameter section turns
them on for the run's SAC updates (`benchmarks.training.demo_sac.DemoSAC`, SB3's ``SAC.train``
with the additions below)::

    demo_regularization:
      bc_weight: 0.4          # β ≥ 0 (dimensionless): weight of the behaviour-cloning term
      bc_decay_steps: 0       # env steps of the run over which β falls linearly to 0 (0: never)
      bc_batch_size: 256      # demonstration states per gradient step (default: batch_size)
      actor_delay: 0          # env steps of the run with the actor and entropy coefficient frozen
      demo_share: 0.0         # share in [0, 1) of each critic batch drawn from the demonstrations

- **Behaviour cloning** (TD3+BC, Fujimoto & Gu 2021): the actor loss becomes

      (α log π(a|s) − min Q(s, a))  +  β · mean|Q| · mean ||tanh(μ(s_d)) − a_d||²

  over SAC's batch s (a ~ π) and ``bc_batch_size`` demonstration states s_d, with a_d the
  expert's label there in the agent's normalised action space [−1, 1]³ (the squared error is
  averaged over the action entries, as the jump start's imitation loss), tanh μ SAC's
  deterministic action, and mean|Q| the batch's mean |min Q(s, a)|, detached. This is TD3+BC's
  λ·(α log π − Q)/mean|Q| + BC with λ = 1/β, multiplied by mean|Q|/λ, which Adam's step does not
  see (it divides by the gradients' running scale): TD3+BC's α = 2.5 is β = 0.4; β = 0 is SAC's
  update bit for bit. With ``bc_decay_steps`` the weight is β·max(0, 1 − t/bc_decay_steps) at the
  run's env step t: the actor is held at the expert while the critic learns the online data, then
  released to improve on it.
- **Actor delay**: for the run's first ``actor_delay`` env steps the actor and the entropy
  coefficient take no step; the critic learns SAC's TD targets of the online data from the
  jump-started policy.
- **Symmetric sampling** (RLPD, Ball et al. 2023): a share ``demo_share`` of every batch (critic
  and actor) comes from the demonstration transitions (n-step returns as SAC's buffer computes
  them), the rest from the replay buffer, which holds them too (`benchmarks.training.warm_start`):
  with 0.5, RLPD's 50/50 whatever the buffer's size. RLPD's LayerNorm critic is not built.

The demonstrations are the labelled transitions of an off-policy jump start
(`benchmarks.training.transitions`: the states DAgger visited with the expert's command in
each): the run's initial agent must carry them (``init_from``, or a schedule's phase after a
jump start). The run copies the file into its folder, where a resumed run reads them and a
schedule's next phase finds them beside the selected agent (its replay buffer starts with them,
and its own ``demo_regularization``, inherited or not, has them). A jump-start phase ignores the
key (its actor is fitted, not trained by SAC). The saved agent is a plain SAC zip (the
demonstrations are not in it): ``controllers.make("agent", path=...)`` loads it as any SAC agent.

Measured on one seed (sac_helix.yml's SAC keys with 16 envs on the generalist's task
distribution, a 131 072-step DAgger jump start at 0.228 m RMS distance and no termination on 16
validation episodes of ``validation_paper_start``): plain SAC and symmetric sampling alone lose
the jump start within 25 000 SAC steps (16 of 16 episodes terminate); β = 0.4 keeps it (0.18 to
0.23 m, 1 to 3 terminated, single episodes drifting metres off between 100 000 and 175 000
steps), and with a 25 000-step actor delay improves it steadily to 0.177 m at 200 000 steps
(1 terminated); a β decaying to 0 loses it again as β nears 0. The BC term costs about 10 %
of SAC's env steps per second.

Every value is checked with the rest of the file (`read_zoo_config`): a one-line ValueError
naming the file and the key; the initial agents' labels before any worker starts
(`check_demonstrations`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "DEMO_ALGORITHMS",
    "DEMO_KEY",
    "DemoRegularization",
    "check_demonstrations",
    "parse_demo_regularization",
    "read_demonstrations",
]

DEMO_KEY = "demo_regularization"
DEMO_ALGORITHMS = ("sac",)  # whose `train` `benchmarks.training.demo_sac.DemoSAC` extends


@dataclass(frozen=True)
class DemoRegularization:
    """The settings of ``demo_regularization`` (module doc); ``bc_batch_size`` None: SAC's."""

    bc_weight: float = 0.4
    bc_decay_steps: int = 0
    bc_batch_size: int | None = None
    actor_delay: int = 0
    demo_share: float = 0.0

    def weight(self, timesteps: int) -> float:
        """β at the run's env step ``timesteps`` (the linear decay, when there is one)."""
        if self.bc_decay_steps <= 0:
            return self.bc_weight
        return self.bc_weight * max(0.0, 1.0 - timesteps / self.bc_decay_steps)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def parse_demo_regularization(value: Any, algo: str, where: str) -> DemoRegularization:
    """`DemoRegularization` from a section's mapping; one-line ValueError naming ``where`` (the
    file and env id) and the key for anything else."""
    fields = list(DemoRegularization.__dataclass_fields__)
    at = f"{where}: {DEMO_KEY}"
    if algo not in DEMO_ALGORITHMS:
        raise ValueError(
            f"{at}: adds a behaviour-cloning term to SAC's update ({'/'.join(DEMO_ALGORITHMS)}), "
            f"not {algo}'s"
        )
    if not isinstance(value, Mapping):
        raise ValueError(f"{at} must be a mapping of {fields}, got {value!r:.80}")
    unknown = sorted(set(value) - set(fields))
    if unknown:
        raise ValueError(f"{at}: unknown keys {unknown}; valid: {fields}")
    weight = value.get("bc_weight", DemoRegularization.bc_weight)
    if not _number(weight) or weight < 0:
        raise ValueError(f"{at}: bc_weight must be a finite number >= 0, got {weight!r}")
    share = value.get("demo_share", DemoRegularization.demo_share)
    if not _number(share) or not 0.0 <= share < 1.0:
        raise ValueError(f"{at}: demo_share must be a number in [0, 1), got {share!r}")
    batch = value.get("bc_batch_size")
    if batch is not None:
        batch = _integer(value, "bc_batch_size", 1, at)
    return DemoRegularization(
        bc_weight=float(weight),
        bc_decay_steps=_integer(value, "bc_decay_steps", 0, at),
        bc_batch_size=batch,
        actor_delay=_integer(value, "actor_delay", 0, at),
        demo_share=float(share),
    )


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _integer(value: Mapping[str, Any], key: str, smallest: int, at: str) -> int:
    got = value.get(key, getattr(DemoRegularization, key))
    if isinstance(got, float) and got.is_integer():
        got = int(got)
    if isinstance(got, bool) or not isinstance(got, int) or got < smallest:
        raise ValueError(f"{at}: {key} must be an integer >= {smallest}, got {value.get(key)!r}")
    return got


def check_demonstrations(
    cfg: Any, agents: Sequence[str | Path], obs_names: Sequence[str], action_dim: int, where: str
) -> None:
    """A run of ``cfg`` with ``demo_regularization`` (and no jump start) starts from agents that
    carry labelled transitions (module doc): ValueError naming ``where`` (the config), the key
    and the agent otherwise. Nothing for other runs."""
    if getattr(cfg, "demo_regularization", None) is None or cfg.jump_start is not None:
        return
    if not agents:
        raise ValueError(
            f"{where}: {DEMO_KEY} needs the expert's labelled transitions of an off-policy jump "
            "start: start from its agent (init_from, or a schedule phase after a jump start)"
        )
    for agent in agents:
        read_demonstrations(Path(agent), obs_names, action_dim, where)


def read_demonstrations(
    folder: Path, obs_names: Sequence[str], action_dim: int, where: str
) -> dict[str, np.ndarray]:
    """The labelled transitions beside an agent (or in a run folder): the stream of its
    `TRANSITIONS_FILE` with ``labels``; ValueError naming ``where``, the key and the folder
    when they are missing."""
    from benchmarks.training.transitions import LABELS, TRANSITIONS_FILE, read_transitions

    path = Path(folder) / TRANSITIONS_FILE
    at = f"{where}: {DEMO_KEY}"
    if not path.is_file():
        raise ValueError(
            f"{at}: {str(folder)!r} holds no {TRANSITIONS_FILE} (the labelled transitions of an "
            "off-policy jump start)"
        )
    stream = read_transitions(path, obs_names, action_dim, f"{at}: init_from")
    if LABELS not in stream:
        raise ValueError(
            f"{at}: {path} has no expert labels (written before the jump start recorded them): "
            "run the jump start again"
        )
    if len(stream[LABELS]) == 0:
        raise ValueError(f"{at}: {path} holds no transitions")
    return stream
