"""The agent observation (``observation="preview"``): path preview, velocity over ground, previous
action; the ids that register it; v0 untouched."""

from __future__ import annotations

import math
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import auv_gym
from auv_gym import AUVPath3DEnv, ObservationConfig
from auv_gym.paths import Helix, Spline, StraightLine
from auv_gym.sim.observation import OBS_DIM, OBS_NAMES
from tests.test_vector_env import DISTURBED, SHORT, run_parity

PREVIEW = ObservationConfig("preview", points=4, spacing=3.0)
HEAD = 6  # ground velocity, previous action


def body_frame(theta: float, psi: float) -> np.ndarray:
    """R_B = Rz(ψ)Ry(θ) (docs/model.md §2.0): body → earth."""
    c, s = math.cos, math.sin
    rz = np.array([[c(psi), -s(psi), 0], [s(psi), c(psi), 0], [0, 0, 1]])
    ry = np.array([[c(theta), 0, s(theta)], [0, 1, 0], [-s(theta), 0, c(theta)]])
    return rz @ ry


def preview_points(obs: np.ndarray, points: int) -> np.ndarray:
    return obs[OBS_DIM + HEAD :].reshape(points, 5)


def stepped_env(path, steps: int = 60, **kwargs) -> tuple[AUVPath3DEnv, np.ndarray]:
    env = AUVPath3DEnv(path=path, observation=PREVIEW, disturbance="none", **kwargs)
    obs, _ = env.reset(seed=4)
    rng = np.random.default_rng(0)
    for _ in range(steps):
        obs, *_ = env.step(rng.uniform(-0.3, 0.6, size=3))
    return env, obs


def test_layout_names_units_and_bounds():
    names = PREVIEW.names
    assert names[:OBS_DIM] == OBS_NAMES
    assert len(names) == OBS_DIM + HEAD + 5 * 4 == 41
    assert names[OBS_DIM : OBS_DIM + 7] == (
        "u_ground",
        "v_ground",
        "w_ground",
        "a_X_prev",
        "a_M_prev",
        "a_N_prev",
        "preview1_x",
    )
    assert names[-1] == "preview4_torsion" and PREVIEW.units["preview4_torsion"] == "1/m"
    assert PREVIEW.units["u_ground"] == "m/s" and PREVIEW.units["preview2_z"] == "m"
    low, high = PREVIEW.bounds()
    assert low.dtype == high.dtype == np.float32
    assert np.all(low[OBS_DIM:] == -high[OBS_DIM:]) and np.all(low[OBS_DIM:] < 0)
    # a point is at most √3·500 m (the errors' bounds) plus 1.5·K·Δs away
    assert high[OBS_DIM + HEAD] == pytest.approx(math.sqrt(3) * 500 + 1.5 * 12, rel=1e-6)
    env = gym.make("AUVPath3D-v0", observation=PREVIEW)
    assert env.observation_space.shape == (41,)


def test_helix_points_equal_the_path_at_arc_steps_in_the_body_frame():
    helix = Helix()  # the paper's: ‖p′‖ = √(π² + 1), κ and τ constant
    env, obs = stepped_env(helix)
    st = env.unwrapped.state
    speed = math.sqrt(math.pi**2 + 1.0)
    rotation = body_frame(st[3], st[4])
    points = preview_points(obs, 4)
    for k in range(1, 5):
        p, _, _ = helix.evaluate(st[10] + k * 3.0 / speed)
        expected = rotation.T @ (p - st[:3])
        np.testing.assert_allclose(points[k - 1, :3], expected, rtol=1e-6, atol=1e-5)
    # (R cos ωs, R sin ωs, −cs): κ = Rω²/(R²ω² + c²), τ = −cω/(R²ω² + c²)
    omega = math.pi / 20
    np.testing.assert_allclose(points[:, 3], 20 * omega**2 / speed**2, rtol=1e-6)
    np.testing.assert_allclose(points[:, 4], -omega / speed**2, rtol=1e-6)


