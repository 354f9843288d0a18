"""Guidance against ocean currents (`controllers.alos`): observer, crab angles, ALOS, speed."""

from __future__ import annotations

import math

import numpy as np
import pytest

import controllers
from auv_gym.metrics import compute_metrics
from auv_gym.rollout import rollouts
from controllers.alos import crab_angles, path_tangent, speed_reference

COLOS = ["fbsm_colos", "backstepping_colos"]


def body_current(tr, mean):
    """R_Bᵀ v_c at the samples of a trajectory, R_B = Rz(ψ)Ry(θ) [m/s]."""
    psi, theta = tr["psi"], tr["theta"]
    cps, sps, cth, sth = np.cos(psi), np.sin(psi), np.cos(theta), np.sin(theta)
    a = cps * mean[0] + sps * mean[1]
    return np.column_stack(
        [cth * a - sth * mean[2], -sps * mean[0] + cps * mean[1], sth * a + cth * mean[2]]
    )


def test_crab_angles_reduce_to_the_papers_attack_angle_in_still_water():
    u, w, theta = 1.2, 0.07, 0.3
    beta, alpha = crab_angles(u, 0.0, w, theta)
    assert beta == 0.0
    assert alpha == pytest.approx(math.atan(w / u), abs=1e-15)
    # sideslip on a climbing vehicle: β_c = atan2(v, u cosθ + w sinθ), the 3-D sideslip
    beta, _ = crab_angles(u, 0.1, w, theta)
    assert beta == pytest.approx(math.atan2(0.1, u * math.cos(theta) + w * math.sin(theta)))


def test_speed_reference_gives_u_d_over_ground_along_the_path():
    t = path_tangent(0.2, 0.1, 0.3)
    assert np.linalg.norm(t) == pytest.approx(1.0, abs=1e-15)
    assert speed_reference(1.0, *t, 0.0, 0.0, 0.0) == 1.0  # still water: exactly u_D
    along = 0.3 * np.asarray(t)
    assert speed_reference(1.0, *t, *along) == pytest.approx(0.7, abs=1e-12)  # with the current
    # a strong following current: never slower through the water than |ĉ| + 0.2 u_D
    assert speed_reference(1.0, *t, *(2.0 * along)) == pytest.approx(0.8, abs=1e-12)
    across = 0.3 * np.array([-t[1], t[0], 0.0]) / math.hypot(t[0], t[1])
    assert speed_reference(1.0, *t, *across) == pytest.approx(math.hypot(1.0, 0.3), abs=1e-12)
    assert speed_reference(1.0, *t, *(-3.0 * np.asarray(t))) == 2.0  # limited to 2 u_D


def test_observer_estimates_the_current_in_body_axes_without_measuring_it():
    """Helix, constant current with a vertical component: ĉ converges to R_Bᵀ v_c although the
    controller sees only the observation (position errors, attitude, velocity through water)."""
    mean = (0.1, 0.25, 0.05)
    (tr,) = rollouts(
        controllers.make("backstepping_colos"),
        [0],
        path="helix",
        disturbance="none",
        current={"mean": mean},
        max_time=60.0,
    )
    estimate = tr["current_hat"]  # ĉ updated with the observation at sample k
    truth = body_current(tr, mean)[:-1]
    error = np.abs(estimate - truth).max(axis=1)
    assert error[0] > 0.2  # it starts from zero
    assert error[tr.t[:-1] >= 10.0].max() < 0.01  # measured 0.005 m/s while turning in
    assert error[tr.t[:-1] >= 30.0].max() < 1e-3  # measured 2e-4 m/s


@pytest.mark.parametrize("name", COLOS)
def test_straight_line_in_a_constant_current_errors_go_to_zero(name):
    """A descending line in a 0.3 m/s cross current with a 0.05 m/s vertical component: the
    paper's LOS keeps constant cross- and vertical-track offsets; the new guidance removes
    them (< 1 cm) and keeps the virtual point from lagging (speed over ground)."""
    env = {
        "path": {"kind": "line", "direction": [1.0, 0.0, 0.25]},
        "disturbance": "none",
        "current": {"mean": (0.0, 0.3, 0.05)},
        "max_time": 300.0,
    }
    base = name.split("_")[0]
    (plain,) = rollouts(controllers.make(base), [0], **env)
    (new,) = rollouts(controllers.make(name), [0], **env)
    late = new.t >= 200.0
    assert np.abs(plain["y_e"][late]).min() > 2.5  # measured 3.6 m
    assert np.abs(plain["z_e"][late]).min() > 0.05  # measured 0.1 m
    assert np.abs(new["y_e"][late]).max() < 0.01
    assert np.abs(new["z_e"][late]).max() < 0.01
    assert np.abs(new["x_e"][late]).max() < 0.01
    assert new.termination_reason == "time_limit"


