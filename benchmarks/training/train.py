"""Train (or resume) one agent, one seed: `TrainOptions` → a run directory (see the package doc)."""

from __future__ import annotations

import datetime as _dt
import json
import os
import pickle
import sys
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import auv_gym
from auv_gym import SPEED_LIMIT_ENV_ID, VARIANTS
from auv_gym.sim.observation import ObservationConfig
from auv_gym.support.files import LOCK_FILE, git_commit, json_default, versions
from benchmarks.catalog.tasks import test_seeds
from benchmarks.options import comma_integers, option, whole_number
from benchmarks.training.agent_interface import pin_scales, wrap_actions
from benchmarks.training.checkpoints import (
    REPLAY_FILE,
    capture_training_state,
    export_agent,
    latest_checkpoint,
    read_training_state,
    restore_env_state,
    restore_random_state,
    save_agent,
    write_metadata,
)
from benchmarks.training.config import ALGORITHMS, read_zoo_config
from benchmarks.training.envs import (  # importable from here too (`benchmarks.speed.training`)
    describe_env,
    make_training_env,
    thread_limit,
    zero_correction_layer,
)
from benchmarks.training.evaluation import (
    EVAL_SEEDS,
    HELD_OUT_SEEDS,
    check_evaluation_duration,
    trained_platform,
    write_held_out_evaluation,
)
from benchmarks.training.learning_curve import EVAL_FILE, truncate_rows
from benchmarks.training.residual import privileged_names
from benchmarks.training.vehicle_share import check_native
from benchmarks.training.warm_start import agent_for_seed, check_warm_start, warm_start
from controllers.agent import METADATA_FILE, MODEL_FILE, VECNORM_FILE
from controllers.residual import residual_observation_names

__all__ = [
    "TrainOptions",
    "check_options",
    "make_training_env",
    "thread_limit",
    "train",
    "zero_correction_layer",
]

HERE = Path(__file__).resolve().parent.parent  # benchmarks/
VEC_ENVS = ("auto", "native", "dummy")  # `envs.make_training_env`


# The hyper-parameter file an algorithm trains with when none is given: its reference agent's.
DEFAULT_CONFIGS = {"ppo": "ppo_helix.yml", "sac": "sac_helix.yml"}


def default_config(algo: str) -> str:
    """The default hyper-parameter file of ``algo`` (`DEFAULT_CONFIGS`); ValueError naming the
    algorithms that have one otherwise (another algorithm needs --config)."""
    if algo not in DEFAULT_CONFIGS:
        raise ValueError(
            f"--algo {algo} has no default hyper-parameter file (defaults exist for "
            f"{sorted(DEFAULT_CONFIGS)}): give --config"
        )
    return str(HERE / "hyperparams" / DEFAULT_CONFIGS[algo])