def test_hand_computed_case_level_vehicle_on_a_line():
    # Vehicle at rest at the origin heading north, path along +x from (10, 0, 0): the virtual
    # point starts at s = 0, so preview point k is (10 + 3k, 0, 0) m ahead, κ = τ = 0.
    line = StraightLine(start=(10.0, 0.0, 0.0), direction=(2.0, 0.0, 0.0))
    env = AUVPath3DEnv(
        path=line,
        observation=PREVIEW,
        disturbance="none",
        start_position=(0.0, 0.0, 0.0),
        start_heading=0.0,
    )
    obs, _ = env.reset(seed=0)
    np.testing.assert_array_equal(obs[OBS_DIM : OBS_DIM + HEAD], np.zeros(HEAD))
    expected = [[10.0 + 3.0 * k, 0.0, 0.0, 0.0, 0.0] for k in range(1, 5)]
    np.testing.assert_allclose(preview_points(obs, 4), expected, atol=1e-12)
    # heading east instead: the same points lie to port (body y < 0)
    env = AUVPath3DEnv(
        path=line,
        observation=PREVIEW,
        disturbance="none",
        start_position=(0.0, 0.0, 0.0),
        start_heading=math.pi / 2,
    )
    obs, _ = env.reset(seed=0)
    expected = [[0.0, -(10.0 + 3.0 * k), 0.0, 0.0, 0.0] for k in range(1, 5)]
    np.testing.assert_allclose(preview_points(obs, 4), expected, atol=1e-5)


def test_spline_points_are_the_spline_at_arc_steps():
    spline = Spline([(0, 0, 5), (40, 10, 8), (80, -5, 12), (120, 20, 10)])
    env, obs = stepped_env(spline, steps=200)
    st = env.unwrapped.state
    rotation = body_frame(st[3], st[4])
    points = preview_points(obs, 4)
    s_grid = np.linspace(st[10], st[10] + 20.0, 20001)
    p, _, _ = spline.evaluate(s_grid)
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    for k in range(1, 5):
        target = np.interp(3.0 * k, arc, s_grid)  # the parameter 3k m of arc ahead
        expected = rotation.T @ (spline.evaluate(target)[0] - st[:3])
        np.testing.assert_allclose(points[k - 1, :3], expected, atol=2e-3)  # the march's error
    _, d1, d2 = spline.evaluate(np.interp(3.0, arc, s_grid))
    kappa = np.linalg.norm(np.cross(d1, d2)) / np.linalg.norm(d1) ** 3
    assert points[0, 3] == pytest.approx(kappa, rel=1e-3)


def test_preview_past_the_end_continues_along_the_last_tangent():
    spline = Spline([(0, 0, 5), (30, 0, 5), (60, 10, 5)])
    env = AUVPath3DEnv(path=spline, observation={"points": 6, "spacing": 10.0}, disturbance="none")
    env.reset(seed=0)
    sim = env.unwrapped.sim
    sim.state[0, 10] = spline.s_end - 5.0  # the virtual point 5 m of parameter before the end
    sim._extend(np.array([0]))  # the extra entries of that state, as after a step
    obs = sim.observations()[0]
    p_end, d_end, _ = spline.evaluate(spline.s_end)
    tangent = d_end / np.linalg.norm(d_end)
    st = sim.state[0]
    rotation = body_frame(st[3], st[4])
    points = obs[OBS_DIM + HEAD :].reshape(6, 5)
    assert np.all(np.isfinite(points))
    for k in range(2, 7):  # points 2… lie beyond the end: on the tangent line, κ = τ = 0
        earth = rotation @ points[k - 1, :3] + st[:3]
        offset = earth - p_end
        np.testing.assert_allclose(np.cross(offset, tangent), 0.0, atol=1e-3)
        assert offset @ tangent > 0 and points[k - 1, 3] == points[k - 1, 4] == 0.0
    gaps = np.linalg.norm(np.diff(rotation @ points[1:, :3].T, axis=1), axis=0)
    np.testing.assert_allclose(gaps, 10.0, rtol=1e-5)  # still Δs of arc apart


