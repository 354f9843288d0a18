"""Off-policy training cost on this machine: SAC, TQC and CrossQ on one hyper-parameter file.

Each algorithm is built as `benchmarks.training.train` builds it — the file's env, vehicles,
action box, `VecNormalize` and network sizes; keys an algorithm does not take (CrossQ has no
target networks: no ``tau``) are dropped — on one torch thread, as the trainer runs. For each:

- collection: env steps/s while the replay buffer fills (`--warmup` steps, no gradient step);
- gradient step: wall time of one update (critics, actor, entropy coefficient) on a batch of
  the file's ``batch_size``, the mean of `--gradient-steps` after `--warmup` transitions;
- training rate: env steps/s at a replay ratio r (gradient steps per env step; the file's,
  ``gradient_steps / (train_freq · n_envs)``, or `--replay-ratio`):
  1 / (1/collection + r · gradient step).

    auv-gym speed off-policy                                  # sac_helix.yml, about a minute
    auv-gym speed off-policy --algos crossq --critic 1024 --replay-ratio 1

CrossQ's critics default to the file's layers (`--critic` sets their width, two layers: the
CrossQ paper's critics are 2048 wide, sb3-contrib's default 1024).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from benchmarks.arguments import parse_options, program_name
from benchmarks.options import option

ALGOS = ("sac", "tqc", "crossq")
HYPERPARAMS = Path(__file__).resolve().parents[1] / "hyperparams"


@dataclass
class Options:
    """The command line of `auv-gym speed off-policy`."""

    config: str = option(str(HYPERPARAMS / "sac_helix.yml"), "SAC hyper-parameter file to time")
    env_id: str = option("AUVPath3DPreview-v0", "the file's env id")
    algos: tuple[str, ...] = option(ALGOS, "algorithms to time", nargs="+", choices=ALGOS)
    warmup: int = option(2000, "env steps collected before the gradient steps are timed")
    gradient_steps: int = option(100, "timed gradient steps per algorithm")
    replay_ratio: float | None = option(None, "gradient steps per env step (default: the file's)")
    critic: int | None = option(None, "CrossQ critic width, two layers (default: the file's)")


def _kwargs(algo: str, cfg: Any, opts: Options) -> dict[str, Any]:
    """The file's SAC keyword arguments as ``algo`` takes them, with a buffer for the warm-up."""
    from controllers.algorithms import ALGORITHMS

    accepted = ALGORITHMS[algo].hyperparameters
    kwargs = {k: v for k, v in cfg.model_kwargs().items() if k in accepted}
    kwargs.update(buffer_size=opts.warmup + 1000, learning_starts=opts.warmup)
    policy_kwargs = dict(cfg.policy_kwargs)
    if algo == "crossq":
        layers = policy_kwargs.pop("net_arch", [256, 256])
        actor = layers.get("pi", layers) if isinstance(layers, dict) else layers
        critic = layers.get("qf", layers) if isinstance(layers, dict) else layers
        if opts.critic is not None:
            critic = [opts.critic, opts.critic]
        policy_kwargs["net_arch"] = {"pi": list(actor), "qf": list(critic)}
    return {**kwargs, "policy_kwargs": policy_kwargs}


def measure(algo: str, opts: Options) -> dict[str, Any]:
    """Collection rate, gradient-step time and training rate of ``algo`` (module doc)."""
    import torch
    from stable_baselines3.common.vec_env import VecNormalize

    from auv_gym import VARIANTS
    from benchmarks.training.agent_interface import wrap_actions
    from benchmarks.training.config import ALGORITHMS, read_zoo_config
    from benchmarks.training.envs import make_training_env
    from benchmarks.training.train import observation_layout_of

    torch.set_num_threads(1)
    cfg = read_zoo_config(opts.config, opts.env_id, "sac")
    names = observation_layout_of(opts.env_id, cfg.env_kwargs).names
    venv = make_training_env(cfg.n_envs, 0, cfg.env_kwargs, env_id=opts.env_id, threads=1)
    venv = wrap_actions(venv, cfg, names, {**VARIANTS.get(opts.env_id, {}), **cfg.env_kwargs})
    venv = VecNormalize(venv, **cfg.normalize)
    kwargs = _kwargs(algo, cfg, opts)
    model = ALGORITHMS[algo].sb3_class()(cfg.policy, venv, seed=0, device="cpu", **kwargs)
    began = time.perf_counter()
    model.learn(total_timesteps=opts.warmup)
    collection = model.num_timesteps / (time.perf_counter() - began)
    model.train(gradient_steps=5, batch_size=model.batch_size)  # first calls: not timed
    began = time.perf_counter()
    model.train(gradient_steps=opts.gradient_steps, batch_size=model.batch_size)
    step = (time.perf_counter() - began) / opts.gradient_steps
    ratio = opts.replay_ratio
    if ratio is None:
        train_freq = cfg.algo_kwargs.get("train_freq", 1)
        ratio = cfg.algo_kwargs.get("gradient_steps", 1) / (train_freq * cfg.n_envs)
    venv.close()
    return {
        "algo": algo,
        "critic": kwargs["policy_kwargs"].get("net_arch"),
        "collection_steps_per_s": collection,
        "gradient_step_ms": 1e3 * step,
        "replay_ratio": ratio,
        "training_steps_per_s": 1.0 / (1.0 / collection + ratio * step),
    }


def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    opts, parser = parse_options(
        Options, argv, program_name("benchmarks.speed.off_policy"), __doc__
    )
    if opts.warmup < 1 or opts.gradient_steps < 1:
        parser.error("--warmup and --gradient-steps must be >= 1")
    if opts.replay_ratio is not None and not opts.replay_ratio > 0:
        parser.error(f"--replay-ratio must be > 0, got {opts.replay_ratio}")
    if opts.critic is not None and opts.critic < 1:
        parser.error(f"--critic must be >= 1, got {opts.critic}")
    if not Path(opts.config).is_file():
        parser.error(f"--config: {opts.config} does not exist")
    rows = [measure(algo, opts) for algo in opts.algos]
    print(f"\noff-policy training cost, {Path(opts.config).name} on {opts.env_id}, 1 torch thread")
    print(
        f"{'algo':<8} {'collection [steps/s]':>21} {'gradient step [ms]':>19} "
        f"{'replay ratio':>13} {'training [steps/s]':>19}"
    )
    for r in rows:
        print(
            f"{r['algo']:<8} {r['collection_steps_per_s']:>21.0f} {r['gradient_step_ms']:>19.1f} "
            f"{r['replay_ratio']:>13.3g} {r['training_steps_per_s']:>19.0f}"
        )
    return rows


if __name__ == "__main__":
    main()
