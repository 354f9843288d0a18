"""The exploration-noise schedule (`benchmarks.training.noise_schedule`): the cap's hand-computed
values, bad schedules named, and a PPO run whose σ is capped from the schedule's start on."""

from __future__ import annotations

import math

import pytest

pytest.importorskip("stable_baselines3")

from benchmarks.training.noise_schedule import StdSchedule, parse_std_schedule


def test_the_cap_is_geometric_from_the_initial_sigma_to_the_final_one():
    schedule = StdSchedule(start=0.5, final=0.05)
    assert schedule.cap(0.49, 0.4) == math.inf
    assert schedule.cap(0.5, 0.4) == pytest.approx(0.4)
    assert schedule.cap(0.75, 0.4) == pytest.approx(math.sqrt(0.4 * 0.05))  # halfway: the mean
    assert schedule.cap(1.0, 0.4) == pytest.approx(0.05)
    assert schedule.cap(1.2, 0.4) == pytest.approx(0.05)  # a run longer than planned


@pytest.mark.parametrize(
    "value",
    [
        {"start": 1.0, "final": 0.1},
        {"start": 0.5, "final": 0.0},
        {"start": 0.5},
        {"start": 0.5, "final": 2.0},
        {"start": True, "final": 0.1},
        [0.5, 0.1],
    ],
)
def test_bad_schedules_are_named(value):
    with pytest.raises(ValueError, match=r"cfg: action_std_schedule must be \{start"):
        parse_std_schedule(value, "cfg")


@pytest.mark.rl
def test_a_ppo_run_is_capped_before_each_rollout_from_the_start_on():
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    from benchmarks.training.noise_schedule import AnnealActionStd
    from benchmarks.training.train import make_training_env

    venv = VecNormalize(make_training_env(2, 0, {"max_time": 5.0}))
    policy_kwargs = {"net_arch": [8], "log_std_init": -1.0}
    model = PPO(
        "MlpPolicy",
        venv,
        n_steps=64,
        batch_size=64,
        n_epochs=1,
        learning_rate=0.0,
        policy_kwargs=policy_kwargs,
        device="cpu",
        seed=0,
    )
    seen = []

    class Record(AnnealActionStd):
        def _on_rollout_start(self) -> None:
            super()._on_rollout_start()
            seen.append(model.policy.log_std.detach().exp().tolist())

    model.learn(512, callback=Record(StdSchedule(0.5, 0.05), 512, math.exp(-1.0)))
    # 4 rollouts of 128 steps: progress 0, 0.25 (uncapped), 0.5 (σ₀) and 0.75 (√(σ₀·0.05))
    assert seen[0] == pytest.approx([math.exp(-1.0)] * 3)
    assert seen[1] == pytest.approx([math.exp(-1.0)] * 3)
    assert seen[3] == pytest.approx([math.sqrt(math.exp(-1.0) * 0.05)] * 3, rel=1e-5)
    venv.close()
