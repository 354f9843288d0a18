"""The options of multi-seed training (`SeedsOptions`) and its seed list: the command line
`auv-gym train-seeds` is generated from these fields and `TrainOptions`' (`benchmarks.options`)."""

from __future__ import annotations

from dataclasses import dataclass

from benchmarks.options import option
from benchmarks.training.train import TrainOptions

__all__ = [
    "DEFAULT_EVAL_EPISODES",
    "MAX_SEED",
    "MAX_SEEDS",
    "TASK_SETS",
    "SeedsOptions",
    "parse_seeds",
]

# Validation episodes (model selection): "paper", the paper scenario (helix, white noise ±35 N /
# N·m) on `EVAL_SEEDS`, or any set of role "validation" in benchmarks/tasks.toml (its env arguments
# on its first `eval_episodes` seeds, or on the given eval seeds, which must lie in its range). The
# per-seed test report is the paper scenario on `HELD_OUT_SEEDS` either way; the whole test suite is
# `benchmarks.runner.evaluate_suite`. The training distribution is the config's env_kwargs.
TASK_SETS = {"paper": "paper scenario: validation seeds 100-104, test seeds 0-9"}
DEFAULT_EVAL_EPISODES = 32  # validation episodes drawn from a task set
MAX_SEEDS = 1000  # training runs of one command
MAX_SEED = 2**32 - 1  # np.random.seed (SB3's set_random_seed) takes seeds below 2**32


def parse_seeds(text: str) -> tuple[int, ...]:
    """ "N" (N ≥ 1 seeds 0…N−1, as `benchmarks.runner.compare --seeds`), "a-b" (inclusive) or
    "a,b,c"; at most `MAX_SEEDS` seeds, each at most `MAX_SEED` (the count is checked before the
    seeds are listed: a typo like 1e9 costs no memory)."""
    text = str(text).strip()
    try:
        if "," in text:
            seeds = tuple(int(s) for s in text.split(",") if s.strip())
        elif "-" in text[1:]:
            low, high = (int(s) for s in text.split("-", 1))
            if high < low:
                raise ValueError(f"range {text!r} is empty (high {high} < low {low})")
            _check_count(high - low + 1, text)
            seeds = tuple(range(low, high + 1))
        else:
            count = int(text)
            if count < 1:
                raise ValueError(f"a seed count must be at least 1, got {count}")
            _check_count(count, text)
            seeds = tuple(range(count))
    except ValueError as exc:
        if str(exc).startswith("--seeds"):
            raise
        raise ValueError(
            f"--seeds {text!r}: {exc}; use a count N >= 1 (seeds 0..N-1), a range a-b or a "
            "list a,b,c of non-negative integers"
        ) from None
    if not seeds:
        raise ValueError(f"--seeds {text!r} selects no seed")
    _check_count(len(seeds), text)
    if min(seeds) < 0:
        raise ValueError(f"--seeds {text!r}: seeds must be non-negative, got {min(seeds)}")
    if max(seeds) > MAX_SEED:
        raise ValueError(
            f"--seeds {text!r}: seeds must be at most {MAX_SEED} (numpy's seed "
            f"range), got {max(seeds)}"
        )
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"--seeds {text!r} repeats a seed")
    return seeds


def _check_count(count: int, text: str) -> None:
    if count > MAX_SEEDS:
        raise ValueError(
            f"--seeds {text!r} selects {count} seeds, more than {MAX_SEEDS}: "
            "every seed is a whole training run"
        )


@dataclass
class SeedsOptions:
    """Arguments of `train_seeds` (CLI `python -m benchmarks.training.seeds_cli`)."""

    train: TrainOptions  # the per-seed options; `out` and `seed` are set per seed
    seeds: tuple[int, ...] = option(
        (0,), "count N, range a-b or list a,b,c", parse=parse_seeds, required=True
    )
    out: str = option("runs/seeds", "multi-seed run directory", required=True)
    workers: int = option(2, "seeds trained at once")
    backend: str = option("local", "local processes or a Ray cluster", choices=("local", "ray"))
    # None: a local Ray instance.
    address: str | None = option(None, "Ray cluster address (host:port)")
    resume: bool = option(False, "continue every unfinished seed")
    task_set: str = option(
        "paper",
        f"validation episodes: {sorted(TASK_SETS)} or a validation "
        "set of benchmarks/tasks.toml (e.g. 'validation')",
    )
    eval_episodes: int = option(
        DEFAULT_EVAL_EPISODES, "validation episodes taken from a task set (its first seeds)"
    )
    export: str | None = option(None, "copy the selected agent here")
    results: str | None = option(None, "write every seed's test evaluation and learning curve here")
    progress: bool = option(True, "no progress bar", flag="--quiet", invert=True)
    poll_s: float = 5.0  # [s] between progress updates
