"""Controllers: the Policy protocol, batching, memory resets, fuzzy basis, the laws' structure."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import controllers
from auv_gym import OBS_INDEX, OBS_NAMES
from auv_gym.sim.observation import OBS_DIM
from controllers.base import Policy
from controllers.fuzzy import N_RULES, WORK_DIM, adaptive_loop, fuzzy_basis
from controllers.gains import ControllerGains, pack_gains
from controllers.los import FILTER_DIM, LOOP_DIM, loop_errors

NAMES = [
    "fbsm",
    "backstepping",
    "fbsm_ilos",
    "backstepping_ilos",
    "fbsm_colos",
    "backstepping_colos",
    "pid_los",
    "pid_ilos",
    "pid_colos",
]


def observations(n, seed=0):
    rng = np.random.default_rng(seed)
    obs = np.zeros((n, OBS_DIM), dtype=np.float32)
    for name, (lo, hi) in {
        "x_e": (-5, 5),
        "y_e": (-5, 5),
        "z_e": (-5, 5),
        "psi_error": (-3, 3),
        "theta": (-0.4, 0.4),
        "theta_F": (0.2, 0.4),
        "u": (0.0, 1.5),
        "v": (-0.2, 0.2),
        "w": (-0.2, 0.2),
        "q": (-0.2, 0.2),
        "r": (-0.2, 0.2),
        "u_p": (0, 2),
        "psi_F_dot": (0.0, 0.2),
    }.items():
        obs[:, OBS_INDEX[name]] = rng.uniform(lo, hi, n)
    obs[:, OBS_INDEX["u_D"]] = 1.0
    return obs


@pytest.mark.parametrize("name", NAMES)
def test_protocol_single_and_batched(name):
    policy = controllers.make(name)
    assert isinstance(policy, Policy)
    action, state = policy.predict(observations(1)[0])
    assert action.shape == (3,) and action.dtype == np.float32
    actions, state = policy.predict(observations(5))
    assert actions.shape == (5, 3)
    assert np.all(np.abs(actions) <= 1.0)
    assert state["started"].all()


@pytest.mark.parametrize("name", NAMES)
def test_batched_equals_per_row(name):
    policy = controllers.make(name)
    batch_obs = [observations(4, seed=k) for k in range(20)]
    batch_actions, state = [], None
    for obs in batch_obs:
        a, state = policy.predict(obs, state)
        batch_actions.append(a)
    for row in range(4):
        row_state = None
        for k, obs in enumerate(batch_obs):
            a, row_state = policy.predict(obs[row : row + 1], row_state)
            np.testing.assert_array_equal(a[0], batch_actions[k][row])
        for key, value in state.items():  # the memory too (weights, filters, integrators)
            np.testing.assert_array_equal(row_state[key][0], value[row], err_msg=key)
    big = observations(100)  # the threaded kernel gives the same numbers
    threaded, _ = policy.predict(big)
    serial = np.vstack([policy.predict(big[i : i + 1])[0] for i in range(100)])
    np.testing.assert_array_equal(threaded, serial)


@pytest.mark.parametrize("name", NAMES)
def test_episode_start_resets_memory_of_those_rows_only(name):
    policy = controllers.make(name)
    obs = [observations(2, seed=k) for k in range(30)]
    state = None
    for o in obs:
        _, state = policy.predict(o, state)
    fresh_action, _ = policy.predict(obs[0][1:2])
    action, state = policy.predict(obs[0], state, episode_start=np.array([False, True]))
    np.testing.assert_array_equal(action[1], fresh_action[0])
    continued, _ = policy.predict(obs[0][:1], None)
    assert not np.array_equal(action[0], continued[0])  # row 0 kept its memory


def test_fbsm_adapts_and_keeps_b_hat_within_projection_bounds():
    policy = controllers.make("fbsm")
    state = None
    for k in range(200):
        _, state = policy.predict(observations(3, seed=k), state)
    assert np.abs(state["theta_f"]).max() > 0.0
    b = np.asarray(policy.b_nominal)[None, :, None]
    assert np.all(state["theta_b"] >= 0.5 * b - 1e-15)
    assert np.all(state["theta_b"] <= 2.0 * b + 1e-15)
    diag = policy.diagnostics(state)
    assert {"theta_d", "psi_d_rel", "norm_theta_f_surge", "b_hat_yaw"} <= set(diag)
    assert diag["norm_theta_f_pitch"].shape == (3,)


def test_fuzzy_basis_is_a_normalised_product_of_memberships():
    rng = np.random.default_rng(0)
    v = rng.uniform(-1, 1, (7, 5))
    xi = fuzzy_basis(v, p=1.0, q_mf=0.5, sigma=1.0)
    assert xi.shape == (7, N_RULES)
    np.testing.assert_allclose(xi.sum(axis=1), 1.0, rtol=1e-12)
    centres = -1.0 + 0.5 * np.arange(5)
    mu = np.exp(-(((v[:, :, None] - centres) / 1.0) ** 2))
    rule = (2, 4, 0, 1, 3)
    direct = np.prod([mu[:, i, j] for i, j in enumerate(rule)], axis=0)
    all_rules = np.prod(mu.sum(axis=2), axis=1)
    index = np.ravel_multi_index(rule, (5,) * 5)
    np.testing.assert_allclose(xi[:, index], direct / all_rules, rtol=1e-12)
    far = fuzzy_basis(np.full((1, 5), 1e3), p=1.0, q_mf=0.5, sigma=0.1)  # no underflow → NaN
    assert np.isfinite(far).all() and far[0, -1] == pytest.approx(1.0)


def d_basis(S, sigma_d):
    """ξ_d(S): three normalised Gaussians of width σ_d centred at −σ_d, 0, σ_d
    (docs/model.md §4.5)."""
    mu = np.exp(-(((S - sigma_d * np.array([-1.0, 0.0, 1.0])) / sigma_d) ** 2))
    return mu / mu.sum()


@pytest.mark.parametrize("leak", [0.0, 0.05])
@pytest.mark.parametrize("separate", [False, True])
def test_fuzzy_kernel_matches_the_reference_basis_and_adaptive_laws(leak, separate):
    """The compiled loop: f̂ = θ_fᵀξ, b̂ = θ_bᵀξ_b, d̂ = θ_dᵀξ_d(S), τ = (−f̂ − d̂ + rest)/b̂, and
    one Euler step of (30) with leakage and projection; frozen while saturated (anti-windup)."""
    gains = ControllerGains(sigma_leak=leak, separate_b_basis=separate)
    b_n, dt, limit = 0.12, 0.05, 10.0
    g = pack_gains(gains, dt, (0.03, b_n, b_n), (0.0, 1.0, 50.0, limit, limit))
    mf = gains.pitch_mf
    rng = np.random.default_rng(3)
    v_in = np.array([0.9, 0.05, -0.04, 0.1, -0.08])
    theta_f = 0.1 * rng.standard_normal(N_RULES)
    theta_b = b_n * rng.uniform(0.5, 2.0, N_RULES)
    theta_b[:5], theta_b[5:10] = 0.5 * b_n, 2.0 * b_n  # entries on the projection bounds
    theta_d = rng.standard_normal(3)
    xi = fuzzy_basis(v_in, mf.p, mf.q_mf, mf.sigma)[0]
    xi_b = fuzzy_basis(v_in, mf.p, mf.q_mf, mf.sigma_b)[0] if separate else xi
    S, rest = 0.2, 0.3
    xi_d = d_basis(S, mf.sigma_d)
    f_hat, b_hat, d_hat = theta_f @ xi, theta_b @ xi_b, theta_d @ xi_d
    tau = (-f_hat - d_hat + rest) / b_hat
    assert abs(tau) < limit

    new_f, new_b, new_d, diag = theta_f.copy(), theta_b.copy(), theta_d.copy(), np.empty(3)
    action = adaptive_loop(
        1, v_in, S, rest, limit, b_n, new_f, new_b, new_d, g, np.empty(WORK_DIM), diag
    )
    np.testing.assert_allclose(diag, [f_hat, b_hat, d_hat], rtol=1e-12)
    assert action == pytest.approx(tau / limit, rel=1e-12)
    a_f, a_b, a_d = gains.alpha_f, gains.alpha_b, gains.alpha_d
    np.testing.assert_allclose(
        new_f, theta_f + dt * a_f * (S * xi - leak * theta_f), rtol=1e-12, atol=1e-15
    )
    expected_b = theta_b + dt * a_b * (S * xi_b * tau - leak * (theta_b - b_n))
    np.testing.assert_allclose(new_b, np.clip(expected_b, 0.5 * b_n, 2.0 * b_n), rtol=1e-12)
    np.testing.assert_allclose(new_d, theta_d + dt * a_d * (S * xi_d - leak * theta_d), rtol=1e-12)

    frozen_f, frozen_b, frozen_d = theta_f.copy(), theta_b.copy(), theta_d.copy()
    action = adaptive_loop(
        1, v_in, S, 1e3, limit, b_n, frozen_f, frozen_b, frozen_d, g, np.empty(WORK_DIM), diag
    )
    assert action == 1.0  # saturated: no adaptation
    np.testing.assert_array_equal(frozen_f, theta_f)
    np.testing.assert_array_equal(frozen_b, theta_b)
    np.testing.assert_array_equal(frozen_d, theta_d)


def test_yaw_error_decays_at_k2_plus_c2_over_cos_theta_on_the_surface():
    """docs/model.md §10.6: with S3 = 0, ż3 = −(k2 + c2/cosθ) z3 (the 1/cosθ correction)."""
    gains = ControllerGains()
    g = pack_gains(gains, 0.05, (0.03, 0.12, 0.12), (0.0, 1.0, 50.0, 10.0, 10.0))
    o = np.zeros(OBS_DIM)
    theta, z3, psi_dot_f = 0.4, 0.3, 0.05
    o[OBS_INDEX["theta"]] = theta
    o[OBS_INDEX["u"]] = 0.05  # below the guard: β = 0, so ψ_d = ψ_F + x_y with x_y = 0
    o[OBS_INDEX["psi_error"]] = z3
    o[OBS_INDEX["psi_F_dot"]] = psi_dot_f
    # r such that S3 = c2 z3 + r − cosθ(−k2 z3 + ψ̇_F) = 0
    o[OBS_INDEX["r"]] = math.cos(theta) * (-gains.k2 * z3 + psi_dot_f) - gains.c2 * z3
    out = np.empty(LOOP_DIM)
    loop_errors(o, g, np.zeros(FILTER_DIM), False, out)
    assert out[5] == pytest.approx(z3)
    assert out[7] == pytest.approx(0.0, abs=1e-12)
    assert out[8] == pytest.approx(-(gains.k2 + gains.c2 / math.cos(theta)) * z3, rel=1e-12)


def test_controllers_read_the_observation_by_name_only():
    import inspect

    import controllers.backstepping
    import controllers.fbsm
    import controllers.los

    for module in (controllers.los, controllers.fbsm, controllers.backstepping):
        source = inspect.getsource(module)
        assert "OBS_INDEX[" in source
        assert "o[6]" not in source and "obs[:, 6]" not in source
    assert OBS_NAMES[OBS_INDEX["u"]] == "u"


def test_controllers_run_inside_sb3_evaluate_policy():
    pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.evaluation import evaluate_policy
    from stable_baselines3.common.monitor import Monitor

    from auv_gym.rollout import rollouts

    for name in NAMES:
        env = Monitor(gym.make("AUVPath3D-v0", max_time=20.0, disturbance="none"))
        mean, std = evaluate_policy(controllers.make(name), env, n_eval_episodes=2)
        assert std == 0.0  # noise-free: the two episodes are identical
        (reference,) = rollouts(controllers.make(name), [0], max_time=20.0, disturbance="none")
        assert mean == pytest.approx(reference["reward"].sum(), rel=1e-5)


def test_fins_actuator_normalises_by_speed_dependent_authority():
    fins = controllers.make("backstepping", actuator="fins")
    paper = controllers.make("backstepping")
    obs = observations(1)
    obs[0, OBS_INDEX["u"]] = 1.0
    a_fins, _ = fins.predict(obs)
    a_paper, _ = paper.predict(obs)
    authority = 6.15 * math.pi / 6
    expected = np.clip(a_paper[0, 1:] * 10.0 / authority, -1, 1)
    np.testing.assert_allclose(a_fins[0, 1:], expected, rtol=1e-5)
    obs[0, OBS_INDEX["u"]] = 0.0
    a_rest, _ = fins.predict(obs)
    assert set(np.abs(a_rest[0, 1:])) <= {0.0, 1.0}  # no authority at rest: saturated or zero


@pytest.mark.parametrize(
    ("kwargs", "error"),
    [
        ({"control_dt": -0.05}, "control_dt"),
        ({"actuator": "jets"}, "actuator"),
        ({"k1": -1.0}, "k1"),
        ({"bogus_gain": 1.0}, r"unknown \w+ keyword arguments \[.bogus_gain.\]; valid: \[.gains."),
        ({"params": "remus"}, "AUVParams"),
        ({"threads": 2}, "threads"),
        ({"ilos_y": -1.0}, "ilos_y must be >= 0"),
        ({"ilos_z": math.nan}, "ilos_z"),
        ({"current_observer": -1.0}, r"current_observer must be a finite number in \[0, ∞\) rad/s"),
        ({"current_observer": math.nan}, "current_observer must be a finite number"),
        ({"current_observer": "3"}, "current_observer must be a real number"),
        ({"alos_y": -0.01}, r"alos_y must be a finite number in \[0, ∞\)"),
        ({"alos_z": math.inf}, "alos_z must be a finite number"),
        ({"alos_radius": 0.0}, r"alos_radius must be a finite number in \(0, ∞\) m, got 0.0"),
        ({"alos_radius": math.nan}, "alos_radius must be a finite number"),
        ({"alos_max": -0.1}, "alos_max must be a finite number in"),
        ({"alos_max": 2.0}, r"alos_max must be a finite number in \(0, 1.5708\) rad, got 2.0"),
        ({"speed_over_ground": "yes"}, "speed_over_ground must be True or False"),
        ({"current_observer": 20.0}, "current_observer × control_dt must be below 0.828"),
        ({"speed_over_ground": True}, "speed_over_ground=True needs current_observer > 0"),
    ],
)
def test_bad_configuration_raises(kwargs, error):
    with pytest.raises(ValueError, match=error):
        controllers.make("fbsm", **kwargs)


def test_bad_observations_and_names_raise():
    policy = controllers.make("fbsm")
    with pytest.raises(ValueError, match="shape"):
        policy.predict(np.zeros(14))
    with pytest.raises(ValueError, match="finite"):
        policy.predict(np.full(OBS_DIM, np.nan))
    _, state = policy.predict(observations(2))
    with pytest.raises(ValueError, match="vehicles"):
        policy.predict(observations(3), state)
    with pytest.raises(ValueError, match="unknown controller 'lqr'"):
        controllers.make("lqr")
    # a reference agent's name is the benchmark's: the message says how Python loads it
    with pytest.raises(ValueError, match=r"benchmarks/agents/ included, loads by its folder"):
        controllers.make("ppo_generalist")


def test_speed_benchmark_runs_in_closed_loop():
    from benchmarks.speed.controllers import closed_loop, episode_wall_time

    out = closed_loop("fbsm", n=3, steps=4, threads=1, warmup=2)
    assert out["rate"] > 0.0 and 0.0 <= out["saturated"] <= 1.0
    assert 0.0 < episode_wall_time("backstepping") < 60.0


@pytest.mark.parametrize("control_dt", [0.05, 0.01])
@pytest.mark.parametrize("name", ["fbsm", "backstepping"])
def test_integral_los_removes_the_offset_a_constant_current_leaves(name, control_dt):
    """A 0.3 m/s cross current on a straight line: the paper's LOS (no integral action) settles
    at a constant cross-track offset; integral LOS (`<name>_ilos`, σ_y = 3) drives it to zero."""
    from auv_gym.rollout import rollouts

    env = {
        "path": "line",
        "disturbance": "none",
        "current": {"mean": (0.0, 0.3, 0.0)},
        "max_time": 300.0,
        "control_dt": control_dt,
    }
    (los,) = rollouts(controllers.make(name, control_dt=control_dt), [0], **env)
    (ilos,) = rollouts(controllers.make(f"{name}_ilos", control_dt=control_dt), [0], **env)
    late = los.t >= 200.0
    assert np.all(np.abs(los["y_e"][late]) > 2.5)  # measured 2.84 m, constant
    assert np.ptp(los["y_e"][late]) < 0.01
    assert np.all(np.abs(ilos["y_e"][late]) < 0.02)  # measured < 0.007 m after 200 s
    assert abs(ilos["y_e"][-1]) < 1e-3
    assert ilos.termination_reason == los.termination_reason == "time_limit"


def test_loop_errors_refuses_a_filter_memory_of_the_wrong_size():
    g = pack_gains(ControllerGains(), 0.05, (1.0, 1.0, 1.0), (0.0, 1.0, 50.0, 10.0, 10.0))
    with pytest.raises(ValueError, match="FILTER_DIM"):
        loop_errors(observations(1)[0], g, np.zeros(6), False, np.zeros(LOOP_DIM))
