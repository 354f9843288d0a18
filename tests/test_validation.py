"""Issue 11: every argument checked at the boundary, episode length = max_time, observations.

One regression test per bad input found by the fuzz and bad-input campaign (the issue's list and
the ones found since); the property-based suite is tests/test_properties.py.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import auv_gym  # noqa: F401  (registers the ids)
from auv_gym import AUVPath3DEnv
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.ocean.disturbances import CurrentConfig, NoiseConfig
from auv_gym.paths import Helix, Spline, StraightLine
from auv_gym.sim.config import SimConfig
from auv_gym.sim.integrator import CONFIG_FIELDS
from auv_gym.sim.observation import OBS_HIGH, OBS_INDEX, OBS_LOW
from auv_gym.sim.task import REWARD_TERMS, TERMINATION_REASONS, RewardWeights, TaskLimits, task_row
from auv_gym.support.validation import ArgumentTypeError, choice, flag, integer, real, vector
from auv_gym.vehicle import AUVParams

STILL = np.zeros(3, np.float32)


def steps_until_truncated(env, limit: int) -> int:
    env.reset(seed=0)
    for k in range(1, limit + 1):
        _, _, terminated, truncated, _ = env.step(STILL)
        assert not terminated
        if truncated:
            return k
    return -1


# ------------------------------------------------------------------ episode length (item 2)
def test_gym_make_truncates_at_max_time_for_a_short_control_period():
    """Was: control_dt=0.01 truncated by the registered TimeLimit after 6000 steps, at 60 s."""
    env = gym.make("AUVPath3D-v0", control_dt=0.01, disturbance="none", max_time=61.0)
    assert env.spec.max_episode_steps == 6100
    assert steps_until_truncated(env, 6200) == 6100  # 61 s, not 60 s


def test_gym_make_truncates_at_a_long_max_time():
    """Was: max_time=600 cut at 300 s (6000 steps) by the registered TimeLimit."""
    env = gym.make("AUVPath3D-v0", max_time=600.0, disturbance="none")
    assert env.spec.max_episode_steps == 12000
    assert steps_until_truncated(env, 12100) == 12000


def test_make_vec_truncates_at_max_time_and_its_spec_says_so():
    env = gym.make_vec(
        "AUVPath3D-v0", num_envs=2, control_dt=0.01, max_time=60.5, disturbance="none"
    )
    assert env.spec.max_episode_steps == 6050
    env.reset(seed=0)
    ends = [env.step(np.zeros((2, 3)))[3].copy() for _ in range(6060)]
    assert np.flatnonzero(np.asarray(ends)[:, 0]).tolist() == [6049]  # step 6050; reset after


def test_the_registration_has_no_time_limit_and_the_default_is_6000_steps():
    assert gym.spec("AUVPath3D-v0").max_episode_steps is None
    env = gym.make("AUVPath3D-v0")
    assert not isinstance(env, gym.wrappers.TimeLimit)
    assert env.spec.max_episode_steps == env.unwrapped.config.max_steps == 6000
    assert AUVPath3DEnv().spec is None  # built directly: no spec, as before
    assert gym.make_vec("AUVPath3D-v0", num_envs=2).spec.max_episode_steps == 6000
    # A user's TimeLimit still applies on top, and the outer spec names it.
    short = gym.make("AUVPath3D-v0", max_episode_steps=7, disturbance="none")
    assert short.spec.max_episode_steps == 7
    assert steps_until_truncated(short, 10) == 7


def test_truncation_coincident_with_termination_reports_both():
    """The env truncates at max_time whether or not that step terminates, as TimeLimit did."""
    env = AUVPath3DEnv(max_time=0.1, disturbance="none")
    env.reset(seed=0)
    env.step(STILL)
    env.sim.state[0, 3] = 1.2  # pitch beyond 60°: the second (last) step terminates
    _, _, terminated, truncated, info = env.step(STILL)
    assert terminated and truncated and info["termination_reason"] == "pitch"


@pytest.mark.parametrize(
    ("control_dt", "max_time", "steps"),
    [(0.05, 1.0, 20), (0.03, 1.0, 34), (0.1, 0.1, 1), (0.07, 0.5, 8)],
)
def test_truncation_is_the_first_step_at_or_after_max_time(control_dt, max_time, steps):
    env = AUVPath3DEnv(control_dt=control_dt, max_time=max_time, disturbance="none")
    assert env.config.max_steps == steps == math.ceil(max_time / control_dt - 1e-9)
    assert steps_until_truncated(env, steps + 2) == steps


# -------------------------------------------------------------- timing arguments (item 1)
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"control_dt": 1e20}, r"control_dt .*\(0, 100\] s"),  # substeps overflowed int64
        ({"physics_dt": 1e-300}, r"physics_dt .*\[1e-06, 0.1\] s.*1e-300"),
        ({"physics_dt": 1e-12}, r"physics_dt .*1e-12"),  # one step() ran for minutes
        ({"physics_dt": 1e-5, "control_dt": 0.10001}, r"control_dt .*10000 physics steps"),
        ({"max_time": 1e300}, r"max_time .*1e\+06"),
        ({"max_time": 1e-300}, r"max_time .*at least one control_dt"),
        ({"max_time": True}, r"max_time must be a real number"),
        ({"noise_hold": 0.02, "disturbance": NoiseConfig(hold=0.03)}, r"noise_hold .*conflicts"),
    ],
)
def test_timing_arguments_out_of_range_raise(kwargs, match):
    with pytest.raises(ValueError, match=match):
        SimConfig.from_kwargs(**kwargs)


def test_substeps_are_bounded_at_ten_thousand():
    assert SimConfig.from_kwargs(physics_dt=1e-5, control_dt=0.1, max_time=0.1).substeps == 10_000
    with pytest.raises(ValueError, match="10000 physics steps"):
        SimConfig.from_kwargs(physics_dt=1e-5, control_dt=0.10001, max_time=1.0)


@pytest.mark.parametrize("physics_dt", [0.02, 0.03, 0.1])
def test_physics_dt_over_the_documented_range_needs_no_noise_hold_without_noise(physics_dt):
    """Was: "noise hold (noise_hold, a NoiseConfig's hold or 0.01) = 0.01 s must be a whole
    multiple of physics_dt" for every physics_dt above 0.01 s, even with no noise to hold."""
    for disturbance in ("none", 0.0, NoiseConfig(0.0)):
        config = SimConfig.from_kwargs(
            disturbance=disturbance, physics_dt=physics_dt, control_dt=physics_dt
        )
        assert config.packed()[list(CONFIG_FIELDS).index("hold_steps")] == 1.0
    env = AUVPath3DEnv(disturbance="none", physics_dt=physics_dt, control_dt=physics_dt)
    env.reset(seed=0)
    for _ in range(5):
        _, _, terminated, _, info = env.step(STILL)
        assert not terminated and not np.any(info["disturbance"])


