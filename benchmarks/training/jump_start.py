"""A jump start: the actor (and the critic) pre-trained on a classical expert before PPO or SAC.

A ``jump_start`` entry in a hyper-parameter file's section (in a schedule: a phase of its own)
makes the run imitate instead of running its algorithm (PPO: `benchmarks.training.dagger` does
the work; SAC and TQC: `benchmarks.training.dagger_sac`)::

    jump_start:
      expert: fbsm_colos        # a classical controller (controllers.CLASSICAL), queried in
                                # every state the learner visits
      dataset: runs/demos/fbsm  # and/or demonstrations recorded by `auv-gym demos`
      method: dagger            # "bc" (behaviour cloning) or "dagger" (default with an expert)
      steps: 262144             # env steps the phase flies (expert, then learner episodes)
      iterations: 3             # DAgger rounds after the first
      expert_share: 0.5         # round i flies the expert's command with probability 0.5^i
      epochs: 10                # passes over the aggregated data per round
      batch_size: 1024
      learning_rate: 0.001      # Adam, for the jump start only (PPO's optimiser is untouched)
      value: true               # also fit the critic (PPO: to the data's λ-returns)

Round 0 is behaviour cloning on the dataset and on ``steps`` (DAgger: ``steps``/(iterations+1))
env steps flown by the expert; each DAgger round after it flies the learner (its sampled
actions, as PPO will start it, mixed with the expert's at the round's share), labels every
visited state with the expert's command (the expert flies alongside, its memory restarting with
each episode: `benchmarks.training.expert`), adds the states to the data and fits again. The
actor is fitted by least squares on its mean action (the label is the expert's command in the
agent's action space); its log-std stays at ``log_std_init``, which maximum likelihood would
shrink towards the expert's noiseless commands and so take PPO's exploration away. The critic is
fitted to the λ-returns (γ and λ of the section) of the normalised rewards, bootstrapped where an
episode was truncated. Observation and return statistics of `VecNormalize` are those of the
data. The run then holds an ordinary PPO agent: the next phase warm-starts from it
(`benchmarks.training.warm_start`).

SAC (and sb3-contrib's TQC, whose actor and update are SAC's) fly the same rounds; the actor's
deterministic action, tanh of its mean in the normalised action space, is fitted by least
squares, its ``log_std`` and the entropy coefficient left as built; the critic is warmed up by
SAC's own TD updates on the replay buffer with the actor frozen (``epochs`` passes in SAC's
``batch_size``; why not λ-returns: `benchmarks.training.dagger_sac`); every transition flown
(and the dataset's) fills the replay buffer, which the run writes beside its agents with the
expert's label of each (`benchmarks.training.transitions`) and the next phase starts with,
``learning_starts`` counting it (`benchmarks.training.warm_start`); a SAC phase with
``demo_regularization`` keeps its actor near the labels
(`benchmarks.training.demo_regularization`). CrossQ (batch-normalised critics, no target
networks) has no jump start.

Everything is checked with the rest of the file (`read_zoo_config`), before any training step:
a jump start without an expert or a dataset, unknown keys, an algorithm without a jump start,
a dataset that does not exist, is damaged, or was recorded for another observation or action
interface (`benchmarks.training.demonstrations.check_dataset`), an expert whose commands cannot
be put in the agent's action space. The ``imitation`` package (1.0.1) is not used: it pins
Gymnasium 0.29 and stable-baselines3 2.2, which this project has left behind.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Any

__all__ = [
    "JUMP_START_ALGORITHMS",
    "JUMP_START_KEY",
    "METHODS",
    "JumpStart",
    "check_jump_start",
    "parse_jump_start",
]

JUMP_START_KEY = "jump_start"
METHODS = ("bc", "dagger")
JUMP_START_ALGORITHMS = ("ppo", "sac", "tqc")  # the algorithms a jump start pre-trains (module doc)


@dataclass(frozen=True)
class JumpStart:
    """The settings of a jump start (module doc)."""

    expert: str | None = None
    dataset: str | None = None
    method: str = "dagger"
    steps: int = 0
    iterations: int = 3
    expert_share: float = 0.5
    epochs: int = 10
    batch_size: int = 1024
    learning_rate: float = 1e-3
    value: bool = True

    @property
    def rounds(self) -> int:
        """Rounds of fitting: the first, then DAgger's iterations."""
        return 1 + (self.iterations if self.method == "dagger" else 0)

    def round_steps(self, n_envs: int) -> list[int]:
        """Env steps flown in each round (whole vector steps of ``n_envs`` vehicles): none in
        round 0 of DAgger with a dataset (the dataset is its data), none without an expert."""
        if self.expert is None:
            return [0]
        flying = [
            not (k == 0 and self.dataset and self.method == "dagger") for k in range(self.rounds)
        ]
        share = self.steps // max(1, sum(flying))
        per = max(n_envs, share // n_envs * n_envs)
        return [per if fly else 0 for fly in flying]

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def parse_jump_start(value: Any, where: str) -> JumpStart:
    """A `JumpStart` from a file's ``jump_start`` mapping; one-line ValueError naming ``where``
    and the key for anything else."""
    fields = list(JumpStart.__dataclass_fields__)
    at = f"{where}: {JUMP_START_KEY}"
    if not isinstance(value, Mapping):
        raise ValueError(f"{at} must be a mapping of {fields}, got {value!r}")
    unknown = sorted(set(value) - set(fields))
    if unknown:
        raise ValueError(f"{at}: unknown keys {unknown}; valid: {fields}")
    expert, dataset = value.get("expert"), value.get("dataset")
    if expert is None and dataset is None:
        raise ValueError(
            f"{at}: needs an expert (a classical controller, e.g. expert: fbsm_colos) or a "
            "dataset (a folder written by auv-gym demos), got neither"
        )
    if expert is not None:
        from benchmarks.training.expert import check_expert_name

        check_expert_name(expert, at)
    if dataset is not None and (not isinstance(dataset, str) or not dataset):
        raise ValueError(f"{at}: dataset must be a folder path, got {dataset!r}")
    method = value.get("method", "dagger" if expert is not None else "bc")
    if method not in METHODS:
        raise ValueError(f"{at}: method must be one of {list(METHODS)}, got {method!r}")
    if method == "dagger" and expert is None:
        raise ValueError(
            f"{at}: method dagger asks an expert in the states the learner visits: name one "
            "(expert: ...), or use method: bc on the dataset"
        )
    if method == "bc" and ("iterations" in value or "expert_share" in value):
        raise ValueError(f"{at}: iterations and expert_share are DAgger's, not method bc's")
    settings = {
        "steps": _integer(value, "steps", 0, at),
        "iterations": _integer(value, "iterations", 1, at),
        "epochs": _integer(value, "epochs", 1, at),
        "batch_size": _integer(value, "batch_size", 2, at),
    }
    if expert is not None and settings["steps"] < 1 and not (dataset and method == "bc"):
        raise ValueError(
            f"{at}: steps (env steps the expert and the learner fly) must be >= 1 with an "
            f"expert, got {value.get('steps', 0)!r}"
        )
    if expert is None and "steps" in value:
        raise ValueError(f"{at}: steps are flown by an expert; without one the dataset is all")
    rate = value.get("learning_rate", JumpStart.learning_rate)
    if not _number(rate) or not rate > 0:
        raise ValueError(f"{at}: learning_rate must be a finite number > 0, got {rate!r}")
    share = value.get("expert_share", JumpStart.expert_share)
    if not _number(share) or not 0.0 <= share <= 1.0:
        raise ValueError(f"{at}: expert_share must be a number in [0, 1], got {share!r}")
    fit_value = value.get("value", True)
    if not isinstance(fit_value, bool):
        raise ValueError(f"{at}: value must be true or false, got {fit_value!r}")
    return JumpStart(
        expert=expert,
        dataset=dataset,
        method=method,
        learning_rate=float(rate),
        expert_share=float(share),
        value=fit_value,
        **settings,
    )


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _integer(value: Mapping[str, Any], key: str, smallest: int, at: str) -> int:
    got = value.get(key, getattr(JumpStart, key))
    if isinstance(got, float) and got.is_integer():
        got = int(got)
    if isinstance(got, bool) or not isinstance(got, int) or got < smallest:
        raise ValueError(f"{at}: {key} must be an integer >= {smallest}, got {value.get(key)!r}")
    return got


def check_jump_start(cfg: Any, env_id: str, where: str) -> None:
    """The jump start of a checked config (`benchmarks.training.config.ZooConfig`) fits its
    agent: PPO, SAC or TQC (its replay buffer laid out by rows: no optimize_memory_usage), not
    residual; the expert's commands can be put in the agent's action space
    (`ExpertLabels`); the dataset is intact and recorded for this observation and action
    interface. One-line ValueError naming ``where`` (and the dataset file)."""
    jump = cfg.jump_start
    if jump is None:
        return
    at = f"{where}: {JUMP_START_KEY}"
    if cfg.algo not in JUMP_START_ALGORITHMS:
        raise ValueError(
            f"{at}: a jump start pre-trains the actor and critic of "
            f"{'/'.join(JUMP_START_ALGORITHMS)}, not {cfg.algo}"
        )
    if cfg.algo != "ppo" and cfg.algo_kwargs.get("optimize_memory_usage"):
        raise ValueError(
            f"{at}: the jump start's transitions fill a replay buffer with next observations "
            "of their own: set optimize_memory_usage false"
        )
    if cfg.residual is not None:
        raise ValueError(f"{at}: a residual agent starts as its base already (no jump start)")
    share = getattr(cfg, "vehicle_share", None)
    if share is not None:
        raise ValueError(
            f"{at}: the jump start flies the section's own {share.argument} only, not the "
            f"vehicles of its {share.key}: give the share in a phase after the jump start"
        )
    from benchmarks.training.demonstrations import DemoSource, check_dataset

    source = DemoSource(env_id, dict(cfg.env_kwargs), tuple(cfg.stages), cfg.action_bounds)
    if jump.expert is not None:
        from benchmarks.training.expert import ExpertLabels

        ExpertLabels(
            jump.expert, source.full_kwargs, source.obs_names, cfg.stages, cfg.action_bounds, at
        )
    if jump.dataset is not None:
        check_dataset(jump.dataset, source.obs_names, source.interface, f"{at}: dataset")