@dataclass
class TrainOptions:
    """Arguments of `train`; the CLIs `auv-gym train` / `train-seeds` are generated from the
    fields (`benchmarks.options`), so each default and its help is written here only."""

    algo: str = option(
        "ppo",
        "RL algorithm (the saved agent records it; every one loads as "
        "controllers.make('agent', path=...))",
        choices=sorted(ALGORITHMS),
    )
    # The command line's default None stands for the algorithm's file (`default_config`).
    config: str = option(
        str(HERE / "hyperparams" / "ppo_helix.yml"),
        "RL-Zoo hyper-parameter YAML (top-level key = env id; default: the reference agent's "
        "file of the algorithm, benchmarks/hyperparams/ppo_helix.yml or sac_helix.yml)",
        cli_default=None,
    )
    # Top-level key of the config and Gymnasium id; the surge-limited task by default, so that a
    # new agent cannot win by sprinting at speeds a REMUS cannot reach (docs/results.md).
    env_id: str = option(
        SPEED_LIMIT_ENV_ID,
        "Gymnasium id and YAML key (AUVPath3D-v0: the paper's task without a speed limit)",
    )
    out: str = option(
        "runs/ppo_helix", "run directory (checkpoints, best/, final/, evaluations.csv, tb/)"
    )
    seed: int = option(0, "seed of torch, numpy and the training environments")
    n_timesteps: int | None = option(None, "override the config's n_timesteps", parse=whole_number)
    # Pause at the first rollout start at or after this many env steps (None: train to
    # n_timesteps); SB3 collects whole rollouts (PPO: n_steps x n_envs env steps, SAC:
    # train_freq x n_envs), so the pause is up to one rollout later. The schedules (learning
    # rate, clip range) still run over n_timesteps, and the pause writes a checkpoint with the
    # whole training state, so a later --resume (with a larger stop_at or none) continues bit for
    # bit as if the run had never paused (`checkpoints` module doc).
    stop_at: int | None = option(
        None,
        "pause at the first rollout start at or after this many "
        "env steps (PPO: a multiple of n_steps x n_envs); schedules "
        "still run over n_timesteps; a later --resume continues bit "
        "for bit as if never paused",
        parse=whole_number,
    )
    # Continue from the newest checkpoint in `out`: exactly (weights, evaluations, checkpoints) for
    # a pause or a checkpoint of the same settings, e.g. after a kill; a larger n_timesteps
    # continues with schedules over the new budget instead.
    resume: bool = option(
        False,
        "continue from the newest checkpoint in --out; exact (same "
        "weights and evaluations as an uninterrupted run) after a pause or "
        "a kill",
    )
    checkpoint_freq: int = option(
        100_000,
        "env steps between checkpoints (a kill loses at most this many)",
        parse=whole_number,
    )
    keep_checkpoints: int = option(3, "number of newest checkpoints kept on disk")
    eval_freq: int = option(100_000, "env steps between evaluations (0: none)", parse=whole_number)
    eval_seeds: tuple[int, ...] = option(
        EVAL_SEEDS,
        "comma-separated evaluation seeds (disjoint from the test seeds)",
        parse=comma_integers,
    )
    eval_duration: float = option(300.0, "evaluation episode length [s]")
    # Env keyword arguments of the evaluation episodes on top of the id's fixed ones; empty: the
    # paper scenario. A validation task set of benchmarks/tasks.toml fills it (train_seeds).
    eval_env: dict[str, Any] = field(default_factory=dict)  # no command-line option
    vec_env: str = option(
        "auto",
        "auto | native (auv_gym.envs.sb3 batched adapter) | dummy (SB3 DummyVecEnv)",
        choices=VEC_ENVS,
    )
    threads: int = option(
        1,
        "torch and numba threads during training, restored after (1 is "
        "fastest on 2 shared cores, docs/design.md §4)",
    )
    # On cores loaded by other jobs two update threads are 15-50x slower. The trained weights are
    # the same up to float rounding; bit for bit only where torch's kernels sum alike on 1 and 2
    # threads (tests/test_sb3_infos.py).
    update_threads: int = option(
        0,
        "torch threads of the gradient updates between rollouts (0: "
        "--threads); 2 speeds PPO's update up about 1.4x on an idle "
        "2-core machine, slows it down on loaded cores",
    )
    # `callbacks.AdaptiveUpdateThreads`.
    adaptive_threads: bool = option(
        False,
        "time the updates on --threads and on max(2, "
        "--update-threads) torch threads, keep the faster and probe "
        "the other now and then (the same weights up to float "
        "rounding; bit for bit only where torch's kernels reduce "
        "alike on 1 and 2 threads)",
    )
    # A curriculum's later phase: a new run (own budget and schedules) from a saved agent
    # (`warm_start`); a multi-seed run replaces "{seed}" by each seed's number.
    init_from: str | None = option(
        None,
        "start from this saved agent's weights and normalisation statistics instead of random "
        "weights (same algorithm and observation); '{seed}' in the path is replaced by the "
        "seed",
    )
    progress_bar: bool = option(True, "show the progress bar (tqdm + rich)")
    export: str | None = option(
        None,
        "copy the best agent (model, statistics, metadata) to this directory at the end "
        "(of a run paused by --stop-at too: the best so far)",
    )
    verbose: int = option(0, "SB3 verbosity; 1 also prints every evaluation")