@pytest.mark.parametrize("disturbance", ["none", 0.0])
def test_a_hold_or_an_amplitude_draw_without_noise_is_refused(disturbance):
    """Was: accepted and ignored (random_noise still took a task draw per episode)."""
    with pytest.raises(ValueError) as caught:
        SimConfig.from_kwargs(disturbance=disturbance, noise_hold=0.5)
    assert str(caught.value) == (
        f"noise_hold = 0.5 s would hold nothing: disturbance = {disturbance!r} has no noise "
        "(every amplitude 0); drop it or give the noise an amplitude"
    )
    with pytest.raises(ValueError, match=r"^random_noise = 0.5 scales the noise's amplitude"):
        SimConfig.from_kwargs(disturbance=disturbance, random_noise=0.5)
    assert SimConfig.from_kwargs(disturbance="paper", noise_hold=0.5, random_noise=0.5)


def test_a_noise_hold_off_the_physics_step_names_one_to_give():
    with pytest.raises(ValueError) as caught:
        SimConfig.from_kwargs(physics_dt=0.02, control_dt=0.04)
    assert str(caught.value) == (
        "noise hold = 0.01 s (noise_hold, else the hold of the NoiseConfig or of disturbance's "
        "preset: 0.01 s, 'ocean' 1 s) must be a whole multiple of physics_dt = 0.02 s: give "
        "noise_hold = 0.02 s, say (with a NoiseConfig or a disturbance dict: that hold)"
    )
    assert SimConfig.from_kwargs(physics_dt=0.02, control_dt=0.04, noise_hold=0.02).substeps == 2


def test_noise_config_hold_is_honoured_not_overridden():
    """Was: NoiseConfig(hold=0.02) silently replaced by the noise_hold default 0.01 s."""
    config = SimConfig.from_kwargs(disturbance=NoiseConfig(hold=0.02))
    assert config.noise.hold == 0.02
    assert SimConfig.from_kwargs(disturbance=NoiseConfig(hold=0.02), noise_hold=0.02).noise.hold
    with pytest.raises(ValueError, match=r"noise_hold = 0.01 s conflicts .*hold=0.02"):
        SimConfig.from_kwargs(disturbance=NoiseConfig(hold=0.02), noise_hold=0.01)
    assert SimConfig.from_kwargs(noise_hold=0.05).noise.hold == 0.05
    assert SimConfig.from_kwargs().noise.hold == 0.01
    env = AUVPath3DEnv(control_dt=0.01, disturbance=NoiseConfig(hold=0.02))
    env.reset(seed=1)
    f = np.array([env.step(STILL)[4]["disturbance"] for _ in range(40)])
    assert np.all(f[0::2] == f[1::2])  # held for two control periods of 0.01 s


# ------------------------------------------------------------- observation range (item 3)
def test_nan_start_heading_is_refused():
    """Was: start_heading=nan gave a NaN observation on reset."""
    for heading in (math.nan, math.inf, 1e300, 7.0):
        with pytest.raises(ValueError, match=r"start_heading .*\[-6.28319, 6.28319\] rad"):
            AUVPath3DEnv(start_heading=heading)
    obs, _ = AUVPath3DEnv(start_heading=-2 * math.pi).reset(seed=0)
    assert np.all(np.isfinite(obs))


def test_u_desired_is_bounded_by_the_observation_envelope():
    """Was: u_desired above the bound accepted, and every episode ended on step 1."""
    with pytest.raises(ValueError, match=r"u_desired .*\(0, 10\] m/s.*got 10.5"):
        AUVPath3DEnv(u_desired=10.5)
    env = AUVPath3DEnv(u_desired=10.0, path="line")
    obs, _ = env.reset(seed=0)
    assert obs[OBS_INDEX["u_D"]] == 10.0 and env.observation_space.contains(obs)
    _, _, terminated, _, _ = env.step(STILL)
    assert not terminated


def test_far_start_position_is_refused_at_construction():
    """Was: reset returned x_e = 9970 m, outside observation_space."""
    with pytest.raises(ValueError, match=r"start_position .*9970 m from the path's start"):
        AUVPath3DEnv(start_position=(1e4, 0.0, 0.0))
    # 500 m is observable, but not with the ±2 m random offsets on top.
    edge = (30.0 + 499.0, 0.0, -8.0)
    assert AUVPath3DEnv(start_position=edge, corridor=500.0).observation_space.contains(
        AUVPath3DEnv(start_position=edge, corridor=500.0).reset(seed=0)[0]
    )
    with pytest.raises(ValueError, match="randomize_start"):
        AUVPath3DEnv(start_position=edge, randomize_start=True)


@pytest.mark.parametrize(
    "path",
    [
        Helix(radius=0.01, omega=100.0),  # a tiny, fast-turning helix
        Spline([(0, 0, 0), (0.01, 0.0, 0.0), (0.01, 0.01, 0.0), (0.0, 0.01, 0.01)]),
    ],
)
def test_tiny_paths_that_turn_beyond_the_observation_are_refused(path):
    """Was: with randomize_start, reset returned psi_F_dot outside observation_space."""
    with pytest.raises(ValueError, match=r"path turns at up to .* rad/s, beyond the observation"):
        AUVPath3DEnv(path=path, randomize_start=True)


