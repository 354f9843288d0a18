r"""A critic that sees the true path errors, an actor that does not (docs/design.md §3.24).

With the sensors modelled, the agent observes the errors of the navigation's estimate ê while
the reward is charged on the true errors e (`auv_gym.sim.navigation`): a critic given only what
the actor sees must predict a return whose largest term it cannot observe, and the advantage of
every action carries that noise. An asymmetric actor-critic (Pinto et al., "Asymmetric Actor
Critic for Image-Based Robot Learning", RSS 2018) gives the critic privileged inputs that exist
only in simulation; the actor, the part that flies, keeps the vehicle's own.

In training the residual agent's observation (`benchmarks.training.residual_env`) is followed by
`PRIVILEGED_NAMES`, the true x_e, y_e, z_e [m] of the env's ``info``; `PrivilegedCriticPolicy`
reads the first ``public_dim`` entries in the actor and all of them in the critic. An agent is
saved as the actor alone (`deployable`): an ordinary `ActorCriticPolicy` over the public
observation, its actor's weights copied exactly, its critic the privileged one's with the
privileged inputs at their running mean (normalised 0), and the observation statistics of the
public entries. So every loader, the ONNX export and the ensembles read it as any agent, and no
deployed policy can read the truth. Checkpoints keep the whole model, so a run resumes exactly.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import torch
from gymnasium import spaces
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.running_mean_std import RunningMeanStd
from stable_baselines3.common.torch_layers import MlpExtractor

from benchmarks.training.residual import PRIVILEGED_NAMES

__all__ = [
    "PRIVILEGED_NAMES",
    "PrivilegedCriticPolicy",
    "PrivilegedMlpExtractor",
    "deployable",
    "is_privileged",
    "widen_for_privileged_critic",
]

# The critic's first layer, the only weights whose shape the privileged inputs change: its
# network's first layer, or with no hidden layers for the critic (net_arch's vf: []) its output.
_CRITIC_INPUTS = ("mlp_extractor.value_net.0.weight", "value_net.weight")


def _critic_input(state: dict[str, Any]) -> str:
    """The key of the critic's first layer in a policy's ``state``."""
    return next(key for key in _CRITIC_INPUTS if key in state)


class PrivilegedMlpExtractor(MlpExtractor):
    """`MlpExtractor` whose policy network reads the first ``public_dim`` features and whose
    value network reads all ``feature_dim`` of them."""

    def __init__(
        self,
        feature_dim: int,
        public_dim: int,
        net_arch: list[int] | dict[str, list[int]],
        activation_fn: type[torch.nn.Module],
        device: torch.device | str = "auto",
    ) -> None:
        super().__init__(feature_dim, net_arch, activation_fn, device)
        self.public_dim = int(public_dim)
        actor = MlpExtractor(self.public_dim, net_arch, activation_fn, device)
        self.policy_net = actor.policy_net

    def forward(self, features: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.forward_actor(features), self.forward_critic(features)

    def forward_actor(self, features: torch.Tensor) -> torch.Tensor:
        return self.policy_net(features[..., : self.public_dim])


class PrivilegedCriticPolicy(ActorCriticPolicy):
    """PPO's actor-critic with the critic alone reading the observation's last entries
    (``public_dim``: how many entries the actor reads; the rest are privileged)."""

    def __init__(self, *args: Any, public_dim: int, **kwargs: Any) -> None:
        self.public_dim = int(public_dim)
        super().__init__(*args, **kwargs)

    def _build_mlp_extractor(self) -> None:
        full = int(self.features_dim)
        if not 0 < self.public_dim < full:
            raise ValueError(
                f"public_dim must lie between 1 and {full - 1} (the observation has {full} "
                f"entries, the privileged ones among them), got {self.public_dim}"
            )
        self.mlp_extractor = PrivilegedMlpExtractor(
            self.features_dim,
            self.public_dim,
            net_arch=self.net_arch,
            activation_fn=self.activation_fn,
            device=self.device,
        )

    def _get_constructor_parameters(self) -> dict[str, Any]:
        return {**super()._get_constructor_parameters(), "public_dim": self.public_dim}


def is_privileged(model: Any) -> bool:
    """Whether ``model``'s policy is a `PrivilegedCriticPolicy`."""
    return isinstance(getattr(model, "policy", None), PrivilegedCriticPolicy)