def test_ground_velocity_reveals_the_current_and_previous_action_is_the_saturated_one():
    current = (0.2, -0.3, 0.05)
    env = AUVPath3DEnv(observation=PREVIEW, disturbance="none", current={"mean": current})
    obs, _ = env.reset(seed=1)
    st = env.state
    ground = obs[OBS_DIM : OBS_DIM + 3]
    # at rest in the water, the vehicle moves with the current: R_Bᵀ v_c
    np.testing.assert_allclose(ground, body_frame(st[3], st[4]).T @ np.array(current), atol=1e-7)
    obs, *_ = env.step(np.array([2.5, -0.4, 0.1]))
    np.testing.assert_array_equal(obs[OBS_DIM + 3 : OBS_DIM + 6], np.float32([1.0, -0.4, 0.1]))
    st = env.state
    velocity = np.array([st[5], st[6], st[7]])
    np.testing.assert_allclose(
        obs[OBS_DIM : OBS_DIM + 3],
        velocity + body_frame(st[3], st[4]).T @ np.array(current),
        atol=1e-6,
    )
    obs, _ = env.reset(seed=2)
    assert np.all(obs[OBS_DIM + 3 : OBS_DIM + 6] == 0.0)


def test_paper_entries_and_classical_controllers_are_unchanged_by_the_preview():
    import controllers

    kwargs = {"path": "waypoints", "current": {"mean": (0.0, 0.2, 0.0)}, "max_time": 20.0}
    plain, extended = AUVPath3DEnv(**kwargs), AUVPath3DEnv(observation="preview", **kwargs)
    fbsm_plain, fbsm_extended = controllers.make("fbsm"), controllers.make("fbsm")
    o1, _ = plain.reset(seed=7)
    o2, _ = extended.reset(seed=7)
    for _ in range(150):
        np.testing.assert_array_equal(o2[:OBS_DIM], o1)
        a1, _ = fbsm_plain.predict(o1)
        a2, _ = fbsm_extended.predict(o2)
        np.testing.assert_array_equal(a1, a2)
        o1, r1, *_ = plain.step(a1)
        o2, r2, *_ = extended.step(a2)
        assert r1 == r2


@pytest.mark.parametrize(
    "mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP], ids=lambda m: m.name
)
def test_batched_equals_single_bit_for_bit_with_autoresets(mode):
    counts = run_parity(5, mode, steps=110, seed=3, observation=PREVIEW, **DISTURBED)
    assert counts["terminated"] >= 1 and counts["truncated"] >= 1
    integrating = {"points": 3, "spacing": 1.5, "integral_time": 5.0}
    counts = run_parity(4, mode, steps=100, seed=8, path="random", observation=integrating, **SHORT)
    assert counts["terminated"] + counts["truncated"] >= 4


def test_observations_stay_inside_the_space_on_random_paths():
    env = gym.make_vec(
        "AUVPath3DPreview-v0",
        num_envs=16,
        path="random",
        random_current=0.5,
        current={"std": (0.1, 0.1, 0.03), "time_constant": 60.0},
    )
    space = env.single_observation_space
    obs, _ = env.reset(seed=0)
    rng = np.random.default_rng(1)
    for _ in range(300):
        assert np.all((obs >= space.low) & (obs <= space.high))
        obs, *_ = env.step(rng.uniform(-1, 1, size=(16, 3)))


@pytest.mark.parametrize(
    "bad, message",
    [
        ({"points": 0}, "observation points"),
        ({"points": 2.5}, "observation points"),
        ({"spacing": 0.0}, "observation spacing"),
        ({"spacing": math.nan}, "observation spacing"),
        ({"spacing": math.inf}, "observation spacing"),
        ({"points": 64, "spacing": 10.0}, "K·Δs"),
        ({"kind": "future"}, "observation kind"),
        ({"depth": 3}, "observation"),
    ],
)
def test_bad_preview_arguments_name_the_argument(bad, message):
    with pytest.raises(ValueError, match=message):
        AUVPath3DEnv(observation=bad)
    with pytest.raises(TypeError, match="observation must be"):
        AUVPath3DEnv(observation=5)