def test_a_turn_rate_check_that_fits_u_desired_accepts_the_path():
    path = Helix(radius=0.5, omega=1.0, climb=0.2)  # 1.86 rad/m
    with pytest.raises(ValueError, match=r"use u_desired <= 2.69"):
        AUVPath3DEnv(path=path, u_desired=3.0)
    env = AUVPath3DEnv(path=path, u_desired=2.6, randomize_start=True, start_position=(1, 0, 0))
    for seed in range(20):
        assert env.observation_space.contains(env.reset(seed=seed)[0])


def test_reset_outside_the_space_raises_naming_the_component():
    env = AUVPath3DEnv()
    env.sim._pdata[0, 3] = 1e4  # the helix centre moved behind the configuration's back
    with pytest.raises(ValueError, match=r"reset gave x_e = -10005 m \(vehicle 0\), outside"):
        env.reset(seed=0)
    venv = AUVPath3DVectorEnv(3)
    venv.sim._pdata[0, 3] = 1e4
    with pytest.raises(ValueError, match=r"reset gave x_e = -10005 m \(vehicle 0\)"):
        venv.reset(seed=0)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -1e39])
def test_a_non_finite_observation_of_a_finite_state_is_non_finite(bad):
    """Was: a NaN observation with a finite state (absurd path scales) did not end the episode,
    the envelope test being false for NaN; now `task_row` reports "non_finite", with the
    termination penalty as the only (finite) reward term."""
    env = AUVPath3DEnv()
    env.reset(seed=0)
    sim = env.sim
    obs = sim.obs[0].copy()
    obs[OBS_INDEX["psi_F_dot"]] = bad  # the state stays finite
    terms = np.zeros(len(REWARD_TERMS))
    reward, code = task_row(
        sim.state[0], sim.guid[0], obs, np.zeros(3), OBS_LOW, OBS_HIGH, sim._task[0], terms
    )
    assert TERMINATION_REASONS[code] == "non_finite"
    assert reward == -100.0 and terms.tolist() == [0] * (len(REWARD_TERMS) - 1) + [-100.0]
    obs[OBS_INDEX["psi_F_dot"]] = 9.0  # inside: the same call runs on
    assert (
        task_row(
            sim.state[0], sim.guid[0], obs, np.zeros(3), OBS_LOW, OBS_HIGH, sim._task[0], terms
        )[1]
        == 0
    )


def test_an_observation_beyond_float32_ends_the_episode_as_non_finite():
    for n in (1, 3):
        env = AUVPath3DVectorEnv(n, autoreset_mode="SameStep") if n > 1 else AUVPath3DEnv()
        env.reset(seed=0)
        zeros = np.zeros((n, 3)) if n > 1 else STILL
        last = env.step(zeros)[0]
        env.sim.state[0, 0] = 1e200  # finite in float64, inf in float32
        obs, reward, terminated, _, info = env.step(zeros)
        if n > 1:
            assert terminated.tolist() == [True, False, False]
            assert info["final_info"]["termination_reason"][0] == "non_finite"
            np.testing.assert_array_equal(info["final_obs"][0], last[0])
            assert np.all(np.isfinite(obs)) and np.all(np.isfinite(reward))
        else:
            assert terminated and info["termination_reason"] == "non_finite"
            np.testing.assert_array_equal(obs, last)
            assert math.isfinite(reward)


def test_rewards_stay_finite_at_the_extremes_of_the_ranges():
    env = AUVPath3DEnv(
        corridor=0.01, reward_weights=dict.fromkeys(RewardWeights().__dict__, 1e6), u_desired=1e-9
    )
    env.reset(seed=0)
    env.sim.state[0, 0:3] = 3e38  # the largest errors that are still float32-finite
    _, reward, terminated, *_ = env.step(STILL)
    assert terminated and math.isfinite(reward)


# ------------------------------------------------------------ types and coercion (item 1)
BAD_TYPES = [
    ("path", ["helix"]),
    ("path", {"kind"}),
    ("path", 3),
    ("disturbance", [1, 2, 3, 4, 5]),
    ("disturbance", True),
    ("disturbance", 1j),
    ("current", "0.3"),
    ("current", 0.3),
    ("current", {"mean": "abc"}),
    ("param_uncertainty", "0.1"),
    ("actuator", ["paper"]),
    ("actuator", 0),
    ("control_dt", "0.05"),
    ("control_dt", None),
    ("control_dt", [0.05]),
    ("physics_dt", "0.01"),
    ("noise_hold", "0.01"),
    ("max_time", True),
    ("max_time", "300"),
    ("randomize_start", "False"),
    ("randomize_start", 0),
    ("randomize_start", None),
    ("u_desired", "1"),
    ("u_desired", 1 + 0j),
    ("sigma", b"0.5"),
    ("virtual_point_law", ["corrected"]),
    ("corridor", "30"),
    ("max_pitch", "1.0"),
    ("reward_weights", 5),
    ("reward_weights", [1.0]),
    ("reward_weights", {"progress": "1"}),
    ("params", ["m", 30.0]),
    ("params", "remus100"),
    ("start_position", "abc"),
    ("start_position", (1, 2, "3")),
    ("start_position", 5.0),
    ("start_heading", "0.5"),
    ("start_heading", [0.5]),
]


@pytest.mark.parametrize(("name", "value"), BAD_TYPES, ids=lambda v: repr(v)[:20])
def test_wrong_types_raise_a_type_error_naming_the_argument(name, value):
    """Was, e.g.: actuator=['paper'] → "unhashable type: 'list'", reward_weights=5 → "astuple()
    should be called on dataclass instances"; randomize_start="False" became True."""
    with pytest.raises(TypeError) as caught:
        AUVPath3DEnv(**{name: value})
    assert isinstance(caught.value, ValueError)  # also caught by `except ValueError`
    message = str(caught.value)
    key = {"reward_weights": "reward"}.get(name, name)
    assert key in message, message


