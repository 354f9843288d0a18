"""The ocean preset (disturbance="ocean", docs/model.md §16) and the sea surface it places above
any path (surface_above_path, §13.8)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from auv_gym import AUVPath3DEnv
from auv_gym.ocean.depth_envelope import path_depth_range
from auv_gym.ocean.disturbances import NoiseConfig
from auv_gym.ocean.forcing import OCEAN
from auv_gym.ocean.preset import OCEAN_PRESET, SURFACE_ABOVE_PATH
from auv_gym.sim.config import SimConfig
from benchmarks.catalog.scenarios import load_scenarios


def test_the_preset_fills_every_part_left_at_none():
    config = SimConfig.from_kwargs(disturbance="ocean")
    assert config.noise == OCEAN_PRESET.noise
    assert config.noise.amplitude == (1.0, 1.0, 1.0, 0.3, 0.3) and config.noise.hold == 1.0
    assert config.current == OCEAN_PRESET.current
    assert config.random_current == 0.2 and config.param_uncertainty == 0.2
    assert config.waves == OCEAN_PRESET.waves and config.current_profile is not None
    assert config.surface_above_path == SURFACE_ABOVE_PATH


def _parts(config: SimConfig) -> tuple:
    """The ocean's parts of a config beside its noise."""
    return (
        config.current,
        config.random_current,
        config.param_uncertainty,
        config.waves,
        config.current_profile,
        config.surface_above_path,
    )


PRESET_PARTS = (
    OCEAN_PRESET.current,
    OCEAN_PRESET.random_current,
    OCEAN_PRESET.param_uncertainty,
    OCEAN_PRESET.waves,
    OCEAN_PRESET.current_profile,
    SURFACE_ABOVE_PATH,
)


def test_noise_hold_replaces_the_hold_of_the_ocean_noise_only():
    """Was: refused ("noise_hold cannot be given with disturbance='ocean'"), and the NoiseConfig
    it asked for dropped every other part: the ocean had no physics_dt but multiples of 1 s."""
    config = SimConfig.from_kwargs(
        disturbance="ocean", physics_dt=0.003, control_dt=0.03, noise_hold=0.999
    )
    assert config.noise == NoiseConfig((1.0, 1.0, 1.0, 0.3, 0.3), 0.999)
    assert _parts(config) == PRESET_PARTS


def test_a_disturbance_dict_replaces_the_ocean_noise_only():
    quiet = SimConfig.from_kwargs(disturbance={"preset": "ocean", "amplitude": 0.0})
    assert quiet.noise == NoiseConfig(0.0, 1.0) and _parts(quiet) == PRESET_PARTS
    held = SimConfig.from_kwargs(disturbance={"preset": "ocean", "hold": 0.5}, noise_hold=0.5)
    assert held.noise == NoiseConfig((1.0, 1.0, 1.0, 0.3, 0.3), 0.5)
    assert _parts(held) == PRESET_PARTS
    # without a preset, a dict is the paper's noise with its fields replaced, and no ocean
    paper = SimConfig.from_kwargs(disturbance={"hold": 0.02})
    assert paper.noise == NoiseConfig(35.0, 0.02) and paper.waves is None
    assert SimConfig.from_kwargs(disturbance={"preset": "ocean"}).noise == OCEAN_PRESET.noise


def test_false_switches_a_part_of_the_preset_off():
    """Was: waves=None still gave sea state 3 (None is "the preset's"), and nothing else could
    switch a part off."""
    assert SimConfig.from_kwargs(disturbance="ocean", waves=None).waves == OCEAN_PRESET.waves
    no_waves = SimConfig.from_kwargs(disturbance="ocean", waves=False)
    assert no_waves.waves is None
    assert _parts(no_waves)[:3] == PRESET_PARTS[:3] and _parts(no_waves)[4:] == PRESET_PARTS[4:]
    no_profile = SimConfig.from_kwargs(disturbance="ocean", current_profile=False)
    assert no_profile.current_profile is None and no_profile.waves == OCEAN_PRESET.waves
    # with neither, nothing reads a surface: none is placed
    calm = SimConfig.from_kwargs(disturbance="ocean", waves=False, current_profile=False)
    assert calm.surface_above_path is None and calm.noise == OCEAN_PRESET.noise
    with pytest.raises(ValueError, match=r"move the path at least \d+ m further down"):
        SimConfig.from_kwargs(disturbance="ocean", surface_above_path=False)  # surface z = 0
    deep = SimConfig.from_kwargs(
        disturbance="ocean", surface_above_path=False, path_offset=(0.0, 0.0, 120.0)
    )
    assert deep.surface_above_path is None and deep.waves == OCEAN_PRESET.waves
    assert SimConfig.from_kwargs(waves=False, current_profile=False).waves is None  # no preset


