"""Hull variation (`auv_gym.vehicle.variation`, env argument ``hull_variation``): the mass,
centre of gravity, added mass and damping drawn per episode within their ranges, on both
plants, from a stream of the episode's own; off, nothing changes."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import auv_gym  # noqa: F401  (registers the env ids)
from auv_gym.vehicle.params import PARAM_INDEX, remus100
from auv_gym.vehicle.remus6dof import REMUS6DOF
from auv_gym.vehicle.six_dof import SIX_DOF
from auv_gym.vehicle.variation import (
    ADDED_MASS_FIELDS,
    DAMPING_FIELDS,
    HullDraw,
    HullVariation,
    varied_hull_row,
    varied_params,
)

RANGES = {"mass": 0.1, "cg_offset": 0.005, "added_mass": 0.3, "damping": 0.3}
NO_DRAW = HullDraw(1.0, (0.0, 0.0), (1.0,) * 6, (1.0,) * 6, 1.0)


def _env(**kwargs):
    return gym.make("AUVPath3D-v0", max_time=30.0, **kwargs).unwrapped


def test_a_draw_of_ones_is_the_vehicle_itself_on_both_plants():
    assert varied_params(remus100(), NO_DRAW) == remus100()
    np.testing.assert_array_equal(varied_hull_row(REMUS6DOF, NO_DRAW), REMUS6DOF.kernel_vector())


def test_draws_stay_in_their_ranges_and_fill_them():
    variation = HullVariation(**RANGES)
    rng = np.random.default_rng(0)
    draws = [variation.draw(rng) for _ in range(400)]
    mass = np.array([d.mass for d in draws])
    cg = np.array([d.cg_offset for d in draws])
    added = np.array([d.added_mass for d in draws])
    damping = np.array([d.damping for d in draws])
    for values, half_width in ((mass - 1, 0.1), (cg, 0.005), (added - 1, 0.3), (damping - 1, 0.3)):
        assert np.abs(values).max() <= half_width
        assert np.abs(values).max() > 0.95 * half_width  # uniform: the edges are reached


def test_the_5dof_record_takes_each_factor_where_it_belongs():
    added, damping = (0.8, 0.9, 1.1, 1.2, 1.3, 0.7), (0.6, 0.7, 0.8, 0.9, 1.1, 1.2)
    draw = HullDraw(1.1, (0.003, -0.004), added, damping, 1.0)
    base, varied = remus100(), varied_params(remus100(), draw)
    assert varied.m == pytest.approx(base.m * 1.1) and varied.W == pytest.approx(base.W * 1.1)
    assert varied.I_y == pytest.approx(base.I_y * 1.1) and varied.B == base.B
    assert varied.z_g == pytest.approx(base.z_g - 0.004)  # the 5-DOF model has no x_g
    axes = ("surge", "sway", "heave", "roll", "pitch", "yaw")
    for k, axis in enumerate(axes):
        for name in ADDED_MASS_FIELDS.get(axis, ()):
            assert getattr(varied, name) == pytest.approx(getattr(base, name) * draw.added_mass[k])
        for name in DAMPING_FIELDS.get(axis, ()):
            assert getattr(varied, name) == pytest.approx(getattr(base, name) * draw.damping[k])
    assert varied.M_uw == base.M_uw and varied.fin_moment_coeff == base.fin_moment_coeff


def test_the_6dof_hull_row_is_consistent_and_keeps_its_buoyancy():
    draw = HullDraw(1.2, (0.01, 0.005), (0.8, 0.9, 1.1, 1.2, 1.3, 0.7), (1.1,) * 6, 0.5)
    row = varied_hull_row(REMUS6DOF, draw)
    nominal = REMUS6DOF.kernel_vector()

    def block(name: str) -> np.ndarray:
        start = getattr(SIX_DOF, f"{name}_00")
        return row[start : start + 36].reshape(6, 6)

    np.testing.assert_allclose(block("mass") @ block("inverse_mass"), np.eye(6), atol=1e-12)
    np.testing.assert_allclose(
        np.diag(block("added")), np.diag(REMUS6DOF.added_mass) * draw.added_mass, rtol=1e-15
    )
    rigid = block("mass") - block("added")
    assert rigid[0, 0] == pytest.approx(REMUS6DOF.mass_kg * 1.2)
    # The centre of gravity's offset couples surge and pitch: M_RB[0, 4] = m z_g.
    assert rigid[0, 4] == pytest.approx(REMUS6DOF.mass_kg * 1.2 * (REMUS6DOF.r_bg[2] + 0.005))
    assert row[SIX_DOF.weight] == pytest.approx(nominal[SIX_DOF.weight] * 1.2)
    assert row[SIX_DOF.buoyancy] == nominal[SIX_DOF.buoyancy]
    assert row[SIX_DOF.x_g] == pytest.approx(0.01)
    assert row[SIX_DOF.damping_u] == pytest.approx(nominal[SIX_DOF.damping_u] * 1.1)
    assert row[SIX_DOF.crossflow_coeff] == pytest.approx(nominal[SIX_DOF.crossflow_coeff] * 0.5)


@pytest.mark.parametrize("plant", ["5dof", "6dof"])
def test_off_changes_nothing_and_on_changes_only_the_hull(plant):
    kwargs = {"plant": plant, "param_uncertainty": 0.2, "disturbance": "paper"}
    plain, off = _env(**kwargs), _env(hull_variation={}, **kwargs)
    varied, again = _env(hull_variation=RANGES, **kwargs), _env(hull_variation=RANGES, **kwargs)
    actions = np.random.default_rng(3).uniform(-0.5, 0.5, (200, 3)).astype(np.float32)
    runs = []
    for env in (plain, off, varied, again):
        obs, _ = env.reset(seed=11)
        trace = [obs]
        for action in actions:
            obs, *_ = env.step(action)
            trace.append(obs)
        runs.append(np.array(trace))
    np.testing.assert_array_equal(runs[0], runs[1])  # all ranges 0: the same episode
    np.testing.assert_array_equal(runs[2], runs[3])  # the same seed: the same draw
    np.testing.assert_array_equal(runs[0][0], runs[2][0])  # the start is the seed's either way
    assert np.abs(runs[2][-1] - runs[0][-1]).max() > 1e-3  # the hull did change the flight
    # On top of the same parameter-uncertainty draw: the rigid mass is not uncertain, the
    # surge added mass is (both plants keep the 5-DOF row too).
    draw, ours, theirs = varied.sim._hull_draw(0), varied.sim.params[0], plain.sim.params[0]
    assert ours[PARAM_INDEX["m"]] / theirs[PARAM_INDEX["m"]] == pytest.approx(draw.mass)
    assert theirs[PARAM_INDEX["X_udot"]] != remus100().X_udot  # perturbed
    ratio = ours[PARAM_INDEX["X_udot"]] / theirs[PARAM_INDEX["X_udot"]]
    assert ratio == pytest.approx(draw.added_mass[0])


def test_both_plants_read_the_same_draw_of_a_seed():
    five, six = _env(hull_variation=RANGES), _env(hull_variation=RANGES, plant="6dof")
    draws = []
    for seed in (0, 1, 2):
        five.reset(seed=seed)
        six.reset(seed=seed)
        assert five.sim._hull_draw(0) == six.sim._hull_draw(0)
        draws.append(five.sim._hull_draw(0))
    assert len({d.mass for d in draws}) == 3  # and each seed its own


def test_a_heavier_6dof_hull_sinks_and_a_lighter_one_rises():
    """The buoyancy stays: a drawn mass above the record's is a net weight (ballast error)."""
    kwargs = {"plant": "6dof", "disturbance": "none"}
    nominal, varied = _env(**kwargs), _env(hull_variation={"mass": 0.1}, **kwargs)
    stop = np.zeros(3, dtype=np.float32)  # no thrust, no moments
    signs = []
    for seed in range(8):
        depths = []
        for env in (nominal, varied):
            env.reset(seed=seed)
            for _ in range(200):  # 10 s
                env.step(stop)
            depths.append(float(env.sim.state[0, 2]))
        factor = varied.sim._hull_draw(0).mass
        if abs(factor - 1.0) > 0.02:
            signs.append((np.sign(factor - 1.0), np.sign(depths[1] - depths[0])))
    assert len(signs) >= 5
    assert all(mass_sign == depth_sign for mass_sign, depth_sign in signs)  # z is down (NED)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"hull_variation": {"mass": 0.6}}, "hull_variation.mass"),
        ({"hull_variation": {"damping": -0.1}}, "hull_variation.damping"),
        ({"hull_variation": {"added_mass": float("nan")}}, "hull_variation.added_mass"),
        ({"hull_variation": {"inertia": 0.1}}, "inertia"),
        ({"hull_variation": 0.1}, "hull_variation must be None, a HullVariation or a mapping"),
        ({"hull_variation": {"cg_offset": 0.02}}, "centre of buoyancy (z_g − z_b = 0.0196 m"),
        (
            {"hull_variation": {"cg_offset": 0.03}, "plant": "6dof"},
            "z_g − z_b = 0.02 m on the 6-DOF plant",
        ),
        (
            {
                "hull_variation": {"damping": 0.9, "mass": 0.5},
                "plant": "6dof",
                "param_uncertainty": 0.3,
                "physics_dt": 0.1,
                "control_dt": 0.1,
                "noise_hold": 0.1,
            },
            "faster than RK4 at physics_dt = 0.1 s can step",
        ),
    ],
)
def test_bad_ranges_are_refused_in_one_line(kwargs, message):
    with pytest.raises((ValueError, TypeError)) as error:
        gym.make("AUVPath3D-v0", **kwargs)
    assert message in str(error.value) and "\n" not in str(error.value)
