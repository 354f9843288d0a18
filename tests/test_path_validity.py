"""Path and parameter-draw validity that sampling cannot fool: proven bounds on |p'| and the turn
rates (`auv_gym.paths.bounds`), waypoint paths that double back, path distributions and
parameter draws that are valid for every seed or refused when built."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import auv_gym  # registers the ids
from auv_gym.paths.bounds import _kernel_rates, min_tangent_squared, spline_turn_rates
from auv_gym.paths.guidance import path_angles
from auv_gym.paths.shapes import MIN_TANGENT, Spline, fit_curve, path_eval
from auv_gym.sim.config import SimConfig, path_turn_rates
from auv_gym.sim.observation import PATH_RATE_BOUND
from auv_gym.sim.path_generator import (
    CURVATURE_SLACK,
    FAMILIES,
    MAX_TURN_RATE,
    PathDistribution,
    curvature_and_angle,
)
from auv_gym.vehicle.dynamics import STATE
from auv_gym.vehicle.params import HYDRODYNAMIC_FIELDS, remus100

DATA = Path(__file__).parent / "data"

CI = settings(
    deadline=None, derandomize=True, database=None, suppress_health_check=[HealthCheck.too_slow]
)


def dense_rates(path, per_segment: int = 2000) -> tuple[float, float, float]:
    """Largest ψ and θ rates [rad/m] and smallest |p'|² at many points per segment, as the
    kernels compute them."""
    n_seg = int(path.data[0])
    seg = np.repeat(np.arange(n_seg), per_segment)
    u = np.tile(np.linspace(0.0, 1.0, per_segment), n_seg)
    psi, theta, speed2 = _kernel_rates(path.data, seg, u)
    return float(psi.max()), float(theta.max()), float(speed2.min())


# --- waypoint paths that double back -----------------------------------------------------------


def test_an_out_and_back_line_is_refused_naming_the_waypoint():
    # Before: ZeroDivisionError from inside the turn-rate check.
    with pytest.raises(ValueError) as error:
        gym.make("AUVPath3D-v0", path=[(0, 0, 0), (100, 0, 0), (0, 0, 0)])
    assert str(error.value) == (
        "path as a list of (x, y, z) waypoints: Spline: the path doubles back at waypoint 1 "
        "(s = 100 m: |p'(s)| = 0 < 1e-06); add a turn waypoint beside waypoint 1 (or split the "
        "path there)"
    )


def test_an_out_and_back_survey_with_a_turn_waypoint_is_followable():
    env = gym.make(
        "AUVPath3D-v0",
        path=[(0, 0, 0), (100, 0, 0), (110, 10, 0), (100, 20, 0), (0, 20, 0)],
        randomize_start=True,
    )
    psi, theta = path_turn_rates(env.unwrapped.config.path)
    assert 0.2 < psi < 0.3 and theta == 0.0  # a turn of about 4 m radius at the far end
    for seed in range(50):
        obs, _ = env.reset(seed=seed)
        assert np.all(np.isfinite(obs))


def test_a_near_reversal_between_samples_is_refused_at_construction():
    # Before: accepted (64 samples per segment saw at most 2.5 rad/m), then ψ̇_F of about 3e8
    # rad/s near s = 19.15 m: a reset there raised, inside step() at a vector env's autoreset.
    path = [(0, 0, 0), (20, 0, 0), (5, 0.001, 0)]
    with pytest.raises(
        ValueError,
        match=r"^path turns at up to 1\.478e\+08 rad/m \(near s = "
        r"19\.1485, waypoint 1\): .* needs a turn waypoint beside the reversal\)$",
    ):
        gym.make("AUVPath3D-v0", path=path)
    spline = Spline(path)
    psi, _ = spline_turn_rates(spline.data)
    *_, dx, dy, dz, ddx, ddy, ddz = path_eval(spline.kind, spline.data, psi.s)
    _, _, dpsi_ds, _, speed = path_angles(dx, dy, dz, ddx, ddy, ddz)
    assert abs(dpsi_ds) / speed == psi.reached > 1e8  # the kernel's own rate there


def test_the_turn_rate_check_still_accepts_a_path_just_within_the_bound():
    spline = Spline([(0, 0, 0), (3, 1, -0.2), (6, -0.5, -0.4), (9, 0, 0)])
    psi, theta = path_turn_rates(spline)
    u_max = PATH_RATE_BOUND / (2 * max(psi, theta))
    SimConfig.from_kwargs(path=spline, u_desired=u_max * (1 - 1e-9))
    with pytest.raises(ValueError, match="path turns at up to"):
        SimConfig.from_kwargs(path=spline, u_desired=u_max * 1.01)


def test_the_preview_stays_in_its_bounds_at_a_near_reversal():
    # Accepted at this u_desired (the turn-rate check allows 1e9 rad/m). Before: with the
    # virtual point just before the reversal, the preview's midpoint march stepped by
    # Δs/‖p′‖ with ‖p′‖ nearly 0 and put a point 3 km away, outside the space (4 of these 601
    # virtual-point positions; the fuzz raised at a reset inside step()).
    path = [(0.0, 0.0, 0.0), (24.0, 0.0, 0.0), (-15.0, 0.0004, 0.0)]
    env = gym.make("AUVPath3DPreview-v0", path=path, u_desired=1e-10)
    env.reset(seed=0)
    sim = env.unwrapped.sim
    for s in np.linspace(20.0, 26.0, 601):  # the virtual point anywhere near the reversal
        sim.state[0, STATE.s] = s
        sim._extend(np.array([0]))
        assert env.observation_space.contains(sim.observations()[0])


# --- proven bounds -----------------------------------------------------------------------------


waypoint_steps = st.lists(
    st.tuples(*[st.floats(-1.0, 1.0, allow_nan=False)] * 3).filter(lambda d: math.hypot(*d) > 1e-2),
    min_size=1,
    max_size=6,
)


@settings(CI, max_examples=150)
@given(waypoint_steps, st.floats(0.1, 1e3))
def test_the_bounds_enclose_every_value_the_kernels_compute(steps, scale):
    points = scale * np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])
    try:
        spline = Spline(points)
    except ValueError as error:  # doubles back: |p'| below the minimum, proven by a value
        assert "doubles back at waypoint" in str(error)
        assert -min_tangent_squared(_natural(points)).reached < MIN_TANGENT**2
        return
    psi, theta = spline_turn_rates(spline.data)
    low = min_tangent_squared(spline.data)
    dense_psi, dense_theta, dense_speed2 = dense_rates(spline, 400)
    # Absolute tolerances at the scale of rounding, not of paths: a dense sample of a nearly
    # straight segment carries ~1e-12 rad/m of noise, and a bound of a turn rate below 1e-4
    # rad/m (a 10-km radius) need not be tight (examples: 4.6e-12 sampled against a 1.5e-15
    # bound; 2.67e-5 against 2.34e-5 reached). The noise of a turn rate [1/m] grows as the path
    # shrinks: 1.7e-10 sampled against a 2.9e-14 bound on a nearly straight 0.4-m segment.
    noise = 1e-10 / min(scale, 1.0) ** 2
    for bound, dense in ((psi, dense_psi), (theta, dense_theta)):
        assert bound.upper >= dense * (1 - 1e-9) - noise  # an upper bound, never a sample
        assert bound.upper <= bound.reached * (1 + 1e-3) + 1e-4  # and tight: 0.1 %
    assert -low.upper <= dense_speed2 * (1 + 1e-9)
    assert -low.upper >= MIN_TANGENT**2


@settings(CI, max_examples=30)
@given(waypoint_steps, st.floats(1.0, 100.0), st.floats(0.1, 2.0))
def test_an_accepted_waypoint_path_resets_for_every_seed(steps, scale, u_desired):
    points = scale * np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])
    try:
        env = gym.make(
            "AUVPath3D-v0",
            path=points,
            u_desired=u_desired,
            randomize_start=True,
            disturbance="none",
        )
    except ValueError as error:  # doubles back or turns too fast: refused when built
        assert "doubles back at waypoint" in str(error) or "path turns at up to" in str(error)
        return
    for seed in range(100):  # 3,000 resets in all, anywhere on the path's first 40 m
        obs, _ = env.reset(seed=seed)
        assert env.observation_space.contains(obs)


def _natural(points: np.ndarray) -> np.ndarray:
    """The SPLINE kernel vector of the natural spline through ``points``, unchecked."""
    from auv_gym.paths.kernels import natural_cubic_coefficients, spline_data

    knots = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))]
    return spline_data(knots, natural_cubic_coefficients(knots, points))


def test_the_bound_of_the_default_waypoints_is_exact_to_the_tolerance():
    spline = Spline(auv_gym.paths.shapes.DEFAULT_WAYPOINTS)
    psi, theta = spline_turn_rates(spline.data)
    dense_psi, dense_theta, _ = dense_rates(spline, 20_000)
    assert dense_psi <= psi.upper <= dense_psi * 1.001
    assert dense_theta <= theta.upper <= dense_theta * 1.001
    np.testing.assert_allclose([psi.upper, theta.upper], [0.14265, 0.027798], rtol=1e-4)


def test_fit_curve_checks_the_tangent_everywhere_not_at_three_points():
    # Before: accepted (the check points ¼, ½, ¾ of each segment miss s = 5, a knot) although
    # p'(5) = 0: ṡ = u_p/|p'| infinite there.
    with pytest.raises(ValueError) as error:
        fit_curve(lambda s: ((s - 5.0) ** 3, 0.0, 0.0), 10.0)
    # The tangent found there is rounding noise (its digits are the arithmetic's), not a value.
    found = re.fullmatch(
        r"fit_curve: \|p'\(s\)\| must be >= 1e-06 m per unit s everywhere, got (\S+) at s = 5; "
        r"the curve must not stop or double back",
        str(error.value),
    )
    assert found is not None, str(error.value)
    assert float(found.group(1)) < 1e-12


# --- path distributions ------------------------------------------------------------------------


def test_a_lawnmower_that_ends_in_a_turn_draws_for_every_seed():
    # Before: "no lawnmower path within the limits after 20 draws" at every reset: every track
    # ends inside a turn, where the natural spline's p'' = 0 overshoots the curvature limit.
    narrow = PathDistribution(
        families=("lawnmower",), radius=(15.0, 15.0), leg_length=(20.0, 20.0), length=64.6
    )
    for seed in range(200):
        path = narrow.draw(np.random.default_rng(seed))
        kappa, _ = curvature_and_angle(path)
        assert kappa <= CURVATURE_SLACK / 15.0
        assert 59.5 < path.s_end <= 60.0  # 13 waypoints about 5 m apart


def test_end_tangents_clamp_a_spline_that_ends_inside_a_turn():
    angles = np.linspace(0.0, math.pi / 2, 8)  # a quarter circle of radius 20 m
    arc = np.stack([20 * np.sin(angles), 20 * (1 - np.cos(angles)), 0 * angles], axis=1)
    ends = [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0)]
    natural, clamped = Spline(arc), Spline(arc, end_tangents=ends)
    assert curvature_and_angle(natural)[0] * 20 > 1.2  # straightened ends, a tighter middle
    assert abs(curvature_and_angle(clamped)[0] * 20 - 1.0) < 0.01
    with pytest.raises(TypeError, match=r"end_tangents must be two \(x, y, z\) vectors"):
        Spline(arc, end_tangents=[(1.0, 0.0, 0.0)])


def test_successful_draws_are_unchanged():
    """The draws of the code before the fallback and the proven checks were added, recorded in
    tests/data/path_draws.json: the same family and size exactly, the same points to 1e-9 m
    (a spline's linear solves round differently with another CPU's LAPACK, so a hash of the
    bytes was a test of the machine)."""
    recorded = json.loads((DATA / "path_draws.json").read_text())["draws"]
    draws = []
    for distribution in (
        PathDistribution(),
        PathDistribution(families=("spline", "lawnmower"), radius=(8.0, 12.0), length=150.0),
    ):
        draws += [distribution.draw(np.random.default_rng(seed)) for seed in range(40)]
    assert len(draws) == len(recorded) == 80
    for path, want in zip(draws, recorded, strict=True):
        family = getattr(path, "family", None) or type(path).__name__
        assert (int(path.kind), family, int(path.data.size)) == (
            want["kind"],
            want["family"],
            want["size"],
        )
        s_end = want["s_end"] if want["s_end"] is not None else 300.0
        positions = path.evaluate(np.array([0.0, 0.37 * s_end, s_end]))[0]
        np.testing.assert_allclose(positions, want["positions"], rtol=0, atol=1e-9)


def _span(low: float, high: float) -> st.SearchStrategy[tuple[float, float]]:
    return st.one_of(
        st.floats(low, high).map(lambda a: (a, a)),  # narrow: the same shape every draw
        st.tuples(st.floats(low, high), st.floats(low, high)).map(lambda t: tuple(sorted(t))),
    )


distributions = st.builds(
    PathDistribution,
    families=st.lists(st.sampled_from(FAMILIES), min_size=1, max_size=4, unique=True).map(tuple),
    radius=_span(8.0, 200.0),
    spline_radius=st.one_of(st.none(), _span(8.0, 200.0)),
    climb_angle_deg=_span(0.0, 25.0),
    piece_length=_span(20.0, 300.0),
    leg_length=_span(20.0, 300.0),
    length=st.floats(50.0, 250.0).map(lambda x: round(x, 1)),
)


@settings(CI, max_examples=60)
@given(distributions, st.integers(0, 2**32 - 1))
def test_an_accepted_distribution_draws_a_valid_path_for_every_seed(distribution, seed):
    for k in range(25):  # 1,500 draws in all
        path = distribution.draw(np.random.default_rng([seed, k]))
        if path.kind == 2:
            kappa, gamma = curvature_and_angle(path)
            radius = distribution.spline_radius if path.family == "spline" else distribution.radius
            assert kappa <= CURVATURE_SLACK / radius[0]
            assert gamma <= math.radians(distribution.climb_angle_deg[1] + 0.5)
            assert -min_tangent_squared(path.data, MIN_TANGENT**2).upper >= MIN_TANGENT**2
        psi, theta = path_turn_rates(path, accept_below=MAX_TURN_RATE)
        assert max(psi, theta) <= MAX_TURN_RATE  # proven: any u_desired fits


def test_a_random_path_vector_env_resets_for_every_seed():
    env = gym.make_vec(
        "AUVPath3D-v0",
        num_envs=8,
        vectorization_mode="vector_entry_point",
        path={
            "families": ["lawnmower", "spline"],
            "radius": [15.0, 15.0],
            "leg_length": [20.0, 20.0],
            "length": 64.6,
        },
        randomize_start=True,
    )
    for seed in range(0, 256, 8):  # before: every reset raised
        obs, _ = env.reset(seed=seed)
        assert np.all(np.isfinite(obs))
    env.close()


# --- parameter draws ---------------------------------------------------------------------------


def test_a_param_uncertainty_that_can_draw_an_invalid_vehicle_is_refused():
    # Before: accepted, then 17 of the first 100 resets raised "m11 = m − X_udot must be
    # positive".
    with pytest.raises(ValueError) as error:
        gym.make("AUVPath3D-v0", params={"X_udot": 20.0}, param_uncertainty=0.9)
    assert str(error.value) == (
        "param_uncertainty = 0.9 can draw an invalid vehicle: m11 = m - X_udot·(1 + δ) falls to "
        "-7.52 at δ = +0.9 (m = 30.48, X_udot = 20); use param_uncertainty < 0.524 or a "
        "smaller X_udot"
    )
    env = gym.make("AUVPath3D-v0", params={"X_udot": 20.0}, param_uncertainty=0.52)
    for seed in range(100):
        env.reset(seed=seed)


def test_a_coefficient_the_draw_could_overflow_is_refused():
    with pytest.raises(ValueError, match=r"scale AUVParams\.X_uu = -1e\+308 beyond the float"):
        remus100(X_uu=-1e308).check_perturbation(0.9)


@settings(CI, max_examples=80)
@given(
    st.dictionaries(st.sampled_from(HYDRODYNAMIC_FIELDS), st.floats(-100.0, 100.0), max_size=6),
    st.floats(0.0, 0.999),
)
def test_accepted_parameter_ranges_draw_valid_vehicles_for_every_seed(values, epsilon):
    try:
        params = remus100(**values)
    except ValueError:  # not a vehicle to begin with
        assume(False)
    try:
        params.check_perturbation(epsilon)
    except ValueError as error:
        assert "can draw an invalid vehicle" in str(error)
        return
    for seed in range(40):  # 3,200 draws in all
        params.perturbed(np.random.default_rng(seed), epsilon)
