"""The wave field: sea-state statistics of long records, depth decay, the kernel's use of it,
determinism, batched = single, and bad input (docs/model.md §13)."""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from auv_gym import AUVPath3DEnv
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.ocean.forcing import OCEAN, OCEAN_HEADER, ocean_row
from auv_gym.ocean.waves import (
    COMPONENT,
    COMPONENT_DIM,
    GRAVITY,
    MAX_STEEPNESS,
    SEA_STATES,
    WaveConfig,
    draw_components,
    peak_wavelength,
    surface_elevation,
    wave_kinematics,
)
from auv_gym.sim.config import SimConfig
from auv_gym.sim.simulator import Simulator

DEEP = {"path_offset": (0.0, 0.0, 110.0)}  # waves act below the surface: the helix moved down

RECORD_S, RECORD_DT = 7200.0, 0.5  # [s] two hours sampled at 2 Hz: ~800 peak periods


def _peak_period(z: np.ndarray, dt: float, period: float) -> float:
    """T_p [s] of a record: the peak of its periodogram smoothed by a Gaussian of 0.1/T_p Hz."""
    p = np.abs(np.fft.rfft(z)) ** 2 * dt / len(z)
    f = np.fft.rfftfreq(len(z), dt)
    width = 0.1 / period
    h = np.arange(-4 * width, 4 * width + f[1], f[1])
    kernel = np.exp(-0.5 * (h / width) ** 2)
    return 1.0 / f[np.argmax(np.convolve(p, kernel / kernel.sum(), mode="same"))]


def _record(config: WaveConfig, seed: int) -> np.ndarray:
    components = draw_components(config, np.random.default_rng(seed))
    return surface_elevation(components, 12.0, -7.0, np.arange(0.0, RECORD_S, RECORD_DT))


@pytest.mark.parametrize("sea_state", sorted(SEA_STATES))
def test_jonswap_records_have_the_configured_height_and_peak_period(sea_state):
    config = WaveConfig.from_spec(f"sea_state_{sea_state}")
    for seed in range(4):
        z = _record(config, seed)
        assert 4.0 * z.std() == pytest.approx(config.significant_height, rel=0.05)
        assert _peak_period(z, RECORD_DT, config.peak_period) == pytest.approx(
            config.peak_period, rel=0.05
        )


def test_pierson_moskowitz_records_have_the_configured_height_and_peak_period():
    # PM's peak is broad: a single 32-line record locates it to about ±6 % (docs/model.md
    # §13.2), so the peak period is checked on the mean of eight records.
    config = WaveConfig.from_spec({"sea_state": 4, "spectrum": "pierson_moskowitz"})
    periods = []
    for seed in range(8):
        z = _record(config, seed)
        assert 4.0 * z.std() == pytest.approx(config.significant_height, rel=0.05)
        periods.append(_peak_period(z, RECORD_DT, config.peak_period))
    assert np.mean(periods) == pytest.approx(config.peak_period, rel=0.05)


def test_components_obey_the_deep_water_dispersion_relation_and_carry_m0():
    config = WaveConfig(significant_height=2.0, peak_period=8.0, components=40)
    c = draw_components(config, np.random.default_rng(3))
    np.testing.assert_allclose(c[:, COMPONENT.k] * GRAVITY, c[:, COMPONENT.omega] ** 2)
    np.testing.assert_allclose(np.hypot(c[:, COMPONENT.kx], c[:, COMPONENT.ky]), c[:, COMPONENT.k])
    amplitude = c[:, COMPONENT.a_omega] / c[:, COMPONENT.omega]
    assert 4.0 * math.sqrt(np.sum(amplitude**2) / 2.0) == pytest.approx(2.0, rel=1e-12)
    omega_p = 2 * math.pi / 8.0
    assert np.all((c[:, COMPONENT.omega] >= 0.5 * omega_p) & (c[:, COMPONENT.omega] <= 3 * omega_p))


def test_long_crested_waves_travel_toward_the_mean_direction():
    config = WaveConfig(spreading=1000.0, direction=0.5)
    beta = np.arctan2(*draw_components(config, np.random.default_rng(0))[:, [1, 0]].T)
    np.testing.assert_allclose(beta, 0.5, atol=0.2)
    spread = WaveConfig(spreading=2.0, direction=0.5, components=400)
    beta = np.arctan2(*draw_components(spread, np.random.default_rng(0))[:, [1, 0]].T)
    assert 0.4 < np.std(beta - 0.5) < 1.0  # cos-2s with s = 2: σ ≈ 0.72 rad


