"""The privileged critic (`benchmarks.training.privileged`): the critic reads the true path
errors, the actor only what the vehicle senses; the saved agent is the actor alone, predicting
as the model that trained it; a run with it trains, saves, flies and resumes bit for bit."""

from __future__ import annotations

import json
import pickle
from pathlib import Path

import numpy as np
import pytest
import yaml
from gymnasium.vector import AutoresetMode

from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from benchmarks.training.residual import PRIVILEGED_NAMES, ResidualTraining
from benchmarks.training.residual_env import ResidualVectorEnv
from controllers.residual import residual_observation_names

pytestmark = pytest.mark.rl

# 80 control steps per episode, the Kalman navigation: the estimate drifts from the truth.
ENV = {"disturbance": "paper", "max_time": 4.0, "sensors": "typical_kalman"}
NAMES = residual_observation_names()
ERRORS = [NAMES.index(name) for name in ("x_e", "y_e", "z_e")]


def _env(n: int, privileged: bool) -> ResidualVectorEnv:
    core = AUVPath3DVectorEnv(n, autoreset_mode=AutoresetMode.SAME_STEP, **ENV)
    return ResidualVectorEnv(core, ResidualTraining(privileged_critic=privileged))


def test_the_critic_sees_the_true_errors_and_the_actor_what_it_saw_before():
    """The observation is the plain agent's, bit for bit, then the true x_e, y_e, z_e of the
    info (the ended episodes' in their final observations); the truth differs from the
    estimate the actor sees."""
    n, steps = 3, 100  # every vehicle's episode ends once
    corrections = np.random.default_rng(2).uniform(-1.0, 1.0, size=(steps, n, 3))
    plain, privileged = _env(n, False), _env(n, True)
    d = len(NAMES)
    assert privileged.single_observation_space.shape == (d + 3,)
    np.testing.assert_array_equal(
        privileged.single_observation_space.high[d:], plain.single_observation_space.high[ERRORS]
    )
    obs0, _ = plain.reset(seed=7)
    obs1, info = privileged.reset(seed=7)
    np.testing.assert_array_equal(obs1[:, :d], obs0)
    gaps, ended = [], 0
    for k in range(steps):
        obs0, r0, term, trunc, info0 = plain.step(corrections[k])
        obs1, r1, _, _, info = privileged.step(corrections[k])
        np.testing.assert_array_equal(obs1[:, :d], obs0)
        np.testing.assert_array_equal(r1, r0)
        truth = np.stack([info[key] for key in ("x_e", "y_e", "z_e")], 1).astype(np.float32)
        np.testing.assert_array_equal(obs1[:, d:], truth)
        for i in np.flatnonzero(term | trunc):
            ended += 1
            final = info["final_info"]
            expected = [final[key][i] for key in ("x_e", "y_e", "z_e")]
            np.testing.assert_array_equal(info["final_obs"][i][:d], info0["final_obs"][i])
            np.testing.assert_array_equal(info["final_obs"][i][d:], np.float32(expected))
        gaps.append(np.abs(obs1[:, d:] - obs1[:, ERRORS]).max())
    assert ended == n
    assert max(gaps) > 1e-3  # the navigation's error: the critic learns something new


def _policy(public: int = 5, private: int = 3):
    import torch
    from gymnasium import spaces

    from benchmarks.training.privileged import PrivilegedCriticPolicy

    space = spaces.Box(-10.0, 10.0, (public + private,), np.float32)
    actions = spaces.Box(-1.0, 1.0, (3,), np.float32)
    torch.manual_seed(0)
    return PrivilegedCriticPolicy(
        space, actions, lambda _: 3e-4, net_arch=[16, 16], log_std_init=-1.0, public_dim=public
    )


def test_the_actor_reads_no_privileged_entry_and_the_critic_does():
    import torch

    policy = _policy()
    with torch.no_grad():  # an action head that is not zero, as after training
        policy.action_net.weight.normal_()
    obs = torch.as_tensor(np.random.default_rng(0).standard_normal((20, 8)), dtype=torch.float32)
    other = obs.clone()
    other[:, 5:] += 3.0
    with torch.no_grad():
        a, b = policy.get_distribution(obs), policy.get_distribution(other)
        torch.testing.assert_close(a.distribution.mean, b.distribution.mean, rtol=0, atol=0)
        assert (policy.predict_values(obs) - policy.predict_values(other)).abs().min() > 0
    assert policy.mlp_extractor.policy_net[0].in_features == 5
    assert policy.mlp_extractor.value_net[0].in_features == 8


@pytest.mark.parametrize(("public", "private"), [(0, 8), (8, 0)])
def test_an_actor_reading_nothing_or_everything_is_refused(public, private):
    message = rf"between 1 and 7 \(the observation has 8 entries, .*\), got {public}"
    with pytest.raises(ValueError, match=message):
        _policy(public, private)


