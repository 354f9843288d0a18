"""`DemoSAC`: SB3's SAC with the demonstration terms of `benchmarks.training.demo_regularization`.

`DemoSAC.train` is stable-baselines3 2.9's ``SAC.train`` line for line, with four additions
marked ``# demo:`` (the settings and their units: `benchmarks.training.demo_regularization`):

- the batch: a share ``demo_share`` drawn from the demonstrations' own n-step buffer, the rest
  from the replay buffer (RLPD's symmetric sampling; none at 0);
- the actor delay: no actor or entropy-coefficient step before ``actor_delay`` env steps;
- the behaviour-cloning term β·mean|Q|·MSE(tanh μ(s_d), a_d) added to the actor loss, on
  ``bc_batch_size`` demonstration states drawn with numpy's global generator (as SB3 draws its
  batches: a checkpoint's training state holds it, so a resumed run continues exactly);
- its log: ``train/bc_loss``, ``train/bc_weight``.

Without demonstrations attached (`attach_demonstrations`), or with β = 0, no delay and no share,
it updates bit for bit as ``SAC.train`` (tests/test_demo_sac.py). The demonstrations are not
saved with the model (`_excluded_save_params`): its zip is a plain SAC's, loaded by ``SAC.load``
and ``controllers.make("agent", path=...)``; a resumed run attaches them again.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import torch as th
from stable_baselines3 import SAC
from stable_baselines3.common.type_aliases import ReplayBufferSamples
from stable_baselines3.common.utils import polyak_update
from torch.nn import functional as F

from benchmarks.training.demo_regularization import DemoRegularization
from benchmarks.training.transitions import LABELS, fill_buffer

__all__ = ["DemoSAC", "Demonstrations"]


class Demonstrations:
    """The demonstration data of a run: raw observations (n, d) and the expert's labels (n, 3)
    in [−1, 1]³, and with ``demo_share`` an n-step replay buffer of the transitions (one
    column: the stream's breaks cut its n-step returns, `benchmarks.training.transitions`)."""

    def __init__(self, model: Any, settings: DemoRegularization, stream: Mapping[str, Any]):
        self.settings = settings
        self.observations = np.asarray(stream["observations"], dtype=np.float32)
        self.labels = np.asarray(stream[LABELS], dtype=np.float32)
        self.buffer = None
        if settings.demo_share > 0:
            kwargs = dict(model.replay_buffer_kwargs)
            self.buffer = model.replay_buffer_class(
                len(self.labels),
                model.observation_space,
                model.action_space,
                device=model.device,
                n_envs=1,
                optimize_memory_usage=False,
                **kwargs,
            )
            fill_buffer(self.buffer, stream)

    def __len__(self) -> int:
        return len(self.labels)


def _concatenate(first: ReplayBufferSamples, second: ReplayBufferSamples) -> ReplayBufferSamples:
    return ReplayBufferSamples(
        *(None if a is None else th.cat([a, b]) for a, b in zip(first, second, strict=True))
    )


class DemoSAC(SAC):
    """SAC whose update keeps its actor near demonstrations (module doc)."""

    demonstrations: Demonstrations | None = None

    def attach_demonstrations(
        self, settings: DemoRegularization, stream: Mapping[str, Any]
    ) -> Demonstrations:
        """Train with ``settings`` on the labelled transitions ``stream``
        (`benchmarks.training.transitions.read_transitions`, with labels)."""
        self.demonstrations = Demonstrations(self, settings, stream)
        return self.demonstrations

    def _excluded_save_params(self) -> list[str]:
        return [*super()._excluded_save_params(), "demonstrations"]

    def _demo_batch(self, size: int) -> tuple[th.Tensor, th.Tensor]:
        """``size`` demonstration states (normalised as SB3 normalises its batches) and labels."""
        demos = self.demonstrations
        rows = np.random.randint(0, len(demos), size=size)  # noqa: NPY002 - SB3's generator
        obs = demos.observations[rows]
        if self._vec_normalize_env is not None:
            obs = self._vec_normalize_env.normalize_obs(obs)
        return (
            th.as_tensor(np.asarray(obs, dtype=np.float32), device=self.device),
            th.as_tensor(demos.labels[rows], device=self.device),
        )

    def train(self, gradient_steps: int, batch_size: int = 64) -> None:
        demos = self.demonstrations  # demo:
        settings = demos.settings if demos is not None else DemoRegularization(bc_weight=0.0)
        bc_weight = settings.weight(self.num_timesteps)
        actor_frozen = self.num_timesteps < settings.actor_delay
        demo_size = (
            0 if demos is None else min(batch_size - 1, round(settings.demo_share * batch_size))
        )
        bc_size = settings.bc_batch_size or batch_size
        bc_losses = []
        # Switch to train mode (this affects batch norm / dropout)
        self.policy.set_training_mode(True)
        # Update optimizers learning rate
        optimizers = [self.actor.optimizer, self.critic.optimizer]
        if self.ent_coef_optimizer is not None:
            optimizers += [self.ent_coef_optimizer]

        # Update learning rate according to lr schedule
        self._update_learning_rate(optimizers)

        ent_coef_losses, ent_coefs = [], []
        actor_losses, critic_losses = [], []

        for gradient_step in range(gradient_steps):
            # Sample replay buffer
            if demo_size > 0:  # demo: the demonstrations' share of the batch (RLPD)
                online = self.replay_buffer.sample(
                    batch_size - demo_size, env=self._vec_normalize_env
                )  # type: ignore[union-attr]
                demo = demos.buffer.sample(demo_size, env=self._vec_normalize_env)
                replay_data = _concatenate(online, demo)
            else:
                replay_data = self.replay_buffer.sample(batch_size, env=self._vec_normalize_env)  # type: ignore[union-attr]
            # For n-step replay, discount factor is gamma**n_steps (when no early termination)
            discounts = replay_data.discounts if replay_data.discounts is not None else self.gamma

            # We need to sample because `log_std` may have changed between two gradient steps
            if self.use_sde:
                self.actor.reset_noise()

            # Action by the current actor for the sampled state
            actions_pi, log_prob = self.actor.action_log_prob(replay_data.observations)
            log_prob = log_prob.reshape(-1, 1)

            ent_coef_loss = None
            if self.ent_coef_optimizer is not None and self.log_ent_coef is not None:
                # Important: detach the variable from the graph
                # so we don't change it with other losses
                # see https://github.com/rail-berkeley/softlearning/issues/60
                ent_coef = th.exp(self.log_ent_coef.detach())
                assert isinstance(self.target_entropy, float)
                ent_coef_loss = -(
                    self.log_ent_coef * (log_prob + self.target_entropy).detach()
                ).mean()
                ent_coef_losses.append(ent_coef_loss.item())
            else:
                ent_coef = self.ent_coef_tensor

            ent_coefs.append(ent_coef.item())

            # Optimize entropy coefficient, also called
            # entropy temperature or alpha in the paper
            if (
                ent_coef_loss is not None
                and self.ent_coef_optimizer is not None
                and not actor_frozen
            ):  # demo: delay
                self.ent_coef_optimizer.zero_grad()
                ent_coef_loss.backward()
                self.ent_coef_optimizer.step()

            with th.no_grad():
                # Select action according to policy
                next_actions, next_log_prob = self.actor.action_log_prob(
                    replay_data.next_observations
                )
                # Compute the next Q values: min over all critics targets
                next_q_values = th.cat(
                    self.critic_target(replay_data.next_observations, next_actions), dim=1
                )
                next_q_values, _ = th.min(next_q_values, dim=1, keepdim=True)
                # add entropy term
                next_q_values = next_q_values - ent_coef * next_log_prob.reshape(-1, 1)
                # td error + entropy term
                target_q_values = (
                    replay_data.rewards + (1 - replay_data.dones) * discounts * next_q_values
                )

            # Get current Q-values estimates for each critic network
            # using action from the replay buffer
            current_q_values = self.critic(replay_data.observations, replay_data.actions)

            # Compute critic loss
            critic_loss = 0.5 * sum(
                F.mse_loss(current_q, target_q_values) for current_q in current_q_values
            )
            assert isinstance(critic_loss, th.Tensor)  # for type checker
            critic_losses.append(critic_loss.item())  # type: ignore[union-attr]

            # Optimize the critic
            self.critic.optimizer.zero_grad()
            critic_loss.backward()
            self.critic.optimizer.step()

            # Compute actor loss
            # Alternative: actor_loss = th.mean(log_prob - qf1_pi)
            # Min over all critic networks
            q_values_pi = th.cat(self.critic(replay_data.observations, actions_pi), dim=1)
            min_qf_pi, _ = th.min(q_values_pi, dim=1, keepdim=True)
            actor_loss = (ent_coef * log_prob - min_qf_pi).mean()
            actor_losses.append(actor_loss.item())
            if bc_weight > 0 and not actor_frozen:  # demo: the behaviour-cloning term (TD3+BC)
                demo_obs, labels = self._demo_batch(bc_size)
                mean, _, _ = self.actor.get_action_dist_params(demo_obs)
                bc_loss = ((th.tanh(mean) - labels) ** 2).mean()
                bc_losses.append(bc_loss.item())
                actor_loss = actor_loss + bc_weight * min_qf_pi.abs().mean().detach() * bc_loss

            # Optimize the actor
            if not actor_frozen:  # demo: delay
                self.actor.optimizer.zero_grad()
                actor_loss.backward()
                self.actor.optimizer.step()

            # Update target networks
            if gradient_step % self.target_update_interval == 0:
                polyak_update(self.critic.parameters(), self.critic_target.parameters(), self.tau)
                # Copy running stats, see GH issue #996
                polyak_update(self.batch_norm_stats, self.batch_norm_stats_target, 1.0)

        self._n_updates += gradient_steps

        self.logger.record("train/n_updates", self._n_updates, exclude="tensorboard")
        self.logger.record("train/ent_coef", np.mean(ent_coefs))
        self.logger.record("train/actor_loss", np.mean(actor_losses))
        self.logger.record("train/critic_loss", np.mean(critic_losses))
        if len(ent_coef_losses) > 0:
            self.logger.record("train/ent_coef_loss", np.mean(ent_coef_losses))
        if demos is not None:  # demo: its log
            self.logger.record("train/bc_weight", bc_weight)
            if bc_losses:
                self.logger.record("train/bc_loss", np.mean(bc_losses))