def test_orbital_velocity_decays_as_exp_minus_k_depth_per_component():
    config = WaveConfig(components=16)
    components = draw_components(config, np.random.default_rng(7))
    depths = np.array([0.0, 1.0, 5.0, 10.0, 25.0, 60.0])
    for c in components:
        row = c.copy()
        speed = []
        for d in depths:
            vx, vy, vz, ax, ay, az, jx, jy, jz = wave_kinematics(row, 0, 1, 3.0, -4.0, d, 17.0)
            speed.append(math.sqrt(vx * vx + vy * vy + vz * vz))
            # the local acceleration is ω times the velocity, a quarter period ahead
            assert math.hypot(ax, ay, az) == pytest.approx(c[COMPONENT.omega] * speed[-1])
            np.testing.assert_allclose(
                (jx, jy, jz), -(c[COMPONENT.omega] ** 2) * np.array((vx, vy, vz))
            )
        expected = c[COMPONENT.a_omega] * np.exp(-c[COMPONENT.k] * depths)
        np.testing.assert_allclose(speed, expected, rtol=1e-12)
    # above the surface the field stays at its surface value
    assert wave_kinematics(components[0], 0, 1, 3.0, -4.0, -10.0, 17.0) == wave_kinematics(
        components[0], 0, 1, 3.0, -4.0, 0.0, 17.0
    )


def test_vertical_orbital_velocity_at_the_surface_is_the_elevation_rate():
    components = draw_components(WaveConfig(), np.random.default_rng(1))
    row = components.ravel()
    t, h = 40.0, 1e-4
    rate = (surface_elevation(components, 2.0, 3.0, np.array([t + h, t - h])) @ [1, -1]) / (2 * h)
    vz = wave_kinematics(row, 0, len(components), 2.0, 3.0, 0.0, t)[2]
    assert -vz == pytest.approx(rate, rel=1e-6)  # NED: v_z positive down


@pytest.mark.parametrize(("interval", "tolerance"), [(0.05, 4e-3), (0.01, 1e-3)])
def test_a_vehicle_at_rest_rides_the_orbital_motion(make_sim, interval, tolerance):
    # A neutral vehicle with no thrust and no noise moves with the water (docs/model.md §13.3):
    # its track is the integral of the orbital velocity along it, here by a fine Euler sum.
    # The kernel holds the field at the refresh position between refreshes (§13.3).
    waves = WaveConfig(update_interval=interval)
    sim = make_sim(disturbance="none", waves=waves, start_position=(0.0, 0.0, 3.0), **DEEP)
    row = sim.ocean[0]
    n = int(row[OCEAN.wave_components])
    p = sim.state[0, :3].copy()
    dt = 0.001
    for k in range(10_000):  # 10 s
        v = wave_kinematics(row, OCEAN_HEADER, n, p[0], p[1], p[2], (k + 0.5) * dt)
        p += dt * np.array(v[:3])
    for _ in range(200):
        sim.step(np.zeros((1, 3)))
    assert np.linalg.norm(p - [0.0, 0.0, 3.0]) > 0.4  # the excursion
    assert np.linalg.norm(p - sim.state[0, :3]) < tolerance
    np.testing.assert_allclose(sim.state[0, 5:10], 0.0, atol=1e-12)  # no relative motion


def test_ocean_rows_depend_on_the_seed_only():
    a, b = AUVPath3DEnv(waves="sea_state_4", **DEEP), AUVPath3DEnv(waves="sea_state_4", **DEEP)
    a.reset(seed=11)
    b.reset(seed=11)
    rows = a.sim.ocean.copy()
    assert np.array_equal(rows, b.sim.ocean)
    for _ in range(20):
        a.step(np.array([1.0, 0.5, -0.5], np.float32))
        b.step(np.array([0.0, -1.0, 1.0], np.float32))
    assert np.array_equal(a.sim.ocean, rows) and np.array_equal(b.sim.ocean, rows)
    b.reset(seed=12)
    assert not np.array_equal(b.sim.ocean, rows)


def test_same_seed_gives_identical_wavy_episodes():
    runs = []
    for _ in range(2):
        env = AUVPath3DEnv(waves={"sea_state": 5, "components": 8}, max_time=5.0, **DEEP)
        obs = [env.reset(seed=4)[0]]
        actions = np.random.default_rng(2).uniform(-1, 1, size=(100, 3)).astype(np.float32)
        obs += [env.step(a)[0] for a in actions]
        runs.append(np.array(obs))
    assert np.array_equal(*runs)


