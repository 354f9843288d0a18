"""The compiled 6-DOF plant (`auv_gym.vehicle.six_dof`, ``plant="6dof"``): its accelerations
against the reference implementation's numbers, its vehicle record, and the env running it."""

from __future__ import annotations

import json
import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import auv_gym  # noqa: F401  (registers the env ids)
import controllers
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.metrics import compute_metrics
from auv_gym.rollout import rollouts
from auv_gym.vehicle.actuators import actuator_record
from auv_gym.vehicle.remus6dof import (
    COEFFICIENTS,
    REMUS6DOF,
    SixDofVehicle,
    _current,
)
from auv_gym.vehicle.six_dof import six_dof_actuation, six_dof_nu_dot

REFERENCE = Path(__file__).parent / "data" / "pvs_remus100_6dof.json"
SHORT = {"max_time": 20.0}


def _compiled_accelerations(row: np.ndarray, hull: np.ndarray, a) -> np.ndarray:
    """ν̇ of the compiled plant at one grid row, posed as the reference poses it: its current
    is earth-fixed and horizontal (ν̇ = ν̇_r + ν̇_c) and its propeller advances at the speed over
    ground |ν|."""
    eta, nu = row[0:6], row[6:12]
    nu_c, dnu_c = _current(nu, eta[5], row[15], row[16])
    nu_r = tuple(float(value) for value in nu - nu_c)
    rudder = float(np.clip(row[12], -a.delta_max_rudder, a.delta_max_rudder))
    stern = float(np.clip(row[13], -a.delta_max_stern, a.delta_max_stern))
    rpm = float(np.clip(row[14], -a.rpm_max, a.rpm_max))
    speed = math.sqrt(nu[0] ** 2 + nu[1] ** 2 + nu[2] ** 2)
    scale = REMUS6DOF.propeller_torque_scale
    tau = six_dof_actuation(rpm, stern, rudder, nu_r, speed, scale, a)
    return dnu_c + np.array(six_dof_nu_dot(nu_r, eta[3], eta[4], tau, hull))


def test_compiled_accelerations_equal_the_reference_on_its_grid():
    rows = np.array(json.loads(REFERENCE.read_text())["rows"])
    assert rows.shape[0] >= 300
    hull = REMUS6DOF.kernel_vector()
    a = actuator_record(REMUS6DOF.actuators)
    worst = max(
        np.linalg.norm(_compiled_accelerations(row, hull, a) - row[17:23])
        / np.linalg.norm(row[17:23])
        for row in rows
    )
    assert worst <= 1e-9


def test_a_vehicle_record_round_trips_and_names_what_is_wrong():
    record = REMUS6DOF.record()
    assert tuple(record) == COEFFICIENTS
    np.testing.assert_array_equal(
        SixDofVehicle.from_record(record).kernel_vector(), REMUS6DOF.kernel_vector()
    )
    heavier = SixDofVehicle.from_record({**record, "length": 1.8})
    assert heavier.mass_kg > REMUS6DOF.mass_kg * 1.12
    incomplete = {k: v for k, v in record.items() if k != "hull_drag_coeff"}
    with pytest.raises(ValueError, match=r"missing the coefficient\(s\) \['hull_drag_coeff'\]"):
        SixDofVehicle.from_record(incomplete)
    with pytest.raises(ValueError, match=r"plant_params.*'fin_size'"):
        SixDofVehicle.from_record({**record, "fin_size": 1.0})
    with pytest.raises(ValueError, match="diameter"):
        SixDofVehicle(diameter=2.0)
    with pytest.raises(ValueError, match="roll_damping_ratio"):
        SixDofVehicle(roll_damping_ratio=math.nan)


def test_the_env_refuses_an_unknown_plant_and_hull_without_the_6dof():
    with pytest.raises(ValueError, match=r"unknown plant '7dof'; valid: \['5dof', '6dof'\]"):
        gym.make("AUVPath3D-v0", plant="7dof")
    with pytest.raises(ValueError, match="plant_params describe the hull of plant='6dof'"):
        gym.make("AUVPath3D-v0", plant_params=REMUS6DOF.record())
    record = {k: v for k, v in REMUS6DOF.record().items() if k != "strips"}
    with pytest.raises(ValueError, match=r"missing the coefficient\(s\) \['strips'\]"):
        gym.make("AUVPath3D-v0", plant="6dof", plant_params=record)