def test_the_preset_without_overrides_is_unchanged():
    """The noise hold given equal to the preset's, and every part given as the preset's, fly
    the preset's episode bit for bit."""
    runs = []
    for kwargs in (
        {},
        {"noise_hold": 1.0},
        {"disturbance": {"preset": "ocean", "amplitude": (1.0, 1.0, 1.0, 0.3, 0.3)}},
    ):
        env = AUVPath3DEnv(**{"disturbance": "ocean", **kwargs})
        env.reset(seed=4)
        runs.append([env.step(np.array([0.3, 0.1, -0.1], np.float32))[0] for _ in range(50)])
    np.testing.assert_array_equal(runs[0], runs[1])
    np.testing.assert_array_equal(runs[0], runs[2])


def test_explicit_arguments_replace_their_part_only():
    config = SimConfig.from_kwargs(
        disturbance="ocean", current=[0.0, 0.3, 0.0], random_current=0.0, param_uncertainty=0.0
    )
    assert config.current.mean == (0.0, 0.3, 0.0) and config.current.std == (0.0, 0.0, 0.0)
    assert config.random_current == 0.0 and config.param_uncertainty == 0.0
    assert config.waves == OCEAN_PRESET.waves  # the rest stays the preset's
    assert SimConfig.from_kwargs().param_uncertainty == 0.0  # None means 0 elsewhere


@pytest.mark.parametrize("path", ["helix", "line", "waypoints", "random"])
def test_any_path_gets_its_surface_ten_metres_above_its_shallowest_point(path):
    """The paper helix climbs 97 m from z = 0: the surface goes 10 m above its top, so its
    start is ~107 m deep and its end 10 m deep; the waves act there, not above the water."""
    env = AUVPath3DEnv(path=path, disturbance="ocean")
    env.reset(seed=2)
    sim = env.unwrapped.sim
    surface = sim.ocean[0, OCEAN.surface_z]
    path_now = sim.paths[0]
    tangent = float(np.linalg.norm(path_now.evaluate(0.0)[1]))
    top, _ = path_depth_range(path_now, 300.0 / tangent)
    assert surface == pytest.approx(min(top, sim.state[0, 2]) - 10.0)
    for _ in range(100):
        env.step(np.array([0.3, 0.0, 0.0], np.float32))
    assert sim.state[0, 2] - surface > 9.0  # below the surface, at the operating depth


def test_waves_at_the_operating_depth_move_the_vehicle():
    """Sea state 3 at 10 m depth (orbital speed ~0.15 m/s) against the same episode without
    waves: the tracks part by more than 5 cm within 30 s."""
    tracks = []
    for waves in (None, {"sea_state": 3, "significant_height": 1e-6}):
        env = AUVPath3DEnv(
            path={"kind": "helix", "climb": 0.0, "center": [10.0, 0.0, 0.0]},
            start_position=[15.0, 5.0, 0.0],
            disturbance="ocean",
            waves=waves,
            param_uncertainty=0.0,
        )
        env.reset(seed=0)
        for _ in range(600):
            env.step(np.array([0.3, 0.0, 0.0], np.float32))
        tracks.append(env.unwrapped.sim.state[0, :3].copy())
    assert np.linalg.norm(tracks[0] - tracks[1]) > 0.05


def test_with_a_depth_envelope_the_surface_is_z_zero():
    scenarios = load_scenarios()
    config = SimConfig.from_kwargs(**scenarios["as_built_survey"].env)
    assert config.surface_above_path is None
    env = AUVPath3DEnv(**scenarios["as_built_coastal"].env)
    env.reset(seed=0)
    assert env.unwrapped.sim.ocean[0, OCEAN.surface_z] == 0.0