def test_batched_wavy_episodes_equal_single_envs_bit_for_bit(single_env_observations):
    kwargs = {
        **DEEP,
        "waves": {"sea_state": 4, "components": 8},
        "current_profile": {
            "surface_speed": 0.3,
            "reference_depth": 40.0,
            "drift_amplitude": 0.2,
            "drift_period": 300.0,
        },
        "start_position": (0.0, 0.0, 5.0),
        "max_time": 2.0,
    }
    n, steps = 3, 50  # 40 control steps per episode: every vehicle autoresets once
    venv = AUVPath3DVectorEnv(n, **kwargs)
    actions = np.random.default_rng(0).uniform(-0.5, 0.5, size=(steps, n, 3))
    batched = [venv.reset(seed=20)[0]] + [venv.step(a)[0] for a in actions]
    for i in range(n):
        single, _ = single_env_observations(kwargs, 20 + i, actions[:, i])
        assert np.array_equal(single, np.array(batched)[:, i])


def test_no_waves_no_profile_leaves_the_ocean_row_inactive():
    config = SimConfig.from_kwargs()
    row = ocean_row(config.waves, config.current_profile, np.array([1, 2], np.uint64), 0.01)
    assert row.shape == (OCEAN_HEADER,) and not row.any()
    wavy = ocean_row(WaveConfig(components=5), None, np.array([1, 2], np.uint64), 0.01)
    assert wavy.shape == (OCEAN_HEADER + 5 * COMPONENT_DIM,)
    assert wavy[OCEAN.active] == 1.0 and wavy[OCEAN.wave_every] == 5.0


@pytest.mark.parametrize(
    ("waves", "message"),
    [
        (
            {"significant_height": -1.0},
            r"waves significant_height must be a finite number in "
            r"\(0, 30\] m, got -1.0",
        ),
        ({"significant_height": math.nan}, "waves significant_height must be a finite number"),
        ({"peak_period": math.inf}, r"waves peak_period must be a finite number in \[1, 30\] s"),
        ({"peak_period": -8.0}, r"waves peak_period must be a finite number in \[1, 30\] s"),
        ({"spreading": -2.0}, r"waves spreading must be a finite number in \[0, 1000\], got -2"),
        ({"spreading": math.nan}, "waves spreading must be a finite number"),
        ({"components": 0}, r"waves components must be an integer in \[1, 1024\], got 0"),
        ({"components": -3}, r"waves components must be an integer in \[1, 1024\], got -3"),
        (
            {"spectrum": "bretschneider"},
            "unknown waves spectrum 'bretschneider'; valid: "
            r"\['jonswap', 'pierson_moskowitz'\]",
        ),
        ({"gamma": 0.5}, r"waves gamma must be a finite number in \[1, 7\]"),
        ({"update_interval": 0.0}, r"waves update_interval must be a finite number in \(0, 1\]"),
        ({"height": 2.0}, r"waves has unknown key\(s\) \['height'\]"),
        ("sea_state_9", r"unknown waves sea state 'sea_state_9'; valid: \['sea_state_3'"),
        (2.5, "waves must be None, a sea state"),
    ],
)
def test_bad_wave_arguments_name_the_argument(waves, message):
    with pytest.raises(ValueError, match=message):
        AUVPath3DEnv(waves=waves, **DEEP)


@settings(deadline=None, derandomize=True, database=None, max_examples=60)
@given(
    height=st.floats(0.01, 30.0),
    period=st.floats(1.0, 30.0),  # seas steeper than the breaking limit are refused (below)
    spectrum=st.sampled_from(["jonswap", "pierson_moskowitz"]),
    components=st.integers(1, 200),
    spreading=st.floats(0.0, 1000.0),
    seed=st.integers(0, 2**32 - 1),
)
def test_every_valid_sea_carries_its_energy_in_its_band(
    height, period, spectrum, components, spreading, seed
):
    assume(height / peak_wavelength(period) <= MAX_STEEPNESS)
    config = WaveConfig(
        significant_height=height,
        peak_period=period,
        spectrum=spectrum,
        components=components,
        spreading=spreading,
    )
    c = draw_components(config, np.random.default_rng(seed))
    amplitude = c[:, COMPONENT.a_omega] / c[:, COMPONENT.omega]
    assert 4.0 * math.sqrt(np.sum(amplitude**2) / 2.0) == pytest.approx(height, rel=1e-9)
    omega_p = 2 * math.pi / period
    assert np.all(c[:, COMPONENT.omega] >= 0.5 * omega_p * (1 - 1e-12))
    assert np.all(c[:, COMPONENT.omega] <= 3.0 * omega_p * (1 + 1e-12))
    np.testing.assert_allclose(np.hypot(c[:, COMPONENT.cos_beta], c[:, COMPONENT.sin_beta]), 1.0)
    # the orbital speed anywhere is bounded by the sum of the component speeds
    v = wave_kinematics(c.ravel(), 0, components, 5.0, 9.0, 0.0, 123.0)
    assert math.hypot(*v[:3]) <= np.sum(c[:, COMPONENT.a_omega]) * (1 + 1e-12)


