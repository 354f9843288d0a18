"""User paths (waypoints, fitted curves, port helices, vehicle parameters by name) and the seeded
task distribution (`path="random"`, domain randomisation): docs/model.md §3.8."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import auv_gym
import controllers
from auv_gym.envs.env import AUVPath3DEnv
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.paths.shapes import HELIX, Helix, Spline, fit_curve, make_path
from auv_gym.rollout import evaluate
from auv_gym.sim.config import SimConfig
from auv_gym.sim.integrator import rk4_step
from auv_gym.sim.path_generator import (
    CURVATURE_SLACK,
    FAMILIES,
    MAX_FLIGHT_PATH_ANGLE_DEG,
    MIN_TURN_RADIUS,
    PathDistribution,
    curvature_and_angle,
    overlaps,
)
from auv_gym.sim.randomization import task_for_seed
from auv_gym.support.validation import ArgumentTypeError
from auv_gym.vehicle import remus100
from auv_gym.vehicle.dynamics import STATE, STATE_DIM

WAYPOINTS = [(0.0, 0.0, 5.0), (40.0, 10.0, 8.0), (80.0, -5.0, 12.0), (120.0, 5.0, 10.0)]


# ------------------------------------------------------------------------------ user paths
def test_fit_curve_reproduces_the_helix():
    """docs/model.md §3.8: the paper's helix as a callable, fitted over five turns."""
    helix = Helix()
    fitted = fit_curve(lambda s: helix.evaluate(s)[0], 200.0)
    assert fitted.kind == helix.kind + 2 and fitted.s_end == 200.0  # SPLINE, the user's s
    assert fitted.segments == 128
    assert fitted.position_error <= 1e-3 and fitted.tangent_error <= 2e-4
    s = np.linspace(0.0, 200.0, 20001)
    p, dp, _ = fitted.evaluate(s)
    p_true, dp_true, _ = helix.evaluate(s)
    position = np.linalg.norm(p - p_true, axis=1).max()
    cosine = np.sum(dp * dp_true, axis=1) / np.linalg.norm(dp, axis=1)
    cosine /= np.linalg.norm(dp_true, axis=1)
    tangent = np.arccos(np.clip(cosine, -1.0, 1.0)).max()
    assert 1e-5 < position <= 2e-4, position  # 0.19 mm
    assert tangent <= 2e-4, tangent  # 0.11 mrad
    # A tighter tolerance buys accuracy with segments (h⁴ convergence).
    finer = fit_curve(lambda s: helix.evaluate(s)[0], 200.0, tolerance=2e-5)
    assert finer.segments == 256 and finer.position_error <= 2e-5


def test_a_fitted_curve_runs_in_the_env_like_the_analytic_path():
    helix = Helix()
    fitted = fit_curve(lambda s: helix.evaluate(s)[0], 200.0, tolerance=1e-5)
    fbsm = controllers.make("fbsm")
    exact = evaluate(fbsm, [0], path=helix, max_time=60.0, transient=20.0)[0]
    approx = evaluate(
        fbsm,
        [0],
        path=fitted,
        max_time=60.0,
        transient=20.0,
        start_position=(15.0, 5.0, 0.0),
        start_heading=0.0,
    )[0]
    assert approx["termination_reason"] == "time_limit"
    assert abs(approx["rms_distance"] - exact["rms_distance"]) < 1e-3


def test_waypoint_lists_are_accepted_by_make_and_make_vec():
    env = gym.make("AUVPath3D-v0", path=WAYPOINTS)
    path = env.unwrapped.config.path
    assert isinstance(path, Spline) and np.array_equal(path.waypoints, np.array(WAYPOINTS))
    obs, _ = env.reset(seed=3)
    venv = gym.make_vec("AUVPath3D-v0", num_envs=2, path=np.array(WAYPOINTS))
    vobs, _ = venv.reset(seed=3)
    assert np.array_equal(obs, vobs[0])
    # The default start: 15 m behind p(0), 5 m to starboard, 8 m deeper, heading ψ_F(0).
    p0, dp0, _ = path.evaluate(0.0)
    psi = math.atan2(dp0[1], dp0[0])
    state = env.unwrapped.state
    assert state[STATE.psi] == pytest.approx(psi)
    offset = state[:3] - p0
    c, s = math.cos(psi), math.sin(psi)
    assert [
        c * offset[0] + s * offset[1],
        -s * offset[0] + c * offset[1],
        offset[2],
    ] == pytest.approx([-15.0, 5.0, 8.0])