@pytest.mark.parametrize("critic", [[16], []])
def test_the_saved_form_values_states_as_the_critic_at_the_privileged_mean(critic):
    """Was: with no hidden layer for the critic (net_arch vf: []) its first layer, then the value
    head, was not found by name, and converting the model failed on a size mismatch."""
    import gymnasium as gym
    import torch
    from gymnasium import spaces
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from benchmarks.training.privileged import PrivilegedCriticPolicy, deployable

    class _Box(gym.Env):
        observation_space = spaces.Box(-10.0, 10.0, (8,), np.float32)
        action_space = spaces.Box(-1.0, 1.0, (3,), np.float32)

    venv = VecNormalize(DummyVecEnv([_Box]))
    arch = {"net_arch": {"pi": [16], "vf": critic}, "public_dim": 5}
    model = PPO(PrivilegedCriticPolicy, venv, policy_kwargs=arch, n_steps=32, device="cpu", seed=0)
    with torch.no_grad():  # weights on the privileged columns that matter
        for parameter in model.policy.parameters():
            parameter.normal_()
    public, stats = deployable(model, venv)
    obs = torch.as_tensor(np.random.default_rng(1).standard_normal((6, 8)), dtype=torch.float32)
    at_mean = obs.clone()
    at_mean[:, 5:] = 0.0
    with torch.no_grad():
        torch.testing.assert_close(
            public.policy.predict_values(obs[:, :5]), model.policy.predict_values(at_mean)
        )
        assert (
            model.policy.predict_values(obs) - model.policy.predict_values(at_mean)
        ).abs().min() > 0
        torch.testing.assert_close(
            public.policy.get_distribution(obs[:, :5]).distribution.mean,
            model.policy.get_distribution(obs).distribution.mean,
        )
    assert stats.obs_rms.mean.shape == (5,)


def test_privileged_critic_must_be_a_yes_or_no():
    with pytest.raises(ValueError, match="privileged_critic must be true or false, got 'yes'"):
        ResidualTraining(privileged_critic="yes")
    assert ResidualTraining(privileged_critic=True).to_dict()["privileged_critic"] is True
    assert "privileged_critic" not in ResidualTraining().to_dict()  # agents record what they did


def _config(tmp_path: Path, n_timesteps: int = 512) -> Path:
    section = {
        "policy": "MlpPolicy",
        "n_envs": 4,
        "n_timesteps": n_timesteps,
        "normalize": "dict(norm_obs=True, norm_reward=True)",
        "n_steps": 32,
        "batch_size": 64,
        "n_epochs": 2,
        "learning_rate": "lin_3e-4",
        "policy_kwargs": "dict(net_arch=[16, 16], log_std_init=-1.0)",
        "residual": {"base": "fbsm_colos", "privileged_critic": True},
        "env_kwargs": {**ENV, "max_time": 5.0, "randomize_start": True},
    }
    path = tmp_path / "privileged.yml"
    path.write_text(yaml.safe_dump({"AUVPath3D-v0": section}))
    return path


def _options(tmp_path: Path, out: str, **extra):
    from tests.test_resume_exact import small_run_options

    return small_run_options(_config(tmp_path), "AUVPath3D-v0", tmp_path / out, seed=4, **extra)