def test_ids_print_nothing_and_former_ids_are_refused():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for env_id in auv_gym.VARIANTS:
            gym.make(env_id).close()
    assert gym.spec("AUVPath3DPreview-v0").kwargs == {
        "surge_limit": "vehicle",
        "observation": "preview",
    }
    # Leaky integrals of y_e, z_e: the preview observation and the two integrals after it.
    integral = gym.make("AUVPath3DPreview-v0", observation={"kind": "preview", "integral_time": 10})
    preview = gym.make("AUVPath3DPreview-v0")
    assert integral.observation_space.shape == (preview.observation_space.shape[0] + 2,) == (48,)
    obs, _ = integral.reset(seed=3)
    reference, _ = preview.reset(seed=3)
    np.testing.assert_array_equal(obs[:-2], reference)
    action = np.float32([0.1, -0.2, 0.3])
    obs, *_ = integral.step(action)
    reference, *_ = preview.step(action)
    decay = math.exp(-0.05 / 10.0)  # T = 10 s, the paper's 0.05-s control period
    np.testing.assert_allclose(obs[-2:], 10.0 * (1.0 - decay) * reference[1:3], rtol=1e-6)
    # The integral option: x_e, y_e, z_e integrated, each clipped to ±1 m·s (anti-windup).
    antiwindup = gym.make("AUVPath3DPreview-v0", observation="preview_integral")
    assert antiwindup.observation_space.shape == (49,)
    assert antiwindup.observation_space.high[-3:].tolist() == [1.0, 1.0, 1.0]
    obs, _ = antiwindup.reset(seed=3)
    np.testing.assert_array_equal(obs[:-3], preview.reset(seed=3)[0])
    obs, *_ = antiwindup.step(action)
    reference, *_ = preview.step(action)
    np.testing.assert_allclose(
        obs[-3:], np.clip(10.0 * (1.0 - decay) * reference[:3], -1, 1), rtol=1e-6
    )
    with pytest.raises(ValueError, match=r"unknown env id 'AUVPath3D-v1'"):  # renamed, then gone
        auv_gym.resolve_env_id("AUVPath3D-v1")
    for removed in ("AUVPath3DPreviewIntegral-v0", "AUVPath3DPreviewAntiWindup-v0"):
        with pytest.raises(ValueError, match=f"unknown env id '{removed}'"):  # gone with sac_helix
            auv_gym.resolve_env_id(removed)
    with pytest.raises(ValueError, match=r"unknown env id 'AUVPath3D-v9'.*AUVPath3DPreview-v0"):
        auv_gym.resolve_env_id("AUVPath3D-v9")


@pytest.mark.rl
def test_sb3_adapter_sets_terminal_observation_and_truncation_on_every_autoreset():
    """Truncations (time limit) and terminations (corridor) both: every done carries the
    46-entry terminal observation; "TimeLimit.truncated" is True exactly for the time limits."""
    from auv_gym.envs.sb3 import make_sb3_vec_env

    n = 6
    env = make_sb3_vec_env(n, seed=0, max_time=1.0, corridor=17.75, observation="preview")
    obs = env.reset()
    assert obs.shape == (n, 46)
    actions = np.tile(np.float32([0.8, 0.0, 0.0]), (n, 1))
    actions[::2, 0] = -1.0  # astern: those leave the 17.75 m corridor before the time limit
    seen = {"truncated": 0, "terminated": 0}
    for _ in range(60):
        last = obs
        obs, _, dones, infos = env.step(actions)
        for i in range(n):
            info = infos[i]
            if not dones[i]:
                assert "terminal_observation" not in info and info["TimeLimit.truncated"] is False
                continue
            final = info["terminal_observation"]
            assert final.shape == (46,) and final.dtype == np.float32
            assert np.all(final[OBS_DIM + 3 : OBS_DIM + 6] == actions[i])  # its last action
            assert np.all(obs[i, OBS_DIM + 3 : OBS_DIM + 6] == 0.0)  # the new episode's first
            assert not np.array_equal(final, last[i])
            truncated = "termination_reason" not in info
            assert info["TimeLimit.truncated"] is truncated
            seen["truncated" if truncated else "terminated"] += 1
    assert seen["truncated"] >= 3 and seen["terminated"] >= 3