def check_options(opts: TrainOptions) -> None:
    """Refuse options that cannot give a meaningful run, before any work starts: ValueError
    naming the option, its value and the allowed range (the CLIs print it as one line).

    Budgets and frequencies must be positive (``n_timesteps`` None: the config's), evaluation
    seeds non-empty, unique and disjoint from the held-out seeds `HELD_OUT_SEEDS` of the
    reported results, the algorithm known, the config readable for ``env_id`` and its plant
    share (if any) on the native vector env.
    """
    if opts.algo not in ALGORITHMS:
        raise ValueError(f"algo {opts.algo!r} is unknown; valid: {sorted(ALGORITHMS)}")
    if opts.n_timesteps is not None and not opts.n_timesteps >= 1:
        raise ValueError(
            f"n_timesteps must be a positive number of env steps, got {opts.n_timesteps}"
        )
    if opts.stop_at is not None and not opts.stop_at >= 1:
        raise ValueError(f"stop_at must be a positive number of env steps, got {opts.stop_at}")
    if opts.update_threads < 0:
        raise ValueError(f"update_threads must be >= 0 (0: threads), got {opts.update_threads}")
    for name in ("checkpoint_freq", "keep_checkpoints", "threads"):
        if not getattr(opts, name) >= 1:
            raise ValueError(f"{name} must be a positive integer, got {getattr(opts, name)}")
    if opts.eval_freq < 0:
        raise ValueError(
            f"eval_freq must be >= 0 env steps (0: no evaluation), got {opts.eval_freq}"
        )
    seeds = tuple(opts.eval_seeds)
    if not seeds or len(set(seeds)) != len(seeds) or min(seeds) < 0:
        raise ValueError(f"eval_seeds must be distinct non-negative integers, got {list(seeds)}")
    overlap = sorted(set(seeds) & (set(HELD_OUT_SEEDS) | test_seeds()))
    if overlap:
        raise ValueError(
            f"eval_seeds {overlap[:5]} overlap the held-out test seeds of the reported results "
            f"({HELD_OUT_SEEDS[0]}-{HELD_OUT_SEEDS[-1]} and every test set's, "
            "`benchmarks.catalog.tasks.test_seeds`): choose evaluation (validation) seeds "
            "outside them, e.g. 100-104"
        )
    if not (opts.eval_duration > 0 and opts.eval_duration < float("inf")):
        raise ValueError(f"eval_duration must be a positive time in s, got {opts.eval_duration}")
    cfg = read_zoo_config(opts.config, opts.env_id, opts.algo)
    check_native(cfg.vehicle_share, opts.vec_env, str(opts.config))
    if cfg.jump_start is not None and (opts.resume or opts.stop_at is not None):
        raise ValueError(
            f"{opts.config}: a jump start runs whole, in one go (no --resume, no --stop-at)"
        )
    if opts.init_from:
        check_warm_start(agent_for_seed(opts.init_from, opts.seed), opts.algo)


def target_timesteps(n_timesteps: int, stop_at: int | None) -> int:
    """Env steps a run trains to in this invocation: n_timesteps, or stop_at when smaller."""
    return int(n_timesteps if stop_at is None else min(n_timesteps, stop_at))


def _eval_kwargs(opts: TrainOptions, env_kwargs: dict[str, Any]) -> dict[str, Any]:
    """The evaluation episodes: `eval_env` (empty: the paper scenario) under the trained id's
    fixed arguments (the surge limit of AUVPath3DSpeedLimit-v0) and the training env's
    observation, vehicle, plant and actuator (`trained_platform`), `eval_duration` long."""
    seen = {"observation": env_kwargs["observation"]} if "observation" in env_kwargs else {}
    return {
        **VARIANTS.get(opts.env_id, {}),
        **seen,
        **trained_platform(env_kwargs),
        **opts.eval_env,
        "max_time": float(opts.eval_duration),
    }


def observation_layout_of(env_id: str, env_kwargs: dict[str, Any]) -> ObservationConfig:
    """The observation an agent trained on ``env_id`` with ``env_kwargs`` sees."""
    spec = env_kwargs.get("observation", VARIANTS.get(env_id, {}).get("observation"))
    return ObservationConfig.from_spec(spec)


def agent_observation_names(cfg: Any, env_id: str) -> tuple[str, ...]:
    """The names of what the network of config ``cfg`` sees on ``env_id``: the env's
    observation (`observation_layout_of`), and for a residual agent its base's and its previous
    action after it (`controllers.residual.residual_observation_names`)."""
    layout = observation_layout_of(env_id, cfg.env_kwargs)
    return layout.names if cfg.residual is None else residual_observation_names(layout)


def train(opts: TrainOptions, argv: Sequence[str] | None = None) -> Path:
    """Train (or resume) as configured; returns the run directory (see `benchmarks.training`).

    torch's and numba's thread counts are set to ``opts.threads`` for the run and restored.
    An evaluation duration that cannot produce a metric is refused before anything starts.
    """
    if opts.eval_freq > 0 or opts.export:
        check_evaluation_duration(opts.eval_duration)
    with thread_limit(opts.threads):
        return _train(opts, argv)