def test_a_run_saves_the_actor_alone_flies_it_and_resumes_bit_for_bit(tmp_path):
    """Checkpoints hold the whole model (resumed exactly); best/, final/ and the export hold
    the actor over the public observation, which predicts what the trained model's actor does
    and loads and flies like any residual agent."""
    from stable_baselines3 import PPO

    from benchmarks.training.privileged import deployable
    from benchmarks.training.train import train
    from controllers.loader import load_policy
    from tests.test_resume_exact import _assert_same_agent, _curve

    train(_options(tmp_path, "a", export=str(tmp_path / "agent")))
    train(_options(tmp_path, "b", stop_at=256))
    train(_options(tmp_path, "b", resume=True))
    assert _curve(tmp_path / "b") == _curve(tmp_path / "a")
    for folder in ("final", "best", "checkpoints/step_0000000512"):
        _assert_same_agent(tmp_path / "a" / folder, tmp_path / "b" / folder)

    d = len(NAMES)
    checkpoint = tmp_path / "a" / "checkpoints" / "step_0000000512"
    full = PPO.load(checkpoint / "model.zip", device="cpu")
    assert full.observation_space.shape == (d + 3,)
    stats = np.load(checkpoint / "vecnormalize.npz")
    assert list(stats["obs_names"][d:]) == list(PRIVILEGED_NAMES)
    final = PPO.load(tmp_path / "a" / "final" / "model.zip", device="cpu")
    assert type(final.policy).__name__ == "ActorCriticPolicy"
    assert final.observation_space.shape == (d,)
    with (checkpoint / "vecnormalize.pkl").open("rb") as f:
        normalization = pickle.load(f)
    public, public_normalization = deployable(full, normalization)
    np.testing.assert_array_equal(public_normalization.obs_rms.mean, stats["mean"][:d])
    obs = np.random.default_rng(1).standard_normal((16, d + 3)).astype(np.float32)
    a_full, _ = full.policy.predict(obs, deterministic=True)
    a_public, _ = public.policy.predict(obs[:, :d], deterministic=True)
    np.testing.assert_array_equal(a_full, a_public)
    assert np.abs(a_full).max() > 0  # trained: the correction is no longer exactly zero

    meta = json.loads((tmp_path / "agent" / "metadata.json").read_text())
    assert meta["residual"]["privileged_critic"] is True
    assert meta["observation_shape"] == [d]
    policy = load_policy(tmp_path / "agent")
    from auv_gym.rollout import evaluate

    (result,) = evaluate(policy, [3], **{**ENV, "max_time": 5.0})
    assert np.isfinite(result["rms_distance"])

    # A later run with a privileged critic starts from the saved agent: the same actor, the
    # critic widened (valuing every state as the saved one at the true errors' mean), the true
    # errors' statistics those of the observed ones.
    import torch
    from stable_baselines3.common.vec_env import VecNormalize

    from benchmarks.training.envs import make_training_env
    from benchmarks.training.privileged import PrivilegedCriticPolicy
    from benchmarks.training.warm_start import warm_start

    settings = ResidualTraining(base="fbsm_colos", privileged_critic=True)
    venv = VecNormalize(make_training_env(4, 0, ENV, env_id="AUVPath3D-v0", residual=settings))
    arch = {"net_arch": [16, 16], "log_std_init": -1.0, "public_dim": d}
    model = PPO(PrivilegedCriticPolicy, venv, policy_kwargs=arch, n_steps=32, device="cpu")
    record = warm_start(model, venv, tmp_path / "agent", "ppo", NAMES)
    assert record["optimizer"].startswith("restarted")
    saved = PPO.load(tmp_path / "agent" / "model.zip", device="cpu")
    a_model, _ = model.policy.predict(obs, deterministic=True)
    a_saved, _ = saved.policy.predict(obs[:, :d], deterministic=True)
    np.testing.assert_array_equal(a_model, a_saved)
    at_mean = torch.as_tensor(obs).clone()
    at_mean[:, d:] = 0.0
    with torch.no_grad():
        values = model.policy.predict_values(at_mean)
        torch.testing.assert_close(values, saved.policy.predict_values(at_mean[:, :d]))
    agent_stats = np.load(tmp_path / "agent" / "vecnormalize.npz")
    np.testing.assert_array_equal(venv.obs_rms.mean[:d], agent_stats["mean"])
    np.testing.assert_array_equal(venv.obs_rms.mean[d:], agent_stats["mean"][ERRORS])


def test_an_evaluation_converts_once_per_flight_and_once_per_save(tmp_path, monkeypatch):
    """Each conversion of a privileged model to its saved form draws a new policy's initial
    weights from torch's global generator, which the training shares: how many an evaluation
    makes is part of every seed's trajectory. The recipe's seeds were trained with one per
    flight (plant) and one more for each new best agent; one per evaluation (tried in a
    refactor) trained other agents from the same command."""
    import benchmarks.training.callbacks as callbacks
    from benchmarks.training.train import train

    conversions: list[int] = []
    per_evaluation: list[tuple[int, bool]] = []
    convert, evaluate = callbacks.deployable, callbacks.PeriodicEvaluation.evaluate

    def counted(model, vec_normalize):
        conversions.append(1)
        return convert(model, vec_normalize)

    def recorded(self):
        before, best = len(conversions), dict(self.best).get("score")
        evaluate(self)
        per_evaluation.append((len(conversions) - before, self.best.get("score") != best))

    monkeypatch.setattr(callbacks, "deployable", counted)
    monkeypatch.setattr(callbacks.PeriodicEvaluation, "evaluate", recorded)
    train(_options(tmp_path, "a"))
    assert len(per_evaluation) == 3  # at 0, 256 and 512 env steps, one plant each
    assert per_evaluation[0] == (2, True)  # the first evaluation always saves best/
    assert all(count == 1 + saved for count, saved in per_evaluation)


def test_an_off_policy_learner_with_a_privileged_critic_is_refused(tmp_path):
    from benchmarks.training.config import read_zoo_config

    section = {
        "policy": "MlpPolicy",
        "n_envs": 4,
        "n_timesteps": 512,
        "normalize": "dict(norm_obs=True, norm_reward=True)",
        "residual": {"base": "fbsm_colos", "privileged_critic": True},
    }
    config = tmp_path / "sac.yml"
    config.write_text(yaml.safe_dump({"AUVPath3D-v0": section}))
    with pytest.raises(ValueError, match=r"privileged_critic gives PPO.s value network .* sac"):
        read_zoo_config(config, "AUVPath3D-v0", "sac")