BAD_VALUES = [
    ("disturbance", -5.0),
    ("disturbance", math.nan),
    ("disturbance", 1e5),
    ("current", (0.1, 0.2)),
    ("current", (20.0, 0.0, 0.0)),
    ("current", {"std": (-1, 0, 0)}),
    ("current", {"time_constant": 0.0}),
    ("current", {"speed": 1.0}),
    ("param_uncertainty", 1.0),
    ("param_uncertainty", -0.1),
    ("param_uncertainty", math.nan),
    ("actuator", "jets"),
    ("control_dt", 0.0),
    ("control_dt", -0.05),
    ("control_dt", math.inf),
    ("control_dt", 0.015),
    ("physics_dt", 0.0),
    ("physics_dt", 0.5),
    ("noise_hold", 0.005),
    ("noise_hold", -0.01),
    ("max_time", math.nan),
    ("max_time", 0.0),
    ("u_desired", 0.0),
    ("u_desired", -1.0),
    ("sigma", 0.0),
    ("sigma", math.inf),
    ("virtual_point_law", "other"),
    ("corridor", 0.0),
    ("corridor", 0.001),
    ("corridor", 501.0),
    ("max_pitch", math.pi / 2),
    ("max_pitch", 0.0),
    ("reward_weights", {"speed": -1.0}),
    ("reward_weights", {"x": 1.0}),
    ("reward_weights", {"termination": math.inf}),
    ("reward_weights", {"effort": 1e7}),
    ("start_position", (0.0, 0.0)),
    ("start_position", (math.nan, 0.0, 0.0)),
    ("start_position", (1e7, 0.0, 0.0)),
    ("start_heading", -7.0),
    ("max_time", 10**400),
]


@pytest.mark.parametrize(("name", "value"), BAD_VALUES, ids=lambda v: repr(v)[:20])
def test_out_of_range_values_raise_a_value_error_naming_argument_and_range(name, value):
    with pytest.raises(ValueError) as caught:
        AUVPath3DEnv(**{name: value})
    message = str(caught.value)
    key = {"reward_weights": "reward"}.get(name, name)
    assert key in message or (name == "noise_hold" and "noise hold" in message), message


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (lambda: NoiseConfig(hold=0.0), r"NoiseConfig.hold .*\(0, 1e\+06\] s"),
        (lambda: NoiseConfig(amplitude="35"), r"NoiseConfig.amplitude"),
        (lambda: NoiseConfig(amplitude=(1, 2)), r"NoiseConfig.amplitude must be 5 real"),
        (lambda: CurrentConfig(mean=(0, 0, math.inf)), r"current mean"),
        (lambda: CurrentConfig(time_constant="60"), r"current time_constant"),
        (lambda: RewardWeights(progress=True), r"reward weight progress"),
        (lambda: TaskLimits(s_end=0.0), r"s_end"),
        (lambda: TaskLimits(max_pitch=2.0), "max_pitch"),
        (lambda: Helix(radius=1e300), r"Helix radius .*\(0, 100000\] m"),
        (lambda: Helix(omega=1e300), r"Helix omega"),
        (lambda: Helix(center="abc"), "Helix center"),
        (lambda: Helix(radius=1e-300, omega=1e-300, climb=0.0), r"\|p'\(s\)\|"),
        (lambda: Helix(s_end="10"), "Helix s_end"),
        (lambda: Helix(s_end=-1.0), "Helix s_end"),
        (lambda: StraightLine(start=(1e300, 0, 0)), "StraightLine start"),
        (lambda: StraightLine(direction=(1e-300, 0, 0)), "StraightLine: direction"),
        (lambda: StraightLine(length=math.nan), "StraightLine length"),
        (lambda: Spline("abc"), "Spline waypoints"),
        (lambda: Spline([[0, 0, 0], [1, 1]]), "Spline"),
        (lambda: Spline(np.zeros((1001, 3)) + np.arange(1001)[:, None]), "1000"),
        (lambda: Spline([(0, 0, 0), (1e300, 0, 0)]), "Spline"),
        (lambda: AUVParams(m=True), r"AUVParams.m "),
        (lambda: AUVParams(X_uu="1"), "AUVParams.X_uu"),
        (lambda: AUVParams(surge_coriolis="yes"), "AUVParams.surge_coriolis"),
        (lambda: AUVParams(fin_max=4.0), "AUVParams.fin_max"),
        (lambda: AUVParams(X_uu=10**400), "AUVParams.X_uu"),
    ],
)
def test_dataclasses_and_paths_check_their_fields(build, match):
    with pytest.raises(ValueError, match=match):
        build()


def test_accepted_numbers_are_canonical_floats():
    config = SimConfig.from_kwargs(
        max_time=300,
        control_dt=np.float64(0.05),
        u_desired=np.int64(1),
        start_position=np.array([15, 5, 0]),
        start_heading=0,
    )
    assert type(config.max_time) is float and config.max_time == 300.0
    assert type(config.u_desired) is float and config.start_position == (15.0, 5.0, 0.0)
    assert type(config.start_heading) is float
    assert config.randomize_start is False
    assert SimConfig.from_kwargs(randomize_start=np.bool_(True)).randomize_start is True


# ---------------------------------------------------------------------- actions and reset
@pytest.mark.parametrize(
    "action",
    [
        ["0.1", "0", "0"],
        np.array([0.1 + 1j, 0, 0]),
        [True, False, True],
        [None, 0, 0],
        np.array(["a", "b", "c"]),
        [0.1, [0], 0],
    ],
)
def test_non_numeric_actions_raise_type_error(action):
    """Was: strings and complex numbers were converted and stepped."""
    env = AUVPath3DEnv()
    env.reset(seed=0)
    before = env.state
    with pytest.raises(TypeError, match="action must be an array of real numbers"):
        env.step(action)
    np.testing.assert_array_equal(env.state, before)
    venv = AUVPath3DVectorEnv(2)
    venv.reset(seed=0)
    with pytest.raises(TypeError, match="action"):
        venv.step(np.array([action, action], dtype=object))


def test_integer_and_float32_actions_are_accepted_unchanged():
    a, b = AUVPath3DEnv(), AUVPath3DEnv()
    a.reset(seed=3)
    b.reset(seed=3)
    out_a = a.step(np.array([1, 0, -1], dtype=np.int32))
    out_b = b.step(np.array([1.0, 0.0, -1.0]))
    np.testing.assert_array_equal(out_a[0], out_b[0])


