"""Equations of motion (paper (1)–(2), docs/model.md §2.1): each group of terms vs hand values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from auv_gym.vehicle.dynamics import eta_dot, generalized_forces, nu_dot
from auv_gym.vehicle.params import DERIVED_INERTIAS, PARAM_INDEX, AUVParams, params_record, remus100

ZERO_TAU = (0.0, 0.0, 0.0)
ZERO_F = (0.0, 0.0, 0.0, 0.0, 0.0)
M_ZG = 30.48 * 0.0196  # m z_g [kg m]


def _forces(nu, theta=0.0, tau=ZERO_TAU, f=ZERO_F, params: AUVParams | None = None):
    p = params_record((params or remus100()).to_vector())
    return np.array(generalized_forces(nu, math.sin(theta), tau, f, p))


def test_actuation_and_disturbance_enter_their_rows_alone():
    forces = _forces((0.0,) * 5, tau=(10.0, 2.0, -3.0), f=(1.0, -2.0, 3.0, -0.5, 0.25))
    np.testing.assert_array_equal(forces, [11.0, -2.0, 3.0, 1.5, -2.75])


def test_restoring_moment_is_the_only_term_at_rest():
    """g: pitch −(z_g W − z_b B) sin θ = −5.8604 sin θ N·m; no force (B = W)."""
    forces = _forces((0.0,) * 5, theta=0.3)
    np.testing.assert_allclose(
        forces, [0.0, 0.0, 0.0, -0.0196 * 299.0 * math.sin(0.3), 0.0], rtol=1e-15, atol=0.0
    )
    lifted = _forces((0.0,) * 5, theta=0.3, params=remus100(z_b=-0.01))
    assert lifted[3] == pytest.approx(-(0.0196 * 299.0 + 0.01 * 299.0) * math.sin(0.3), rel=1e-15)


def test_damping_and_centripetal_terms_of_single_velocities():
    # u = 1 m/s: axial drag X_u|u| = −1.62 N only.
    np.testing.assert_allclose(_forces((1.0, 0.0, 0.0, 0.0, 0.0)), [-1.62, 0, 0, 0, 0], atol=1e-15)
    # q = 0.1 rad/s: X_qq q², m z_g q² (heave) and M_q|q| q|q|.
    np.testing.assert_allclose(
        _forces((0.0, 0.0, 0.0, 0.1, 0.0)),
        [-1.93 * 0.01, 0.0, M_ZG * 0.01, -188.0 * 0.01, 0.0],
        rtol=1e-14,
        atol=1e-15,
    )
    # w = −0.2 m/s: Z_w|w| w|w| (M_w|w| = 0 for REMUS).
    heave_only = [0.0, 0.0, 131.0 * 0.04, 0.0, 0.0]
    np.testing.assert_allclose(_forces((0.0, 0.0, -0.2, 0.0, 0.0)), heave_only, rtol=1e-14)


def test_coriolis_terms_and_their_switch():
    """v = 0.1 m/s, r = 0.2 rad/s: surge X_rr r² + (X_vr + m) v r, pitch −m z_g(w q − v r)."""
    nu = (0.0, 0.1, 0.0, 0.0, 0.2)
    expected = [
        -1.93 * 0.04 + (35.5 + 30.48) * 0.02,  # surge: centripetal + Coriolis
        -131.0 * 0.01,  # sway: Y_v|v| v|v| (the Coriolis term has u = 0)
        0.0,
        M_ZG * 0.02,  # pitch
        -3.18 * 0.01 - 94.0 * 0.04,
    ]  # yaw: N_v|v| v|v| + N_r|r| r|r|
    np.testing.assert_allclose(_forces(nu), expected, rtol=1e-13, atol=1e-15)
    without = _forces(nu, params=remus100(surge_coriolis=False))
    assert without[0] == pytest.approx(-1.93 * 0.04, rel=1e-14)
    np.testing.assert_array_equal(without[1:], _forces(nu)[1:])
    # u-proportional terms at u = 1.5 m/s, r = 0.2 rad/s, q = −0.1 rad/s:
    u, q, r = 1.5, -0.1, 0.2
    forces = _forces((u, 0.0, 0.0, q, r))
    m = 30.48
    assert forces[1] == pytest.approx(-(m - 5.22) * u * r, rel=1e-14)
    assert forces[2] == pytest.approx((m - 5.22) * u * q + M_ZG * q * q, rel=1e-14)
    assert forces[4] == pytest.approx(-2.0 * u * r - 94.0 * r * r, rel=1e-14)


def test_accelerations_are_the_rows_over_the_packed_inertias():
    params = remus100().perturbed(np.random.default_rng(4), 0.3)
    vector = params.to_vector()
    inertias = [params.m11, params.m22, params.m33, params.I55, params.I66]
    assert [vector[PARAM_INDEX[k]] for k in DERIVED_INERTIAS] == inertias
    nu, theta = (1.2, 0.1, -0.05, 0.02, -0.03), 0.1
    tau, f = (10.0, 1.0, -2.0), (0.5, -0.3, 0.2, 0.1, -0.1)
    forces = _forces(nu, theta, tau, f, params)
    accel = np.array(nu_dot(nu, theta, tau, f, params_record(vector)))
    np.testing.assert_array_equal(accel, forces / np.array(inertias))


def test_kinematics_at_level_heading_and_pitched():
    """Paper (2): at θ = ψ = 0 the body axes are the NED axes; ψ̇ = r/cosθ."""
    nu = (1.0, 0.2, -0.1, 0.05, 0.3)
    np.testing.assert_allclose(eta_dot(nu, 1.0, 0.0, 1.0, 0.0), [1.0, 0.2, -0.1, 0.05, 0.3])
    theta, psi = 0.4, 1.1
    ct, st, cp, sp = math.cos(theta), math.sin(theta), math.cos(psi), math.sin(psi)
    rotation = np.array([[cp * ct, -sp, cp * st], [sp * ct, cp, sp * st], [-st, 0.0, ct]])
    got = np.array(eta_dot(nu, ct, st, cp, sp))
    np.testing.assert_allclose(got[:3], rotation @ np.array(nu[:3]), rtol=1e-14)
    assert got[3] == 0.05
    assert got[4] == pytest.approx(0.3 / ct, rel=1e-15)


def test_heave_coriolis_sign_is_the_corrected_one():
    """docs/model.md §6 row 2: heave +(m + Z_uq) u q (NED rigid body), not the paper's printed
    −(m − Z_uq) u q. At u = 1 m/s, q = 0.1 rad/s (all else 0) a nose-up pitch rate pushes the
    body down its z_b axis: ẇ = ((m + Z_uq) u q + m z_g q²) / (m − Z_ẇ)
    = (25.26·0.1 + 0.005974) / 65.98 = +0.03837 m/s²; the printed sign would give −0.0540."""
    p = params_record(remus100().to_vector())
    w_dot = nu_dot((1.0, 0.0, 0.0, 0.1, 0.0), 0.0, ZERO_TAU, ZERO_F, p)[2]
    assert w_dot == pytest.approx(0.03837, abs=5e-6)
    expected = ((30.48 - 5.22) * 0.1 + M_ZG * 0.01) / (30.48 + 35.5)
    assert w_dot == pytest.approx(expected, rel=1e-14)