def test_error_integrals_are_leaky_integrals_of_the_track_errors():
    """integral_time T: I_k = e^(−Δt/T) I_{k−1} + T(1 − e^(−Δt/T)) e_k, 0 after a reset; the
    other entries are those of the same observation without integrals."""
    with_integrals = ObservationConfig("preview", points=2, spacing=3.0, integral_time=20.0)
    assert with_integrals.names[-2:] == ("y_e_integral", "z_e_integral")
    assert with_integrals.units["z_e_integral"] == "m·s"
    assert with_integrals.bounds()[1][-1] == 500.0 * 20.0
    assert with_integrals.to_dict()["integral_time"] == 20.0
    env = AUVPath3DEnv(observation=with_integrals, max_time=10.0)
    plain = AUVPath3DEnv(observation={"points": 2, "spacing": 3.0}, max_time=10.0)
    obs, _ = env.reset(seed=5)
    reference, _ = plain.reset(seed=5)
    assert np.all(obs[-2:] == 0.0)
    decay = math.exp(-0.05 / 20.0)
    integral = np.zeros(2)
    rng = np.random.default_rng(2)
    for _ in range(100):
        action = rng.uniform(-0.5, 0.5, size=3)
        obs, *_ = env.step(action)
        reference, *_ = plain.step(action)
        integral = decay * integral + 20.0 * (1.0 - decay) * np.array([obs[1], obs[2]], float)
        np.testing.assert_array_equal(obs[:-2], reference)
        np.testing.assert_allclose(obs[-2:], integral, rtol=1e-5, atol=1e-6)  # float32 errors
    obs, _ = env.reset(seed=6)
    assert np.all(obs[-2:] == 0.0)
    with pytest.raises(ValueError, match="observation integral_time"):
        ObservationConfig("preview", integral_time=-1.0)


def test_along_track_integral_comes_first_and_the_default_layout_is_unchanged():
    """integral_errors "xyz": x_e_integral, y_e_integral, z_e_integral, the same leaky law on
    (x_e, y_e, z_e); the y/z integrals equal those of the default "yz" layout bit for bit."""
    xyz = ObservationConfig(
        "preview", points=2, spacing=3.0, integral_time=30.0, integral_errors="xyz"
    )
    yz = ObservationConfig("preview", points=2, spacing=3.0, integral_time=30.0)
    assert xyz.names[-3:] == ("x_e_integral", "y_e_integral", "z_e_integral")
    assert xyz.extra_dim == yz.extra_dim + 1 and xyz.integrals == 3
    assert xyz.to_dict()["integral_errors"] == "xyz" and "integral_errors" not in yz.to_dict()
    assert ObservationConfig.from_spec(xyz.to_dict()) == xyz
    env = AUVPath3DEnv(observation=xyz, max_time=10.0)
    plain = AUVPath3DEnv(observation=yz, max_time=10.0)
    obs, _ = env.reset(seed=3)
    reference, _ = plain.reset(seed=3)
    assert np.all(obs[-3:] == 0.0)
    decay = math.exp(-0.05 / 30.0)
    integral = np.zeros(3)
    rng = np.random.default_rng(4)
    for _ in range(60):
        action = rng.uniform(-0.5, 0.5, size=3)
        obs, *_ = env.step(action)
        reference, *_ = plain.step(action)
        integral = decay * integral + 30.0 * (1.0 - decay) * obs[:3].astype(float)
        np.testing.assert_array_equal(obs[:-3], reference[:-2])
        np.testing.assert_array_equal(obs[-2:], reference[-2:])
        np.testing.assert_allclose(obs[-3:], integral, rtol=1e-5, atol=1e-6)
    assert abs(obs[-3]) > 0.1  # the along-track error was integrated, not left at 0
    with pytest.raises(ValueError, match="observation integral_errors 'xy'"):
        ObservationConfig("preview", integral_time=10.0, integral_errors="xy")
    with pytest.raises(ValueError, match=r"unknown key\(s\) \['integral_axes'\]"):
        ObservationConfig.from_spec({"integral_axes": "xyz"})


def test_integral_limit_clips_each_integral_after_every_update():
    """integral_limit L: I ← clip(e^(−Δt/T) I + T(1 − e^(−Δt/T)) e, −L, L); the bound is L; the
    approach from the paper's start (x_e = −15 m) saturates x_e's integral at −L."""
    limit = 0.5
    clipped = ObservationConfig(
        "preview",
        points=2,
        spacing=3.0,
        integral_time=30.0,
        integral_errors="xyz",
        integral_limit=limit,
    )
    assert clipped.bounds()[1][-3:].tolist() == [limit] * 3
    assert clipped.to_dict()["integral_limit"] == limit
    assert ObservationConfig.from_spec(clipped.to_dict()) == clipped
    env = AUVPath3DEnv(observation=clipped, max_time=10.0)
    obs, _ = env.reset(seed=3)
    decay = math.exp(-0.05 / 30.0)
    integral = np.zeros(3)
    saturated = 0
    rng = np.random.default_rng(4)
    for _ in range(100):
        obs, *_ = env.step(rng.uniform(-0.5, 0.5, size=3))
        integral = np.clip(
            decay * integral + 30.0 * (1.0 - decay) * obs[:3].astype(float), -limit, limit
        )
        np.testing.assert_allclose(obs[-3:], integral, rtol=1e-5, atol=1e-6)
        saturated += bool(np.isclose(obs[-3], -limit))
    assert saturated > 50  # x_e ≈ −15 m charges −0.5 m·s in 0.7 s, then stays clipped
    with pytest.raises(ValueError, match="observation integral_limit"):
        ObservationConfig("preview", integral_time=10.0, integral_limit=-1.0)


