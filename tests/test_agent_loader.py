"""One agent loader: `controllers.make("agent", path=...)` loads a saved agent of any algorithm of
the one table training shares (`controllers.algorithms`), plain or residual; "ppo", its former name,
is refused naming the call that replaces it; errors name the algorithm found; `auv-gym train --algo`
chooses the algorithm and its file."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

import controllers
from controllers.agent import check_agent
from controllers.algorithms import ALGORITHMS

ROOT = Path(__file__).resolve().parent.parent
AGENTS = ROOT / "benchmarks" / "agents"


def test_training_and_loading_share_one_algorithm_table():
    from benchmarks.training import ALGORITHMS as TRAINED
    from benchmarks.training.config import ALGORITHMS as READ

    assert TRAINED is ALGORITHMS and READ is ALGORITHMS
    assert {name: (a.package, a.class_name) for name, a in ALGORITHMS.items()} == {
        "ppo": ("stable_baselines3", "PPO"),
        "sac": ("stable_baselines3", "SAC"),
        "tqc": ("sb3_contrib", "TQC"),
        "crossq": ("sb3_contrib", "CrossQ"),
    }
    assert controllers.AGENT_NAMES == ("agent", "sac", "tqc", "crossq")
    assert "tau" not in ALGORITHMS["crossq"].hyperparameters  # no target networks
    assert "top_quantiles_to_drop_per_net" in ALGORITHMS["tqc"].hyperparameters


def test_check_agent_reports_the_algorithm_and_names_it_in_errors(tmp_path):
    assert check_agent(AGENTS / "sac_generalist").algo == "sac"
    assert check_agent(AGENTS / "ppo_generalist").algo == "ppo"
    older = shutil.copytree(AGENTS / "ppo_generalist", tmp_path / "older")
    metadata = json.loads((older / "metadata.json").read_text())
    del metadata["algo"]  # agents of the first releases recorded no algorithm: PPO's
    (older / "metadata.json").write_text(json.dumps(metadata))
    assert check_agent(older).algo == "ppo"
    agent = tmp_path / "sac"
    shutil.copytree(AGENTS / "sac_generalist", agent)
    (agent / "model.zip").write_bytes(b"not a zip")
    with pytest.raises(ValueError, match=r"^SAC model .*model.zip is not a valid zip file"):
        check_agent(agent)
    for stats in ("vecnormalize.npz", "vecnormalize.pkl"):
        (agent / stats).unlink(missing_ok=True)
    with pytest.raises(FileNotFoundError, match=r"^SAC agent .*normalisation statistics missing"):
        check_agent(agent)
    with pytest.raises(FileNotFoundError, match=r"^agent .*missing does not exist"):
        check_agent(tmp_path / "missing")
    # was: "normalisation statistics missing", as if the file were a model without them
    with pytest.raises(ValueError, match=r"policy\.onnx is an ONNX export \(fly it as onnx:FI"):
        check_agent(AGENTS / "ppo_generalist" / "policy.onnx")
    with pytest.raises(ValueError, match=r"metadata\.json is a file, not a saved agent: give"):
        check_agent(AGENTS / "ppo_generalist" / "metadata.json")


def test_make_needs_a_path_and_knows_the_names():
    with pytest.raises(ValueError, match=r"controllers.make\('agent'\) needs path="):
        controllers.make("agent")
    valid = r"valid: \[.*'agent', 'sac', 'tqc', 'crossq', 'onnx', 'residual'"
    with pytest.raises(ValueError, match=valid):
        controllers.make("dqn", path="x")


def test_the_former_name_ppo_is_refused_in_one_line():
    for kwargs in ({}, {"path": str(AGENTS / "ppo_generalist")}):
        with pytest.raises(ValueError) as error:
            controllers.make("ppo", **kwargs)
        assert str(error.value) == (
            "controller 'ppo' was renamed: use controllers.make('agent', path=...)"
        )


@pytest.mark.rl
def test_an_agent_takes_the_plants_keywords_as_a_classical_controller_does():
    """``actuator="fins"`` builds the generalist's allocation for the fins, as the fins env
    does; the same observation then gives other commands than on the paper's actuator."""
    import gymnasium as gym

    path = str(AGENTS / "ppo_generalist")
    names = lambda policy: [type(stage).__name__ for stage in policy.stages]  # noqa: E731
    on_fins = controllers.make("agent", path=path, actuator="fins")
    assert names(on_fins) == ["GuardStage", "AllocationStage"]
    assert names(controllers.make("agent", path=path)) == ["GuardStage"]
    env = gym.make("AUVPath3DPreview-v0", actuator="fins", observation="preview_integral")
    assert names(controllers.make("agent", env, path=path)) == names(on_fins)
    # an explicit keyword wins over the env's
    assert names(controllers.make("agent", env, path=path, actuator="paper")) == ["GuardStage"]
    obs = env.reset(seed=3)[0]
    fins_action = on_fins.predict(obs, deterministic=True)[0]
    paper_action = controllers.make("agent", path=path).predict(obs, deterministic=True)[0]
    assert not np.allclose(fins_action, paper_action)


def test_an_agent_refuses_unknown_keywords_and_actuators_in_one_line():
    path = str(AGENTS / "ppo_generalist")
    with pytest.raises(ValueError, match=r"^unknown actuator 'nope'; valid: \['fins'"):
        controllers.make("agent", path=path, actuator="nope")
    with pytest.raises(ValueError) as error:
        controllers.make("agent", path=path, gains=1)
    assert str(error.value).startswith("controllers.make('agent'): unknown keywords ['gains']")
    assert "'actuator'" in str(error.value) and "\n" not in str(error.value)


@pytest.mark.rl
def test_agent_and_sac_load_the_same_policy_and_sac_checks_the_algorithm():
    obs = np.linspace(-0.5, 0.5, 49, dtype=np.float32)  # its integral preview observation
    path = str(AGENTS / "sac_generalist")
    actions = [controllers.make(name, path=path).predict(obs)[0] for name in ("agent", "sac")]
    assert type(controllers.make("agent", path=path)).__name__ == "StagedPolicy"  # its stages
    for action in actions[1:]:
        np.testing.assert_array_equal(action, actions[0])
    with pytest.raises(
        ValueError, match=r"ppo_generalist/model.zip was trained with 'ppo', not 'sac'"
    ):
        controllers.make("sac", path=str(AGENTS / "ppo_generalist"))
    with pytest.raises(
        ValueError, match=r"sac_generalist/model.zip was trained with 'sac', not 'tqc'"
    ):
        controllers.make("tqc", path=path)
    residual = controllers.make("agent", path=str(AGENTS / "ppo_residual"))
    assert type(residual).__name__ == "ResidualPolicy" and residual.filter_max == 0.8


def test_train_takes_the_algorithm_and_its_default_file():
    from benchmarks.training import TrainOptions
    from benchmarks.training.train_cli import parse_args

    opts, _ = parse_args([])
    assert (opts.algo, opts.config) == ("ppo", TrainOptions().config)
    opts, _ = parse_args(["--algo", "sac"])
    assert opts.algo == "sac" and opts.config == str(ROOT / "benchmarks/hyperparams/sac_helix.yml")
    opts, _ = parse_args(["--algo", "sac", "--config", "x.yml"])
    assert opts.config == "x.yml"
    with pytest.raises(SystemExit):
        parse_args(["--algo", "dqn"])