def test_helices_turn_both_ways():
    starboard, port = Helix(omega=math.pi / 20), Helix(omega=-math.pi / 20)
    psi_rate = []
    for path in (starboard, port):
        env = AUVPath3DEnv(path=path, disturbance="none")
        obs, _ = env.reset(seed=0)
        psi_rate.append(obs[auv_gym.OBS_INDEX["psi_F_dot"]])
    assert psi_rate[0] == 0.0 == psi_rate[1]  # the virtual point is at rest at the start
    _, dp, _ = port.evaluate(0.0)
    assert dp[1] < 0.0  # heading −y: the mirror image of the paper's helix
    fbsm = controllers.make("fbsm")
    results = [evaluate(fbsm, [0], path=p, max_time=150.0)[0] for p in (starboard, port)]
    assert all(r["termination_reason"] == "time_limit" for r in results)
    # The mirrored start lies outside the port turn, inside the starboard one: 0.064 vs 0.046 m.
    assert results[0]["rms_distance"] < 0.1 and results[1]["rms_distance"] < 0.1


def test_vehicle_parameters_by_name_and_scale():
    env = AUVPath3DEnv(params={"m": 32.0, "scale": {"X_uu": 1.5}})
    assert env.config.params.m == 32.0 and env.config.params.X_uu == -1.62 * 1.5
    assert env.config.params.W == remus100().W
    with pytest.raises(ValueError, match=r"params has unknown key\(s\) \['mass'\]"):
        AUVPath3DEnv(params={"mass": 32.0})
    with pytest.raises(ValueError, match=r"params scale has unknown key\(s\) \['Xuu'\]"):
        AUVPath3DEnv(params={"scale": {"Xuu": 1.2}})
    with pytest.raises(ArgumentTypeError, match=r"params scale X_uu must be a real number"):
        AUVPath3DEnv(params={"scale": {"X_uu": "big"}})
    with pytest.raises(ValueError, match=r"AUVParams.m must be positive"):
        AUVPath3DEnv(params={"m": -1.0})


def test_scenario_files_take_waypoints_and_params(tmp_path):
    from benchmarks.catalog.scenarios import load_scenarios

    file = tmp_path / "s.toml"
    file.write_text(
        '[survey]\ndescription = "x"\n'
        "env = { path = [[0, 0, 5], [40, 10, 8], [80, -5, 12]], params = { m = 32.0 } }\n"
    )
    scenario = load_scenarios(file)["survey"]
    config = SimConfig.from_kwargs(**scenario.env)
    assert isinstance(config.path, Spline) and config.params.m == 32.0
    file.write_text("[bad]\nenv = { params = { mass = 32.0 } }\n")
    with pytest.raises(ValueError, match=r"scenario 'bad'.*params has unknown key\(s\) \['mass'\]"):
        load_scenarios(file)


@pytest.mark.parametrize(
    ("make", "error", "match"),
    [
        (lambda: Helix(omega=0.0), ValueError, r"Helix omega must be non-zero"),
        (lambda: Helix(omega=-2e3), ValueError, r"Helix omega must be a finite number"),
        (lambda: make_path(lambda s: (s, 0, 0)), ArgumentTypeError, r"fit_curve\(p, s_end\)"),
        (lambda: make_path([(0, 0, 0)]), ValueError, r"path as a list of .* waypoints: Spline"),
        (lambda: fit_curve("helix", 10.0), ArgumentTypeError, r"curve must be a callable"),
        (lambda: fit_curve(lambda s: (s, 0, 0), 0.0), ValueError, r"fit_curve s_end"),
        (
            lambda: fit_curve(lambda s: (s, 0, 0), 10.0, tolerance=-1.0),
            ValueError,
            r"fit_curve tolerance",
        ),
        (lambda: fit_curve(lambda s: (s, 0), 10.0), ValueError, r"curve\(s\) at s = 0"),
        (lambda: fit_curve(lambda s: (s, math.nan, 0), 10.0), ValueError, r"curve\(s\) at s"),
        (
            lambda: fit_curve(lambda s: (math.sin(1e3 * s), 0, 0), 10.0, max_segments=16),
            ValueError,
            r"16 segments fit the curve to .* above tolerance",
        ),
        (lambda: fit_curve(lambda s: (0.0, 0.0, 0.0), 10.0), ValueError, r"\|p'\(s\)\| must be"),
    ],
)
def test_bad_user_paths_raise_named_errors(make, error, match):
    with pytest.raises(error, match=match):
        make()


