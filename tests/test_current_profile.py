"""The depth-profiled current with heading drift (docs/model.md §13.5)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from auv_gym import AUVPath3DEnv
from auv_gym.ocean.current_profile import CurrentProfile, profile_velocity
from auv_gym.ocean.forcing import OCEAN


def _speed(profile: CurrentProfile, depth: float) -> float:
    p = profile
    vx, vy, vz = profile_velocity(
        p.surface_speed,
        p.reference_speed,
        p.reference_depth,
        p.exponent,
        p.direction,
        0.0,
        1.0,
        0.0,
        depth,
        0.0,
    )
    assert vz == 0.0
    return math.hypot(vx, vy)


def test_linear_shear_layer_and_power_law_speeds():
    shear = CurrentProfile(
        surface_speed=0.6, reference_depth=40.0, reference_speed=0.2, exponent=1.0
    )
    speeds = [_speed(shear, d) for d in (-5.0, 0.0, 10.0, 20.0, 40.0, 100.0)]
    np.testing.assert_allclose(speeds, [0.6, 0.6, 0.5, 0.4, 0.2, 0.2], rtol=1e-12)
    power = CurrentProfile(surface_speed=1.0, reference_depth=30.0)  # 1/7 law, zero at the bed
    expected = [1.0, 0.5 ** (1 / 7), (1 / 30) ** (1 / 7), 0.0]
    speeds = [_speed(power, d) for d in (0.0, 15.0, 29.0, 30.0)]
    np.testing.assert_allclose(speeds, expected, rtol=1e-12)


def test_heading_drift_turns_the_current_sinusoidally():
    args = (0.5, 0.5, 10.0, 1.0, 0.3, 0.2, 2 * math.pi / 100.0, 1.0)
    for t in (0.0, 10.0, 37.5):
        vx, vy, _ = profile_velocity(*args, 5.0, t)
        chi = 0.3 + 0.2 * math.sin(2 * math.pi * t / 100.0 + 1.0)
        assert math.atan2(vy, vx) == pytest.approx(chi, abs=1e-12)
        assert math.hypot(vx, vy) == pytest.approx(0.5, rel=1e-12)


def test_a_vehicle_at_rest_drifts_with_the_current_at_its_depth(make_sim):
    profile = {
        "surface_speed": 0.5,
        "reference_depth": 40.0,
        "reference_speed": 0.1,
        "exponent": 1.0,
        "direction": math.pi / 2,
    }
    sim = make_sim(
        disturbance="none",
        current_profile=profile,
        current=(0.1, 0.0, 0.0),
        start_position=(0.0, 0.0, 10.0),
        path_offset=(0.0, 0.0, 110.0),  # a current profile acts below the surface
    )
    p0 = sim.state[0, :3].copy()
    for _ in range(200):  # 10 s
        sim.step(np.zeros((1, 3)))
    # U(10 m) = 0.1 + 0.4·0.75 = 0.4 m/s toward y, on top of the uniform 0.1 m/s toward x
    np.testing.assert_allclose(sim.state[0, :3] - p0, [1.0, 4.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(sim.state[0, 5:10], 0.0, atol=1e-12)


def test_the_drift_phase_is_drawn_per_episode_and_the_track_follows_it(make_sim):
    profile = {
        "surface_speed": 0.5,
        "reference_depth": 40.0,
        "drift_amplitude": 1.0,
        "drift_period": 20.0,
    }
    sims = [
        make_sim(
            seed=s,
            disturbance="none",
            current_profile=profile,
            start_position=(0.0, 0.0, 0.0),
            path_offset=(0.0, 0.0, 110.0),
        )
        for s in (0, 1)
    ]
    phases = [s.ocean[0, OCEAN.drift_phase] for s in sims]
    assert phases[0] != phases[1]
    sim, phase = sims[0], phases[0]
    for _ in range(200):  # 10 s, half a drift period
        sim.step(np.zeros((1, 3)))
    t = (np.arange(1000) + 0.5) * 0.01  # the kernel's mid-step times
    chi = np.sin(2 * math.pi * t / 20.0 + phase)
    expected = 0.5 * 0.01 * np.array([np.cos(chi).sum(), np.sin(chi).sum()])
    np.testing.assert_allclose(sim.state[0, :2], expected, atol=1e-9)


@pytest.mark.parametrize(
    ("profile", "message"),
    [
        (
            {"surface_speed": -0.1, "reference_depth": 10.0},
            r"current_profile surface_speed must be a finite number in \[0, 10\] m/s, got -0.1",
        ),
        (
            {"surface_speed": 0.5, "reference_depth": 0.0},
            r"current_profile reference_depth must be a finite number in \(0, 11000\] m, got 0.0",
        ),
        (
            {"surface_speed": 0.5, "reference_depth": math.inf},
            "current_profile reference_depth must be a finite number",
        ),
        (
            {"surface_speed": 0.5, "reference_depth": 10.0, "reference_speed": 20.0},
            r"current_profile reference_speed must be a finite number in \[0, 10\] m/s",
        ),
        (
            {"surface_speed": 0.5, "reference_depth": 10.0, "exponent": 0.0},
            r"current_profile exponent must be a finite number in \(0, 10\], got 0.0",
        ),
        (
            {"surface_speed": 0.5, "reference_depth": 10.0, "drift_amplitude": 4.0},
            r"current_profile drift_amplitude must be a finite number in \[0, 3.14159\] rad",
        ),
        (
            {"surface_speed": 0.5, "reference_depth": 10.0, "drift_period": -1.0},
            r"current_profile drift_period must be a finite number in \(0, 1e\+06\] s",
        ),
        ({"surface_speed": 0.5}, "current_profile needs reference_depth"),
        (
            {"surface_speed": 0.5, "reference_depth": 10.0, "depth": 3.0},
            r"current_profile has unknown key\(s\) \['depth'\]",
        ),
        ("shear", "current_profile must be None, a dict of CurrentProfile fields"),
    ],
)
def test_bad_profile_arguments_name_the_argument(profile, message):
    with pytest.raises(ValueError, match=message):
        AUVPath3DEnv(current_profile=profile, path_offset=(0.0, 0.0, 110.0))


@pytest.mark.parametrize(
    ("profile", "message"),
    [
        (
            {"surface_speed": 0.3, "reference_depth": 50.0, "drift_period": 5.0},
            "current_profile drift_period = 5.0 s does nothing without a heading drift "
            "(drift_amplitude = 0): give a drift_amplitude > 0 or leave drift_period out",
        ),
        (
            {"surface_speed": 0.3, "reference_depth": 50.0, "drift_period": 3600.0},
            "current_profile drift_period = 3600.0 s does nothing without a heading drift "
            "(drift_amplitude = 0): give a drift_amplitude > 0 or leave drift_period out",
        ),
        (
            {
                "surface_speed": 0.3,
                "reference_depth": 50.0,
                "drift_amplitude": 0.2,
                "drift_period": 1e-9,
            },
            "current_profile drift_period = 1e-09 s is below 1 s: the kernels sample the drift "
            "once per physics step (up to 0.1 s), too seldom for a faster turn",
        ),
    ],
)
def test_a_drift_period_without_drift_or_too_short_to_sample_is_refused(profile, message):
    """Was: accepted; without an amplitude the period does nothing, and 1e-9 s aliased."""
    with pytest.raises(ValueError) as caught:
        CurrentProfile.from_spec(profile)
    assert str(caught.value) == message
    if profile["drift_period"] != 3600.0:  # built directly: a period other than the default
        with pytest.raises(ValueError) as caught:
            CurrentProfile(**profile)
        assert str(caught.value) == message


def test_the_drift_period_floor_samples_every_accepted_physics_step_ten_times():
    from auv_gym.ocean.current_profile import MIN_DRIFT_PERIOD
    from auv_gym.sim.config import PHYSICS_DT_RANGE

    assert MIN_DRIFT_PERIOD >= 10 * PHYSICS_DT_RANGE[1]
    drift = {"surface_speed": 0.3, "reference_depth": 50.0, "drift_amplitude": 0.2}
    assert CurrentProfile.from_spec({**drift, "drift_period": 1.0}).drift_period == 1.0


def test_a_gauss_markov_time_constant_without_its_std_is_refused():
    """Was: current={"time_constant": 5} accepted with std 0, where τ does nothing."""
    from auv_gym.ocean.disturbances import CurrentConfig

    with pytest.raises(ValueError) as caught:
        CurrentConfig.from_spec({"time_constant": 5})
    assert str(caught.value) == (
        "current time_constant = 5 s does nothing without a Gauss–Markov current (std = 0 on "
        "every axis): give a std > 0 or leave time_constant out"
    )
    # the default τ stays accepted (tests/test_mirror.py gives it with std 0), so does any τ
    # with a std
    assert CurrentConfig.from_spec({"std": [0, 0, 0], "time_constant": 60.0}) == CurrentConfig()
    assert CurrentConfig.from_spec({"std": [0, 0, 0.01], "time_constant": 5}).time_constant == 5
