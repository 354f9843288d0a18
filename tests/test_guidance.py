"""Paths, Serret–Frenet errors and the virtual point (docs/model.md §3, §8 checks 1 and 5)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from auv_gym.paths import PATHS, Helix, Spline, StraightLine, make_path
from auv_gym.paths.guidance import (
    body_errors,
    error_rates,
    path_angles,
    virtual_point_speed,
    wrap_angle,
)
from auv_gym.vehicle.dynamics import state_derivative
from auv_gym.vehicle.params import params_record, remus100

ALL_PATHS = [Helix(), StraightLine(), make_path("waypoints"), Helix(radius=5.0, climb=-0.5)]


@pytest.mark.parametrize("path", ALL_PATHS, ids=lambda p: type(p).__name__)
def test_path_derivatives_match_finite_differences(path):
    s = np.linspace(0.3, 0.95 * min(path.s_end, 60.0), 25)
    h = 1e-5
    p_plus, dp_plus, _ = path.evaluate(s + h)
    p_minus, dp_minus, _ = path.evaluate(s - h)
    _, dp, ddp = path.evaluate(s)
    np.testing.assert_allclose((p_plus - p_minus) / (2 * h), dp, atol=1e-6)
    np.testing.assert_allclose((dp_plus - dp_minus) / (2 * h), ddp, atol=1e-5)


def test_helix_matches_the_paper():
    helix = Helix()
    p, dp, _ = helix.evaluate(np.array([0.0, 10.0]))
    np.testing.assert_allclose(p[0], [30.0, 0.0, -8.0])
    np.testing.assert_allclose(p[1], [10.0, 20.0, -18.0], atol=1e-12)
    psi_f, theta_f, dpsi, dtheta, speed = path_angles(*dp[0], *helix.evaluate(0.0)[2])
    assert psi_f == pytest.approx(math.pi / 2)
    assert math.degrees(theta_f) == pytest.approx(17.657, abs=1e-3)  # climb: z decreases
    assert dpsi == pytest.approx(math.pi / 20)
    assert dtheta == pytest.approx(0.0, abs=1e-12)
    assert speed == pytest.approx(3.2969, abs=1e-4)


@pytest.mark.parametrize("path", ALL_PATHS, ids=lambda p: type(p).__name__)
def test_path_angle_rates_match_finite_differences(path):
    h = 1e-6
    for s in np.linspace(0.5, 0.9 * min(path.s_end, 50.0), 9):
        a_plus = path_angles(*np.ravel(path.evaluate(s + h)[1:]))
        a_minus = path_angles(*np.ravel(path.evaluate(s - h)[1:]))
        a = path_angles(*np.ravel(path.evaluate(s)[1:]))
        assert (a_plus[0] - a_minus[0]) / (2 * h) == pytest.approx(a[2], abs=1e-6)
        assert (a_plus[1] - a_minus[1]) / (2 * h) == pytest.approx(a[3], abs=1e-6)


def test_unknown_path_name_lists_valid_names():
    with pytest.raises(ValueError, match=r"unknown path 'spiral'.*helix.*line.*waypoints"):
        make_path("spiral")
    assert set(PATHS) == {"helix", "line", "waypoints"}


def test_a_mapping_names_a_path_with_arguments():
    """The form a TOML scenario writes: {"kind": name, **arguments}."""
    line = make_path({"kind": "line", "direction": [1.0, 0.0, 0.25]})
    assert isinstance(line, StraightLine)
    np.testing.assert_allclose(
        line.evaluate(4.0)[1], np.array([1.0, 0.0, 0.25]) / math.hypot(1, 0.25)
    )
    assert make_path({"kind": "helix", "radius": 10.0}).radius == 10.0
    with pytest.raises(ValueError, match="unexpected keyword argument 'slope'"):
        make_path({"kind": "line", "slope": 3.0})
    with pytest.raises(ValueError, match="unknown path kind 'spiral'"):
        make_path({"kind": "spiral"})
    with pytest.raises(TypeError, match="path kind must be one of"):
        make_path({"direction": [1, 0, 0]})
    with pytest.raises(ValueError, match="direction must be non-zero"):
        make_path({"kind": "line", "direction": [0, 0, 0]})


@pytest.mark.parametrize(
    "build",
    [
        lambda: Helix(radius=-1.0),
        lambda: Helix(omega=float("nan")),
        lambda: StraightLine(direction=(0, 0, 0)),
        lambda: Spline([(0, 0, 0)]),
        lambda: Spline([(0, 0, 0), (0, 0, 0), (1, 1, 1)]),
    ],
)
def test_impossible_paths_raise(build):
    with pytest.raises(ValueError):
        build()


def test_error_model_matches_finite_differences():
    """Check 1: d/dt of ε = R_Bᵀ(η − p(s)) equals the exact error dynamics within 1e−6."""
    rng = np.random.default_rng(0)
    path = Helix()
    params = params_record(remus100().to_vector())
    zeros = np.zeros(5)
    for _ in range(50):
        st = np.r_[
            rng.uniform(-20, 20, 3),
            rng.uniform(-0.6, 0.6),
            rng.uniform(-3, 3),
            rng.uniform(0, 1.5),
            rng.uniform(-0.3, 0.3, 2),
            rng.uniform(-0.3, 0.3, 2),
            rng.uniform(0, 30),
        ]
        deriv = np.array(
            state_derivative(
                st,
                (10.0, 1.0, -1.0),
                zeros,
                (0.0, 0.0, 0.0),
                params,
                path.kind,
                path.data,
                1.0,
                0.5,
            )
        )

        def eps_at(h, st=st, deriv=deriv):
            x = st + h * deriv  # first-order flow; the central difference cancels the rest
            p = path.evaluate(x[10])[0]
            return np.array(body_errors(x[0], x[1], x[2], x[3], x[4], *p))

        h = 1e-6
        fd = (eps_at(h) - eps_at(-h)) / (2 * h)
        eps = eps_at(0.0)
        psi_f, theta_f, *_ = path_angles(*np.ravel(path.evaluate(st[10])[1:]))
        u_p = virtual_point_speed(eps[0], 1.0, 0.5)
        exact = error_rates(eps, st[5:10], st[3], st[4], psi_f, theta_f, u_p)
        np.testing.assert_allclose(fd, exact, atol=1e-6)


def test_virtual_point_law_uses_the_corrected_sign():
    assert virtual_point_speed(-15.0, 1.0, 0.5) < 1e-6  # P waits for a vehicle behind it
    assert virtual_point_speed(0.0, 1.0, 0.5) == 1.0
    assert virtual_point_speed(3.0, 1.0, 0.5) == pytest.approx(2.0, abs=1e-4)


def test_virtual_point_sanity_along_an_episode(make_sim):
    """Check 5: 0 ≤ u_p ≤ 2u_D and ṡ ≥ 0 always; at t = 0, x_e = −15 m and u_p < 1e−6."""
    sim = make_sim(disturbance="paper")
    assert sim.guid[0, 0] == pytest.approx(-15.0)
    np.testing.assert_allclose(sim.guid[0, 0:3], [-15.0, 5.0, 8.0])
    assert sim.guid[0, 8] < 1e-6
    rng = np.random.default_rng(1)
    s_prev = sim.state[0, 10]
    for _ in range(2000):
        sim.step(
            np.array([[rng.uniform(0.2, 1.0), rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1)]])
        )
        if sim.code[0]:
            break
        assert 0.0 <= sim.guid[0, 8] <= 2.0
        assert sim.guid[0, 9] >= 0.0
        assert sim.state[0, 10] >= s_prev
        s_prev = sim.state[0, 10]
    assert s_prev > 1.0


@pytest.mark.parametrize(
    ("angle", "wrapped"),
    [
        (0.0, 0.0),
        (math.pi, math.pi),
        (-math.pi, math.pi),
        (3 * math.pi, math.pi),
        (2 * math.pi + 0.1, 0.1),
        (-2 * math.pi - 0.1, -0.1),
        (7.0, 7.0 - 2 * math.pi),
    ],
)
def test_wrap_angle_to_half_open_interval(angle, wrapped):
    assert wrap_angle(angle) == pytest.approx(wrapped, abs=1e-12)


def test_printed_virtual_point_law_is_available_for_negative_tests(make_sim):
    printed = make_sim(disturbance="none", virtual_point_law="printed")
    assert printed.guid[0, 8] == pytest.approx(2.0, abs=1e-6)  # 1 − tanh(−15/0.5) = 2
    with pytest.raises(ValueError, match="virtual_point_law"):
        make_sim(virtual_point_law="typo")
