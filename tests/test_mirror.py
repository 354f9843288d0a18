"""The port-starboard mirror: the plant and the observation are symmetric under y → −y as the
sign table says, and the mirror stage makes any network equivariant (controllers.mirror)."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from auv_gym.paths.shapes import Helix
from auv_gym.sim.observation import ObservationConfig, mirror_signs
from controllers.mirror import ACTION_MIRROR, MirroredNetwork
from controllers.residual import RESIDUAL_OBS_NAMES
from controllers.stages import check_stage_specs

ROOT = Path(__file__).resolve().parents[1]
GENERALIST = ROOT / "benchmarks" / "agents" / "ppo_generalist"
NAMES = ObservationConfig.from_spec("preview_integral").names


def _mirrored_env(side: float):
    """A preview-integral env on a helix turning to starboard (side +1) or its mirror image
    (side −1: port turn, centre, start and current mirrored)."""
    import gymnasium as gym

    import auv_gym  # noqa: F401  (registers the ids)

    return gym.make(
        "AUVPath3DPreview-v0",
        observation="preview_integral",
        path=Helix(radius=18.0, omega=side * math.pi / 18.0, center=(10.0, side * 4.0, -8.0)),
        start_position=(24.0, side * 9.0, -5.0),
        start_heading=side * 1.2,
        disturbance="none",
        current={"mean": [0.1, side * 0.2, 0.0], "std": [0.0, 0.0, 0.0], "time_constant": 60.0},
    ).unwrapped


def test_the_plant_and_the_observation_are_mirror_symmetric():
    """The mirrored world driven by mirrored commands gives the mirrored observation at every
    step, bit for bit (30 s of random commands on a helix in a current): the sign table is the
    simulator's own symmetry, every entry of the agent observation included."""
    signs = mirror_signs(NAMES)
    starboard, port = _mirrored_env(1.0), _mirrored_env(-1.0)
    obs_s, _ = starboard.reset(seed=0)
    obs_p, _ = port.reset(seed=0)
    assert abs(obs_s[1]) > 1.0 and abs(obs_s[3]) > 0.1  # off the path, turned away
    rng = np.random.default_rng(1)
    worst = float(np.abs(obs_p - signs * obs_s).max())
    for _ in range(600):
        action = rng.uniform(-1.0, 1.0, 3).astype(np.float32)
        obs_s, reward_s, *_ = starboard.step(action)
        obs_p, reward_p, *_ = port.step(action * ACTION_MIRROR)
        worst = max(worst, float(np.abs(obs_p - signs * obs_s).max()))
        assert reward_p == reward_s
    assert worst == 0.0
    assert np.abs(obs_s[signs < 0]).max() > 0.1  # the odd entries were exercised


def test_the_sign_table_by_hand_and_its_refusals():
    signs = dict(zip(NAMES, mirror_signs(NAMES), strict=True))
    odd = {n for n, s in signs.items() if s < 0}
    assert odd == {
        "y_e",
        "psi_error",
        "v",
        "r",
        "psi_F_dot",
        "v_ground",
        "a_N_prev",
        "y_e_integral",
        *(f"preview{k}_{f}" for k in range(1, 6) for f in ("y", "torsion")),
    }
    with pytest.raises(ValueError, match=r"\['base_X', 'base_M'.*no defined port-starboard mirror"):
        mirror_signs(RESIDUAL_OBS_NAMES)


class _Affine:
    """A stand-in network: clip(W·o + b) with a bias b that breaks the symmetry."""

    def __init__(self, dim: int, seed: int) -> None:
        rng = np.random.default_rng(seed)
        self.weight = rng.normal(0.0, 0.3, (3, dim)).astype(np.float32)
        self.bias = np.array([0.1, -0.2, 0.4], np.float32)
        self.action_space = SimpleNamespace(low=-np.ones(3), high=np.ones(3))
        self.calls = 0

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        self.calls += 1
        return np.clip(np.atleast_2d(observation) @ self.weight.T + self.bias, -1.0, 1.0), state