def test_reset_options_and_seeds_are_checked():
    env = AUVPath3DEnv()
    env.reset(seed=0, options={})  # SB3's DummyVecEnv passes an empty dict
    with pytest.raises(ValueError, match=r"takes no options, got \['foo'\]"):
        env.reset(options={"foo": 1})
    with pytest.raises(TypeError, match="options must be None or a dict"):
        env.reset(options=["reset_mask"])
    venv = AUVPath3DVectorEnv(2)
    venv.reset(seed=0, options={})
    with pytest.raises(ValueError, match=r"unknown reset option\(s\) \['mask'\]"):
        venv.reset(options={"mask": np.ones(2, bool)})
    for seed, match in (
        (1.5, "seed must be"),
        ("1", "seed must be"),
        (True, "seed must be"),
        (-1, "seed must be an integer"),
        ([0, "1"], r"seed\[1\]"),
        ([0, -2], r"seed\[1\]"),
        ([0, 1.0], r"seed\[1\]"),
    ):
        with pytest.raises(ValueError, match=match):
            venv.reset(seed=seed)
    venv.reset(seed=[3, None])
    venv.reset(seed=np.int64(4))


def test_vector_env_integer_arguments_name_themselves():
    for kwargs, match in (
        ({"num_envs": 2**70}, r"num_envs .*16777216"),
        ({"max_episode_steps": 1.5}, "max_episode_steps"),
        ({"threads": "2"}, "threads"),
        ({"num_envs": "4"}, "num_envs"),
    ):
        with pytest.raises(ValueError, match=match):
            AUVPath3DVectorEnv(**kwargs)
    env = AUVPath3DVectorEnv(2, max_episode_steps=10**30, max_time=0.5, disturbance="none")
    env.reset(seed=0)
    ends = [env.step(np.zeros((2, 3)))[3][0] for _ in range(10)]
    assert ends.index(True) == 9  # max_time's 10 steps, no overflow from the huge limit


# -------------------------------------------------------------------------- the checkers
def test_checkers_name_argument_value_and_range():
    assert real("x", 3, 0, 5) == 3.0
    with pytest.raises(ValueError, match=r"x must be a finite number in \(0, 5\) m, got 5"):
        real("x", 5, 0, 5, low_open=True, high_open=True, unit="m")
    with pytest.raises(ArgumentTypeError, match=r"x must be a real number in \[0, ∞\), got True"):
        real("x", True, 0)
    assert integer("n", np.int32(4), 1) == 4
    with pytest.raises(ArgumentTypeError, match=r"n must be an integer in \[1, ∞\], got 2.0"):
        integer("n", 2.0, 1)
    assert flag("f", np.False_) is False
    with pytest.raises(ArgumentTypeError, match="f must be True or False, got 'True'"):
        flag("f", "True")
    assert choice("c", "a", ["a", "b"]) == "a"
    with pytest.raises(ValueError, match=r"unknown c 'z'; valid: \['a', 'b'\]"):
        choice("c", "z", ["a", "b"])
    assert vector("v", np.array([1, 2, 3]), 3) == (1.0, 2.0, 3.0)
    with pytest.raises(ValueError, match=r"v must be 3 real numbers in \[0, 1\]"):
        vector("v", [0.5, 0.5, 2.0], 3, 0.0, 1.0)
    with pytest.raises(ArgumentTypeError, match="v must be 3 real numbers"):
        vector("v", np.zeros((3, 1)), 3)


def test_observation_bounds_are_what_the_ranges_assume():
    """The ranges above are derived from these bounds; a change there must revisit them."""
    assert OBS_HIGH[OBS_INDEX["x_e"]] == 500.0 and OBS_HIGH[OBS_INDEX["u_D"]] == 10.0
    assert OBS_HIGH[OBS_INDEX["u_p"]] == 20.0 and OBS_LOW[OBS_INDEX["u_p"]] == 0.0
    assert OBS_HIGH[OBS_INDEX["psi_F_dot"]] == 10.0


# ------------------------------------------------- the same checks in evaluation (item 1)
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"control_dt": 1e20}, "control_dt"),
        ({"start_heading": math.nan}, "start_heading"),
        ({"randomize_start": "False"}, "randomize_start"),
        ({"u_desired": 10.5}, "u_desired"),
        ({"actuator": ["paper"]}, "actuator"),
        ({"reward_weights": 5}, "reward"),
    ],
)
def test_rollouts_and_evaluate_refuse_what_the_env_refuses(kwargs, match):
    """The evaluation entry points build their `SimConfig` through the same validation layer."""
    from auv_gym.rollout import evaluate, rollouts

    class Idle:
        def predict(self, observation, state=None, episode_start=None, deterministic=True):
            return np.zeros((len(observation), 3), np.float32), state

    for run in (rollouts, evaluate):
        with pytest.raises(ValueError, match=match):
            run(Idle(), [0], max_time=0.1, **kwargs)


# --------------------------------------------- issue 55 item 5: the edges of the newest options
def _hull(**changes):
    from auv_gym.vehicle.remus6dof import REMUS6DOF

    return {**REMUS6DOF.record(), **changes}


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        (  # was: a bare ZeroDivisionError (the spheroid's eccentricity rounded to 1)
            {"diameter": 1e-10},
            r"^SixDofVehicle.diameter = 1e-10 m must be at least length/1000 = 0.0016 m",
        ),
        ({"length": 1e200}, r"^SixDofVehicle.length must be a finite number in \[0.01, 1000\] m"),
        ({"water_density": 1e300}, r"^SixDofVehicle.water_density must be a finite number in"),
    ],
)
def test_a_hull_of_unphysical_size_is_one_line(changes, message):
    with pytest.raises(ValueError, match=message):
        AUVPath3DEnv(plant="6dof", plant_params=_hull(**changes))


