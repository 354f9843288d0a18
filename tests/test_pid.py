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
from benchmarks.catalog.scenarios import load_scenarios
from controllers.base import Policy
from controllers.gains import FIN_GAIN
from controllers.pid import PIDGains, _climb_reference, pid_tuning
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
    assert set(state) == {"filter", "integral", "started", "diag", "climb"}
    assert state["started"].all()


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


def test_climb_reference_steps_towards_the_speed_the_pitch_demand_needs():
    """u_M = √(|M|/(share·Kδ_max)); u_c moves Δt_c/T_c of the way to clip(u_M, u_ref, u_max)
    each control period; the loop tracks max(u_ref, u_c) and feeds its rate forward."""
    policy = controllers.make("pid_los", actuator="fins", climb_speed=1.5, climb_time=2.0)
    g, k = policy._g, policy._k
    share_of_authority = 0.8 * g[FIN_GAIN]  # [N·m per (m/s)²]
    climb = np.array([1.0])
    # the demand at 1.2 m/s: a 1/40 step from 1.0 towards 1.2, the rate 0.005/0.05 fed forward
    u_ref, du_ref = _climb_reference(1.44 * share_of_authority, 1.0, 0.0, g, k, climb, True)
    assert (u_ref, du_ref) == pytest.approx((1.005, 0.1), rel=1e-12)
    assert climb[0] == u_ref
    # a demand beyond what 1.5 m/s gives is capped there, and the sign of M does not matter
    climb[0] = 1.0
    u_ref, _ = _climb_reference(-100.0 * share_of_authority, 1.0, 0.0, g, k, climb, True)
    assert u_ref == pytest.approx(1.0 + 0.5 / 40.0, rel=1e-12)
    # no demand: u_c decays towards u_ref and the loop tracks u_ref with its own rate once below
    climb[0] = 1.01
    u_ref, du_ref = _climb_reference(0.0, 1.0, 0.0, g, k, climb, True)
    assert u_ref == pytest.approx(1.01 - 0.01 / 40.0, rel=1e-12) and du_ref < 0.0
    assert _climb_reference(0.0, 1.2, 0.3, g, k, climb, True) == (1.2, 0.3)
    # a fresh vehicle starts from u_ref whatever the memory held
    climb[0] = 7.0
    assert _climb_reference(0.0, 1.0, 0.0, g, k, climb, False) == (1.0, 0.0)


def test_climb_speed_keeps_the_6dof_hull_on_the_as_built_helix():
    """The guarded as-built PID on the 6-DOF plant (test seed 2, 300 s): its stern plane is at
    the limit on the climb at u_D and z_e grows to metres; with the climb-speed law the surge
    reference rises to at most 1.4 m/s and the depth error stays in decimetres."""
    scenario = load_scenarios()["as_built_helix"]
    env = {**scenario.env, "max_time": 300.0, "plant": "6dof"}
    results = {}
    for name in ("pid_as_built_guarded", "pid_as_built_climb_guarded"):
        (tr,) = rollouts(controllers.make(name, env=env, **scenario.controller), [2], **env)
        assert tr.termination_reason == "time_limit"
        results[name] = (tr, compute_metrics(tr, transient=100.0))
    plain, climbing = results["pid_as_built_guarded"][1], results["pid_as_built_climb_guarded"][1]
    assert plain["rms_z_e"] > 2.0  # measured 3.88 m
    assert climbing["rms_z_e"] < 0.2 and climbing["rms_distance"] < 0.3  # measured 0.091, 0.183 m
    reference = results["pid_as_built_climb_guarded"][0]["climb_reference"]
    assert reference.max() <= 1.4 and np.quantile(reference, 0.9) > 1.2