def _public_space(space: spaces.Box, dim: int) -> spaces.Box:
    return spaces.Box(space.low[:dim], space.high[:dim], dtype=space.dtype)


def _public_kwargs(model: Any) -> dict[str, Any]:
    """``model``'s policy keywords as an ordinary `ActorCriticPolicy` takes them."""
    return {k: v for k, v in model.policy_kwargs.items() if k != "public_dim"}


def _public_policy(model: Any) -> ActorCriticPolicy:
    """The plain `ActorCriticPolicy` over the public observation with the actor's weights (and
    the critic's at privileged inputs normalised to 0)."""
    source = model.policy
    dim = source.public_dim
    policy = ActorCriticPolicy(
        _public_space(source.observation_space, dim),
        source.action_space,
        model.lr_schedule,
        use_sde=model.use_sde,
        **_public_kwargs(model),
    )
    state = source.state_dict()
    critic = _critic_input(state)  # the privileged columns dropped: their normalised inputs at 0
    state[critic] = state[critic][:, :dim].clone()
    policy.load_state_dict(state)
    policy.set_training_mode(False)
    return policy


def _public_normalization(vec_normalize: Any, dim: int) -> Any:
    """A copy of ``vec_normalize`` whose observation statistics and space are the public
    entries' (the running copy keeps training)."""
    public = object.__new__(type(vec_normalize))  # its pickling drops what copy.copy needs
    public.__dict__.update(vec_normalize.__dict__)
    rms = vec_normalize.obs_rms
    stats = RunningMeanStd(shape=(dim,))
    stats.mean = np.array(rms.mean[:dim], dtype=np.float64)
    stats.var = np.array(rms.var[:dim], dtype=np.float64)
    stats.count = rms.count
    public.obs_rms = stats
    public.observation_space = _public_space(vec_normalize.observation_space, dim)
    return public


def deployable(model: Any, vec_normalize: Any) -> tuple[Any, Any]:
    """(model, VecNormalize) as an agent is saved and evaluated: unchanged for an ordinary
    policy; for a `PrivilegedCriticPolicy`, a shallow copy of the algorithm holding the public
    policy (module doc) and the public entries' statistics. The copy saves and predicts; it
    is not for training."""
    if not is_privileged(model):
        return model, vec_normalize
    dim = model.policy.public_dim
    public = copy.copy(model)
    public.policy = _public_policy(model)
    public.policy_class = ActorCriticPolicy
    public.policy_kwargs = _public_kwargs(model)
    public.observation_space = public.policy.observation_space
    public._last_obs = None  # a learn() would start from a reset, not a privileged observation
    return public, _public_normalization(vec_normalize, dim)


def widen_for_privileged_critic(model: Any, state: dict[str, Any]) -> None:
    """Load a saved agent's policy ``state`` (`controllers.agent.read_policy_state` of its
    model.zip: an `ActorCriticPolicy` over the public observation) into ``model``'s
    `PrivilegedCriticPolicy`: every weight as saved, the critic's first layer widened by zero
    columns for the privileged inputs. The optimiser's state is not loaded (the widened layer's
    moments have no saved counterpart)."""
    state = dict(state)
    target = model.policy.state_dict()
    critic = _critic_input(target)
    if critic in state:  # else load_state_dict names what is missing
        weight = state[critic]
        extra = target[critic].shape[1] - weight.shape[1]
        if extra != len(PRIVILEGED_NAMES):
            raise ValueError(
                f"the saved critic reads {weight.shape[1]} entries, this run's "
                f"{target[critic].shape[1]} with {len(PRIVILEGED_NAMES)} privileged"
            )
        state[critic] = torch.cat([weight, weight.new_zeros(weight.shape[0], extra)], 1)
    model.policy.load_state_dict(state, strict=True)