@pytest.mark.parametrize(
    ("changes", "physics_dt", "message"),
    [
        (  # was: every episode "non_finite" at step 1
            {"roll_damping_ratio": 100.0},
            0.01,
            r"^plant_params roll_damping_ratio = 100 must be at most 19.3: its roll mode moves at "
            r"1293 rad/s, faster than the 250 rad/s that RK4 at physics_dt = 0.01 s can step "
            r"\(\|λ\|·dt <= 2.5\); or use physics_dt <= 0.00193 s$",
        ),
        ({"yaw_time_constant": 1e-6}, 0.01, r"yaw_time_constant = 1e-06 must be at least 0.004 s"),
        (
            {"surge_time_constant": 1e-6},
            0.01,
            r"surge_time_constant = 1e-06 must be at least 0.00401",
        ),
        ({"pitch_damping_ratio": 100.0}, 0.1, r"pitch_damping_ratio = 100 must be at most 13.8"),
    ],
)
def test_a_hull_rk4_cannot_step_is_refused_with_its_bound(changes, physics_dt, message):
    with pytest.raises(ValueError, match=message):
        AUVPath3DEnv(plant="6dof", plant_params=_hull(**changes), physics_dt=physics_dt)


def test_a_stiff_hull_runs_at_the_bound_and_with_a_shorter_step():
    """The bound is RK4's: at it (19.3) and with the step the message names, episodes stay
    finite; the REMUS 100 hull passes at the default physics_dt with any uncertainty, and at
    the largest (0.1 s) up to ±90 % (its yaw time constant 1 s × 0.04 is RK4's limit there)."""
    from auv_gym.vehicle.remus6dof import REMUS6DOF

    for changes, physics_dt in (
        ({"roll_damping_ratio": 19.3}, 0.01),
        ({"yaw_time_constant": 0.004}, 0.01),
        ({"roll_damping_ratio": 100.0}, 0.001),
    ):
        env = AUVPath3DEnv(
            plant="6dof", plant_params=_hull(**changes), physics_dt=physics_dt, max_time=2.0
        )
        env.reset(seed=0)
        for _ in range(40):
            _, _, terminated, truncated, info = env.step(np.full(3, 0.5, np.float32))
            assert not terminated, info.get("termination_reason")
        assert truncated
    for uncertainty in (0.0, 0.5, 0.9):
        REMUS6DOF.check_step(0.1, uncertainty)
    REMUS6DOF.check_step(0.01, 0.99)


def test_parameter_uncertainty_too_wide_for_the_vehicles_hull_is_named():
    """Was: "plant_params yaw_time_constant = 1 must be at least 4 s" with no plant_params given:
    REMUS 100's hull steps at 0.01 s, only ε = 0.999's stiffest draws do not."""
    with pytest.raises(ValueError) as caught:
        AUVPath3DEnv(plant="6dof", param_uncertainty=0.999)
    assert str(caught.value) == (
        "param_uncertainty = 0.999 draws 6-DOF hulls too stiff for RK4 at physics_dt = 0.01 s "
        "(the vehicle's damping time constants × (1 − 0.999) at the stiff end; |λ|·dt <= 2.5, "
        "docs/model.md §15.1): give param_uncertainty <= 0.996 or physics_dt <= 0.0025 s"
    )
    SimConfig.from_kwargs(plant="6dof", param_uncertainty=0.996)  # the bounds named fit
    SimConfig.from_kwargs(plant="6dof", param_uncertainty=0.999, physics_dt=0.0025)


def test_parameter_uncertainty_is_bounded_at_its_stiff_end():
    """±50 % makes a yaw time constant of 0.006 s reach 0.003 s: refused, the bound named."""
    with pytest.raises(ValueError, match=r"yaw_time_constant = 0.006 must be at least 0.008 s"):
        AUVPath3DEnv(
            plant="6dof", plant_params=_hull(yaw_time_constant=0.006), param_uncertainty=0.5
        )


@pytest.mark.parametrize(
    ("sensors", "message"),
    [
        (  # was: accepted, then ZeroDivisionError in step() at the first fix (t = 10 s)
            {
                "preset": "typical_kalman",
                "fix_noise": 1e-200,
                "filter_velocity_noise": 1e-200,
                "filter_bias_noise": 1e-200,
                "filter_initial_scale": 1e-200,
                "filter_initial_heading": 1e-200,
            },
            r"^sensors filter_velocity_noise must be a finite number in \[1e-06, 10\] m/s, "
            r"got 1e-200$",
        ),
        (
            {"preset": "typical_kalman", "fix_noise": 1e-200},
            r"^sensors fix_noise = 1e-200 m is below 1e-06 m, the smallest fix error the "
            r"navigation filter can divide by",
        ),
        (  # was: ignored silently
            {"preset": "typical", "filter_velocity_noise": 0.1},
            r"^sensors filter_velocity_noise sets the model of the navigation filter; with "
            r"navigation='dead_reckoning' there is no filter and it would do nothing: drop it or "
            r"give navigation='kalman'$",
        ),
    ],
)
def test_navigation_filter_settings_it_cannot_use_are_refused(sensors, message):
    with pytest.raises(ValueError, match=message):
        AUVPath3DEnv(sensors=sensors)


def test_the_smallest_filter_settings_run_past_the_first_fixes():
    small = dict.fromkeys(
        ("fix_noise", "filter_velocity_noise", "filter_bias_noise", "filter_initial_scale"), 1e-6
    )
    env = AUVPath3DEnv(sensors={"preset": "typical_kalman", **small}, max_time=21.0)
    env.reset(seed=0)
    for _ in range(420):  # fixes at 10 s and 20 s
        _, reward, terminated, _, _ = env.step(STILL)
        assert math.isfinite(reward) and not terminated


def test_the_surface_remedy_adds_to_the_offset_given():
    """Was: 'path_offset = [0, 0, 15]' when (0, 0, 600) was given and 615 is needed."""
    with pytest.raises(ValueError, match=r"\(path_offset = \[2, 0, 615\]\)"):
        AUVPath3DEnv(waves="sea_state_3", path_offset=(2, 0, 600), max_time=2000.0)
    AUVPath3DEnv(waves="sea_state_3", path_offset=(2, 0, 615), max_time=2000.0)  # it suffices
    with pytest.raises(ValueError, match=r"\(path_offset = \[0, 0, 106\]\)"):
        AUVPath3DEnv(waves="sea_state_3", path="random", path_offset=(0, 0, 50))


