"""The RL training harness: RL-Zoo configuration, training runs, checkpoints, evaluation.

`train` (CLI `python -m benchmarks.training.train_cli`) reads an RL-Zoo hyper-parameter file
(`benchmarks/hyperparams/ppo_helix.yml`, top-level key = the env id), normalises observations (and
rewards) with `VecNormalize`, evaluates on the paper scenario (helix, white noise ±35 N / N·m)
with fixed seeds, and writes, under the run directory::

    final/      model.zip, vecnormalize.pkl, vecnormalize.npz, metadata.json: the final agent
    best/       the same files for the best evaluation so far
    metadata.json                                                    copy of final/metadata.json
    checkpoints/step_<num_timesteps>/   the same files, every `checkpoint_freq` env steps
    evaluations.csv                     the learning curve (env steps, wall time, rms distance)
    tb/                                 TensorBoard logs

Every agent directory is complete on its own (model, normalisation statistics, metadata with the
command line, configuration, seed, package versions, git commit, wall time and the observation
layout) and written atomically, so a killed run never leaves a half-written agent.
Checkpoints are taken where SB3 starts a rollout and hold the whole training state
(training_state.pkl: random generators, gSDE noise, the environments mid-episode, VecNormalize's
running return, the schedules); `resume=True` continues from the newest one bit for bit (single
thread, same machine and package versions), after a pause (`stop_at`) or a kill. A kill loses at
most one checkpoint interval of compute, never exactness. The agents load with
`controllers.loader.load_policy` (``controllers.make("agent", path=...)``).

Modules: `config` (YAML files; `ALGORITHMS`, PPO, SAC, TQC and CrossQ, is the loader's table,
`controllers.algorithms`), `residual` and `residual_env` (a residual agent's training settings and
env wrapper), `train` (`TrainOptions`, `train`: one algorithm, one seed, one run directory), `seeds`
(`train_seeds`: N seeds, one run directory each, as local processes or Ray tasks; CLI `python -m
benchmarks.training.seeds_cli`), `callbacks` (evaluation and checkpoints during training),
`checkpoints` (agent directories), `evaluation` (seeds, scoring, held-out evaluation),
`learning_curve` (evaluations.csv); the jump start from the classical controllers: `expert` (a
classical controller's commands in the agent's action space), `demonstrations` (its episodes as a
Minari dataset, `auv-gym demos` in `demos_cli`), `jump_start` (the settings) and `dagger`
(behaviour cloning and DAgger on the PPO policy). SB3 and torch are imported only when training
or evaluating.
"""

from benchmarks.training.config import ALGORITHMS, ZooConfig, read_zoo_config
from benchmarks.training.evaluation import (
    EVAL_SEEDS,
    HELD_OUT_FILE,
    HELD_OUT_SEEDS,
    evaluate_policy_on_seeds,
    held_out_evaluation,
    summarize,
    write_held_out_evaluation,
)
from benchmarks.training.train import TrainOptions, train

__all__ = [
    "ALGORITHMS",
    "EVAL_SEEDS",
    "HELD_OUT_FILE",
    "HELD_OUT_SEEDS",
    "TrainOptions",
    "ZooConfig",
    "evaluate_policy_on_seeds",
    "held_out_evaluation",
    "read_zoo_config",
    "summarize",
    "train",
    "write_held_out_evaluation",
]
