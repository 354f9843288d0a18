"""The depth envelope (sea surface, seabed, "broached"/"grounded"), path_offset and the safety
cost info["cost"]."""

from __future__ import annotations

import math

import numpy as np
import pytest

from auv_gym import AUVPath3DEnv
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.ocean.depth_envelope import DepthEnvelope, path_depth_range
from auv_gym.paths.offset import ShiftedPath, shift_path
from auv_gym.paths.shapes import DEFAULT_WAYPOINTS, Helix, Spline
from auv_gym.sim.config import SimConfig
from auv_gym.sim.safety_cost import SafetyCost, safety_vector
from auv_gym.sim.task import RewardWeights, TaskLimits, task_cost, task_vector
from auv_gym.vehicle.dynamics import STATE, STATE_DIM

# A level line 10 m deep; the default start is 8 m below p(0), at 18 m.
LEVEL = {"kind": "line", "start": [0.0, 0.0, 10.0], "direction": [1.0, 0.0, 0.0]}
ENVELOPE = {
    "path": LEVEL,
    "disturbance": "none",
    "corridor": 100.0,
    "max_pitch": 1.4,
    "depth_envelope": {"seabed_depth": 25.0, "margin": 2.0},
}


def _expected_cost(
    z: float, u: float, theta: float, envelope: DepthEnvelope, cost: SafetyCost
) -> float:
    """The documented formula (auv_gym.sim.safety_cost), written out independently."""
    m = envelope.margin
    seabed = math.inf if envelope.seabed_depth is None else envelope.seabed_depth
    intrusion = max(m - z, z - (seabed - m), 0.0)
    u_c, theta_c = cost.speed_limit, cost.pitch_limit
    return (
        cost.depth * min(intrusion / m, 1.0)
        + cost.speed * min(max(u - u_c, 0.0) / u_c, 1.0)
        + cost.pitch * min(max(abs(theta) - theta_c, 0.0) / theta_c, 1.0)
    )


def _hold_pitch(state: np.ndarray, theta_ref: float) -> np.ndarray:
    """Full thrust and a PD pitch law towards theta_ref [rad] (nose-up positive)."""
    theta, q = state[STATE.theta], state[STATE.q]
    return np.array([1.0, np.clip(4.0 * (theta_ref - theta) - 4.0 * q, -1.0, 1.0), 0.0])


def _drive(env: AUVPath3DEnv, theta_ref: float, seed: int = 0, steps: int = 4000):
    """Steps (state, info) until the episode ends."""
    env.reset(seed=seed)
    history = []
    for _ in range(steps):
        _, _, terminated, truncated, info = env.step(_hold_pitch(env.state, theta_ref))
        history.append((env.state, info))
        if terminated or truncated:
            break
    return history


@pytest.mark.parametrize(("theta_ref", "reason"), [(0.5, "broached"), (-0.5, "grounded")])
def test_a_vehicle_driven_up_broaches_and_one_driven_down_grounds(theta_ref, reason):
    env = AUVPath3DEnv(**ENVELOPE)
    history = _drive(env, theta_ref)
    (last, info), (before, _) = history[-1], history[-2]
    assert info["termination_reason"] == reason
    if reason == "broached":
        assert last[STATE.z] < 0.0 <= before[STATE.z]
    else:
        assert last[STATE.z] > 25.0 >= before[STATE.z]
    assert info["reward_termination"] == -RewardWeights().termination
    # Every step's cost is the formula of the state after it; it grows inside the margin.
    envelope, cost = DepthEnvelope(25.0, 2.0), SafetyCost()
    for state, step_info in history:
        expected = _expected_cost(
            state[STATE.z], state[STATE.u], state[STATE.theta], envelope, cost
        )
        assert step_info["cost"] == pytest.approx(expected, abs=1e-12)
    assert history[0][1]["cost"] == 0.0
    assert info["cost"] >= 1.0  # beyond the boundary the depth term is its full weight