# ------------------------------------------------- issue 55: left from earlier rounds
def test_a_low_surge_limit_is_never_exceeded_by_the_start():
    """Was: surge_limit=1.2 ended 8 of 100 random-start episodes "overspeed" at step 1 (the
    start's surge was drawn up to 1.5 m/s); the speed-limited ids' draws are unchanged."""
    env = AUVPath3DEnv(surge_limit=1.2, randomize_start=True)
    for seed in range(100):
        env.reset(seed=seed)
        assert env.state[5] <= 0.9 + 1e-12
        _, _, terminated, _, info = env.step(STILL)
        assert not terminated, (seed, info.get("termination_reason"))
    free, limited = (
        AUVPath3DEnv(randomize_start=True),
        AUVPath3DEnv(surge_limit=2.0, randomize_start=True),
    )
    for seed in range(20):
        free.reset(seed=seed)
        limited.reset(seed=seed)
        assert np.array_equal(free.state, limited.state)


@pytest.mark.parametrize("value", [[1.2], None, True, complex(2.0)])
def test_a_surge_limit_of_the_wrong_type_is_a_type_error(value):
    with pytest.raises(ArgumentTypeError, match=r"^surge_limit must be a speed in m/s, inf or"):
        AUVPath3DEnv(surge_limit=value)


@pytest.mark.parametrize("bad", [{"seed": -1}, {"options": {"x": 1}}])
def test_a_refused_reset_leaves_the_env_usable(bad):
    """The env checks before it touches the episode. (Through `gym.make`'s default
    PassiveEnvChecker, Gymnasium 1.4 itself raises TypeError at the next step, for CartPole
    too: the checker marks its first reset done before it runs, so it is bypassed here.)"""
    for env in (AUVPath3DEnv(), gym.make("AUVPath3D-v0", disable_env_checker=True)):
        with pytest.raises((ValueError, gym.error.Error)):
            env.reset(**bad)
        env.reset(seed=0)
        assert len(env.step(STILL)) == 5


@pytest.mark.parametrize(
    ("duration", "transient", "message"),
    [
        (0.01, None, r"use an episode of at least 0.1 s \("),  # was: "transient ≤ -0.04 s"
        (0.09, None, r"use a transient ≤ 0.04 s or an episode of at least 0.1 s"),
        (1.0, 0.99, r"use a transient ≤ 0.95 s or an episode of at least 1.04 s"),
    ],
)
def test_the_metrics_window_remedy_is_never_negative(duration, transient, message):
    from auv_gym.metrics import check_window

    with pytest.raises(ValueError, match=message):
        check_window(duration, transient, 0.05)


def test_bootstrap_replicates_are_bounded():
    """Was: suite --reps 1000000000 accepted (still bootstrapping after 200 s)."""
    from benchmarks.analysis.suite_stats import check_stats_options

    with pytest.raises(ValueError, match=r"^--reps must be an integer in \[100, 100000\]"):
        check_stats_options(10**9, 0)
    check_stats_options(100_000, 0)


def _train_seeds(argv, capsys):
    """`auv-gym train-seeds ARGV`: (exit code, the error line)."""
    from benchmarks.cli import main

    code = main(["train-seeds", *argv])
    return code, capsys.readouterr().err.strip()