# ----------------------------------------------------------------------- vehicle limits
def _steady(u_target, n_frac, m_frac, seconds=150.0, dt=0.01):
    """Steady state of REMUS 100 with fin moments a·3.22·u|u| N·m and surge held at u_target."""
    p = remus100()
    p_array = p.to_vector()
    st = np.zeros(STATE_DIM)
    st[STATE.u] = u_target
    out = np.empty(STATE_DIM)
    gain = p.fin_moment_coeff * p.fin_max
    data = np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0])
    for _ in range(round(seconds / dt)):
        u = st[STATE.u]
        thrust = min(50.0, max(-50.0, 200.0 * (u_target - u) + 1.62 * u_target**2))
        tau = (thrust, m_frac * gain * u * abs(u), n_frac * gain * u * abs(u))
        rk4_step(st, tau, (0.0,) * 5, (0.0, 0.0, 0.0), p_array, HELIX, data, 1.0, 0.5, dt, out)
        st[:] = out
    return st


def test_the_vehicle_turns_and_climbs_within_the_generator_limits():
    """docs/model.md §3.8: full fin authority at 1 m/s turns on a 4.0-m radius and holds a
    25.6° climb; the generator keeps radius ≥ 8 m and |γ| ≤ 25°."""
    turn = _steady(1.0, 1.0, 0.0)
    radius = math.hypot(turn[STATE.u], turn[STATE.v]) / turn[STATE.r]
    assert radius == pytest.approx(3.97, abs=0.05)
    assert MIN_TURN_RADIUS >= 2.0 * radius
    climb = _steady(1.0, 0.0, 1.0)
    gamma = math.degrees(climb[STATE.theta] - math.atan2(climb[STATE.w], climb[STATE.u]))
    assert math.degrees(climb[STATE.theta]) == pytest.approx(25.0, abs=0.2)
    assert gamma == pytest.approx(25.6, abs=0.2)
    assert MAX_FLIGHT_PATH_ANGLE_DEG <= gamma


# ------------------------------------------------------------------------- the generator
@pytest.mark.parametrize("family", FAMILIES)
def test_every_drawn_path_lies_within_its_documented_limits(family):
    dist = PathDistribution(families=(family,))
    radii, angles = [], []
    for seed in range(40):
        path = dist.draw(np.random.default_rng(seed))
        assert path.family == family
        assert np.array_equal(path.evaluate(0.0)[0], np.zeros(3))
        kappa, gamma = curvature_and_angle(path)
        if family == "helix":
            assert path.radius == pytest.approx(path.radius) and 15.0 <= path.radius <= 40.0
            tangent = math.hypot(path.radius * path.omega, path.climb)
            assert tangent == pytest.approx(1.0)  # arc length
            radii.append(path.radius * math.copysign(1.0, path.omega))
            angles.append(math.degrees(math.asin(path.climb)))
            assert kappa <= 1.0 / 15.0 and math.degrees(gamma) <= 20.0 + 1e-9
        elif family == "line":
            angles.append(math.degrees(gamma) * -np.sign(path.data[5]))
            assert kappa == 0.0 and math.degrees(gamma) <= 20.0 + 1e-9
        else:
            assert kappa <= 1.05 / 15.0 and math.degrees(gamma) <= 20.5
            assert path.s_end == pytest.approx(400.0, abs=10.0)
            assert len(path.waypoints) <= dist.max_waypoints
    if family == "helix":  # both turning directions, ascending and descending
        assert min(radii) < 0 < max(radii) and min(angles) < 0 < max(angles)
    if family == "line":
        assert min(angles) < 0 < max(angles)


def test_the_generator_is_a_function_of_the_seed():
    dist = PathDistribution()
    first = [dist.draw(np.random.default_rng(k)) for k in range(12)]
    again = [dist.draw(np.random.default_rng(k)) for k in range(12)]
    assert all(np.array_equal(a.data, b.data) for a, b in zip(first, again, strict=True))
    assert len({a.family for a in first}) == len(FAMILIES)  # 12 draws meet every family
    assert len({a.data.tobytes() for a in first}) == 12
    # The path of a seed does not depend on the other randomised parts.
    plain = SimConfig.from_kwargs(path="random")
    busy = SimConfig.from_kwargs(
        path="random", random_current=0.5, random_noise=0.5, actuator="random"
    )
    for seed in range(5):
        assert np.array_equal(
            task_for_seed(plain, seed).path.data, task_for_seed(busy, seed).path.data
        )
        env = AUVPath3DEnv(path="random")
        env.reset(seed=seed)
        assert np.array_equal(env.sim.paths[0].data, task_for_seed(plain, seed).path.data)


