"""The reinforcement-learning algorithms a saved agent may come from: one table for training
(`benchmarks.training`) and loading (`controllers.agent`).

An entry names the stable-baselines3 class and the constructor arguments a hyper-parameter file
may set. A saved agent's ``metadata.json`` records its entry's key under ``"algo"`` (no key:
"ppo", the agents saved before the key existed). Another algorithm is one more entry here: the
training harness then trains it and `controllers.make("agent", path=...)` loads what it saved.
Nothing here imports stable-baselines3 until `Algorithm.sb3_class` is called.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["ALGORITHMS", "DEFAULT_ALGORITHM", "Algorithm", "algorithm_of"]


@dataclass(frozen=True)
class Algorithm:
    """An SB3 algorithm: its class in `stable_baselines3` and the constructor arguments a
    hyper-parameter file may set (`schedules`: those that may be "lin_<x>" schedules;
    `off_policy`: checkpoints also hold the replay buffer)."""

    name: str
    class_name: str
    hyperparameters: frozenset[str]
    schedules: tuple[str, ...] = ()
    off_policy: bool = False

    def sb3_class(self) -> Any:
        """The SB3 class (imports stable_baselines3)."""
        import stable_baselines3

        return getattr(stable_baselines3, self.class_name)


ALGORITHMS: dict[str, Algorithm] = {
    "ppo": Algorithm(
        "ppo",
        "PPO",
        frozenset({
            "learning_rate", "n_steps", "batch_size", "n_epochs", "gamma", "gae_lambda",
            "clip_range", "clip_range_vf", "normalize_advantage", "ent_coef", "vf_coef",
            "max_grad_norm", "use_sde", "sde_sample_freq", "target_kl", "stats_window_size",
        }),
        schedules=("learning_rate", "clip_range"),
    ),
    "sac": Algorithm(
        "sac",
        "SAC",
        frozenset({
            "learning_rate", "buffer_size", "learning_starts", "batch_size", "tau", "gamma",
            "train_freq", "gradient_steps", "optimize_memory_usage", "ent_coef",
            "target_update_interval", "target_entropy", "use_sde", "sde_sample_freq",
            "use_sde_at_warmup", "stats_window_size", "n_steps",
        }),
        schedules=("learning_rate",),
        off_policy=True,
    ),
}  # fmt: skip
DEFAULT_ALGORITHM = "ppo"  # what an agent's metadata without an "algo" key was trained with


def algorithm_of(metadata: dict[str, Any], where: str) -> Algorithm:
    """The `ALGORITHMS` entry an agent's metadata names; ValueError naming ``where`` otherwise."""
    algo = metadata.get("algo", DEFAULT_ALGORITHM)
    if not isinstance(algo, str) or algo not in ALGORITHMS:
        raise ValueError(f"{where}: algo is {algo!r}, expected one of {sorted(ALGORITHMS)}")
    return ALGORITHMS[algo]
