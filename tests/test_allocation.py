"""Control allocation for the realistic actuators (controllers.allocation, docs/model.md §2.7)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import controllers
from auv_gym import OBS_NAMES
from auv_gym.rollout import rollouts
from auv_gym.vehicle import remus100
from auv_gym.vehicle.actuators import ActuatorParams, actuator_forces, actuator_record
from controllers.allocation import allocate, fin_gain

P = ActuatorParams()
LIMITS = np.array([P.rpm_max, P.delta_max_stern, P.delta_max_rudder])


def _forces(commands: np.ndarray, nu: tuple[float, float, float]) -> np.ndarray:
    n_rpm, d_s, d_r = commands * LIMITS
    return np.array(actuator_forces(n_rpm, d_s, d_r, *nu, actuator_record(P)))


@settings(max_examples=300, deadline=None)
@given(
    u=st.floats(0.2, 2.3),
    v=st.floats(-0.3, 0.3),
    w=st.floats(-0.3, 0.3),
    x=st.floats(-30.0, 60.0),
    a_m=st.floats(-1.0, 1.0),
    a_n=st.floats(-1.0, 1.0),
)
def test_allocation_then_actuators_give_back_a_reachable_tau(u, v, w, x, a_m, a_n) -> None:
    """τ_d = (X, M, N) within the fins' authority at this speed and within the propeller's
    thrust: the actuator model at the allocated (n, δ_s, δ_r) reproduces it (relative 1e-9)."""
    stern, rudder = P.fin_moment_coeff()
    tau = np.array(
        [
            x,
            a_m * stern * P.delta_max_stern * (u * u + w * w),
            a_n * rudder * P.delta_max_rudder * (u * u + v * v),
        ]
    )
    commands = allocate(tau, (u, v, w), P)[0]
    assume(np.abs(commands).max() < 1.0)  # reachable: no command at its limit
    got = _forces(commands, (u, v, w))
    np.testing.assert_allclose(got[[0, 3, 4]], tau, rtol=1e-9, atol=1e-9)


def test_round_trip_covers_ahead_astern_and_both_fins() -> None:
    tau = np.array([[40.0, 2.0, -1.5], [-12.0, -3.0, 0.5], [1.62, 0.0, 0.0], [0.0, 0.1, 0.1]])
    nu = np.array([[1.0, 0.05, -0.02], [1.5, 0.0, 0.0], [1.0, 0.0, 0.0], [0.8, 0.1, 0.1]])
    commands = allocate(tau, nu, P)
    assert commands[0, 0] > 0.0 > commands[1, 0]  # ahead, astern
    for c, t, n in zip(commands, tau, nu, strict=True):
        assert np.abs(c).max() < 1.0
        np.testing.assert_allclose(_forces(c, tuple(n))[[0, 3, 4]], t, rtol=1e-9, atol=1e-12)
    # trim at 1 m/s: 1.62 N of drag, X_prop = 1.8 N, T = 4.567 rps²,
    # n = (2.814 + √(2.814² + 4·0.4566·4.567))/0.9132 rps
    assert commands[2, 0] * P.rpm_max == pytest.approx(449.85, abs=0.01)


@pytest.mark.parametrize("kappa", [0.0, 0.5, 2.0])
def test_the_allocation_takes_the_fins_induced_drag_factor(kappa) -> None:
    """Was: the allocation subtracted the fins' drag at κ = 1 whatever the actuator's κ (the
    torpedo's is 0): 0.56 N of surplus thrust at 10 N, u = 2 m/s, half the fins' authority."""
    params = P.replace(fin_induced_drag=kappa)
    limits = np.array([params.rpm_max, params.delta_max_stern, params.delta_max_rudder])
    stern, rudder = params.fin_moment_coeff()
    u = 2.0  # [m/s]
    tau = np.array([10.0, 0.5 * stern * params.delta_max_stern * u * u, 0.0])
    tau[2] = 0.5 * rudder * params.delta_max_rudder * u * u
    commands = allocate(tau, (u, 0.0, 0.0), params)[0]
    n_rpm, d_s, d_r = commands * limits
    got = np.array(actuator_forces(n_rpm, d_s, d_r, u, 0.0, 0.0, actuator_record(params)))
    np.testing.assert_allclose(got[[0, 3, 4]], tau, rtol=1e-9, atol=1e-9)


def test_unreachable_tau_saturates_towards_it() -> None:
    commands = allocate(
        np.array([[500.0, 50.0, -50.0], [-500.0, -50.0, 50.0]]),
        np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]]),
        P,
    )
    np.testing.assert_array_equal(commands, [[1.0, -1.0, -1.0], [-1.0, 1.0, 1.0]])
    m = _forces(commands[0], (1.0, 0.0, 0.0))[3]
    assert m == pytest.approx(fin_gain(P))  # the largest pitch moment, with the demanded sign
    # no flow over the fins: full deflection towards the demanded moment, zero for none
    np.testing.assert_array_equal(
        allocate(np.array([[0.0, 1.0, 0.0]]), (0.0, 0.0, 0.0), P), [[0.0, -1.0, 0.0]]
    )


def test_controllers_allocate_the_fin_limited_law() -> None:
    """On "realistic" a controller computes the "fins" law's τ and allocates it."""
    assert fin_gain(P) == pytest.approx(6.15 * math.pi / 6, rel=1e-14)
    obs = np.zeros((3, len(OBS_NAMES)))
    idx = {k: OBS_NAMES.index(k) for k in ("u", "v", "w", "y_e", "z_e")}
    obs[:, idx["u"]] = (0.6, 1.0, 1.4)
    obs[:, idx["v"]], obs[:, idx["w"]] = 0.05, -0.03
    obs[:, idx["y_e"]], obs[:, idx["z_e"]] = (1.0, -2.0, 0.5), (0.3, 0.4, -1.0)
    for name in ("fbsm", "backstepping", "pid_los", "fbsm_colos"):
        fins, _ = controllers.make(name, actuator="fins").predict(obs)
        real, _ = controllers.make(name, actuator="realistic").predict(obs)
        u = obs[:, idx["u"]]
        authority = fin_gain(P) * u * u
        tau = fins.astype(np.float64) * np.stack([np.full(3, 50.0), authority, authority], 1)
        want = allocate(tau, obs[:, [idx["u"], idx["v"], idx["w"]]], P)
        np.testing.assert_allclose(real, want, rtol=1e-5, atol=1e-6, err_msg=name)


def test_pid_los_follows_the_helix_on_realistic_actuators_with_noise() -> None:
    (tr,) = rollouts(
        controllers.make("pid_los", actuator="realistic"),
        [0],
        actuator="realistic",
        disturbance="paper",
        max_time=120.0,
    )
    assert tr.termination_reason == "time_limit"
    assert tr["distance"][-200:].max() < 2.0
    assert abs(tr["u"][-200:].mean() - 1.0) < 0.1


def test_controllers_take_the_actuator_params_of_the_env() -> None:
    """A controller told the plant's `actuator_params` (here fins of half the area) allocates
    the "fins" law of a vehicle with half the fin moment with them; an unknown key is a named
    error."""
    obs = np.zeros((2, len(OBS_NAMES)))
    obs[:, OBS_NAMES.index("u")] = (0.9, 1.2)
    obs[:, OBS_NAMES.index("z_e")], obs[:, OBS_NAMES.index("y_e")] = (0.4, -0.2), (0.1, 0.6)
    small = P.replace(fin_area_stern=P.fin_area_stern / 2, fin_area_rudder=P.fin_area_rudder / 2)
    weak = remus100(fin_moment_coeff=6.15 / 2)
    u = obs[:, OBS_NAMES.index("u")]
    authority = fin_gain(small) * u * u
    for name in ("fbsm", "backstepping", "pid_los"):
        fins, _ = controllers.make(name, actuator="fins", params=weak).predict(obs)
        real, _ = controllers.make(
            name, actuator="realistic", params=weak, actuator_params=small
        ).predict(obs)
        tau = fins.astype(np.float64) * np.stack([np.full(2, 50.0), authority, authority], 1)
        want = allocate(tau, obs[:, [OBS_NAMES.index(k) for k in "uvw"]], small)
        np.testing.assert_allclose(real, want, rtol=1e-5, atol=1e-6, err_msg=name)
        with pytest.raises(ValueError, match=r"actuator_params has unknown key\(s\) \['area'\]"):
            controllers.make(name, actuator="realistic", actuator_params={"area": 1.0})