def test_domain_randomisation_draws_within_its_ranges():
    config = SimConfig.from_kwargs(
        path="random", random_current=0.4, random_noise=0.5, actuator="random"
    )
    tasks = [task_for_seed(config, seed) for seed in range(200)]
    speeds = np.array([math.hypot(*t.current[:2]) for t in tasks])
    assert all(t.current[2] == 0.0 for t in tasks)
    assert speeds.max() <= 0.4 and speeds.max() > 0.35 and speeds.min() < 0.05
    directions = np.array([math.atan2(t.current[1], t.current[0]) for t in tasks])
    assert directions.min() < -2.5 and directions.max() > 2.5
    scales = np.array([t.noise_scale for t in tasks])
    assert 0.5 <= scales.min() < 0.6 and 1.4 < scales.max() <= 1.5
    assert {t.actuator for t in tasks} == {"paper", "fins"}
    # In the env: the packed row of the episode carries them.
    env = AUVPath3DEnv(path="random", random_current=0.4, random_noise=0.5, actuator="random")
    env.reset(seed=7)
    task = tasks[7]
    cfg = dict(zip(auv_gym.sim.integrator.CONFIG_FIELDS, env.sim._cfg[0], strict=True))
    assert cfg["current_x"] == task.current[0] and cfg["current_y"] == task.current[1]
    assert cfg["noise_f_u"] == 35.0 * task.noise_scale
    assert cfg["actuator"] == {"paper": 0.0, "fins": 1.0}[task.actuator]


def test_batched_random_tasks_equal_single_envs_bit_for_bit(single_env_observations):
    kwargs = {
        "path": "random",
        "random_current": 0.3,
        "random_noise": 0.5,
        "actuator": "random",
        "param_uncertainty": 0.2,
        "max_time": 3.0,
    }
    n, steps = 4, 80  # 60 control steps per episode: every vehicle autoresets once
    venv = AUVPath3DVectorEnv(n, **kwargs)
    actions = np.random.default_rng(0).uniform(-0.5, 0.5, size=(steps, n, 3))
    batched = [venv.reset(seed=10)[0]] + [venv.step(a)[0] for a in actions]
    for i in range(n):
        single, env = single_env_observations(kwargs, 10 + i, actions[:, i])
        assert np.array_equal(single, np.array(batched)[:, i])
        assert np.array_equal(env.sim.paths[0].data, venv.sim.paths[i].data)


def test_the_path_table_holds_the_longest_drawn_path():
    for radius in ((8.0, 9.0), (11.0, 40.0), (15.0, 40.0)):
        dist = PathDistribution(families=("spline", "lawnmower"), radius=radius, length=300.0)
        sizes = [dist.draw(np.random.default_rng(k)).data.size for k in range(10)]
        assert max(sizes) <= dist.max_data_size
        env = AUVPath3DEnv(path=dist)
        for seed in range(3):
            env.reset(seed=seed)
            assert env.sim._pdata.shape == (1, dist.max_data_size)


def test_fixed_paths_share_one_table_row():
    venv = AUVPath3DVectorEnv(8)
    assert venv.sim._pdata.shape == (1, 6) and not venv.sim._row.any()
    rand = AUVPath3DVectorEnv(8, path="random")
    assert rand.sim._pdata.shape == (8, PathDistribution().max_data_size)
    assert rand.sim._row.tolist() == list(range(8))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"radius": (0.0, 10.0)}, r"radius must be positive"),
        ({"radius": (5.0, 10.0)}, r"below the vehicle's smallest followable turn radius 8 m"),
        ({"radius": (20.0, 10.0)}, r"low <= high"),
        ({"climb_angle_deg": (0.0, 30.0)}, r"exceeds the vehicle's largest followable flight"),
        ({"families": ("helix", "spiral")}, r"families must be distinct names among"),
        ({"families": ()}, r"families must be distinct names among"),
        ({"length": 10.0}, r"PathDistribution length"),
        ({"piece_length": (10.0, 50.0)}, r"piece_length must lie in \[20, 1000\]"),
        ({"spline_radius": (5.0, 10.0)}, r"spline_radius \(5\.0, 10\.0\) m starts below the"),
        ({"spline_radius": (20.0, 10.0)}, r"spline_radius must be \(low, high\) with low <= high"),
        ({"spline_radius": (8.0, math.nan)}, r"spline_radius"),
    ],
)
def test_impossible_generator_ranges_raise_one_line_errors(kwargs, match):
    with pytest.raises(ValueError, match=match) as caught:
        PathDistribution(**kwargs)
    assert "\n" not in str(caught.value)
    with pytest.raises(ValueError, match=match):  # through the env's path argument (TOML dict)
        AUVPath3DEnv(path={k: list(v) if isinstance(v, tuple) else v for k, v in kwargs.items()})


