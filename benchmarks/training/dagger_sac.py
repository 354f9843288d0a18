"""Behaviour cloning and DAgger on an SB3 SAC (or sb3-contrib TQC) agent: an off-policy jump start.

The rounds are PPO's (`benchmarks.training.dagger`: the same `collect`, expert, dataset and
shares); what is fitted differs, and the flights are kept:

- **Actor**: least squares of SAC's deterministic action, tanh of the actor's mean (what
  ``predict(obs, deterministic=True)`` gives before the action box's rescaling), on the
  expert's label in the agent's normalised action space [−1, 1]³, ``epochs`` passes of Adam
  (the jump start's ``learning_rate``; SAC's actor optimiser is untouched). The exploration
  parameters, ``log_std`` (a layer without gSDE, a matrix with it), and the entropy coefficient
  stay as built: maximum likelihood would shrink them towards the expert's noiseless commands.
  Both still scale the trunk's features, so the exploration std moves with the fit; every round
  records it (``exploration_std``, mean Gaussian std before the tanh, over the data).
  With gSDE the mean is clipped at ±2 (SB3's ``clip_mean``): a label at the box's edge is
  reached to tanh(2) = 0.964 at best, the floor of the imitation loss there.
- **Critic**: SAC's own TD updates (`model.train`, Polyak targets, twin minimum or TQC's
  truncated quantiles, n-step returns, the entropy term at the built coefficient) on the
  replay buffer, with the actor and the entropy coefficient frozen: ``epochs`` passes over the
  buffer in SAC's ``batch_size`` per round, then the critic is copied into the target networks.
  This, rather than PPO's λ-returns of the actions taken, because SAC's actor learns from the
  critic's action gradient alone (PPO's critic is only a baseline): a critic fitted to
  returns of the expert-mixed behaviour without the entropy term is not the fixed point of
  SAC's update, whose first steps would then move it, and the actor with it. Policy evaluation
  of the jump-started actor with SAC's loss hands SAC a critic its own update keeps, and it is
  SB3's code (TQC's quantile critics come with it). The cost: TD needs many steps to carry
  rewards over γ = 0.995's 200-step horizon, so the critic's level stays below its true value
  for long horizons; its action gradient, set by the nearer rewards, is what the actor needs.
- **Replay buffer**: every flown transition goes into the model's buffer as SAC stores it
  (raw observation and next observation, the terminal one where an episode ended, the action
  taken, scaled to [−1, 1]³, raw reward, done and timeout), a dataset's episodes too, and each
  round's last row is cut (`benchmarks.training.transitions.cut_streams`: the next round's
  envs restart), with the expert's label of every transition (the command DAgger fitted,
  scaled to [−1, 1]³; a dataset's action). The run writes the buffer and the labels beside its
  agents for the next phase (`benchmarks.training.transitions`), whose SAC may keep its actor
  near them (`benchmarks.training.demo_regularization`).

Observation statistics are those of the data, as for PPO: `VecNormalize` learns them while the
rounds fly (and from the dataset first).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from benchmarks.training.dagger import RoundSteps, Segment, float_tensor, run_rounds
from benchmarks.training.jump_start import JumpStart
from benchmarks.training.transitions import LABELS, attach_labels, cut_streams, fill_buffer

__all__ = [
    "EXPLORATION",
    "dataset_stream",
    "deterministic_mse",
    "fit_actor",
    "run_off_policy_jump_start",
    "warm_up_critic",
]

EXPLORATION = "log_std"  # the actor's exploration parameters (SB3's name), never fitted


def deterministic_mse(actor: Any, normed: np.ndarray, targets: np.ndarray, chunk: int = 8192):
    """(mean squared error of tanh(actor mean) against ``targets``, per action entry; mean
    exploration std before the tanh) at the normalised observations ``normed``."""
    import torch

    total, spread = 0.0, 0.0
    with torch.no_grad():
        for k in range(0, len(normed), chunk):
            mean, log_std, extra = actor.get_action_dist_params(float_tensor(normed[k : k + chunk]))
            total += float(((torch.tanh(mean) - float_tensor(targets[k : k + chunk])) ** 2).sum())
            dist = actor.action_dist.proba_distribution(mean, log_std, **extra).distribution
            spread += float(dist.stddev.sum())
    size = max(1, targets.size)
    return total / size, spread / size


def fit_actor(
    model: Any,
    venv: Any,
    segments: Sequence[Segment],
    jump: JumpStart,
    optimizer: Any,
    rng: np.random.Generator,
) -> dict[str, float]:
    """``jump.epochs`` passes of minibatch Adam over ``segments``: least squares of tanh of the
    actor's mean on the labels scaled to [−1, 1]³ (module doc). Returns the losses around it."""
    import torch

    actor = model.actor
    obs = np.concatenate([s.obs for s in segments])
    targets = model.policy.scale_action(np.concatenate([s.labels for s in segments]))
    normed = venv.normalize_obs(obs).astype(np.float32)
    before, std_before = deterministic_mse(actor, normed, targets)
    n = len(normed)
    size = min(jump.batch_size, n)
    model.policy.set_training_mode(True)
    for _ in range(jump.epochs):
        order = rng.permutation(n)
        for k in range(0, n - size + 1, size):
            rows = order[k : k + size]
            mean, _, _ = actor.get_action_dist_params(float_tensor(normed[rows]))
            loss = ((torch.tanh(mean) - float_tensor(targets[rows])) ** 2).mean()
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
    model.policy.set_training_mode(False)
    after, std_after = deterministic_mse(actor, normed, targets)
    return {
        "samples": float(n),
        "imitation_mse_before": before,
        "imitation_mse": after,
        "exploration_std_before": std_before,
        "exploration_std": std_after,
    }


