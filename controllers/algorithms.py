"""The reinforcement-learning algorithms a saved agent may come from: one table for training
(`benchmarks.training`) and loading (`controllers.agent`).

An entry names the stable-baselines3 class (or sb3-contrib's: TQC, CrossQ) and the constructor
arguments a hyper-parameter file may set. A saved agent's ``metadata.json`` records its entry's
key under ``"algo"`` (no key: "ppo", the agents saved before the key existed). Another algorithm
is one more entry here: the training harness then trains it and `controllers.make("agent",
path=...)` loads what it saved.
Nothing here imports stable-baselines3 or sb3-contrib until `Algorithm.sb3_class` is called.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["ALGORITHMS", "DEFAULT_ALGORITHM", "Algorithm", "algorithm_of"]


@dataclass(frozen=True)
class Algorithm:
    """An SB3 algorithm: its class in `package` (`stable_baselines3` or `sb3_contrib`) and the
    constructor arguments a hyper-parameter file may set (`schedules`: those that may be
    "lin_<x>" schedules; `off_policy`: checkpoints also hold the replay buffer, and
    ``ent_coef`` may be "auto")."""

    name: str
    class_name: str
    hyperparameters: frozenset[str]
    schedules: tuple[str, ...] = ()
    off_policy: bool = False
    package: str = "stable_baselines3"

    def sb3_class(self) -> Any:
        """The SB3 class (imports its package; ImportError naming the extra when missing)."""
        import importlib

        try:
            module = importlib.import_module(self.package)
        except ImportError as exc:
            raise ImportError(
                f"{self.class_name} needs the {self.package} package (pip install "
                f"-e '.[rl]'): {exc}"
            ) from exc
        return getattr(module, self.class_name)


# What SAC and its sb3-contrib relatives share (TQC adds quantile truncation; CrossQ has no target
# networks, so no tau or target_update_interval, and delays its actor updates).
_ENTROPY_OFF_POLICY = frozenset(
    {
        "learning_rate",
        "buffer_size",
        "learning_starts",
        "batch_size",
        "gamma",
        "train_freq",
        "gradient_steps",
        "optimize_memory_usage",
        "ent_coef",
        "target_entropy",
        "use_sde",
        "sde_sample_freq",
        "use_sde_at_warmup",
        "stats_window_size",
        "n_steps",
    }
)


ALGORITHMS: dict[str, Algorithm] = {
    "ppo": Algorithm(
        "ppo",
        "PPO",
        frozenset(
            {
                "learning_rate",
                "n_steps",
                "batch_size",
                "n_epochs",
                "gamma",
                "gae_lambda",
                "clip_range",
                "clip_range_vf",
                "normalize_advantage",
                "ent_coef",
                "vf_coef",
                "max_grad_norm",
                "use_sde",
                "sde_sample_freq",
                "target_kl",
                "stats_window_size",
            }
        ),
        schedules=("learning_rate", "clip_range"),
    ),
    "sac": Algorithm(
        "sac",
        "SAC",
        _ENTROPY_OFF_POLICY | {"tau", "target_update_interval"},
        schedules=("learning_rate",),
        off_policy=True,
    ),
    "tqc": Algorithm(
        "tqc",
        "TQC",
        _ENTROPY_OFF_POLICY | {"tau", "target_update_interval", "top_quantiles_to_drop_per_net"},
        schedules=("learning_rate",),
        off_policy=True,
        package="sb3_contrib",
    ),
    "crossq": Algorithm(
        "crossq",
        "CrossQ",
        _ENTROPY_OFF_POLICY | {"policy_delay"},
        schedules=("learning_rate",),
        off_policy=True,
        package="sb3_contrib",
    ),
}
DEFAULT_ALGORITHM = "ppo"  # what an agent's metadata without an "algo" key was trained with


def algorithm_of(metadata: dict[str, Any], where: str) -> Algorithm:
    """The `ALGORITHMS` entry an agent's metadata names; ValueError naming ``where`` otherwise."""
    algo = metadata.get("algo", DEFAULT_ALGORITHM)
    if not isinstance(algo, str) or algo not in ALGORITHMS:
        raise ValueError(f"{where}: algo is {algo!r}, expected one of {sorted(ALGORITHMS)}")
    return ALGORITHMS[algo]