def test_the_mirror_stage_makes_a_network_equivariant():
    """π_sym(M_o·o) = M_a·π_sym(o) for a network that is not; its bias on the yaw command
    cancels on the path (o = 0), and the network is called once per step."""
    network = _Affine(len(NAMES), 0)
    policy = MirroredNetwork(network, NAMES, "test")
    signs = mirror_signs(NAMES)
    obs = np.random.default_rng(2).normal(0.0, 1.0, (64, len(NAMES))).astype(np.float32)
    plain = network.predict(obs)[0]
    action, _ = policy.predict(obs)
    image, _ = policy.predict(obs * signs)
    np.testing.assert_allclose(image, action * ACTION_MIRROR, atol=1e-7)
    assert np.abs(plain - action).max() > 0.1
    centred, _ = policy.predict(np.zeros(len(NAMES), np.float32))
    np.testing.assert_allclose(centred, [0.1, -0.2, 0.0], atol=1e-7)
    assert network.calls == 4  # one batched call each, the plain one included
    with pytest.raises(ValueError, match=r"shape \(49,\) or \(n, 49\)"):
        policy.predict(np.zeros(15, np.float32))
    skewed = _Affine(len(NAMES), 0)
    skewed.action_space = SimpleNamespace(low=np.array([-1.0, -1.0, -0.5]), high=np.ones(3))
    with pytest.raises(ValueError, match="not symmetric in the yaw command"):
        MirroredNetwork(skewed, NAMES, "test")


def test_the_mirror_stage_is_listed_anywhere_once_and_without_settings():
    guard = {"name": "envelope_guard"}
    mirror = {"name": "mirror_symmetry"}
    allocation = {"name": "actuator_allocation"}
    names = [s["name"] for s in check_stage_specs([guard, mirror, allocation], "x")]
    assert names == ["envelope_guard", "mirror_symmetry", "actuator_allocation"]
    with pytest.raises(ValueError, match="stage mirror_symmetry takes no settings"):
        check_stage_specs([{"name": "mirror_symmetry", "gain": 1.0}], "x")
    with pytest.raises(ValueError, match="must each appear once"):
        check_stage_specs([mirror, guard, mirror], "x")


@pytest.mark.rl
def test_a_mirrored_agent_loads_flies_and_exports_with_its_mirror(tmp_path):
    """The reference generalist with the stage in its metadata: `load_policy` flies the
    equivariant agent, and its ONNX graph computes the same commands (parity) and lists it."""
    pytest.importorskip("onnx")
    from controllers.loader import load_policy
    from controllers.onnx_export import export_onnx

    agent = tmp_path / "agent"
    shutil.copytree(GENERALIST, agent)
    meta_file = agent / "metadata.json"
    meta = json.loads(meta_file.read_text())
    meta["stages"] = [*meta["stages"], {"name": "mirror_symmetry"}]
    meta_file.write_text(json.dumps(meta))
    plain, policy = load_policy(GENERALIST), load_policy(agent)
    assert isinstance(policy.actor, MirroredNetwork)
    layout = meta["obs_names"]
    signs = mirror_signs(layout)
    obs = np.random.default_rng(3).normal(0.0, 0.5, (32, len(layout))).astype(np.float32)
    action, _ = policy.predict(obs)
    image, _ = load_policy(agent).predict(obs * signs)
    np.testing.assert_allclose(image, action * ACTION_MIRROR, atol=1e-6)
    assert np.abs(plain.predict(obs)[0] - action).max() > 1e-3
    _, contract, parity = export_onnx(agent, tmp_path / "agent.onnx")
    assert parity["max_abs_error"] < 1e-5
    listed = [s["name"] for s in json.loads(contract.read_text())["stages"]]
    assert listed[0] == "mirror_symmetry"


@pytest.mark.rl
def test_training_inside_the_mirror_is_refused(tmp_path):
    import yaml

    from benchmarks.training.config import read_zoo_config

    section = {"n_envs": 2, "n_timesteps": 64, "policy": "MlpPolicy", "normalize": True}
    config = tmp_path / "bad.yml"
    config.write_text(
        yaml.safe_dump({"AUVPath3DPreview-v0": {**section, "stages": ["mirror_symmetry"]}})
    )
    with pytest.raises(ValueError, match=r"bad\.yml: AUVPath3DPreview-v0: stage mirror_symmetry"):
        read_zoo_config(config, "AUVPath3DPreview-v0", "ppo")
