"""SB3 callbacks of the training harness: periodic evaluation (learning curve, best agent),
periodic checkpoints (and the pause at ``stop_at``) and the exact resume. Imports
stable-baselines3 (the rl extra)."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from stable_baselines3.common.callbacks import BaseCallback

from benchmarks.training.checkpoints import (
    checkpoint_folder,
    prune_checkpoints,
    restore_random_state,
    save_agent,
)
from benchmarks.training.evaluation import (
    chattering_mean,
    evaluate_policy_on_seeds,
    summarize,
    variant_groups,
)
from benchmarks.training.learning_curve import EVAL_FILE, append_row
from benchmarks.training.privileged import deployable
from benchmarks.training.residual import ResidualTraining
from benchmarks.training.selection_rule import DEFAULT_RULE, SelectionRule
from controllers.agent import AgentPolicy
from controllers.env_settings import policy_settings
from controllers.mirror import mirrored
from controllers.residual import ResidualPolicy, base_kwargs_for_env
from controllers.stages import StagedPolicy, build_stages

__all__ = [
    "AdaptiveUpdateThreads",
    "PauseTraining",
    "PeriodicCheckpoint",
    "PeriodicEvaluation",
    "RestoreRandomState",
    "UpdateThreads",
    "policy_from_model",
]

# metadata(extra) → the agent metadata of the model's current state, updated with `extra`.
MetadataFn = Callable[[dict[str, Any]], dict[str, Any]]
# state(phase) → `checkpoints.capture_training_state` of the run now.
StateFn = Callable[[str], dict[str, Any]]


def policy_from_model(
    model: Any,
    vec_normalize: Any,
    residual: ResidualTraining | None = None,
    env_kwargs: dict[str, Any] | None = None,
    stages: tuple[Sequence[dict[str, Any]], Sequence[str]] = ((), ()),
) -> AgentPolicy | ResidualPolicy | StagedPolicy:
    """The Policy of a model in training, with a snapshot of the current statistics (torch's
    thread setting is the training's); with ``residual``, the `ResidualPolicy` of its base
    controller configured for the episodes' ``env_kwargs`` (`base_kwargs_for_env`); with
    ``stages`` (the agent's stage specs, its observation names), that policy inside them, built
    for the plant of ``env_kwargs`` (`controllers.stages.StagedPolicy`)."""
    model, vec_normalize = deployable(model, vec_normalize)  # what the saved agent flies
    policy = _unguarded(model, vec_normalize, residual, env_kwargs)
    specs, obs_names = stages
    policy = mirrored(policy, specs, obs_names, "stages")
    built = build_stages(specs, obs_names, policy_settings(env_kwargs or {}), "stages")
    return StagedPolicy(policy, built) if built else policy


def _unguarded(
    model: Any,
    vec_normalize: Any,
    residual: ResidualTraining | None,
    env_kwargs: dict[str, Any] | None,
) -> Any:
    rms = vec_normalize.obs_rms
    actor = AgentPolicy(
        model.policy, rms.mean.copy(), rms.var.copy(), vec_normalize.clip_obs, vec_normalize.epsilon
    )
    if residual is None:
        return actor
    base = residual.make_base(**base_kwargs_for_env(env_kwargs or {}))
    return ResidualPolicy(base, actor, residual.bound, residual)


def _next_multiple(n: int, every: int) -> int:
    return (n // every + 1) * every


class PeriodicEvaluation(BaseCallback):
    """Every `every` env steps (and at step 0 of a fresh run): the policy on `seeds`, a row of
    the learning curve, and the agent saved to OUT/best when its score (``rule``, the config's
    `SelectionRule`) improves.

    `best` (score, num_timesteps, summary) is shared with the run's metadata, which records it.
    A residual agent (``residual``) is evaluated as its `ResidualPolicy`, an agent with stages
    (``stages``: specs, observation names) inside them. ``next_eval``: the schedule of a resumed
    run (its checkpoint's), else the first multiple of `every` ahead.
    """

    def __init__(
        self,
        out: Path,
        every: int,
        seeds: Sequence[int],
        eval_kwargs: dict[str, Any],
        metadata: MetadataFn,
        start_wall: float,
        best: dict[str, Any],
        verbose: int = 0,
        residual: ResidualTraining | None = None,
        next_eval: int | None = None,
        stages: tuple[Sequence[dict[str, Any]], Sequence[str]] = ((), ()),
        rule: SelectionRule = DEFAULT_RULE,
    ) -> None:
        super().__init__(verbose)
        self.residual, self.stages, self.rule = residual, stages, rule
        self.out, self.every, self.seeds = out, every, tuple(seeds)
        self.eval_kwargs, self.metadata = eval_kwargs, metadata
        self.start_wall, self.best = start_wall, best
        self.t0 = time.monotonic()
        self.next_eval = 0
        self._resumed_next = next_eval

    def _on_training_start(self) -> None:
        n = self.num_timesteps
        if self._resumed_next is not None:
            self.next_eval = self._resumed_next
            return
        self.next_eval = _next_multiple(n, self.every)
        if n == 0:
            self.evaluate()  # the untrained agent: the curve starts at step 0

    def _on_step(self) -> bool:
        if self.num_timesteps >= self.next_eval:
            self.next_eval += self.every
            self.evaluate()
        return True

    def evaluate(self) -> None:
        """Evaluate now: learning-curve row, TensorBoard scalars, best agent."""
        vec_normalize = self.model.get_vec_normalize_env()
        extra = () if self.residual is None else ("chattering",)
        results = []
        for label, env_kwargs in variant_groups(self.eval_kwargs):
            # one batch per plant or actuator, the stages built from its env arguments
            policy = policy_from_model(
                self.model, vec_normalize, self.residual, env_kwargs, self.stages
            )
            rows = evaluate_policy_on_seeds(policy, self.seeds, extra_metrics=extra, **env_kwargs)
            if label is not None:
                rows = [{**row, "variant": label} for row in rows]
            results.extend(rows)
        summary = summarize(results)
        weight = 0.0 if self.residual is None else self.residual.selection_chattering
        if self.residual is not None:  # a residual agent is also judged on smoothness
            summary["chattering_mean"] = chattering_mean(results)
            self.logger.record("eval/chattering_mean", summary["chattering_mean"])
        self.model.policy.set_training_mode(False)
        wall = self.start_wall + (time.monotonic() - self.t0)
        self.logger.record("eval/rms_distance_mean", summary["rms_distance_mean"])
        self.logger.record("eval/n_terminated", summary["n_terminated"])
        append_row(self.out / EVAL_FILE, self.num_timesteps, wall, summary)
        current = self.rule.score(summary, weight)
        if self.best.get("score") is None or current < tuple(self.best["score"]):
            self.best["score"] = list(current)
            self.best["num_timesteps"] = self.num_timesteps
            self.best["summary"] = summary
            meta = self.metadata({"evaluation": summary, "eval_results": results})
            # A privileged model is converted for each flight above and again here: each
            # conversion draws the new policy's initial weights from torch's global generator,
            # which the training shares, so their number is part of a seed's trajectory (one
            # conversion per evaluation trained other agents than the recipe's seeds).
            save_agent(*deployable(self.model, vec_normalize), self.out / "best", meta)
        if self.verbose:
            print(f"[eval] steps={self.num_timesteps} wall={wall:.0f}s {summary}", flush=True)


class PauseTraining(Exception):
    """Raised out of `learn` by `PeriodicCheckpoint` once the pause checkpoint is written."""


class PeriodicCheckpoint(BaseCallback):
    """Checkpoints to OUT/checkpoints/step_<n>/ (the newest `keep` stay), with the replay buffer
    if `replay_buffer` and the training state ``state(phase)`` (`capture_training_state`):

    - where SB3 starts collecting a rollout, once `every` more env steps have passed (SB3 steps
      whole rollouts: PPO's n_steps × n_envs, SAC's train_freq × n_envs; a checkpoint in the
      middle of one could not be resumed exactly);
    - there too once ``stop_at`` env steps are reached, then `PauseTraining` is raised: a run
      pauses at the first rollout start at or after ``stop_at``, before collecting anything;
    - when `learn` returns (the end of this invocation's budget), unless just written.

    ``next_checkpoint``: the schedule of a resumed run (its checkpoint's); ``obs_names``: the
    names of the model's input entries (`save_agent`; a privileged critic's are longer than its
    agent's observation).
    """

    def __init__(
        self,
        out: Path,
        every: int,
        keep: int,
        metadata: MetadataFn,
        replay_buffer: bool = False,
        state: StateFn | None = None,
        stop_at: int | None = None,
        next_checkpoint: int | None = None,
        obs_names: Sequence[str] | None = None,
    ) -> None:
        super().__init__()
        self.out, self.every, self.keep, self.metadata = out, every, keep, metadata
        self.obs_names = obs_names
        self.replay_buffer, self.state, self.stop_at = replay_buffer, state, stop_at
        self.next_checkpoint = 0
        self._resumed_next = next_checkpoint
        self.last_saved: int | None = None

    def _on_training_start(self) -> None:
        if self._resumed_next is not None:
            self.next_checkpoint = self._resumed_next
        else:
            self.next_checkpoint = _next_multiple(self.num_timesteps, self.every)
        self.last_saved = self.num_timesteps if self._resumed_next is not None else None

    def _on_rollout_start(self) -> None:
        n = self.num_timesteps
        pause = self.stop_at is not None and n >= self.stop_at
        if n >= self.next_checkpoint:
            self.next_checkpoint = _next_multiple(n, self.every)
            self.save("rollout_start")
        elif pause and self.last_saved != n:
            self.save("rollout_start")
        if pause:
            raise PauseTraining(f"paused at {n} env steps (stop_at {self.stop_at})")

    def _on_step(self) -> bool:
        return True

    def _on_training_end(self) -> None:
        if self.last_saved != self.num_timesteps:
            self.save("training_end")

    def save(self, phase: str) -> None:
        """The checkpoint of now, taken at ``phase`` (see `capture_training_state`)."""
        n = self.num_timesteps
        state = None if self.state is None else self.state(phase)
        save_agent(
            self.model,
            self.model.get_vec_normalize_env(),
            checkpoint_folder(self.out, n),
            self.metadata({}),
            replay_buffer=self.replay_buffer,
            training_state=state,
            obs_names=self.obs_names,
        )
        prune_checkpoints(self.out, self.keep)
        self.last_saved = n


class RestoreRandomState(BaseCallback):
    """At the first rollout start of a resumed run, put back the random generators and the
    gSDE noise of a "rollout_start" training state (first in the callback list: SB3 has just
    redrawn the noise there, and the other callbacks see the restored run)."""

    def __init__(self, state: dict[str, Any]) -> None:
        super().__init__()
        self.pending: dict[str, Any] | None = state

    def _on_rollout_start(self) -> None:
        if self.pending is not None:
            restore_random_state(self.model, self.pending)
            self.pending = None

    def _on_step(self) -> bool:
        return True


class UpdateThreads(BaseCallback):
    """torch on ``update`` threads for the gradient updates after each rollout, on ``collect``
    threads while collecting (and after training). Collection alternates the policy's forward
    pass and the env's kernel, one core at a time; the update has both cores to itself."""

    def __init__(self, collect: int, update: int) -> None:
        super().__init__()
        self.collect, self.update = int(collect), int(update)

    def _on_rollout_start(self) -> None:
        import torch

        torch.set_num_threads(self.collect)

    def _on_rollout_end(self) -> None:
        import torch

        torch.set_num_threads(self.update)

    def _on_step(self) -> bool:
        return True

    def _on_training_end(self) -> None:
        self._on_rollout_start()


class AdaptiveUpdateThreads(UpdateThreads):
    """`UpdateThreads` that times every update (from the end of a rollout to the start of the
    next) and keeps the faster of ``candidates`` torch thread counts: the first updates try each,
    then the best known runs, and the other is probed again after `probe_every` updates, an
    interval that doubles (up to `MAX_PROBE_EVERY`) each time the probe loses. Two threads are
    about 1.4x faster on an idle 2-core machine and 15-50x slower when other jobs load the cores;
    the weights are the same bit for bit, so the choice never changes the result."""

    PROBE_EVERY = 10  # [updates]
    MAX_PROBE_EVERY = 640

    def __init__(self, collect: int, candidates: Sequence[int] = (1, 2)) -> None:
        super().__init__(collect, int(candidates[0]))
        self.candidates = list(dict.fromkeys(int(c) for c in candidates))
        self.seconds: dict[int, float] = {}  # the last update's wall time per thread count
        self.probe_every, self.since_probe = self.PROBE_EVERY, 0
        self._started: float | None = None
        self.history: list[tuple[int, float]] = []  # (threads, seconds) of every update

    def _choose(self) -> int:
        untried = [c for c in self.candidates if c not in self.seconds]
        if untried:
            return untried[0]
        best = min(self.candidates, key=self.seconds.__getitem__)
        self.since_probe += 1
        if self.since_probe < self.probe_every or len(self.candidates) == 1:
            return best
        self.since_probe = 0
        return next(c for c in self.candidates if c != best)

    def _on_rollout_end(self) -> None:
        self.update = self._choose()
        super()._on_rollout_end()
        self._started = time.perf_counter()

    def _on_rollout_start(self) -> None:
        if self._started is not None:
            seconds = time.perf_counter() - self._started
            best = min(self.seconds, key=self.seconds.__getitem__) if self.seconds else None
            if (
                best is not None
                and self.update != best
                and len(self.seconds) == len(self.candidates)
            ):  # a probe: a loss backs off, a win resets the interval
                won = seconds < self.seconds[best]
                self.probe_every = (
                    self.PROBE_EVERY if won else min(2 * self.probe_every, self.MAX_PROBE_EVERY)
                )
            self.seconds[self.update] = seconds
            self.history.append((self.update, seconds))
            self._started = None
        super()._on_rollout_start()