def warm_up_critic(model: Any, epochs: int) -> dict[str, float]:
    """``epochs`` passes of SAC's own updates over the replay buffer with the actor and the
    entropy coefficient frozen, then the critic copied into its targets (module doc). Returns
    SAC's critic loss over the first and the last pass."""
    import torch

    buffer = model.replay_buffer
    steps = max(1, buffer.size() * buffer.n_envs // model.batch_size)
    actor = [(p, p.requires_grad) for p in model.actor.parameters()]
    had_tensor = hasattr(model, "ent_coef_tensor")
    optimizer = model.ent_coef_optimizer
    losses = []
    try:
        for p, _ in actor:  # its loss still runs in `train`; with no gradient Adam skips it
            p.requires_grad_(False)
        if optimizer is not None:  # a fixed coefficient, as `train` reads one
            model.ent_coef_tensor = torch.exp(model.log_ent_coef.detach())
            model.ent_coef_optimizer = None
        for _ in range(epochs):
            model.train(gradient_steps=steps, batch_size=model.batch_size)
            losses.append(float(model.logger.name_to_value["train/critic_loss"]))
    finally:
        for p, flag in actor:
            p.requires_grad_(flag)
        if optimizer is not None:
            model.ent_coef_optimizer = optimizer
            if not had_tensor:
                del model.ent_coef_tensor
    model.critic_target.load_state_dict(model.critic.state_dict())
    model.policy.set_training_mode(False)
    return {
        "critic_steps": steps * epochs,
        "critic_loss_first": losses[0],
        "critic_loss": losses[-1],
    }


def dataset_stream(episodes: Sequence[dict[str, Any]], policy: Any) -> dict[str, np.ndarray]:
    """A dataset's episodes (`benchmarks.training.demonstrations.read_dataset`) as one flat
    stream of transitions (`benchmarks.training.transitions`), actions scaled to [−1, 1]³ and
    labelled with themselves (the expert flew them)."""
    parts: dict[str, list[np.ndarray]] = {key: [] for key in _STREAM}
    for episode in episodes:
        obs = np.asarray(episode["observations"], dtype=np.float32)
        steps = len(episode["rewards"])
        terminated = np.asarray(episode["terminations"], dtype=bool)[:steps]
        truncated = np.asarray(episode["truncations"], dtype=bool)[:steps]
        ends = np.zeros(steps, dtype=bool)
        ends[-1] = True
        parts["observations"].append(obs[:-1])
        parts["next_observations"].append(obs[1:])
        parts["actions"].append(policy.scale_action(np.asarray(episode["actions"], np.float32)))
        parts[LABELS].append(parts["actions"][-1])  # the expert's own command
        parts["rewards"].append(np.asarray(episode["rewards"], dtype=np.float32))
        parts["dones"].append(terminated | truncated)
        parts["timeouts"].append(truncated & ~terminated)  # SB3's TimeLimit.truncated
        parts["breaks"].append(ends)
    return {key: np.concatenate(values) for key, values in parts.items()}


_STREAM = (
    "observations",
    "next_observations",
    "actions",
    "rewards",
    "dones",
    "timeouts",
    "breaks",
    LABELS,
)


def _sampler(model: Any, n: int) -> Callable[[np.ndarray, int], np.ndarray]:
    """The learner's sampled actions as SAC's rollouts draw them: with gSDE, a new noise matrix
    per vehicle where SAC draws one (each rollout of ``train_freq`` steps starts one, and every
    ``sde_sample_freq`` steps in it)."""
    from stable_baselines3.common.type_aliases import TrainFrequencyUnit

    train_freq = model.train_freq
    per = train_freq.frequency if train_freq.unit == TrainFrequencyUnit.STEP else None
    every = model.sde_sample_freq

    def sample(obs: np.ndarray, t: int) -> np.ndarray:
        if model.use_sde:
            k = t % per if per else t
            if t == 0 or k == 0 or (every > 0 and k % every == 0):
                model.actor.reset_noise(n)
        action, _ = model.policy.predict(obs, deterministic=False)
        return action

    return sample


def _recorder(model: Any, venv: Any) -> Callable[..., None]:
    """`collect`'s ``record``: every vector step into the replay buffer, as SAC's
    ``_store_transition`` stores it (the terminal observation as the next one where an episode
    ended, un-normalised from VecNormalize's info), and the expert's labels, scaled, into the
    buffer's ``labels`` at the same row."""
    buffer = model.replay_buffer

    def record(obs, action, reward, next_obs, dones, infos, labels) -> None:
        following = np.array(next_obs, dtype=np.float32)
        for i in np.flatnonzero(dones):
            if infos[i].get("terminal_observation") is not None:
                following[i] = venv.unnormalize_obs(infos[i]["terminal_observation"])
        scaled = model.policy.scale_action(np.asarray(action, dtype=np.float32))
        buffer.labels[buffer.pos] = model.policy.scale_action(np.asarray(labels, np.float32))
        buffer.add(obs, following, scaled, reward, dones, infos)

    return record


def run_off_policy_jump_start(
    model: Any,
    venv: Any,
    cfg: Any,
    env_id: str,
    seed: int,
    evaluate: Callable[[], None] | None = None,
    progress: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """`dagger.run_rounds` on ``model`` (a fresh SAC or TQC) and ``venv`` (its `VecNormalize`):
    the actor fitted (`fit_actor`), the critic warmed up (`warm_up_critic`), the flights kept in
    ``model.replay_buffer`` with the expert's labels (module doc). Returns the metadata record."""
    buffer = model.replay_buffer

    def make_steps(jump: JumpStart) -> RoundSteps:
        attach_labels(buffer)

        def fit(data: list[Segment], optimizer: Any, rng: np.random.Generator) -> dict:
            losses = fit_actor(model, venv, data, jump, optimizer, rng)
            if jump.value and buffer.size() > 0:
                losses.update(warm_up_critic(model, jump.epochs))
            return losses

        def describe(losses: dict[str, float]) -> str:
            critic = f", critic loss {losses['critic_loss']:.4g}" if "critic_loss" in losses else ""
            return f", exploration std {losses['exploration_std']:.3f}{critic}"

        return RoundSteps(
            parameters=[
                p for name, p in model.actor.named_parameters() if name.split(".")[0] != EXPLORATION
            ],
            fit=fit,
            describe=describe,
            add_dataset=lambda demos: fill_buffer(
                buffer, dataset_stream(demos.episodes, model.policy)
            ),
            sample=_sampler(model, venv.num_envs),
            record=_recorder(model, venv),
            after_collect=lambda: cut_streams(buffer),
            entry_extras=lambda: {"replay_transitions": int(buffer.size() * venv.num_envs)},
        )

    return run_rounds(model, venv, cfg, env_id, seed, make_steps, evaluate, progress)
