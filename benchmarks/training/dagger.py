"""Behaviour cloning and DAgger on an SB3 PPO policy: the work of a jump start.

`run_jump_start` runs the rounds of a `benchmarks.training.jump_start.JumpStart` on a freshly
built model and its training env (`VecNormalize` over the agent's stages and action box, as PPO
would train in it), written directly in torch on the policy: the `imitation` package's releases
pin Gymnasium 0.29 and stable-baselines3 2.2 (see `jump_start`).

Data are kept raw (the agent's observation before `VecNormalize`, the env's reward) and
normalised with the current statistics when fitted, so data of every round meet one
normalisation. Each stream of consecutive steps of one vehicle is a `Segment`; the critic's
targets are λ-returns along it, bootstrapped with the critic's value of the last observation
where an episode was truncated or the data stop mid-episode, 0 where it terminated.

SAC and TQC have their own fitting and hand their flights on in a replay buffer
(`benchmarks.training.dagger_sac`), flown and labelled by the same `collect`.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from benchmarks.training.expert import ExpertLabels
from benchmarks.training.jump_start import JumpStart

__all__ = [
    "RoundSteps",
    "Segment",
    "collect",
    "dataset_segments",
    "fit",
    "float_tensor",
    "imitation_mse",
    "run_jump_start",
    "run_rounds",
]


@dataclass
class Segment:
    """Consecutive steps of one vehicle: raw observations (T, d), labels (T, 3), raw rewards
    (T,), ``ends`` (T,) where an episode ended after the step, and ``next_obs``: the raw
    observation after step t where the λ-return is bootstrapped there (truncated episodes; the
    last step when the data stop mid-episode)."""

    obs: np.ndarray
    labels: np.ndarray
    rewards: np.ndarray
    ends: np.ndarray
    next_obs: dict[int, np.ndarray] = field(default_factory=dict)


def dataset_segments(episodes: Sequence[dict[str, Any]]) -> list[Segment]:
    """One segment per recorded episode (`benchmarks.training.demonstrations.read_dataset`)."""
    segments = []
    for episode in episodes:
        obs = np.asarray(episode["observations"], dtype=np.float32)
        steps = len(episode["rewards"])
        ends = np.zeros(steps, dtype=bool)
        ends[-1] = True
        truncated = bool(episode["truncations"][-1]) and not bool(episode["terminations"][-1])
        segments.append(
            Segment(
                obs[:-1],
                np.asarray(episode["actions"], dtype=np.float32),
                np.asarray(episode["rewards"], dtype=np.float64),
                ends,
                {steps - 1: obs[-1]} if truncated else {},
            )
        )
    return segments


def learn_statistics(venv: Any, segments: Sequence[Segment]) -> None:
    """Update ``venv``'s observation and return statistics with recorded segments, as
    `VecNormalize` would have while they were flown (the discounted return restarts with
    each episode)."""
    venv.obs_rms.update(np.concatenate([s.obs for s in segments]).astype(np.float64))
    returns = []
    for segment in segments:
        running = 0.0
        for reward, end in zip(segment.rewards, segment.ends, strict=True):
            running = running * venv.gamma + float(reward)
            returns.append(running)
            if end:
                running = 0.0
    venv.ret_rms.update(np.asarray(returns, dtype=np.float64))


def collect(
    model: Any,
    venv: Any,
    expert: ExpertLabels,
    steps: int,
    share: float,
    rng: np.random.Generator,
    sample: Callable[[np.ndarray, int], np.ndarray] | None = None,
    record: Callable[..., None] | None = None,
) -> list[Segment]:
    """Fly ``steps`` env steps (whole vector steps) in ``venv`` (a `VecNormalize`, training):
    each vehicle's action is the expert's (probability ``share``) or the learner's sampled
    action; every visited state is labelled with the expert's action. One segment per vehicle.

    ``sample(obs, t)``: the learner's actions at the normalised observations of vector step t
    (default: the policy's sampled action); ``record(obs, action, reward, next_obs, dones,
    infos, labels)``, if given, sees every vector step (raw observations and rewards, the
    expert's labels)."""
    n = venv.num_envs
    horizon = max(1, steps // n)
    obs = venv.reset()
    raw = venv.get_original_obs()
    dim = raw.shape[1]
    observations = np.empty((horizon, n, dim), dtype=np.float32)
    labels = np.empty((horizon, n, 3), dtype=np.float32)
    rewards = np.empty((horizon, n), dtype=np.float64)
    ends = np.zeros((horizon, n), dtype=bool)
    next_obs: list[dict[int, np.ndarray]] = [{} for _ in range(n)]
    starts = np.ones(n, dtype=bool)
    for t in range(horizon):
        label = expert.label(raw, starts)
        if share >= 1.0:
            action = label
        else:
            if sample is None:
                learner, _ = model.policy.predict(obs, deterministic=False)
            else:
                learner = sample(obs, t)
            pick = rng.random(n) < share
            action = np.where(pick[:, None], label, learner).astype(np.float32)
        observations[t], labels[t] = raw, label
        obs, _, dones, infos = venv.step(action)
        rewards[t] = venv.get_original_reward()
        ends[t] = dones
        for i in np.flatnonzero(dones):
            if infos[i].get("TimeLimit.truncated", False):  # bootstrapped from its last state
                next_obs[i][t] = venv.unnormalize_obs(infos[i]["terminal_observation"])
        raw = venv.get_original_obs()
        if record is not None:
            record(observations[t], action, rewards[t], raw, dones, infos, labels[t])
        starts = np.asarray(dones, dtype=bool)
    for i in np.flatnonzero(~ends[-1]):  # the data stop mid-episode
        next_obs[i][horizon - 1] = raw[i].copy()
    return [
        Segment(observations[:, i], labels[:, i], rewards[:, i], ends[:, i], next_obs[i])
        for i in range(n)
    ]


def float_tensor(array: np.ndarray) -> Any:
    """``array`` as a float32 torch tensor."""
    import torch

    return torch.as_tensor(np.asarray(array, dtype=np.float32))


def _values(policy: Any, normed: np.ndarray, chunk: int = 8192) -> np.ndarray:
    import torch

    out = []
    with torch.no_grad():
        for k in range(0, len(normed), chunk):
            out.append(policy.predict_values(float_tensor(normed[k : k + chunk])).numpy().ravel())
    return np.concatenate(out) if out else np.zeros(0)


def lambda_returns(
    policy: Any, venv: Any, segments: Sequence[Segment], gamma: float, lam: float
) -> np.ndarray:
    """The critic's targets for every step of ``segments`` (in order): λ-returns of the
    normalised rewards with the current critic (module doc)."""
    targets = []
    for segment in segments:
        values = _values(policy, venv.normalize_obs(segment.obs))
        rewards = venv.normalize_reward(segment.rewards)
        boot = {}
        if segment.next_obs:
            keys = sorted(segment.next_obs)
            ends = _values(
                policy, venv.normalize_obs(np.stack([segment.next_obs[k] for k in keys]))
            )
            boot = dict(zip(keys, ends, strict=True))
        advantage = 0.0
        result = np.empty(len(values))
        for t in range(len(values) - 1, -1, -1):
            if t in boot:
                next_value, carry = boot[t], not segment.ends[t]
            elif segment.ends[t]:
                next_value, carry = 0.0, False
            else:
                next_value, carry = values[t + 1], True
            delta = rewards[t] + gamma * next_value - values[t]
            advantage = delta + (gamma * lam * advantage if carry else 0.0)
            result[t] = advantage + values[t]
        targets.append(result)
    return np.concatenate(targets)


def imitation_mse(policy: Any, normed: np.ndarray, labels: np.ndarray, chunk: int = 8192) -> float:
    """Mean squared error of the actor's mean action against the labels (per action entry)."""
    import torch

    total = 0.0
    with torch.no_grad():
        for k in range(0, len(normed), chunk):
            mean = _mean_action(policy, float_tensor(normed[k : k + chunk]))
            total += float(((mean - float_tensor(labels[k : k + chunk])) ** 2).sum())
    return total / max(1, labels.size)


def _mean_action(policy: Any, obs: Any) -> Any:
    return policy.get_distribution(obs).distribution.mean


def fit(
    policy: Any,
    venv: Any,
    segments: Sequence[Segment],
    jump: JumpStart,
    optimizer: Any,
    gamma: float,
    lam: float,
    rng: np.random.Generator,
) -> dict[str, float]:
    """``jump.epochs`` passes of minibatch Adam over ``segments``: least squares of the actor's
    mean action on the labels, plus (``jump.value``) of the critic on the λ-returns (computed
    at the start of each pass with the critic as it is then). Returns the losses after it."""
    import torch

    obs = np.concatenate([s.obs for s in segments])
    labels = np.concatenate([s.labels for s in segments])
    normed = venv.normalize_obs(obs).astype(np.float32)
    before = imitation_mse(policy, normed, labels)
    n = len(normed)
    size = min(jump.batch_size, n)
    returns = None
    for _ in range(jump.epochs):
        if jump.value:  # the targets follow the critic (fitted value iteration)
            returns = lambda_returns(policy, venv, segments, gamma, lam)
        policy.set_training_mode(True)
        order = rng.permutation(n)
        for k in range(0, n - size + 1, size):
            rows = order[k : k + size]
            x = float_tensor(normed[rows])
            loss = ((_mean_action(policy, x) - float_tensor(labels[rows])) ** 2).mean()
            if returns is not None:
                value = policy.predict_values(x).flatten()
                loss = loss + ((value - float_tensor(returns[rows])) ** 2).mean()
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
    policy.set_training_mode(False)
    result = {"samples": float(n), "imitation_mse_before": before}
    result["imitation_mse"] = imitation_mse(policy, normed, labels)
    if returns is not None:
        with torch.no_grad():
            values = _values(policy, normed)
        result["value_mse"] = float(np.mean((values - returns) ** 2))
    return result


@dataclass(frozen=True)
class RoundSteps:
    """What an algorithm does in the rounds `run_rounds` shares: PPO's (`ppo_round_steps`) or
    SAC's (`benchmarks.training.dagger_sac`)."""

    parameters: list[Any]  # what the imitation optimiser trains
    fit: Callable[[list[Segment], Any, np.random.Generator], dict[str, float]]  # data, Adam, rng
    describe: Callable[[dict[str, float]], str]  # the progress line's tail, from the losses
    add_dataset: Callable[[Any], None] = lambda demos: None  # after the statistics learnt it
    sample: Callable[[np.ndarray, int], np.ndarray] | None = None  # `collect`'s
    record: Callable[..., None] | None = None  # `collect`'s
    after_collect: Callable[[], None] = lambda: None
    entry_extras: Callable[[], dict[str, Any]] = dict  # added to each round's record


def run_rounds(
    model: Any,
    venv: Any,
    cfg: Any,
    env_id: str,
    seed: int,
    make_steps: Callable[[JumpStart], RoundSteps],
    evaluate: Callable[[], None] | None = None,
    progress: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """The jump start of ``cfg`` (a `ZooConfig` with ``jump_start``) on ``model`` (fresh) and
    ``venv`` (its `VecNormalize`): the dataset first, round 0 (the expert's share 1), then
    DAgger's rounds, each fitted by ``make_steps(jump)``'s algorithm, ``evaluate()`` after each
    (the run's validation: learning curve and best agent). ``model.num_timesteps`` counts the
    dataset's steps and the steps flown. Returns the record for the agent's metadata."""
    import torch

    from benchmarks.training.demonstrations import DemoSource, read_dataset

    jump: JumpStart = cfg.jump_start
    began = time.monotonic()
    source = DemoSource(env_id, dict(cfg.env_kwargs), tuple(cfg.stages), cfg.action_bounds)
    rng = np.random.default_rng(seed)
    steps_of = make_steps(jump)
    optimizer = torch.optim.Adam(steps_of.parameters, lr=jump.learning_rate)
    data: list[Segment] = []
    record: dict[str, Any] = {**jump.to_dict(), "rounds": []}
    model.num_timesteps = 0
    if jump.dataset is not None:
        demos = read_dataset(jump.dataset, source.obs_names, source.interface, "jump_start dataset")
        data += dataset_segments(demos.episodes)
        learn_statistics(venv, data)
        steps_of.add_dataset(demos)
        model.num_timesteps += demos.steps
        record["dataset_steps"] = demos.steps
        record["dataset_policy"] = demos.meta.get("policy")
    expert = None
    if jump.expert is not None:
        expert = ExpertLabels(
            jump.expert,
            source.full_kwargs,
            source.obs_names,
            cfg.stages,
            cfg.action_bounds,
            "jump_start",
        )
    for k, steps in enumerate(jump.round_steps(venv.num_envs)):
        share = 1.0 if k == 0 else jump.expert_share**k
        flown = 0
        if steps and expert is not None:
            data += collect(
                model, venv, expert, steps, share, rng, steps_of.sample, steps_of.record
            )
            steps_of.after_collect()
            flown = (steps // venv.num_envs) * venv.num_envs
            model.num_timesteps += flown
        losses = steps_of.fit(data, optimizer, rng)
        entry = {"round": k, "expert_share": share, "env_steps": flown, **losses}
        entry.update(steps_of.entry_extras())
        entry["wall_s"] = time.monotonic() - began
        record["rounds"].append(entry)
        if progress is not None:
            progress(
                f"jump start round {k}: {int(losses['samples'])} samples, imitation MSE "
                f"{losses['imitation_mse_before']:.4f} -> {losses['imitation_mse']:.4f}"
                + steps_of.describe(losses)
            )
        if evaluate is not None:
            evaluate()
    record["num_timesteps"] = int(model.num_timesteps)
    record["wall_time_s"] = time.monotonic() - began
    return record


def run_jump_start(
    model: Any,
    venv: Any,
    cfg: Any,
    env_id: str,
    seed: int,
    evaluate: Callable[[], None] | None = None,
    progress: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """`run_rounds` on ``model``, a fresh PPO: its actor (all but ``log_std``) and, with
    ``jump.value``, its critic fitted on λ-returns (`fit`)."""
    gamma = float(cfg.algo_kwargs.get("gamma", model.gamma))
    lam = float(cfg.algo_kwargs.get("gae_lambda", getattr(model, "gae_lambda", 0.95)))

    def make_steps(jump: JumpStart) -> RoundSteps:
        return RoundSteps(
            parameters=[p for name, p in model.policy.named_parameters() if name != "log_std"],
            fit=lambda data, optimizer, rng: fit(
                model.policy, venv, data, jump, optimizer, gamma, lam, rng
            ),
            describe=lambda losses: (
                f", value MSE {losses['value_mse']:.4f}" if "value_mse" in losses else ""
            ),
        )

    return run_rounds(model, venv, cfg, env_id, seed, make_steps, evaluate, progress)