def test_ground_speed_bound_covers_every_current_the_config_can_draw():
    """A Gauss–Markov current is unbounded; the bound covers 8 stationary standard deviations
    (an accepted configuration with mean 10 m/s and std 10 m/s raised at 19 of 300 resets
    against the fixed 30 m/s bound)."""
    strong = {"mean": (10.0, 10.0, 10.0), "std": (10.0, 10.0, 10.0)}
    env = gym.make("AUVPath3DPreview-v0", current=strong).unwrapped
    expected = 1.5 * (10.0 + math.sqrt(3.0) * 90.0)
    assert env.observation_space.high[15] == np.float32(expected)
    for seed in range(300):
        obs, _ = env.reset(seed=seed)
        assert env.observation_space.contains(obs)
    # Configurations whose current stays within 10 m/s keep the 30 m/s bound.
    calm = gym.make("AUVPath3DPreview-v0", current={"mean": (0.3, 0, 0), "std": (0.1, 0.1, 0.03)})
    assert calm.observation_space.high[15] == 30.0


_PAPER_HAS_NONE = (
    "needs the agent observation (kind 'preview'); the paper's 15 entries have no preview, "
    "error integrals or history"
)


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        (
            {"kind": "paper", "integral_time": 10},
            f"observation integral_time = 10.0 {_PAPER_HAS_NONE}",
        ),
        ({"kind": "paper", "points": 8}, f"observation points = 8 {_PAPER_HAS_NONE}"),
        ({"kind": "paper", "points": 5}, f"observation points = 5 {_PAPER_HAS_NONE}"),  # default
        (
            {"kind": "paper", "integral_limit": 1},
            f"observation integral_limit = 1.0 {_PAPER_HAS_NONE}",
        ),
        (
            {"integral_limit": 1.0},
            "observation integral_limit = 1.0 does nothing without error integrals "
            "(integral_time = 0): give an integral_time > 0 or leave integral_limit out",
        ),
        (
            {"integral_time": 0.0, "integral_limit": 0.0},  # given, even at the default
            "observation integral_limit = 0.0 does nothing without error integrals "
            "(integral_time = 0): give an integral_time > 0 or leave integral_limit out",
        ),
        (
            {"integral_errors": "xyz"},
            "observation integral_errors = 'xyz' does nothing without error integrals "
            "(integral_time = 0): give an integral_time > 0 or leave integral_errors out",
        ),
    ],
)
def test_settings_the_observation_ignores_are_refused(spec, message):
    """Was: accepted, and the observation identical to the one without them."""
    with pytest.raises(ValueError) as caught:
        ObservationConfig.from_spec(spec)
    assert str(caught.value) == message
    fields = {"kind": "preview", **spec}
    if any(v != getattr(ObservationConfig(), k) for k, v in fields.items() if k != "kind"):
        with pytest.raises(ValueError) as caught:  # built directly: the non-default values
            ObservationConfig(**fields)
        assert str(caught.value) == message


def test_the_defaults_and_presets_with_integrals_still_build():
    assert ObservationConfig.from_spec("preview_integral").integral_limit == 1.0
    assert ObservationConfig.from_spec({"kind": "paper"}) == ObservationConfig()
    assert ObservationConfig.from_spec({"integral_time": 0.0}) == ObservationConfig("preview")
    with_limit = {"integral_time": 10.0, "integral_errors": "xyz", "integral_limit": 1.0}
    assert ObservationConfig.from_spec(with_limit) == ObservationConfig.from_spec(
        "preview_integral"
    )
