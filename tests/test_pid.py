"""PID + LOS autopilot (`controllers.pid`): tuning, closed loop, currents, memory, anti-windup."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import controllers
from auv_gym.metrics import compute_metrics
from auv_gym.rollout import rollouts
from auv_gym.vehicle import remus100
from controllers.base import Policy
from controllers.pid import PIDGains, pid_tuning
from tests.test_controllers import observations

NAMES = ["pid_los", "pid_ilos", "pid_colos"]
CURRENT = {"disturbance": "none", "current": {"mean": (0.0, 0.3, 0.0)}}


def test_pole_placement_gives_the_chosen_closed_loop_poles():
    """Fossen's K_p = mω_n² − k, K_d = 2ζω_n m − d, K_i = ω_n/10·K_p on the REMUS model
    linearised at 1 m/s: the PD loops have the double pole −ω_n, the surge P loop −ω_u."""
    p, pid = remus100(), PIDGains()
    t = pid_tuning(p, pid)
    assert t.kp_theta == pytest.approx(8.33 * 9.0 - 0.0196 * 299.0, rel=1e-12)  # 69.1 N·m/rad
    assert t.kd_theta == pytest.approx(2 * 3.0 * 8.33 - 2.0, rel=1e-12)  # 47.98 N·m·s/rad
    assert t.ki_theta == pytest.approx(0.3 * t.kp_theta, rel=1e-12)
    assert t.kp_psi == pytest.approx(8.33 * 6.25, rel=1e-12)
    assert t.kp_u == pytest.approx(31.41 - 3.24, rel=1e-12)
    assert t.ki_u == pytest.approx(0.1 * t.kp_u, rel=1e-12)
    for m, d, k, kp, kd, wn in (
        (p.I55, 2.0, 0.0196 * 299.0, t.kp_theta, t.kd_theta, 3.0),
        (p.I66, 2.0, 0.0, t.kp_psi, t.kd_psi, 2.5),
    ):
        np.testing.assert_allclose(np.roots([m, d + kd, k + kp]), [-wn, -wn], rtol=1e-6)
    assert (-3.24 - t.kp_u) / p.m11 == pytest.approx(-1.0, rel=1e-12)
    assert controllers.make("pid_los", pitch_wn=2.0).tuning.kp_theta == pytest.approx(
        8.33 * 4.0 - 0.0196 * 299.0, rel=1e-12
    )


@pytest.mark.parametrize("name", NAMES)
def test_registered_like_the_other_classical_controllers(name):
    from benchmarks.catalog.policies import PolicySpec

    policy = controllers.make(name)
    assert isinstance(policy, controllers.PIDLOS) and isinstance(policy, Policy)
    assert name in controllers.CLASSICAL and PolicySpec.parse(name).kind == "classical"
    action, state = policy.predict(observations(1)[0])
    assert action.shape == (3,) and action.dtype == np.float32
    assert set(state) == {"filter", "integral", "started", "diag"} and state["started"].all()


def test_follows_the_paper_helix_without_noise():
    (tr,) = rollouts(controllers.make("pid_los"), [0], disturbance="none")
    m = compute_metrics(tr, transient=100.0)
    assert tr.termination_reason == "time_limit"
    assert m["rms_distance"] < 0.02  # measured 0.0173 m: the LOS residual of docs/model.md §10.5
    assert m["rms_z_e"] < 0.001  # measured 0.0001 m
    assert m["settling_time_0p5"] < 28.0  # measured 23.7 s (FBSM 31.3 s, backstepping 29.7 s)
    assert m["surge_overshoot"] < 0.09  # measured 0.075 m/s: the PI integrates the approach
    # the paper's command filter (ω_n = 2 rad/s) lags inside the depth loop, which then hunts
    (paper,) = rollouts(controllers.make("pid_los", filter_wn=2.0), [0], disturbance="none")
    assert compute_metrics(paper, transient=100.0)["rms_z_e"] > 0.1  # measured 0.126 m


def test_paper_scenario_with_noise():
    """The paper's helix and ±35 N / N·m noise, 300 s, RMS distance over t ≥ 100 s."""
    trs = rollouts(controllers.make("pid_los"), [0, 1, 2])
    metrics = [compute_metrics(tr, transient=100.0) for tr in trs]
    assert [tr.termination_reason for tr in trs] == ["time_limit"] * 3
    rms = [m["rms_distance"] for m in metrics]
    np.testing.assert_allclose(rms, [0.0959, 0.1029, 0.0843], atol=5e-4)  # measured
    assert max(rms) < 0.13 and all(m["success"] for m in metrics)
    assert max(m["chattering"] for m in metrics) < 9.0  # measured 8.1-8.3 1/s (FBSM 20.5)


def test_current_observer_beats_plain_and_integral_los_in_a_constant_current():
    """Helix in a constant 0.3 m/s cross current, no noise: the paper's LOS leaves a crab-angle
    offset; integral LOS only chases the turning crab angle; the observer follows it."""
    rms = {}
    for name in NAMES:
        (tr,) = rollouts(controllers.make(name), [0], **CURRENT)
        assert tr.termination_reason == "time_limit"
        rms[name] = compute_metrics(tr, transient=100.0)["rms_distance"]
    assert rms["pid_los"] > 1.8  # measured 2.06 m
    assert 0.3 < rms["pid_ilos"] < 0.6  # measured 0.42 m
    assert rms["pid_colos"] < 0.03  # measured 0.0195 m
    assert rms["pid_colos"] < rms["pid_ilos"] / 10 < rms["pid_los"] / 10


