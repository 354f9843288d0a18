"""The 6-DOF REMUS 100 (`auv_gym.vehicle.remus6dof`) against the reference implementation's
numbers, and its energy when unforced and undamped."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from auv_gym.vehicle.remus6dof import REMUS6DOF, accelerations, coriolis_matrix

REFERENCE = Path(__file__).parent / "data" / "pvs_remus100_6dof.json"


def test_accelerations_equal_the_reference_on_its_grid():
    data = json.loads(REFERENCE.read_text())
    assert data["columns"][:3] == ["x", "y", "z"] and data["columns"][-1] == "r_dot"
    rows = np.array(data["rows"])
    assert rows.shape == (400, 23)
    saturated = (np.abs(rows[:, 12:14]) > np.radians(15.0)).any(axis=1) | (
        np.abs(rows[:, 14]) > 1525.0
    )
    assert saturated.sum() > 100 and (rows[:, 15] > 0).sum() > 300  # limits and currents met
    worst = 0.0
    for row in rows:
        got = accelerations(REMUS6DOF, row[0:6], row[6:12], row[12:15], row[15], row[16])
        want = row[17:23]
        worst = max(worst, np.linalg.norm(got - want) / np.linalg.norm(want))
    assert worst <= 1e-9


def test_the_vehicle_matches_the_reference_spheroid():
    assert REMUS6DOF.mass_kg == pytest.approx(31.029384975800244, rel=1e-12)  # m of a spheroid
    assert REMUS6DOF.mass[0, 0] == pytest.approx(31.86829356913801, rel=1e-12)  # + X_udot
    np.testing.assert_array_equal(REMUS6DOF.mass, REMUS6DOF.mass.T)
    assert np.all(np.linalg.eigvalsh(REMUS6DOF.mass) > 0)


def test_unforced_undamped_motion_conserves_kinetic_energy():
    """With no forces, damping or restoring moments, M ν̇ = −C(ν)ν and C is skew-symmetric:
    ½ νᵀMν stays constant while the motion exchanges it between the axes."""
    v = REMUS6DOF
    minv = v.inverse_mass

    def f(nu):
        return -minv @ (coriolis_matrix(v, nu) @ nu)

    nu = np.array([1.5, 0.2, -0.1, 0.3, 0.2, -0.25])
    energy = 0.5 * nu @ v.mass @ nu
    dt, start = 1e-3, nu.copy()
    for _ in range(20_000):  # 20 s, RK4
        k1 = f(nu)
        k2 = f(nu + 0.5 * dt * k1)
        k3 = f(nu + 0.5 * dt * k2)
        k4 = f(nu + dt * k3)
        nu = nu + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    assert np.linalg.norm(nu - start) > 0.1  # the energy moved between the axes
    assert 0.5 * nu @ v.mass @ nu == pytest.approx(energy, rel=1e-9)
    for i in range(6):  # C(ν) is skew-symmetric at any ν
        probe = np.random.default_rng(i).normal(size=6)
        c = coriolis_matrix(v, probe)
        np.testing.assert_allclose(c, -c.T, atol=1e-12)


def test_a_neutral_vehicle_at_rest_stays_at_rest_and_rights_itself():
    eta, rest = np.zeros(6), np.zeros(6)
    np.testing.assert_allclose(accelerations(REMUS6DOF, eta, rest, np.zeros(3)), 0.0, atol=1e-15)
    rolled = np.array([0.0, 0.0, 0.0, 0.2, 0.0, 0.0])
    assert accelerations(REMUS6DOF, rolled, rest, np.zeros(3))[3] < 0  # z_g below: righting
    thrust = accelerations(REMUS6DOF, eta, rest, np.array([0.0, 0.0, 1000.0]))
    assert thrust[0] > 0 and thrust[3] != 0  # the propeller pushes and twists in roll
    no_torque = dataclasses.replace(REMUS6DOF, propeller_torque_scale=0.0)
    assert accelerations(no_torque, eta, rest, np.array([0.0, 0.0, 1000.0]))[3] == 0.0


def test_the_5dof_model_against_the_6dof_one_at_zero_roll():
    """docs/model.md §15: the same τ on both, φ = p = 0 (`benchmarks.analysis.plant_limit`)."""
    from auv_gym.vehicle.params import remus100
    from benchmarks.analysis.plant_limit import STATES, compare

    cruise = compare(STATES["cruise 1 m/s"])
    vehicle = remus100()
    drag = -vehicle.X_uu  # [kg/m] the paper's X_u|u| u|u| at u = 1 m/s, in N
    assert cruise["five_dof"][0] == pytest.approx((8.0 - drag) / vehicle.m11, rel=1e-12)
    assert cruise["roll"] == 0.0 and cruise["six_dof"][0] < cruise["five_dof"][0] / 3
    turning = compare(STATES["turning"])
    assert turning["roll"] > 0.05  # the roll the 5-DOF model drops