def _keep_demonstrations(agent: Path, out: Path) -> None:
    """Copy the labelled transitions of the run's initial agent into the run folder (atomically):
    a resumed run reads them there, and a schedule hands them on beside the selected agent
    (`benchmarks.training.demo_regularization`)."""
    import shutil

    from auv_gym.support.files import write_atomic
    from benchmarks.training.transitions import TRANSITIONS_FILE

    with (agent / TRANSITIONS_FILE).open("rb") as data:
        write_atomic(out / TRANSITIONS_FILE, lambda fh: shutil.copyfileobj(data, fh))


# What a resumed run must share with the run it continues (`TrainOptions` fields); the rest
# (stop_at, threads, progress, verbosity, checkpoints kept) may change between sessions.
RESUME_OPTIONS = (
    "algo",
    "env_id",
    "seed",
    "eval_seeds",
    "eval_duration",
    "eval_freq",
    "checkpoint_freq",
    "eval_env",
    "init_from",
    "vec_env",
)


def _as_json(value: Any) -> Any:
    return json.loads(json.dumps(value, default=json_default))


def check_resume(
    checkpoint: Path, opts: TrainOptions, config: Any, budget: int | None = None
) -> None:
    """ValueError naming the setting when ``--resume`` would continue the run of ``checkpoint``
    with other settings than it started with (`RESUME_OPTIONS`, the config file's content): the
    weights of one run under the record of another. A larger ``--n-timesteps`` may extend a
    run (its learning-rate schedule is then the new budget's), unless the run's best agent was
    saved after the checkpoint (a killed run's): the new budget would not make that agent again,
    and it would stay as the best under a record that never saw it. ``budget``: the resumed
    run's env steps (None: not checked). A checkpoint whose metadata.json cannot be read is
    named."""
    meta_file = checkpoint / METADATA_FILE
    try:
        previous = json.loads(meta_file.read_text())
        before = previous["options"]
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise ValueError(f"--resume: {meta_file} cannot be read ({error})") from None
    now = asdict(opts)
    for key in RESUME_OPTIONS:
        if key in before and _as_json(before[key]) != _as_json(now[key]):
            raise ValueError(
                f"--resume: {key} was {before[key]!r:.80} in {meta_file}, now {now[key]!r:.80}; "
                "resume with the same settings (or start another --out)"
            )
    if "config" in previous and _as_json(previous["config"]) != _as_json(config):
        raise ValueError(
            f"--resume: the settings of --config {opts.config} differ from the run's in "
            f"{meta_file}; resume with the same settings (or start another --out)"
        )
    best_file = checkpoint.parent.parent / "best" / METADATA_FILE  # OUT/checkpoints/step_<n>/
    before_budget = previous.get("n_timesteps")
    if budget is not None and before_budget is not None and budget != before_budget:
        best_steps = _num_timesteps(best_file)
        if best_steps > int(previous.get("num_timesteps", 0)):
            raise ValueError(
                f"--resume: {best_file.parent} holds the agent of step {best_steps}, saved "
                f"after the checkpoint {checkpoint.name}; with {budget} env steps instead of "
                f"{before_budget} the run would not make it again: resume with "
                f"--n-timesteps {before_budget} first, then extend"
            )


def _num_timesteps(meta_file: Path) -> int:
    """The env steps an agent's metadata.json records (0 where there is none)."""
    try:
        return int(json.loads(meta_file.read_text()).get("num_timesteps", 0))
    except (OSError, ValueError, TypeError, AttributeError):
        return 0


def check_run_folder(opts: TrainOptions) -> None:
    """What `train` refuses about its run folder, checked before anything is built: a folder
    holding work without ``--resume``; with it, no complete checkpoint to continue or other
    settings than the run's (`check_resume`). ValueError / FileNotFoundError naming it."""
    out = Path(opts.out)
    if out.exists() and any(p.name != LOCK_FILE for p in out.iterdir()) and not opts.resume:
        raise ValueError(f"run directory {out} is not empty; pass --resume or another --out")
    if opts.resume:
        checkpoint = latest_checkpoint(out)
        if checkpoint is None:
            raise FileNotFoundError(f"--resume: no complete checkpoint under {out / 'checkpoints'}")
        cfg = read_zoo_config(opts.config, opts.env_id, opts.algo)
        budget = int(cfg.n_timesteps if opts.n_timesteps is None else opts.n_timesteps)
        check_resume(checkpoint, opts, cfg.raw, budget)