def test_the_cost_of_a_constructed_state_is_the_hand_computed_number():
    # z = 1 m: 1 m into the 2 m margin (0.5 of w_depth = 2); u = 2.5 m/s: 0.25 above u_c = 2
    # (w_speed = 1); θ = 50°: 5° beyond θ_c = 45° (5/45 of w_pitch = 3):
    # c = 2·0.5 + 1·0.25 + 3·(5/45) = 1.25 + 1/3 = 1.583333...
    cost = SafetyCost(depth=2.0, speed=1.0, pitch=3.0)
    task = task_vector(RewardWeights(), TaskLimits(), safety_vector(DepthEnvelope(), cost))
    state = np.zeros(STATE_DIM)
    state[STATE.z], state[STATE.u], state[STATE.theta] = 1.0, 2.5, math.radians(50.0)
    assert task_cost(state, task) == pytest.approx(1.25 + 1.0 / 3.0, rel=1e-12)
    # The same state without an envelope and with the default unit weights: no depth term.
    plain = task_vector(RewardWeights(), TaskLimits())
    assert task_cost(state, plain) == pytest.approx(0.25 + 1.0 / 9.0, rel=1e-12)
    state[STATE.z] = math.nan  # an unknown state costs every weight
    assert task_cost(state, task) == 6.0


def test_the_paper_scenario_costs_nothing():
    import controllers
    from auv_gym.metrics import compute_metrics
    from auv_gym.rollout import rollouts

    (trajectory,) = rollouts(controllers.make("fbsm_colos"), [0])
    assert trajectory.termination_reason == "time_limit"
    assert trajectory.steps == 6000
    assert np.all(trajectory["cost"] == 0.0)
    assert compute_metrics(trajectory)["episode_cost"] == 0.0


def test_without_an_envelope_depth_ends_nothing_and_info_reports_cost():
    env = AUVPath3DEnv(disturbance="none")
    _, reset_info = env.reset(seed=0)
    assert "cost" not in reset_info  # Safety-Gymnasium: a cost per step
    _, _, _, _, info = env.step(np.zeros(3))
    assert info["cost"] == 0.0
    row = env.sim._task[0]
    assert row[-8] == -math.inf and row[-7] == math.inf  # surface, seabed: never reached


def test_the_helix_moved_to_real_depth_stays_below_the_surface():
    env = AUVPath3DEnv(path_offset=(0.0, 0.0, 110.0), depth_envelope={"seabed_depth": 130.0})
    assert isinstance(env.config.path, ShiftedPath)
    position, _ = env.config.path.default_start()
    np.testing.assert_array_equal(position, [15.0, 5.0, 110.0])  # the paper's start, 110 m down
    p0 = env.config.path.evaluate(0.0)[0]
    np.testing.assert_array_equal(p0, [30.0, 0.0, 102.0])


def test_shifted_paths_evaluate_to_the_path_plus_the_offset():
    offset = np.array([1.0, -2.0, 50.0])
    for base in (Helix(), Spline(DEFAULT_WAYPOINTS)):
        s = np.linspace(0.0, min(base.s_end, 200.0), 41)
        (p, dp, ddp), (q, dq, ddq) = ShiftedPath(base, tuple(offset)).evaluate(s), base.evaluate(s)
        np.testing.assert_allclose(p - q, np.tile(offset, (s.size, 1)), atol=1e-9)
        np.testing.assert_array_equal(dp, dq)
        np.testing.assert_array_equal(ddp, ddq)


def test_the_spline_depth_range_is_exact():
    path = Spline(DEFAULT_WAYPOINTS)
    z = path.evaluate(np.linspace(0.0, 150.0, 30001))[0][:, 2]
    low, high = path_depth_range(path, 150.0)
    assert low <= z.min() and high >= z.max()
    assert low == pytest.approx(z.min(), abs=1e-6) and high == pytest.approx(z.max(), abs=1e-6)


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        (
            {"depth_envelope": {"seabed_depth": -5.0}},
            ValueError,
            r"depth_envelope seabed_depth must be a finite number in \(4, 11000\] m .*got -5.0",
        ),
        (
            {"depth_envelope": {"seabed_depth": 3.0, "margin": 2.0}},
            ValueError,
            r"seabed_depth must be a finite number in \(4, 11000\]",
        ),
        (
            {"depth_envelope": {"seabed_depth": 4.0, "margin": 2.0}},
            ValueError,
            r"seabed_depth must be a finite number in \(4, 11000\]",
        ),
        (
            {"depth_envelope": {"margin": math.nan}},
            ValueError,
            r"depth_envelope margin must be a finite number in \(0, 1000\] m, got nan",
        ),
        ({"depth_envelope": {"seabed_depth": math.inf}}, ValueError, r"seabed_depth .*got inf"),
        (
            {"depth_envelope": {"depth": 5.0}},
            ValueError,
            r"depth_envelope has unknown key\(s\) \['depth'\]",
        ),
        ({"depth_envelope": "surface"}, TypeError, r"depth_envelope must be None, True"),
        ({"path_offset": (0.0, 0.0, math.nan)}, ValueError, r"path_offset must be 3 real"),
        (
            {"safety_cost": {"speed_limit": 0.0}},
            ValueError,
            r"safety_cost speed_limit must be a finite number in \(0, 10\] m/s, got 0.0",
        ),
        ({"safety_cost": {"pitch": -1.0}}, ValueError, r"safety_cost pitch must be a finite"),
        ({"safety_cost": 3}, TypeError, r"safety_cost must be None, a dict"),
        # The paper's helix climbs to z = -99 m within the 300 m of an episode on schedule.
        (
            {"depth_envelope": True},
            ValueError,
            r"the path and the start reach z = -98.99 m over the 300 m .*add \(0, 0, 101\) to "
            r"path_offset",
        ),
        (
            {"depth_envelope": True, "path_offset": (0, 0, 100)},
            ValueError,
            r"z = 1.006 m .*add \(0, 0, 1\) to path_offset",
        ),
        (
            {"depth_envelope": {"seabed_depth": 100.0}, "path_offset": (0, 0, 110)},
            ValueError,
            r"reach z = 110 m .*below the depth_envelope's safe band z <= 98 m",
        ),
        ({**ENVELOPE, "start_position": (0.0, 0.0, 1.0)}, ValueError, r"reach z = 1 m"),
    ],
)
def test_bad_input_is_a_named_error(kwargs, error, message):
    with pytest.raises(error, match=message):
        AUVPath3DEnv(**kwargs)