@pytest.mark.parametrize(("name", "bound"), [("fbsm_colos", 0.08), ("backstepping_colos", 0.05)])
def test_helix_in_a_constant_current_settles_below_the_target(name, bound):
    """The helix turns the current through 360° in the path frame every 132 s; RMS distance
    over t ≥ 100 s stays below the issue's 0.10 m (ILOS: 0.56 m, paper's LOS: 2.3 m)."""
    (tr,) = rollouts(
        controllers.make(name), [0], disturbance="none", current={"mean": (0.0, 0.3, 0.0)}
    )
    metrics = compute_metrics(tr, transient=100.0)
    assert metrics["rms_distance"] < bound  # measured 0.053 (FBSM), 0.018 m (backstepping)
    assert metrics["max_distance_window"] < 0.25  # measured 0.12, 0.04 m
    assert metrics["success"]


@pytest.mark.parametrize("name", COLOS)
def test_without_current_the_adaptive_state_stays_near_zero(name):
    """No current: ĉ stays at the discretisation level, the trims small, u_ref = u_D, and the
    distance to the path follows the paper-faithful controller's, then undercuts its 0.017 m
    residual (the crab angle over ground includes the 3-D sideslip correction)."""
    env = {"disturbance": "none", "max_time": 150.0}
    base = name.split("_")[0]
    (paper,) = rollouts(controllers.make(base), [0], **env)
    (new,) = rollouts(controllers.make(name), [0], **env)
    assert np.abs(new["current_hat"]).max() < 0.01  # measured 0.003 (FBSM), 0.004 m/s
    assert np.abs(new["u_ref"] - 1.0).max() < 0.01
    if "beta_hat" in new.extras:  # backstepping: the last metre of the approach, then decays
        assert np.abs(new["beta_hat"]).max() < 0.1  # measured 0.04 rad
        assert np.abs(new["alpha_hat"]).max() < 0.01
    gap = np.abs(new["distance"] - paper["distance"])
    assert gap.max() < 0.4  # measured 0.17 m (FBSM), 0.28 m, during the turn-in
    assert gap[new.t >= 100.0].max() < 0.03  # the paper's residual, 0.017 m, against ≈ 0
    late = new.t >= 100.0
    assert np.abs(new["y_e"][late]).max() < np.abs(paper["y_e"][late]).max()


def test_the_capture_gate_keeps_alos_from_winding_up_on_the_approach():
    """Pure ALOS (Fossen & Aguiar 2024, no observer) from the paper's start 17.7 m away in still
    water: ungated, β̂ integrates the approach up to its projection bound and settling takes
    twice as long; gated to R = 1 m it only sees the last metre."""
    env = {"disturbance": "none", "max_time": 150.0}
    trims = {"alos_y": 0.01, "alos_z": 0.01}
    (gated,) = rollouts(controllers.make("backstepping", **trims, alos_radius=1.0), [0], **env)
    (ungated,) = rollouts(controllers.make("backstepping", **trims, alos_radius=1e6), [0], **env)
    assert np.abs(ungated["beta_hat"]).max() == pytest.approx(0.5)  # at the bound by t = 7 s
    assert np.abs(gated["beta_hat"]).max() < 0.1  # measured 0.048
    assert np.abs(gated["alpha_hat"]).max() < 0.01  # measured 0.005
    gated_settle = compute_metrics(gated)["settling_time_0p5"]
    assert gated_settle < 35.0  # measured 28.3 s (paper's backstepping: 29.7 s)
    assert compute_metrics(ungated)["settling_time_0p5"] > 2.0 * gated_settle  # measured 68.6 s


def test_alos_trims_respect_the_projection_bound():
    (tr,) = rollouts(
        controllers.make("backstepping", alos_y=1.0, alos_z=1.0, alos_radius=1e6, alos_max=0.05),
        [0],
        disturbance="none",
        current={"mean": (0.0, 0.3, 0.0)},
        max_time=60.0,
    )
    assert np.abs(tr["beta_hat"]).max() == pytest.approx(0.05)
    assert np.abs(tr["alpha_hat"]).max() <= 0.05