def test_bad_randomisation_arguments_raise_named_errors():
    with pytest.raises(ValueError, match=r"random_current must be a finite number in \[0, 1\]"):
        AUVPath3DEnv(random_current=1.5)
    with pytest.raises(ValueError, match=r"random_noise must be a finite number in \[0, 1\]"):
        AUVPath3DEnv(random_noise=-0.1)
    with pytest.raises(ValueError, match=r"unknown actuator 'both'"):
        AUVPath3DEnv(actuator="both")
    with pytest.raises(ValueError, match=r"start_position cannot be given with a random path"):
        AUVPath3DEnv(path="random", start_position=(0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match=r"path has unknown key\(s\) \['radii'\]"):
        AUVPath3DEnv(path={"radii": [15, 20]})


def test_fbsm_follows_generated_paths():
    """docs/model.md §3.8: FBSM follows every family of the default distribution (the first
    three seeds of each), the paper's white noise, 200 s."""
    config = SimConfig.from_kwargs(path="random")
    by_family: dict[str, list[int]] = {f: [] for f in FAMILIES}
    for seed in range(100):
        family = task_for_seed(config, seed).path.family
        if len(by_family[family]) < 3:
            by_family[family].append(seed)
    seeds = sorted(seed for chosen in by_family.values() for seed in chosen)
    assert len(seeds) == 12
    results = evaluate(controllers.make("fbsm"), seeds, path="random", max_time=200.0)
    assert [r["termination_reason"] for r in results] == ["time_limit"] * len(seeds)
    rms = np.array([r["rms_distance"] for r in results])
    assert rms.max() < 0.1, rms


# ------------------------------------------------------------------------ path kinds' own checks


def test_a_path_checks_its_kernel_data_and_bounds_its_turn_rates():
    from auv_gym.paths import path_turn_rates
    from auv_gym.paths.offset import ShiftedPath

    broken = Spline(WAYPOINTS)
    broken.data = broken.data[:-1].copy()  # one coefficient short of 1 + 4 knots + 3·12
    text = (
        r"^path Spline has no valid kernel data \(kind, data\); build paths with Helix, "
        r"StraightLine, Spline or make_path$"
    )
    with pytest.raises(ValueError, match=text):
        broken.check_kernel_data()
    with pytest.raises(ValueError, match=text):
        SimConfig(path=broken)
    helix = Helix()  # dψ_F/ds = ω, |p'| = sqrt(R²ω² + c²): 0.0476 rad/m; θ_F constant
    psi, theta = helix.turn_rate_bounds()
    expected = (math.pi / 20) / math.hypot(20 * math.pi / 20, 1.0)
    assert psi.upper == pytest.approx(expected, rel=1e-12) and theta.upper < 1e-15
    assert path_turn_rates(helix) == (psi.upper, theta.upper)
    spline = Spline(WAYPOINTS)
    bound = max(spline.turn_rate_bounds(), key=lambda b: b.upper)
    assert spline.turn_location(bound).startswith(f" (near s = {bound.s:.6g}, waypoint ")
    shifted = ShiftedPath(spline, (0.0, 0.0, 100.0))  # a translation keeps the rates
    assert shifted.turn_rate_bounds() == spline.turn_rate_bounds()
    assert shifted.turn_location(bound) == f" (near s = {bound.s:.6g})"
    assert np.array_equal(shifted.evaluate(3.0)[0], spline.evaluate(3.0)[0] + [0, 0, 100])


def test_spline_radius_bends_the_splines_alone():
    tight = PathDistribution(radius=(15.0, 40.0), spline_radius=(8.0, 9.0), length=200.0)
    assert PathDistribution(radius=(9.0, 12.0)).spline_radius == (9.0, 12.0)  # default: radius
    assert tight.spacing == 2.5  # a third of the smaller radius, rounded down to 0.5 m
    by_family: dict[str, list[float]] = {}
    for seed in range(60):
        path = tight.draw(np.random.default_rng(seed))
        by_family.setdefault(path.family, []).append(curvature_and_angle(path)[0])
    assert set(by_family) == set(FAMILIES)
    # splines turn between 1/15 and 1.05/8 1/m; helix and lawnmower turns stay within 1.05/15
    assert 1.0 / 15.0 < max(by_family["spline"]) <= CURVATURE_SLACK / 8.0
    assert max(by_family["helix"] + by_family["lawnmower"]) <= CURVATURE_SLACK / 15.0
    tight_helices = PathDistribution(families=("helix",), radius=(10.0, 13.0))
    tight_splines = PathDistribution(families=("spline",), radius=(8.5, 13.0))
    assert overlaps(tight_helices, tight) == [] and overlaps(tight_splines, tight) == ["spline"]


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        (
            {"families": ["helix"], "leg_length": (50, 60)},
            "path leg_length = (50, 60) shapes only the lawnmower family, and families "
            "['helix'] does not draw it: leave leg_length out or add 'lawnmower' to families",
        ),
        (
            {"families": ["helix", "lawnmower"], "piece_length": [30, 40]},
            "path piece_length = (30, 40) shapes only the spline family, and families "
            "['helix', 'lawnmower'] does not draw it: leave piece_length out or add 'spline' "
            "to families",
        ),
        (
            {"families": ["helix", "line"], "length": 300.0},
            "path length = 300.0 shapes only the spline and lawnmower families, and families "
            "['helix', 'line'] draws none of them: leave length out or add one of them to "
            "families",
        ),
        (
            {"families": ["line"], "radius": [20, 30]},
            "path radius = (20, 30) shapes only the helix, spline and lawnmower families, and "
            "families ['line'] draws none of them: leave radius out or add one of them to "
            "families",
        ),
        (
            {"families": ["helix"], "spline_radius": [20, 30]},
            "path spline_radius = (20, 30) shapes only the spline and lawnmower families, and "
            "families ['helix'] draws none of them: leave spline_radius out or add one of them "
            "to families",
        ),
    ],
)
def test_a_range_of_a_family_not_drawn_is_refused(spec, message):
    """Was: accepted and ignored (e.g. lawnmower legs for a distribution of helices)."""
    with pytest.raises(ValueError) as caught:
        SimConfig.from_kwargs(path=spec)
    assert str(caught.value) == message