def test_a_config_built_directly_refuses_an_offset_it_would_not_apply():
    from auv_gym.sim.config import SimConfig

    with pytest.raises(ValueError, match=r"path_offset \(0.0, 0.0, 5.0\) m moves drawn paths"):
        SimConfig(path=Helix(), path_offset=(0.0, 0.0, 5.0))


def test_drawn_paths_are_drawn_inside_the_band_and_never_refused_at_a_reset():
    """Was: accepted at construction, then refused at 300 of 300 resets (4 of 300 at 100 m),
    in the vector env from `step()` at an autoreset."""
    # Helices climbing 10-20° from 60 m over a seabed at 130 m: within 300 m they rise or sink
    # 52-103 m, so about half the draws leave the band; every reset gets one inside it.
    kwargs = {
        "path": {"families": ["helix", "line"], "climb_angle_deg": [10.0, 20.0]},
        "path_offset": (0.0, 0.0, 60.0),
        "depth_envelope": {"seabed_depth": 130.0},
    }
    config = SimConfig.from_kwargs(**kwargs)
    raw = [shift_path(config.path.draw(np.random.default_rng(s)), (0, 0, 60.0)) for s in range(40)]
    outside = 0
    for path in raw:
        try:
            config.check_depths(path, drawn=True)
        except ValueError:
            outside += 1
    assert 5 <= outside <= 35  # the distribution itself crosses the band often
    env = AUVPath3DEnv(**kwargs)
    for seed in range(40):
        env.reset(seed=seed)
        config.check_depths(env.sim.paths[0], drawn=True)  # inside the band


def test_a_distribution_that_cannot_fit_the_band_is_refused_at_construction():
    with pytest.raises(ValueError, match=r"none of 64 paths drawn .* fits the safe band"):
        AUVPath3DEnv(path="random", depth_envelope=True)  # paths start at the surface


@pytest.mark.integration
def test_a_vector_env_autoresets_10000_times_inside_the_band():
    venv = AUVPath3DVectorEnv(
        200,
        path={"families": ["helix", "line", "spline"], "climb_angle_deg": [5.0, 20.0]},
        path_offset=(0.0, 0.0, 60.0),
        depth_envelope={"seabed_depth": 130.0},
        max_time=0.5,
        randomize_start=True,
    )
    venv.reset(seed=0)
    resets = 0
    while resets < 10_000:
        *_, terminated, truncated, _ = venv.step(np.zeros((200, 3), np.float32))
        resets += int(np.sum(terminated | truncated))
    assert resets >= 10_000