@pytest.mark.integration  # compiles the threaded kernel with waves (about 70 s on 2 cores)
def test_threaded_kernel_equals_the_serial_one_with_waves():
    config = SimConfig.from_kwargs(
        waves={"sea_state": 5, "components": 6},
        current_profile={"surface_speed": 0.3, "reference_depth": 20.0},
        start_position=(15.0, 5.0, 6.0),
        **DEEP,
    )
    runs = []
    for parallel in (False, True):
        sim = Simulator(config, 4, parallel=parallel)
        sim.reset_rows(range(4), [np.random.default_rng(s) for s in range(4)])
        actions = np.random.default_rng(9).uniform(-1, 1, size=(30, 4, 3))
        for a in actions:
            sim.step(a)
        runs.append(sim.state.copy())
    assert np.array_equal(*runs)


@pytest.mark.integration
def test_wave_depth_benchmark_runs_with_a_tiny_budget(tmp_path):
    out = tmp_path / "depth.json"
    root = Path(__file__).resolve().parents[1]
    subprocess.run(
        [
            sys.executable,
            "-m",
            "benchmarks.reports.wave_depth",
            "--depths",
            "3",
            "--seeds",
            "2",
            "--max-time",
            "4",
            "--json",
            str(out),
            "--figure",
            str(tmp_path / "depth.png"),
        ],
        cwd=root,
        check=True,
        capture_output=True,
        text=True,
    )
    rows = json.loads(out.read_text())
    assert [(r["depth"], r["waves"]) for r in rows] == [(3.0, "sea_state_4"), (3.0, None)]
    assert all(r["episodes"] == 2 and r["low"] <= r["rms_distance"] <= r["high"] for r in rows)
    assert rows[0]["rms_distance"] != rows[1]["rms_distance"]  # the waves moved the vehicle
    assert (tmp_path / "depth.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_snapshots_carry_the_sea_and_older_snapshots_had_a_flat_one():
    actions = np.random.default_rng(1).uniform(-0.5, 0.5, size=(60, 2, 3))
    venv = AUVPath3DVectorEnv(2, waves={"components": 4}, max_time=1.0, **DEEP)  # redraws
    venv.reset(seed=3)
    for a in actions[:30]:
        venv.step(a)
    snapshot = venv.snapshot()
    first = [venv.step(a)[0] for a in actions[30:]]
    venv.restore(snapshot)
    assert np.array_equal(first, [venv.step(a)[0] for a in actions[30:]])
    flat = Simulator(SimConfig.from_kwargs(), 2)
    old = flat.snapshot()
    del old["arrays"]["ocean"]  # written before the ocean rows existed
    flat.ocean[:] = 1.0
    flat.restore(old)
    assert not flat.ocean.any()


def test_only_a_non_neutral_vehicle_feels_the_fluid_acceleration():
    # (ρ∇ − m) R_Bᵀ a with ρ∇ = m B/W (docs/model.md §13.3): zero for the neutral REMUS 100
    from auv_gym.ocean.forcing import NO_WAVE, ocean_forcing
    from auv_gym.vehicle.params import params_record, remus100

    row = ocean_row(WaveConfig(components=3), None, np.array([5, 6], np.uint64), 0.01)
    wave = (*NO_WAVE[:3], 0.1, -0.2, 0.3, *NO_WAVE[6:])  # a = (0.1, −0.2, 0.3) m/s², t₀ = 0
    st = np.zeros(11)
    st[3], st[4] = 0.2, 1.0  # θ, ψ [rad]
    f = (1.0, 2.0, 3.0, 4.0, 5.0)
    neutral = params_record(remus100().to_vector())
    assert ocean_forcing(row, st, 0.0, wave, (0.0, 0.0, 0.0), f, neutral)[1] == f
    nominal = remus100()
    light = params_record(dataclasses.replace(nominal, B=1.1 * nominal.W).to_vector())
    got = np.array(ocean_forcing(row, st, 0.0, wave, (0.0, 0.0, 0.0), f, light)[1]) - f
    c, s = math.cos, math.sin
    rotation = np.array(
        [
            [c(1.0) * c(0.2), s(1.0) * c(0.2), -s(0.2)],
            [-s(1.0), c(1.0), 0.0],
            [c(1.0) * s(0.2), s(1.0) * s(0.2), c(0.2)],
        ]
    )  # R_Bᵀ, roll 0
    expected = 0.1 * nominal.m * rotation @ [0.1, -0.2, 0.3]
    np.testing.assert_allclose(got, [*expected, 0.0, 0.0], rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"waves": "sea_state_4"}, r"waves act below the sea surface .* reach z = -98\.99 m"),
        (
            {"current_profile": {"surface_speed": 0.3, "reference_depth": 20.0}},
            r"current_profile act below the sea",
        ),
        ({"path": "random", "waves": 3}, r"a drawn path .*path_offset = \[0, 0, 106\]"),
        (
            {"waves": {"significant_height": 30.0, "peak_period": 1.0}, **DEEP},
            r"135× the breaking steepness H/L = 1/7 .* peak_period ≥ 11\.6 s",
        ),
        (
            {"actuator_params": {"rpm_max": 1000.0}},
            r"actuator_params configure .* they would do nothing",
        ),
    ],
)
def test_ocean_options_are_checked_as_physics_at_construction(kwargs, message):
    """Was: waves over the default helix (above the sea) applied surface orbital velocities all
    episode (FBSM 0.93 m instead of 0.066 m); a 30-m sea with a 1-s period was accepted; the
    propeller settings were ignored on the paper's actuator."""
    with pytest.raises(ValueError, match=message):
        AUVPath3DEnv(**kwargs)


