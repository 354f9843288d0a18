"""Warm start (`benchmarks/training/warm_start.py`, `--init-from`): a new run begins with the saved
agent's weights and statistics exactly, records where it started, and a missing file, another
algorithm, another observation layout or a missing seed's agent is refused by name before any
training."""

from __future__ import annotations

import json
import pickle
import shutil

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from benchmarks.training.warm_start import agent_for_seed, check_warm_start, warm_start
from controllers.ensemble import write_ensemble

pytestmark = pytest.mark.rl


@pytest.fixture(scope="module")
def agent(tmp_path_factory):
    from conftest import _train_tiny_preview_agent

    return _train_tiny_preview_agent(tmp_path_factory.mktemp("warm"))


def _fresh_model(agent_dir, seed):
    """A new PPO and VecNormalize as `train` builds them for the tiny agent's configuration."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    from benchmarks.training.envs import make_training_env

    meta = json.loads((agent_dir / "metadata.json").read_text())
    venv = VecNormalize(
        make_training_env(4, seed, dict(meta["env_kwargs"]), "auto", meta["env_id"], None)
    )
    model = PPO(
        "MlpPolicy",
        venv,
        n_steps=64,
        batch_size=128,
        n_epochs=1,
        seed=seed,
        device="cpu",
        policy_kwargs={"net_arch": [16]},
    )
    return model, venv, meta


def test_the_new_model_holds_the_agents_weights_and_statistics(agent):
    from stable_baselines3 import PPO

    model, venv, meta = _fresh_model(agent, seed=7)
    saved = PPO.load(agent / "model.zip", device="cpu")
    fresh = {k: v.clone() for k, v in model.policy.state_dict().items()}
    assert any(not (fresh[k] == v).all() for k, v in saved.policy.state_dict().items())
    record = warm_start(model, venv, agent, "ppo", meta["obs_names"])
    for key, value in saved.policy.state_dict().items():
        assert (model.policy.state_dict()[key] == value).all(), key
    with (agent / "vecnormalize.pkl").open("rb") as f:
        stats = pickle.load(f)
    np.testing.assert_array_equal(venv.obs_rms.mean, stats.obs_rms.mean)
    np.testing.assert_array_equal(venv.obs_rms.var, stats.obs_rms.var)
    assert venv.obs_rms.count == stats.obs_rms.count
    assert float(venv.ret_rms.var) == float(stats.ret_rms.var)
    assert record["init_from"] == str(agent)
    assert record["num_timesteps"] == meta["num_timesteps"]


def _tiny_config(agent, folder):
    """The agent's own hyper-parameter section as a file in ``folder``."""
    import yaml

    config = json.loads((agent / "metadata.json").read_text())["config"]
    (folder / "tiny.yml").write_text(yaml.safe_dump({"AUVPath3DPreview-v0": config}))
    return str(folder / "tiny.yml")


@pytest.mark.integration
def test_a_multi_seed_run_starts_each_seed_from_its_agent_and_records_it(agent, tmp_path):
    from benchmarks.training.seeds_cli import main

    shutil.copytree(agent, tmp_path / "agent_3")
    assert (
        main(
            [
                "--algo",
                "ppo",
                "--config",
                _tiny_config(agent, tmp_path),
                "--env-id",
                "AUVPath3DPreview-v0",
                "--seeds",
                "3-3",
                "--workers",
                "1",
                "--init-from",
                str(tmp_path / "agent_{seed}"),
                "--out",
                str(tmp_path / "run"),
                "--n-timesteps",
                "256",
                "--eval-seeds",
                "100",
                "--eval-freq",
                "256",
                "--eval-duration",
                "110",
                "--quiet",
            ]
        )
        == 0
    )
    final = json.loads((tmp_path / "run" / "seed_3" / "final" / "metadata.json").read_text())
    assert final["warm_start"]["init_from"] == str(tmp_path / "agent_3")
    assert final["num_timesteps"] == 256  # a new run: its own budget and schedules


def test_a_missing_seed_agent_is_refused_before_training(agent, tmp_path, capsys):
    from benchmarks.training.seeds_cli import main

    shutil.copytree(agent, tmp_path / "agent_0")
    assert (
        main(
            [
                "--algo",
                "ppo",
                "--config",
                _tiny_config(agent, tmp_path),
                "--env-id",
                "AUVPath3DPreview-v0",
                "--seeds",
                "0-1",
                "--init-from",
                str(tmp_path / "agent_{seed}"),
                "--out",
                str(tmp_path / "run"),
                "--eval-seeds",
                "100",
                "--eval-duration",
                "110",
                "--quiet",
            ]
        )
        == 2
    )
    assert f"init_from '{tmp_path / 'agent_1'}' does not exist" in capsys.readouterr().err
    assert not (tmp_path / "run" / "seed_0").exists()


def test_bad_agents_are_named(agent, tmp_path):
    assert agent_for_seed(str(tmp_path / "a_{seed}" / "x_{seed}"), 4) == str(
        tmp_path / "a_4" / "x_4"
    )
    with pytest.raises(ValueError, match=r"model\.zip is missing"):
        check_warm_start(tmp_path, "ppo")
    copy = tmp_path / "copy"
    shutil.copytree(agent, copy)
    with pytest.raises(ValueError, match=r"trained with 'ppo', this run uses 'sac'"):
        check_warm_start(copy, "sac")
    with pytest.raises(
        ValueError,
        match=r"the agent observes \d+ entries, this run's observation has 2 \(first "
        r"difference at entry 1: 'y_e' against 'u'\)",
    ):
        check_warm_start(copy, "ppo", ["x_e", "u"])
    model = (copy / "model.zip").read_bytes()
    (copy / "model.zip").write_bytes(model[: len(model) // 2])
    # named as the damaged file it is, not as weights that do not fit the network
    with pytest.raises(ValueError, match=r"^init_from '.*copy': PPO model .*model\.zip is not a "):
        check_warm_start(copy, "ppo")
    (copy / "model.zip").write_bytes(model)
    (copy / "metadata.json").write_text("{not json")
    with pytest.raises(ValueError, match=r"metadata\.json is unreadable"):
        check_warm_start(copy, "ppo")


def test_an_ensemble_is_refused_naming_its_members(agent, tmp_path):
    for seed in (1, 2):
        shutil.copytree(agent, tmp_path / f"agent_seed_{seed}")
    members = [tmp_path / "agent_seed_1", tmp_path / "agent_seed_2"]
    ensemble = write_ensemble(tmp_path / "ensemble", members).parent
    first = str(members[0].resolve())
    with pytest.raises(ValueError) as refused:
        check_warm_start(ensemble, "ppo")
    message = str(refused.value)
    assert message.startswith(f"init_from {str(ensemble)!r}: an ensemble of 2 agents")
    assert message.endswith(f"pass one member's folder, e.g. {first!r}")
    # the member it names starts a run
    assert check_warm_start(first, "ppo")["algo"] == "ppo"