def test_episodes_are_deterministic_per_seed_and_batched_equals_single():
    kwargs = {**ENVELOPE, "max_time": 60.0, "disturbance": "paper"}
    n = 3
    vec = AUVPath3DVectorEnv(n, **kwargs)
    vec.reset(seed=10)
    singles = [AUVPath3DEnv(**kwargs) for _ in range(n)]
    for i, env in enumerate(singles):
        env.reset(seed=10 + i)
    refs = [0.5, -0.5, 0.3]
    ended = np.zeros(n, bool)
    reasons: list[str | None] = [None] * n
    for _ in range(1200):
        actions = np.array(
            [_hold_pitch(env.state, r) for env, r in zip(singles, refs, strict=True)]
        )
        _, rewards, _, _, infos = vec.step(actions)
        for i, env in enumerate(singles):
            if ended[i]:
                continue
            _, reward, term, _, info = env.step(actions[i])
            assert rewards[i] == reward and infos["cost"][i] == info["cost"]
            if term:
                ended[i] = True
                reasons[i] = info["termination_reason"]
                assert infos["termination_reason"][i] == reasons[i]
        if ended.all():
            break
    assert reasons[:2] == ["broached", "grounded"]
    again = AUVPath3DEnv(**kwargs)
    first = [info["cost"] for _, info in _drive(again, 0.3, seed=12)]
    second = [info["cost"] for _, info in _drive(again, 0.3, seed=12)]
    assert first == second and max(first) > 0.0


def test_the_sb3_adapter_passes_the_cost_on():
    from auv_gym.envs.sb3 import make_sb3_vec_env

    venv = make_sb3_vec_env(2, seed=0, **ENVELOPE)
    venv.reset()
    venv.step_async(np.zeros((2, 3)))
    _, _, _, infos = venv.step_wait()
    assert [info["cost"] for info in infos] == [0.0, 0.0]


DEEP = {"path_offset": (0.0, 0.0, 110.0), "depth_envelope": {"seabed_depth": 130.0}}


def test_the_renderer_draws_the_surface_and_the_seabed():
    env = AUVPath3DEnv(render_mode="rgb_array", max_time=5.0, **DEEP)
    env.reset(seed=0)
    for _ in range(20):
        env.step(np.zeros(3))
    frame = env.render()
    assert frame.shape == (320, 960, 3)
    renderer = env._renderer
    heights = [poly.get_label() for poly in renderer._boundaries]
    assert heights == ["sea surface", "seabed"]
    low, high = renderer._ax3d.get_zlim()  # height −z: the view holds both planes
    assert low < -130.0 and high > 0.0
    plain = AUVPath3DEnv(render_mode="rgb_array", max_time=5.0, path_offset=(0.0, 0.0, 110.0))
    plain.reset(seed=0)
    plain.render()
    assert plain._renderer._boundaries == []


def test_the_episode_figures_draw_the_surface_and_the_seabed():
    import controllers
    from auv_gym.rollout import rollouts
    from benchmarks.reports.episode_figures import figure_path_3d, figure_vertical
    from benchmarks.reports.plotting import new_figure, plot_track

    (tr,) = rollouts(controllers.make("fbsm"), [0], max_time=5.0, **DEEP)
    lines = {
        line.get_label(): line.get_ydata()[0]
        for line in figure_vertical({"fbsm": tr}).axes[0].get_lines()
    }
    assert lines["sea surface"] == 0.0 and lines["seabed"] == -130.0
    planes = figure_path_3d({"fbsm": tr}).axes[0].collections
    assert {p.get_label() for p in planes} >= {"sea surface", "seabed"}
    fig = new_figure(13.0, 4.4)
    plot_track(
        fig,
        tr_path := AUVPath3DEnv(**DEEP).config.path,
        {"fbsm": tr.position},
        5.0,
        envelope=DepthEnvelope(130.0),
    )
    assert tr_path.offset == (0.0, 0.0, 110.0)
    xz = {line.get_label(): line.get_ydata()[0] for line in fig.axes[2].get_lines()}
    assert xz["sea surface"] == 0.0 and xz["seabed"] == -130.0


def test_the_compare_summary_has_an_episode_cost_column():
    from benchmarks.reports.tables import summarise

    records = [
        {
            "scenario": "deep",
            "policy": "p",
            "seed": seed,
            "metrics": {"episode_cost": cost, "termination_reason": end},
        }
        for seed, cost, end in [
            (0, 1.5, "time_limit"),
            (1, 2.5, "time_limit"),
            (2, 9.0, "broached"),
        ]
    ]
    summary = summarise(records, {"seeds": 3, "duration": 300.0, "transient": 100.0})
    # the broached episode is a failure: counted, and excluded from the mean
    assert summary.endswith(
        "| policy | failed | episode cost |\n|---|---:|---:|\n| p | 1/3 | 2.00 ± 0.50 (n = 2/3) |\n"
    )