@pytest.mark.rl
def test_train_seeds_out_must_name_a_folder(tmp_path, monkeypatch, capsys):
    """Was: --out "" trained into the current folder; --out FILE said "not empty; pass
    --resume"; errors began "python -m benchmarks.training.seeds_cli"."""
    pytest.importorskip("stable_baselines3")
    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("")
    base = ["--algo", "ppo", "--seeds", "1"]
    code, err = _train_seeds([*base, "--out", ""], capsys)
    assert code == 2
    assert err == (
        "auv-gym train-seeds: error: --out '' names no folder: give the run's folder (an empty "
        "path would write into the current folder)"
    )
    code, err = _train_seeds([*base, "--out", "afile"], capsys)
    assert code == 2
    assert (
        err == "auv-gym train-seeds: error: --out 'afile' is a file, not a folder: give the "
        "run's folder"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


@pytest.mark.rl
def test_train_out_must_name_a_folder(tmp_path, monkeypatch, capsys):
    pytest.importorskip("stable_baselines3")
    from benchmarks.training.train_cli import main

    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_info:
        main(["--algo", "ppo", "--out", ""])
    assert exit_info.value.code == 2
    assert "error: --out '' names no folder: give a path" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


@pytest.mark.rl
def test_a_refused_schedule_leaves_its_out_folder_as_it_was(tmp_path, capsys):
    """Was: OUT/configs/ stayed, and the corrected command was refused "not empty"."""
    pytest.importorskip("stable_baselines3")
    from benchmarks.catalog.policies import AGENTS_DIR

    schedule = AGENTS_DIR.parent / "hyperparams" / "ppo_as_built.yml"
    base = ["--algo", "ppo", "--config", str(schedule), "--seeds", "1", "--quiet"]
    (tmp_path / "empty").mkdir()
    for out in (tmp_path / "new", tmp_path / "empty"):
        code, err = _train_seeds([*base, "--out", str(out), "--eval-duration", "0.01"], capsys)
        assert code == 2 and "use an episode of at least 0.1 s" in err, err
    assert not (tmp_path / "new").exists()
    assert not any((tmp_path / "empty").iterdir())


def test_a_finished_schedule_names_the_summary_it_wrote(tmp_path, monkeypatch, capsys):
    """Was: "summary: OUT/summary.json", which a schedule does not write (OUT/schedule.json)."""
    pytest.importorskip("yaml")
    from benchmarks.catalog.policies import AGENTS_DIR
    from benchmarks.training import seeds_cli

    entry = {
        "seed": 0,
        "num_timesteps": 1,
        "wall_time_s": 1.0,
        "test_summary": {"rms_distance_mean": 0.1, "n_terminated": 0, "max_surge_max": 1.0},
    }
    summary = {"seeds": [entry], "selected_seed": 0}
    monkeypatch.setattr(
        seeds_cli,
        "train_schedule",
        lambda *_: {"phases": [{"summary": summary}], "selected_seed": 0},
    )
    schedule = AGENTS_DIR.parent / "hyperparams" / "ppo_as_built.yml"
    out = tmp_path / "run"
    argv = ["--algo", "ppo", "--config", str(schedule), "--seeds", "1", "--out", str(out)]
    assert seeds_cli.main(argv) == 0
    assert f"summary: {out / 'schedule.json'}" in capsys.readouterr().out


# ------------------------------------- issue 55 item 4: every check before the first episode
def _agent_copy(tmp_path, name):
    import shutil

    from benchmarks.catalog.policies import AGENTS_DIR

    copy = tmp_path / name
    shutil.copytree(AGENTS_DIR / name, copy, ignore=shutil.ignore_patterns("*.onnx", "*.pkl"))
    return copy


def _refused(command, argv, capsys):
    """The one error line of `auv-gym COMMAND ARGV`, which must exit 2."""
    from benchmarks.cli import main

    assert main([command, *argv]) == 2
    return capsys.readouterr().err.strip()


@pytest.mark.rl
def test_compare_and_suite_refuse_nan_agent_weights_before_any_episode(tmp_path, capsys):
    """Was: found when the agent's episodes started, after fbsm's had run."""
    torch = pytest.importorskip("torch")
    import io
    import zipfile

    agent = _agent_copy(tmp_path, "ppo_generalist")
    with zipfile.ZipFile(agent / "model.zip") as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    state = torch.load(io.BytesIO(members["policy.pth"]), weights_only=True)
    state["action_net.weight"][0, 0] = float("nan")
    buffer = io.BytesIO()
    torch.save(state, buffer)
    members["policy.pth"] = buffer.getvalue()
    with zipfile.ZipFile(agent / "model.zip", "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    expected = (
        f"error: policy 'agent:{agent}': PPO model {agent}/model.zip: non-finite weights in "
        "['action_net.weight'] (a diverged or damaged model)"
    )
    policies = f"fbsm,agent:{agent}"
    out = tmp_path / "out"
    err = _refused(
        "compare", ["--policies", policies, "--scenarios", "paper", "--out", str(out)], capsys
    )
    assert err == f"auv-gym compare: {expected}"
    err = _refused("suite", ["--policies", policies, "--no-stats", "--out", str(out)], capsys)
    assert err == f"auv-gym suite: {expected}"
    assert not out.exists()


def test_a_factory_that_returns_no_policy_is_named(tmp_path, monkeypatch, capsys):
    """Was: "policy must have predict(...), got int" after fbsm's episodes, naming nothing."""
    (tmp_path / "factories55.py").write_text("def make(**kwargs):\n    return 42\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    out = tmp_path / "out"
    argv = ["--policies", "fbsm,factories55:make", "--scenarios", "paper", "--out", str(out)]
    assert _refused("compare", argv, capsys) == (
        "auv-gym compare: error: scenario 'paper': policy 'factories55:make' gave int 42, not a "
        "Policy (an object with predict(observation, state, episode_start, deterministic))"
    )
    assert not out.exists()


@pytest.mark.rl
def test_a_residual_agents_bad_base_kwargs_name_the_agent_and_its_file(tmp_path, capsys):
    """Was: "scenario 'paper': must be called with a dataclass type or instance"."""
    pytest.importorskip("stable_baselines3")
    import json

    agent = _agent_copy(tmp_path, "ppo_residual")
    meta = json.loads((agent / "metadata.json").read_text())
    meta["residual"]["base_kwargs"] = {"gains": {"nonsense": 1}}
    (agent / "metadata.json").write_text(json.dumps(meta))
    argv = [
        "--policies",
        f"fbsm,agent:{agent}",
        "--scenarios",
        "paper",
        "--out",
        str(tmp_path / "o"),
    ]
    assert _refused("compare", argv, capsys).startswith(
        f"auv-gym compare: error: scenario 'paper': policy 'agent:{agent}': its residual base "
        f"'fbsm_colos' with base_kwargs {{'gains': {{'nonsense': 1}}}} ({agent}/metadata.json) "
        "cannot be built: "
    )


@pytest.mark.rl
def test_train_seeds_checks_every_initial_agent_and_network_before_any_worker(tmp_path, capsys):
    """Was: "seed 0 failed; see log" for an initial agent of another observation, weights that
    do not fit the network, and a network too large to allocate."""
    pytest.importorskip("stable_baselines3")
    from benchmarks.catalog.policies import AGENTS_DIR

    section = (
        "AUVPath3D-v0:\n  n_envs: 2\n  n_timesteps: 64\n  policy: MlpPolicy\n"
        '  normalize: "dict(norm_obs=True, norm_reward=True)"\n  n_steps: 32\n'
        '  batch_size: 64\n  policy_kwargs: "dict(net_arch={arch}, log_std_init=-1.0)"\n'
        "  env_kwargs: {{{env}}}\n"
    )
    cases = {
        "observation": (
            "[64, 64]",
            "observation: preview",
            r"the agent observes 49 entries, "
            r"this run's observation has 46 \(first difference at entry 46: 'x_e_integral' "
            r"against None\)",
        ),
        "weights": (
            "[32, 32]",
            "observation: preview_integral, max_time: 10.0",
            r"its weights \(.*model.zip\) do not fit the "
            r"network of .*weights.yml .*size mismatch for mlp_extractor",
        ),
        "size": (
            "[100000, 100000, 100000]",
            "max_time: 10.0",
            r"size.yml: policy_kwargs "
            r"net_arch \[100000, 100000, 100000\] builds about 4e\+10 weights",
        ),
    }
    import re

    for name, (arch, env, message) in cases.items():
        config = tmp_path / f"{name}.yml"
        config.write_text(section.format(arch=arch, env=env))
        argv = [
            "--algo",
            "ppo",
            "--config",
            str(config),
            "--env-id",
            "AUVPath3D-v0",
            "--seeds",
            "1",
            "--init-from",
            str(AGENTS_DIR / "ppo_generalist"),
            "--out",
            str(tmp_path / name),
        ]
        code, err = _train_seeds(argv, capsys)
        assert code == 2 and re.search(message, err), err
        assert not (tmp_path / name).exists()