def test_the_same_sea_over_a_path_below_the_surface_is_accepted():
    env = AUVPath3DEnv(waves="sea_state_4", **DEEP)
    env.reset(seed=0)
    assert env.sim.config.waves is not None


@pytest.mark.parametrize(
    ("waves", "message"),
    [
        (
            {"sea_state": 4, "spectrum": "pierson_moskowitz", "gamma": 7.0},
            "waves gamma = 7.0 does nothing with spectrum 'pierson_moskowitz' (γ is JONSWAP's "
            "peak enhancement): leave gamma out or give spectrum 'jonswap'",
        ),
        (
            {"spectrum": "pierson_moskowitz", "gamma": 3.3},  # given, even at the default
            "waves gamma = 3.3 does nothing with spectrum 'pierson_moskowitz' (γ is JONSWAP's "
            "peak enhancement): leave gamma out or give spectrum 'jonswap'",
        ),
        (
            {"sea_state": 4.0},  # as waves=4.0 is: a sea state's code is an integer
            "waves sea_state must be a sea state ['sea_state_3', 'sea_state_4', 'sea_state_5'] "
            "or its integer code [3, 4, 5], got 4.0 (float)",
        ),
        (
            {"sea_state": True},
            "waves sea_state must be a sea state ['sea_state_3', 'sea_state_4', 'sea_state_5'] "
            "or its integer code [3, 4, 5], got True (bool)",
        ),
    ],
)
def test_wave_settings_that_do_nothing_or_are_no_sea_state_are_refused(waves, message):
    """Was: gamma was ignored by the Pierson–Moskowitz spectrum; sea_state 4.0 was taken as 4
    in a dict while waves=4.0 was refused."""
    with pytest.raises(ValueError) as caught:
        WaveConfig.from_spec(waves)
    assert str(caught.value) == message
    if waves.get("gamma", 3.3) != 3.3:  # built directly: a gamma other than the default
        with pytest.raises(ValueError) as caught:
            WaveConfig(spectrum="pierson_moskowitz", gamma=waves["gamma"])
        assert str(caught.value) == message


def test_a_sea_state_is_an_integer_code_everywhere_and_its_fields_replace_it():
    with pytest.raises(TypeError, match="waves must be None, a sea state"):
        WaveConfig.from_spec(4.0)
    assert WaveConfig.from_spec(np.int64(4)) == WaveConfig.from_spec({"sea_state": np.int64(4)})
    assert WaveConfig.from_spec(4) == WaveConfig()
    # documented precedence (docs/model.md §13.2): a height or period given replaces the state's
    low = WaveConfig.from_spec({"sea_state": 3, "significant_height": 0.1})
    assert (low.significant_height, low.peak_period) == (0.1, SEA_STATES[3][1])
    pm = WaveConfig.from_spec({"sea_state": 4, "spectrum": "pierson_moskowitz"})
    assert pm.gamma == 3.3  # the default stays, unread