def test_the_as_built_scenarios_are_built_as_described():
    scenarios = load_scenarios()
    for name in ("as_built_helix", "as_built_survey", "as_built_coastal"):
        config = SimConfig.from_kwargs(**scenarios[name].env)
        assert config.actuator == "realistic"
        assert config.sensors.navigation == "kalman" and config.sensors.fix_noise == 0.5
        assert config.noise == OCEAN_PRESET.noise and config.waves is not None
    coastal = SimConfig.from_kwargs(**scenarios["as_built_coastal"].env)
    assert coastal.current.mean == (0.0, 0.3, 0.0) and coastal.random_current == 0.0
    survey = SimConfig.from_kwargs(**scenarios["as_built_survey"].env)
    assert survey.current_profile.surface_speed == 0.4


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"disturbance": "oceanic"}, r"unknown disturbance 'oceanic'; valid: \['none', 'ocean'"),
        (  # the preset's noise is held 1 s: no whole number of 0.003-s steps
            {"disturbance": "ocean", "physics_dt": 0.003, "control_dt": 0.03},
            r"^noise hold = 1.0 s \(noise_hold, else the hold of the NoiseConfig or of "
            r"disturbance's preset: 0.01 s, 'ocean' 1 s\) must be a whole multiple of physics_dt "
            r"= 0.003 s: give noise_hold = 0.999 s, say \(with a NoiseConfig or a disturbance "
            r"dict: that hold\)$",
        ),
        (
            {"disturbance": {"preset": "ocean", "hold": 0.5}, "noise_hold": 0.6},
            r"^noise_hold = 0.6 s conflicts with disturbance = \{'preset': 'ocean', 'hold': 0.5\}",
        ),
        ({"disturbance": {"preset": "sea"}}, r"^unknown disturbance preset 'sea'; valid: \['none'"),
        (
            {"disturbance": {"preset": "ocean", "amp": 1.0}},
            r"^disturbance has unknown key\(s\) \['amp'\]; valid: \['amplitude', 'hold', "
            r"'preset'\]",
        ),
        ({"disturbance": {"amplitude": -1.0}}, r"^disturbance: NoiseConfig.amplitude must be"),
        (
            {"disturbance": "ocean", "depth_envelope": True, "surface_above_path": 5.0},
            r"surface_above_path places the sea surface",
        ),
        ({"surface_above_path": -1.0}, r"surface_above_path must be a finite number"),
        (  # was: accepted and ignored, nothing reads the surface
            {"surface_above_path": 10.0},
            r"^surface_above_path = 10 m places the sea surface for waves and a current "
            r"profile, and neither is on: give waves or current_profile, or leave "
            r"surface_above_path out$",
        ),
        ({"surface_above_path": math.nan}, r"surface_above_path must be a finite number"),
        (
            {"disturbance": "ocean", "depth_envelope": True},
            r"the path and the start reach z = -98.99 m .* move the path at least 101 m down",
        ),
    ],
)
def test_bad_ocean_arguments_raise_one_named_line(kwargs, message):
    with pytest.raises(ValueError, match=message):
        SimConfig.from_kwargs(**kwargs)


def test_a_scenario_asking_for_the_filter_without_sensors_is_refused_on_loading(tmp_path):
    path = tmp_path / "scenarios.toml"
    path.write_text('[bad]\nenv = { disturbance = "ocean", sensors = { navigation = "kalman" } }\n')
    with pytest.raises(ValueError, match=r"scenario 'bad'.*navigation = 'kalman' blends"):
        load_scenarios(path)


def test_a_surface_above_the_path_is_accepted_with_either_reader():
    profile = {"surface_speed": 0.2, "reference_depth": 50.0}
    config = SimConfig.from_kwargs(surface_above_path=10.0, current_profile=profile)
    assert config.surface_above_path == 10.0 and config.waves is None
    assert SimConfig.from_kwargs(surface_above_path=5.0, waves="sea_state_3").waves is not None