def test_the_soft_pitch_loop_rides_the_waves_the_stiff_one_fights():
    """The coastal survey in sea state 3 (test seed 0, 200 s, window t >= 50 s): the climb-speed
    PID's pitch loop at 3 rad/s drives the fins into their rate limit and pitches with the
    waves; the soft-pitch preset's (2 rad/s, zeta 1.4) half as often, and holds the depth better
    (docs/model.md §4.9, "The pitch loop in waves")."""
    scenario = load_scenarios()["as_built_coastal"]
    env = {**scenario.env, "max_time": 200.0}
    seen = {}
    for name in ("pid_as_built_climb", "pid_as_built_climb_soft_pitch"):
        (tr,) = rollouts(controllers.make(name, env=env, **scenario.controller), [0], **env)
        assert tr.termination_reason == "time_limit"
        window = tr.t[:-1] >= 50.0
        seen[name] = (
            float(np.mean(tr["fin_rate_limited"][window])),
            float(np.std(tr["theta"][:-1][window])),
            compute_metrics(tr, transient=50.0)["rms_z_e"],
        )
    stiff, soft = seen["pid_as_built_climb"], seen["pid_as_built_climb_soft_pitch"]
    assert stiff[0] > 0.15 and soft[0] < 0.6 * stiff[0]  # measured 0.205 and 0.110
    assert soft[1] < 0.6 * stiff[1]  # RMS pitch about its mean, measured 0.121 and 0.052 rad
    assert soft[2] < 0.8 * stiff[2]  # RMS z_e, measured 0.204 and 0.133 m


def test_climb_speed_returns_to_u_desired_on_a_level_line():
    """On the approach to a level line (8 m of depth error) the pitch demand raises the surge
    reference; once on the line the demand is small and the reference is u_D again."""
    env = {"disturbance": "none", "actuator": "fins", "max_time": 150.0, "path": "line"}
    (tr,) = rollouts(controllers.make("pid_los", actuator="fins", climb_speed=1.5), [0], **env)
    reference = tr["climb_reference"]
    assert reference[:300].max() > 1.3  # measured 1.43 m/s on the approach
    assert np.abs(reference[len(reference) // 2 :] - 1.0).max() < 1e-9
    assert compute_metrics(tr, transient=100.0)["rms_distance"] < 0.001  # measured 0.00014 m


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
        (
            {"k1": 5.0},
            r"unknown pid_los keyword arguments \[.k1.\]; valid: \[.pid., .gains.*"
            r"its gains \[.*.pitch_wn.",
        ),
        ({"k_y": -0.1}, "ControllerGains.k_y must be positive"),
        ({"filter_wn": 30.0}, r"filter_wn × control_dt must be below 1, got 30.0 rad/s × 0.05 s"),
        ({"pid": "fast"}, "pid must be a PIDGains, got str"),
        ({"control_dt": 0.0}, "control_dt must be a positive time"),
        ({"climb_speed": -1.0}, r"PIDGains.climb_speed must be a finite number in \[0, ∞\) m/s"),
        ({"climb_authority": 0.0}, r"PIDGains.climb_authority must be a finite number in \(0, 1\]"),
        ({"climb_authority": 1.5}, r"PIDGains.climb_authority must be a finite number in \(0, 1\]"),
        ({"climb_time": math.nan}, "PIDGains.climb_time must be a finite number"),
        (
            {"climb_speed": 1.4, "actuator": "fins", "climb_time": 0.01},
            "climb_time = 0.01 s must be at least control_dt = 0.05 s",
        ),
        ({"climb_speed": 1.4}, "climb_speed needs the fins' authority .* got actuator 'paper'"),
    ],
)
def test_bad_gains_raise_one_named_error(kwargs, error):
    with pytest.raises(ValueError, match=error):
        controllers.make("pid_los", **kwargs)


def test_the_climb_law_checks_only_bind_when_it_is_on():
    """A slow control period (3 s > T_c = 2 s) or the paper's actuator is refused only with
    the law on; without it the PID builds as it did before the law existed."""
    slow = {"control_dt": 3.0, "filter_wn": 0.1}
    assert controllers.make("pid_los", **slow).control_dt == 3.0
    with pytest.raises(ValueError, match=r"climb_time = 2\.0 s must be at least control_dt = 3\.0"):
        controllers.make("pid_los", actuator="fins", climb_speed=1.4, **slow)
    assert controllers.make("pid_los", actuator="paper").pid.climb_speed == 0.0


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