def _episode(seed: int, **kwargs) -> tuple[np.ndarray, list[dict]]:
    env = gym.make("AUVPath3D-v0", plant="6dof", **SHORT, **kwargs)
    obs, info = env.reset(seed=seed)
    observations, infos = [obs], [info]
    for k in range(200):
        action = np.array([0.6, 0.1 * math.sin(0.05 * k), 0.3])  # a steady turn
        obs, _, terminated, truncated, info = env.step(action)
        observations.append(obs)
        infos.append(info)
        if terminated or truncated:
            break
    return np.array(observations), infos


def test_the_6dof_env_is_deterministic_and_matches_the_vector_env():
    first, infos = _episode(3, disturbance="paper", param_uncertainty=0.2)
    again, _ = _episode(3, disturbance="paper", param_uncertainty=0.2)
    np.testing.assert_array_equal(first, again)
    vector = AUVPath3DVectorEnv(
        2, plant="6dof", disturbance="paper", param_uncertainty=0.2, **SHORT
    )
    obs, _ = vector.reset(seed=[3, 4])
    np.testing.assert_array_equal(obs[0], first[0])
    for k in range(1, 41):
        action = np.array([0.6, 0.1 * math.sin(0.05 * (k - 1)), 0.3])
        obs, *_, vinfo = vector.step(np.stack([action, action]))
        np.testing.assert_array_equal(obs[0], first[k])
    assert vinfo["phi"][0] == infos[40]["phi"]


def test_a_turn_rolls_the_6dof_vehicle_and_the_5dof_has_no_roll():
    _, infos = _episode(0, disturbance="none")
    roll = np.array([info["phi"] for info in infos])
    # Turning at speed heels the hull (the centripetal force acts at the centre of gravity,
    # below the centre of buoyancy); the restoring moment keeps it to a few degrees.
    assert 0.002 < np.abs(roll).max() < 0.2
    five = gym.make("AUVPath3D-v0", **SHORT)
    _, info = five.reset(seed=0)
    assert "phi" not in info


def test_the_propeller_torque_rolls_the_vehicle():
    def heel(scale: float) -> float:
        hull = REMUS6DOF.record() | {"propeller_torque_scale": scale}
        env = gym.make(
            "AUVPath3D-v0",
            plant="6dof",
            plant_params=hull,
            actuator="realistic",
            disturbance="none",
            **SHORT,
        )
        env.reset(seed=0)
        for _ in range(100):  # full shaft speed, fins centred
            _, _, terminated, _, info = env.step(np.array([1.0, 0.0, 0.0]))
            assert not terminated
        return info["phi"]

    assert abs(heel(0.0)) < 1e-6
    assert abs(heel(0.1)) > 100 * max(abs(heel(0.0)), 1e-9)


def test_a_6dof_rollout_reports_its_maximum_roll():
    env = {"plant": "6dof", "max_time": 30.0}
    trajectories = rollouts(controllers.make("fbsm_colos", env=env), [0, 1], **env)
    for trajectory in trajectories:
        assert trajectory.extras["roll"].shape == (trajectory.steps,)
        assert compute_metrics(trajectory)["max_roll"] == np.abs(trajectory.extras["roll"]).max()
    five = rollouts(controllers.make("fbsm_colos"), [0], max_time=30.0)[0]
    assert "max_roll" not in compute_metrics(five)


def test_a_policy_whose_observation_does_not_fit_is_named():
    """The observation layout is the same on both plants; an exported agent built for another
    layout is refused on the 6-DOF plant as on the 5-DOF, in one line naming both."""
    pytest.importorskip("onnxruntime")
    from benchmarks.catalog.policies import AGENTS_DIR

    graph = AGENTS_DIR / "ppo_generalist" / "policy.onnx"
    with pytest.raises(ValueError, match=r"observations of 49 values.*the env gives 15") as caught:
        controllers.make("onnx", path=str(graph), env={"plant": "6dof"})
    assert "\n" not in str(caught.value)
