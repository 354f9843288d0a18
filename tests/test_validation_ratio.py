"""`benchmarks.analysis.validation_ratio`: policies on a validation set's episodes, each under its
benchmark env id, with the ratio to a reference; bad input is named."""

from __future__ import annotations

import json

import pytest

from benchmarks.analysis.validation_ratio import main
from benchmarks.training.evaluation import evaluate_policy_on_seeds
from controllers.loader import load_policy

AGENT = "benchmarks/results/seeds/ppo_integral/agent_seed_0"


def test_ratios_are_to_the_reference_and_agents_run_under_their_training_env(tmp_path, capsys):
    out = tmp_path / "ratio.json"
    rows = main(
        [
            "--policies",
            f"fbsm_colos,fbsm,gen3={AGENT}",
            "--episodes",
            "2",
            "--duration",
            "30",
            "--json",
            str(out),
        ]
    )
    assert rows["fbsm_colos"]["ratio"] == 1.0
    for label in ("fbsm", "gen3"):
        row = rows[label]
        assert row["ratio"] == row["rms_distance_mean"] / rows["fbsm_colos"]["rms_distance_mean"]
        assert len(row["rms_distance"]) == 2
    assert rows["gen3"]["num_timesteps"] == 5_000_000 and rows["gen3"]["wall_time_s"] > 0
    assert "num_timesteps" not in rows["fbsm"]
    # the agent's episodes are those of its training id with its observation (48 entries)
    policy = load_policy(AGENT)
    from benchmarks.catalog.tasks import load_task_sets

    chosen = load_task_sets()["validation_paper_actuator"]
    env = {
        **dict(chosen.env),
        "max_time": 30.0,
        "surge_limit": "vehicle",
        "observation": policy.metadata["observation"],
    }
    by_hand = evaluate_policy_on_seeds(policy, list(chosen.seeds[:2]), **env)
    assert rows["gen3"]["rms_distance"] == [r["rms_distance"] for r in by_hand]
    assert json.loads(out.read_text())["seeds"] == [100_100, 100_101]
    assert "| gen3 |" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--task-set", "test_steep"], "is not a validation set"),
        (["--episodes", "0"], "--episodes must be 1-100"),
        (["--duration", "nan"], "--duration must be a positive number"),
        (["--policies", "fbsm"], "--reference 'fbsm_colos' is not among --policies ['fbsm']"),
        (["--policies", "fbsm_colos,a=/no/such/agent"], "/no/such/agent"),
    ],
)
def test_bad_input_is_one_line(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err


def test_agent_env_kwargs_are_the_ids_arguments_plus_the_recorded_observation():
    from auv_gym import VARIANTS
    from benchmarks.training.evaluation import agent_env_kwargs

    policy = load_policy(AGENT)
    plain = agent_env_kwargs("AUVPath3DSpeedLimit-v0", {"num_timesteps": 5})
    assert plain == dict(VARIANTS["AUVPath3DSpeedLimit-v0"]) and "observation" not in plain
    plain["extra"] = 1  # a copy: the registry's arguments stay as they are
    assert "extra" not in VARIANTS["AUVPath3DSpeedLimit-v0"]
    with_obs = agent_env_kwargs(policy.metadata["env_id"], policy.metadata)
    assert with_obs["observation"] == policy.metadata["observation"]
    assert with_obs["surge_limit"] == "vehicle"
    with pytest.raises(ValueError, match="AUVPath3DNoSuch-v0"):
        agent_env_kwargs("AUVPath3DNoSuch-v0", {})


def test_a_fixed_actuator_is_told_to_every_policy_as_a_scenario_does():
    """Was: on `validation_fins_start` FBSM was built for the paper's actuator and the agents
    ran without their allocation, so both flew the fins with a third of the moment asked for."""
    from benchmarks.analysis.validation_ratio import policy_and_env
    from benchmarks.catalog.tasks import load_task_sets
    from controllers.actuator_allocation import AllocatedPolicy

    sets = load_task_sets()
    assert sets["validation_fins_start"].controller == {"actuator": "fins"}
    assert sets["validation_fins_start"].env["actuator"] == "fins"
    assert sets["validation_paper_start"].controller == {}
    assert sets["validation"].controller == {}  # drawn per episode: tells none
    fins = sets["validation_fins_start"].controller
    _, fbsm, _, _ = policy_and_env("fbsm", fins)
    assert fbsm.actuator == "fins"
    assert policy_and_env("fbsm", sets["validation_paper_start"].controller)[1].actuator == "paper"
    agent = "benchmarks/results/seeds/ppo_cross_track_guard_alloc/agent_seed_3"
    _, allocated, _, _ = policy_and_env(f"a={agent}", fins)
    assert isinstance(allocated, AllocatedPolicy)
    _, plain, _, _ = policy_and_env(f"a={agent}", sets["validation_paper_start"].controller)
    assert not isinstance(plain, AllocatedPolicy)