def test_batched_rollouts_equal_single_episodes():
    batched = rollouts(controllers.make("pid_colos"), [0, 1], max_time=20.0)
    for seed, tr in zip([0, 1], batched, strict=True):
        (single,) = rollouts(controllers.make("pid_colos"), [seed], max_time=20.0)
        np.testing.assert_array_equal(tr.actions, single.actions)
        np.testing.assert_array_equal(tr["integral"], single["integral"])


def test_episode_start_resets_the_integrators_of_those_rows_only():
    policy = controllers.make("pid_los")
    obs = [observations(2, seed=k) for k in range(30)]
    state = None
    for o in obs:
        _, state = policy.predict(o, state)
    assert np.abs(state["integral"]).min() > 0.0
    kept = state["integral"][0].copy()
    fresh_action, fresh_state = policy.predict(obs[0][1:2])
    action, state = policy.predict(obs[0], state, episode_start=np.array([False, True]))
    np.testing.assert_array_equal(action[1], fresh_action[0])
    np.testing.assert_array_equal(state["integral"][1], fresh_state["integral"][0])
    assert not np.array_equal(state["integral"][0], fresh_state["integral"][0])
    assert not np.array_equal(state["integral"][0], kept)  # row 0 integrated on


def test_anti_windup_keeps_the_fin_limited_vehicle_on_the_path():
    """Fin moments (3.2 N·m at 1 m/s) saturate during the approach. Conditional integration
    keeps |K_i I| within the authority and the PID settles; integrating regardless winds the
    pitch integrator up 26-fold and the depth loop limit-cycles at the fin limit."""
    env = {"disturbance": "none", "actuator": "fins", "max_time": 150.0}
    clamped = controllers.make("pid_los", actuator="fins")
    (tr,) = rollouts(clamped, [0], **env)
    (wound,) = rollouts(controllers.make("pid_los", actuator="fins", anti_windup=False), [0], **env)
    m, m_wound = compute_metrics(tr, transient=100.0), compute_metrics(wound, transient=100.0)
    assert m["rms_distance"] < 0.02  # measured 0.0177 m
    assert m_wound["rms_distance"] > 0.8  # measured 1.08 m
    assert m_wound["saturation_fraction_M"] > 0.9  # measured 0.96 (0.16 with anti-windup)
    authority = 6.15 * math.pi / 6 * tr["u"][:-1] ** 2  # fin moment limit at each sample [N·m]
    k_i = clamped.tuning.ki_theta
    assert np.all(k_i * np.abs(tr["integral"][:, 1]) <= authority * (1 + 1e-6))  # float32 u
    assert np.abs(wound["integral"][:, 1]).max() > 20 * np.abs(tr["integral"][:, 1]).max()


@pytest.mark.parametrize(
    ("kwargs", "error"),
    [
        (
            {"pitch_wn": -1.0},
            r"PIDGains.pitch_wn must be a finite number in \(0, ∞\) rad/s, got -1.0",
        ),
        ({"yaw_wn": math.nan}, "PIDGains.yaw_wn must be a finite number"),
        ({"surge_wn": math.inf}, "PIDGains.surge_wn must be a finite number"),
        ({"yaw_zeta": 0.0}, r"PIDGains.yaw_zeta must be a finite number in \(0, ∞\), got 0.0"),
        ({"integral_ratio": -0.1}, r"PIDGains.integral_ratio must be a finite number in \[0, ∞\)"),
        ({"design_speed": "1"}, "PIDGains.design_speed must be a real number"),
        ({"anti_windup": "yes"}, "PIDGains.anti_windup must be True or False"),
        (
            {"pitch_wn": 0.5},
            r"PIDGains.pitch_wn = 0.5 rad/s gives the pitch loop K_p = m ω_n² − k = "
            r"-3.78 ≤ 0; it must exceed √\(k/m\) = 0.839 rad/s",
        ),
        ({"yaw_wn": 0.1}, "PIDGains.yaw_wn = 0.1 rad/s gives the yaw loop K_d = 2ζω_n m − d"),
        ({"surge_wn": 0.05}, "PIDGains.surge_wn = 0.05 rad/s gives K_p,u"),
        ({"k1": 5.0}, r"unknown pid_los gains \['k1'\]"),
        ({"k_y": -0.1}, "ControllerGains.k_y must be positive"),
        ({"filter_wn": 30.0}, r"filter_wn × control_dt must be below 1, got 30.0 rad/s × 0.05 s"),
        ({"pid": "fast"}, "pid must be a PIDGains, got str"),
        ({"control_dt": 0.0}, "control_dt must be a positive time"),
    ],
)
def test_bad_gains_raise_one_named_error(kwargs, error):
    with pytest.raises(ValueError, match=error):
        controllers.make("pid_los", **kwargs)


def test_runs_inside_sb3_evaluate_policy():
    pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.evaluation import evaluate_policy
    from stable_baselines3.common.monitor import Monitor

    for name in NAMES:
        env = Monitor(gym.make("AUVPath3D-v0", max_time=20.0, disturbance="none"))
        mean, std = evaluate_policy(controllers.make(name), env, n_eval_episodes=2)
        assert std == 0.0  # noise-free: the second episode starts with fresh integrators
        (reference,) = rollouts(controllers.make(name), [0], max_time=20.0, disturbance="none")
        assert mean == pytest.approx(reference["reward"].sum(), rel=1e-5)