def _train(opts: TrainOptions, argv: Sequence[str] | None) -> Path:
    import stable_baselines3
    import torch
    from stable_baselines3.common.callbacks import CallbackList, ProgressBarCallback
    from stable_baselines3.common.utils import set_random_seed
    from stable_baselines3.common.vec_env import VecNormalize

    from benchmarks.training.callbacks import (
        AdaptiveUpdateThreads,
        PauseTraining,
        PeriodicCheckpoint,
        PeriodicEvaluation,
        RestoreRandomState,
        UpdateThreads,
    )

    check_options(opts)
    cfg = read_zoo_config(opts.config, opts.env_id, opts.algo)
    spec = ALGORITHMS[opts.algo]
    algorithm = spec.sb3_class()
    # SAC kept near a jump start's labels (`demo_regularization`); a jump start ignores the key.
    demo = cfg.demo_regularization if cfg.jump_start is None else None
    if demo is not None:
        from benchmarks.training.demo_sac import DemoSAC

        algorithm = DemoSAC
    n_timesteps = int(cfg.n_timesteps if opts.n_timesteps is None else opts.n_timesteps)
    out = Path(opts.out)
    check_run_folder(opts)  # before any env is built
    out.mkdir(parents=True, exist_ok=True)
    eval_kwargs = _eval_kwargs(opts, cfg.env_kwargs)
    set_random_seed(opts.seed)
    residual = cfg.residual
    # One thread: the serial kernel at every N (numba's pool would run it on one thread anyway).
    venv = make_training_env(
        cfg.n_envs,
        opts.seed,
        cfg.env_kwargs,
        opts.vec_env,
        opts.env_id,
        residual,
        threads=1 if opts.threads == 1 else None,
        vehicle_share=cfg.vehicle_share,
    )
    layout = observation_layout_of(opts.env_id, cfg.env_kwargs)
    obs_names = agent_observation_names(cfg, opts.env_id)
    privileged = residual is not None and residual.privileged_critic  # the actor reads obs_names
    action_dim = 3 if residual is None else residual.action_dim  # (X, M, N) or the residual's
    venv = wrap_actions(venv, cfg, obs_names, {**VARIANTS.get(opts.env_id, {}), **cfg.env_kwargs})

    previous: dict[str, Any] = {}
    warm: dict[str, Any] | None = None
    checkpoint = latest_checkpoint(out) if opts.resume else None
    state: dict[str, Any] | None = None
    demos: dict[str, Any] | None = None  # the labelled transitions, read before any work
    if demo is not None:
        from benchmarks.training.demo_regularization import (
            check_demonstrations,
            read_demonstrations,
        )

        source = out if checkpoint is not None else None  # a resumed run's own copy
        if source is None and opts.init_from:
            source = Path(agent_for_seed(opts.init_from, opts.seed))
        if source is None:  # refused: no initial agent to carry them
            check_demonstrations(cfg, [], obs_names, action_dim, str(opts.config))
        demos = read_demonstrations(source, obs_names, action_dim, str(opts.config))
    if checkpoint is not None:
        previous = json.loads((checkpoint / METADATA_FILE).read_text())
        warm = previous.get("warm_start")
        try:
            venv = VecNormalize.load(str(checkpoint / VECNORM_FILE), venv)
        except (OSError, EOFError, pickle.UnpicklingError, ValueError, TypeError) as error:
            raise ValueError(
                f"{checkpoint / VECNORM_FILE} cannot be read ({error}): a damaged checkpoint"
            ) from None
        venv.training = True
        # A model saved with n-step returns names the NStepReplayBuffer SB3 chose for it, which
        # SB3 would take for a custom buffer ("n_steps ignored"); without the name it chooses
        # the same buffer again from the saved n_steps and gamma (the saved buffer is loaded
        # into it below).
        model = algorithm.load(
            checkpoint / MODEL_FILE,
            env=venv,
            device="cpu",
            tensorboard_log=str(out / "tb"),
            verbose=opts.verbose,
            custom_objects={"replay_buffer_class": None, "replay_buffer_kwargs": {}},
        )
        if spec.off_policy and (checkpoint / REPLAY_FILE).is_file():
            model.load_replay_buffer(checkpoint / REPLAY_FILE)
        state = read_training_state(checkpoint)
        if state is None:
            print(
                f"--resume: {checkpoint} holds no training state (an older checkpoint): the "
                "environments restart and the random generators are reseeded, so the run "
                "continues from these weights but not as it would have",
                file=sys.stderr,
            )
        else:
            restore_env_state(model, state)
            if state["phase"] == "training_end":  # SB3 draws nothing before the next rollout
                restore_random_state(model, state)
        truncate_rows(out / EVAL_FILE, model.num_timesteps)
    else:
        venv = VecNormalize(venv, **cfg.normalize)
        pin_scales(venv, cfg, obs_names)
        policy, policy_kwargs = cfg.policy, cfg.policy_kwargs
        if privileged:
            from benchmarks.training.privileged import PrivilegedCriticPolicy

            policy = PrivilegedCriticPolicy
            policy_kwargs = {**policy_kwargs, "public_dim": len(obs_names)}
        model = algorithm(
            policy,
            venv,
            policy_kwargs=policy_kwargs,
            seed=opts.seed,
            device="cpu",
            tensorboard_log=str(out / "tb"),
            verbose=opts.verbose,
            **cfg.model_kwargs(),
        )
        if residual is not None:
            zero_correction_layer(model)
        if opts.init_from:
            warm = warm_start(
                model, venv, agent_for_seed(opts.init_from, opts.seed), opts.algo, obs_names
            )
    demo_record: dict[str, Any] = {}
    if demos is not None:  # attached again at a resume: the zip leaves them out
        model.attach_demonstrations(demo, demos)
        demo_record = {**demo.to_dict(), "transitions": len(demos["rewards"])}
        if checkpoint is None:  # the run's own copy: for a resume and the next phase
            _keep_demonstrations(source, out)
    start_wall = float(previous.get("wall_time_s", 0.0))
    best: dict[str, Any] = dict(previous.get("best", {}))
    sessions = [
        *previous.get("sessions", []),
        {
            "argv": list(argv if argv is not None else sys.argv),
            "started": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
            "resumed_from": None if checkpoint is None else str(checkpoint),
            "exact_resume": None if checkpoint is None else state is not None,
            "start_timesteps": int(model.num_timesteps),
        },
    ]
    t0 = time.monotonic()
    jump: dict[str, Any] = {}  # the jump start's record, once it ran (`dagger.run_jump_start`)
    residual_meta = {} if residual is None else {"residual": residual.to_dict()}
    # The held-out evaluation and the benchmark build the agent's env from this; a residual
    # agent on the paper's observation records none, as residual agents did before they had a
    # choice (their metadata, and the check of saved agents, unchanged).
    if residual is None or layout.kind != "paper":
        residual_meta["observation"] = layout.to_dict()
    share = cfg.vehicle_share

    def metadata(extra: dict[str, Any]) -> dict[str, Any]:
        return {
            "algo": opts.algo,
            "env_id": opts.env_id,
            "seed": opts.seed,
            "num_timesteps": int(model.num_timesteps),
            "n_timesteps": n_timesteps,
            "wall_time_s": start_wall + (time.monotonic() - t0),
            "command": " ".join(sessions[0]["argv"]),
            "sessions": sessions,
            "options": asdict(opts),
            "config_file": str(opts.config),
            "config": cfg.raw,
            "env_kwargs": cfg.env_kwargs,
            "eval_env_kwargs": eval_kwargs,
            "eval_seeds": list(opts.eval_seeds),
            "obs_names": list(obs_names),
            "observation_shape": [len(obs_names)],
            "action_shape": [action_dim],
            **residual_meta,
            **({"stages": list(cfg.stages)} if cfg.stages else {}),
            **({} if share is None else {share.key: share.to_dict(cfg.n_envs)}),
            "versions": versions(),
            "sb3_version": stable_baselines3.__version__,
            "git_commit": git_commit(),
            "vec_env": describe_env(venv),
            "torch_threads": torch.get_num_threads(),
            "cpu_count": os.cpu_count(),
            "best": best,
            "auv_gym_version": auv_gym.__version__,
            **({} if warm is None else {"warm_start": warm}),
            **({"jump_start": dict(jump)} if jump else {}),
            **({} if demos is None else {"demo_regularization": demo_record}),
            **extra,
        }

    schedules = {} if state is None else state["schedules"]
    callbacks: list[Any] = []
    if state is not None and state["phase"] == "rollout_start":
        callbacks.append(RestoreRandomState(state))
    if opts.adaptive_threads:
        candidates = (opts.threads, max(2, opts.update_threads))
        callbacks.append(AdaptiveUpdateThreads(opts.threads, candidates))
    elif opts.update_threads not in (0, opts.threads):
        callbacks.append(UpdateThreads(opts.threads, opts.update_threads))
    evaluation = None
    if opts.eval_freq > 0:
        evaluation = PeriodicEvaluation(
            out,
            opts.eval_freq,
            opts.eval_seeds,
            eval_kwargs,
            metadata,
            start_wall,
            best,
            opts.verbose,
            residual,
            next_eval=schedules.get("next_eval"),
            stages=(cfg.stages, obs_names),
            rule=cfg.selection,
        )
        callbacks.append(evaluation)
    target = target_timesteps(n_timesteps, opts.stop_at)

    def training_state(phase: str) -> dict[str, Any]:
        return capture_training_state(
            model,
            phase,
            {
                "next_eval": None if evaluation is None else evaluation.next_eval,
                "next_checkpoint": checkpoints.next_checkpoint,
            },
        )

    checkpoints = PeriodicCheckpoint(
        out,
        opts.checkpoint_freq,
        opts.keep_checkpoints,
        metadata,
        replay_buffer=spec.off_policy,
        state=training_state,
        stop_at=target if target < n_timesteps else None,
        next_checkpoint=schedules.get("next_checkpoint"),
        obs_names=privileged_names(obs_names) if privileged else None,
    )
    callbacks.append(checkpoints)
    if opts.progress_bar:  # ours, to close it at a pause too
        callbacks.append(ProgressBarCallback())
    try:
        remaining = n_timesteps - int(model.num_timesteps)
        if cfg.jump_start is not None:  # imitation instead of RL (`benchmarks.training.jump_start`)
            from stable_baselines3.common.utils import configure_logger

            if spec.off_policy:  # SAC, TQC: their own fitting, the flights kept for the next phase
                from benchmarks.training.dagger_sac import (
                    run_off_policy_jump_start as run_jump_start,
                )
            else:
                from benchmarks.training.dagger import run_jump_start

            model.set_logger(configure_logger(opts.verbose, str(out / "tb"), "jump_start"))

            def evaluate() -> None:
                if evaluation is not None:
                    evaluation.num_timesteps = int(model.num_timesteps)
                    evaluation.evaluate()

            if evaluation is not None:
                evaluation.init_callback(model)
            jump.update(
                run_jump_start(
                    model,
                    venv,
                    cfg,
                    opts.env_id,
                    opts.seed,
                    evaluate,
                    print if opts.verbose or opts.progress_bar else None,
                )
            )
        elif int(model.num_timesteps) < target:
            try:
                model.learn(
                    remaining,
                    callback=CallbackList(callbacks),
                    progress_bar=False,
                    reset_num_timesteps=checkpoint is None,
                    tb_log_name=algorithm.__name__,
                )
            except PauseTraining:  # the checkpoint of the pause is written; the model is as in it
                for callback in callbacks:
                    if isinstance(callback, ProgressBarCallback | UpdateThreads):
                        callback.on_training_end()
        if jump and spec.off_policy:  # before final/: a finished jump start has its transitions
            from benchmarks.training.transitions import TRANSITIONS_FILE, write_transitions

            write_transitions(out / TRANSITIONS_FILE, model.replay_buffer, obs_names)
        final_meta = metadata({})
        from benchmarks.training.privileged import deployable

        save_agent(*deployable(model, venv), out / "final", final_meta)
        write_metadata(out / METADATA_FILE, final_meta)
    finally:  # SB3's learn leaves its logger (the TensorBoard writer's thread) open
        logger = getattr(model, "_logger", None)  # set once learning or a jump start began
        if logger is not None:
            logger.close()
        venv.close()
    if opts.export:
        source = out / "best" if (out / "best" / MODEL_FILE).is_file() else out / "final"
        export_agent(source, Path(opts.export))
        write_held_out_evaluation(opts.export, opts.eval_duration, opts.env_id)
    return out
