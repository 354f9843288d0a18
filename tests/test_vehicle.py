"""Vehicle model: parameters, open-loop physics (docs/model.md §8 check 2), RK4 order, batching."""

from __future__ import annotations

import math

import numpy as np
import pytest

from auv_gym.paths import Helix
from auv_gym.sim.config import ACTUATOR_LIMITS
from auv_gym.sim.integrator import rk4_step
from auv_gym.vehicle.dynamics import STATE_DIM
from auv_gym.vehicle.params import HYDRODYNAMIC_FIELDS, AUVParams, remus100


def test_derived_inertias_match_model_md():
    p = remus100()
    np.testing.assert_allclose(
        [p.m11, p.m22, p.m33, p.I55, p.I66], [31.41, 65.98, 65.98, 8.33, 8.33], atol=1e-9
    )


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("m", -1.0, "m must be positive"),
        ("I_y", 0.0, "I_y must be positive"),
        ("X_uu", float("nan"), "X_uu must be a finite"),
        ("I_z", float("inf"), "I_z must be a finite"),
        ("X_udot", 40.0, "m11"),
        ("X_uu", 5.0, r"X_uu must be ≤ 0 \(a drag that opposes the motion\), got 5.0"),
        ("N_rr", 0.1, r"N_rr must be ≤ 0"),
    ],
)
def test_impossible_parameters_raise(field, value, match):
    with pytest.raises(ValueError, match=match):
        AUVParams(**{field: value})


def test_params_are_frozen():
    with pytest.raises(AttributeError):
        remus100().m = 1.0  # type: ignore[misc]


def test_perturbed_scales_only_hydrodynamic_coefficients_within_bounds():
    nominal = remus100()
    perturbed = nominal.perturbed(np.random.default_rng(3), 0.3)
    for name in ("m", "W", "B", "I_y", "I_z", "fin_moment_coeff"):
        assert getattr(perturbed, name) == getattr(nominal, name)
    ratios = [
        getattr(perturbed, k) / getattr(nominal, k)
        for k in HYDRODYNAMIC_FIELDS
        if getattr(nominal, k) != 0.0
    ]
    assert all(0.7 <= r <= 1.3 for r in ratios)
    assert np.std(ratios) > 0.05  # each coefficient draws its own δ
    same = nominal.perturbed(np.random.default_rng(3), 0.3)
    assert same == perturbed
    with pytest.raises(ValueError, match="epsilon"):
        nominal.perturbed(np.random.default_rng(0), 1.5)


def test_open_loop_surge_reaches_trim_speed(make_sim):
    """Check 2a: X = 1.62 N from rest gives u → 1.00 ± 0.01 m/s in 150 s; v, w, q, r stay 0."""
    sim = make_sim(disturbance="none")
    action = np.array([[1.62 / ACTUATOR_LIMITS[0], 0.0, 0.0]])
    for _ in range(3000):  # 150 s at 0.05 s
        sim.step(action)
    assert abs(sim.state[0, 5] - 1.0) < 0.01
    assert np.all(np.abs(sim.state[0, 6:10]) < 1e-9)


def test_open_loop_pitch_is_restored(make_sim):
    """Check 2b: θ(0) = 10°, no input: successive |θ| peaks do not grow and stay below 10.5°."""
    sim = make_sim(disturbance="none")
    sim.state[0, 3] = math.radians(10.0)
    theta = np.empty(1200)
    for k in range(theta.size):
        sim.step(np.zeros((1, 3)))
        theta[k] = sim.state[0, 3]
    deg = np.degrees(np.abs(theta))
    assert deg.max() < 10.5
    peaks = deg[1:-1][(deg[1:-1] > deg[:-2]) & (deg[1:-1] >= deg[2:])]
    assert len(peaks) >= 3
    assert np.all(np.diff(peaks) <= 1e-9)


def _integrate(dt: float, t_end: float = 2.0) -> np.ndarray:
    path = Helix()
    # The |v|v-type terms have a kink at 0 that caps any integrator's order when a velocity
    # changes sign; zero them so the measured order is the integrator's own.
    p = remus100(Y_vv=0.0, Z_ww=0.0, M_qq=0.0, N_rr=0.0, N_vv=0.0).to_vector()
    st = np.array([15.0, 5.0, 0.0, 0.05, 0.3, 0.8, 0.05, -0.03, 0.02, 0.1, 1.0])
    out = np.empty(STATE_DIM)
    f = np.array([3.0, -2.0, 1.0, 0.5, -0.5])
    for _ in range(round(t_end / dt)):
        rk4_step(
            st, (20.0, 2.0, -3.0), f, (0.1, -0.2, 0.0), p, path.kind, path.data, 1.0, 0.5, dt, out
        )
        st = out.copy()
    return st


def test_rk4_is_fourth_order():
    reference = _integrate(0.00125)
    errors = [np.abs(_integrate(dt) - reference).max() for dt in (0.08, 0.04, 0.02)]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 3.7), orders
    assert np.all(orders < 4.3), orders


def test_batched_equals_stacked_single_rows(make_sim):
    kwargs = dict(
        disturbance="paper",
        param_uncertainty=0.2,
        current={"mean": (0.1, 0.2, 0.0), "std": (0.05, 0.05, 0.0)},
    )
    batch = make_sim(n=5, seed=10, **kwargs)
    singles = [make_sim(n=1, seed=10 + i, **kwargs) for i in range(5)]
    actions = np.random.default_rng(0).uniform(-1, 1, size=(200, 5, 3))
    actions[..., 0] = np.abs(actions[..., 0])
    for a in actions:
        batch.step(a)
        for i, sim in enumerate(singles):
            sim.step(a[i : i + 1])
    for i, sim in enumerate(singles):
        np.testing.assert_array_equal(batch.state[i], sim.state[0])
        np.testing.assert_array_equal(batch.obs[i], sim.obs[0])
        np.testing.assert_array_equal(batch.reward[i], sim.reward[0])


def test_actuator_limits_come_from_the_vehicle_record():
    from auv_gym.envs.env import AUVPath3DEnv
    from auv_gym.sim.config import SimConfig
    from controllers.base import actuator_vector

    assert remus100().actuator_limits == ACTUATOR_LIMITS == (50.0, 10.0, 10.0)
    assert SimConfig().params.actuator_limits == ACTUATOR_LIMITS
    strong = AUVParams(X_max=60.0, N_max=12.0)
    assert actuator_vector("paper", strong)[2:] == (60.0, 10.0, 12.0)  # the controllers' limits
    env = AUVPath3DEnv(params={"X_max": 60.0, "N_max": 12.0}, disturbance="none")
    assert env.config.params.actuator_limits == (60.0, 10.0, 12.0)
    env.reset(seed=0)
    *_, info = env.step(np.array([1.0, 0.0, -1.0]))  # full surge and yaw: the plant's limits
    assert info["tau"][0] == 60.0 and info["tau"][2] == -12.0
    with pytest.raises(ValueError, match=r"^AUVParams.M_max must be positive, got 0.0$"):
        AUVParams(M_max=0.0)
    with pytest.raises(TypeError, match=r"unexpected keyword argument 'actuator_limits'$"):
        SimConfig(params=strong, actuator_limits=(60.0, 10.0, 12.0))  # removed: params only