def test_ranges_of_drawn_families_still_build():
    # spline_radius sets the waypoint spacing of lawnmowers too (docs/model.md §3.8)
    mower = PathDistribution.from_spec({"families": ["lawnmower"], "spline_radius": [9, 12]})
    assert mower.spacing == 3.0
    helices = PathDistribution.from_spec({"families": ["helix"], "radius": [10, 13]})
    assert helices.radius == (10.0, 13.0)
    assert PathDistribution.from_spec({"climb_angle_deg": [0, 5], "length": 300.0}).length == 300


_SHAPE = "(n, 3) with 2 <= n <= 1000, coordinates in [-1e+06, 1e+06] m"


@pytest.mark.parametrize(
    ("path", "error", "message"),
    [
        (
            [(0, 0, True), (40, 10, 8)],
            ArgumentTypeError,
            "path as a list of (x, y, z) waypoints: Spline waypoints must be real numbers of "
            f"shape {_SHAPE}, got [(0, 0, True), (40, 10, 8)] (a bool)",
        ),
        (
            np.array([[0, 0, 0], [40, 10, 8]], dtype=object),
            ArgumentTypeError,
            "path as a list of (x, y, z) waypoints: Spline waypoints must be real numbers of "
            f"shape {_SHAPE}, got an array of dtype object and shape (2, 3)",
        ),
        (
            {"kind": "waypoints", "waypoints": [(0, 0, 0), (40, 10, 8)]},
            ValueError,
            "path kind 'waypoints' got an unexpected keyword argument 'waypoints'; it takes no "
            "other key (a spline through other waypoints is the list of them, "
            "path=[(x, y, z), ...])",
        ),
        (
            {"kind": "helix", "centre": [0, 0, 0]},
            ValueError,
            "path kind 'helix' got an unexpected keyword argument 'centre'; valid keys: "
            "['center', 'climb', 'omega', 'radius', 's_end']",
        ),
    ],
)
def test_bad_waypoints_and_keys_raise_one_named_line(path, error, message):
    """Was: a bool taken as 0 or 1; a multi-line array repr; "<lambda>() got an unexpected
    keyword argument 'waypoints'"."""
    with pytest.raises(error) as caught:
        SimConfig.from_kwargs(path=path)
    assert str(caught.value) == message
