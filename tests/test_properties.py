"""Property-based tests (hypothesis) over the whole documented argument space (issue 11, item 7).

Configurations are drawn from the ranges documented in `AUVPath3DEnv` (bounds imported from the
modules that enforce them), actions from [−3, 3]³ (saturating beyond ±1). Invariants:
- every observation is finite float32; it lies in `observation_space` unless the step
  terminated with a documented reason; every reward is finite;
- `truncated` is True exactly from the first control step at which t ≥ max_time, through
  `gym.make` and `gym.make_vec`, and `spec.max_episode_steps` is that step count;
- the same seed gives bit-identical episodes; vehicle i of the vector env is the single env
  reset with seed k + i;
- an argument outside its range, or of the wrong type, raises TypeError/ValueError naming it.

The examples are bounded and derandomized so that CI is fast and repeatable;
`python -m benchmarks.checks.fuzz` is the long random exploration (≥ 10⁷ vehicle-steps).
"""

from __future__ import annotations

import math
import warnings

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import auv_gym  # noqa: F401  (registers the ids)
from auv_gym import AUVPath3DEnv
from auv_gym.envs.vector_env import AUVPath3DVectorEnv
from auv_gym.ocean.disturbances import (
    MAX_CURRENT_SPEED,
    MAX_CURRENT_TIME_CONSTANT,
    MAX_NOISE_AMPLITUDE,
    CurrentConfig,
    NoiseConfig,
)
from auv_gym.paths.shapes import POSITION_BOUND, Helix, Spline, StraightLine, make_path
from auv_gym.sim.config import MAX_SUBSTEPS, PHYSICS_DT_RANGE, path_turn_rates
from auv_gym.sim.observation import ERROR_BOUND, PATH_RATE_BOUND, SPEED_BOUND
from auv_gym.sim.task import MAX_REWARD_WEIGHT, MIN_CORRIDOR, REWARD_TERMS, TERMINATION_REASONS
from auv_gym.vehicle import remus100

# may leave the observation space
FAILURES = {"corridor", "pitch", "envelope", "non_finite", "overspeed", "broached", "grounded"}
assert FAILURES | {"path_end", ""} == set(TERMINATION_REASONS)
PHYSICS_STEPS_PER_EXAMPLE = 20_000  # keeps an example in milliseconds
CI = settings(
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


def log_uniform(low: float, high: float) -> st.SearchStrategy[float]:
    """Floats spread evenly in log10 over [low, high], the bounds themselves included."""
    return st.one_of(
        st.sampled_from([low, high]),
        st.floats(math.log10(low), math.log10(high)).map(lambda e: min(max(10.0**e, low), high)),
    )


def vec3(bound: float) -> st.SearchStrategy[tuple[float, float, float]]:
    f = st.floats(-bound, bound, allow_nan=False)
    return st.tuples(f, f, f)


@st.composite
def paths(draw):
    kind = draw(st.sampled_from(["helix", "line", "waypoints", "Helix", "StraightLine", "Spline"]))
    if kind in ("helix", "line", "waypoints"):
        return kind
    end = draw(st.one_of(st.just(math.inf), log_uniform(1e-3, 1e4)))
    if kind == "Helix":
        radius, omega = draw(log_uniform(1e-3, 1e5)), draw(log_uniform(1e-4, 1e3))
        climb = draw(st.floats(-1e3, 1e3))
        if math.hypot(radius * omega, climb) < 1e-5:  # below the documented |p'| >= 1e-6
            climb = 1.0
        return Helix(radius, omega, climb, draw(vec3(POSITION_BOUND)), s_end=end)
    if kind == "StraightLine":
        direction = draw(vec3(1.0).filter(lambda d: math.hypot(*d) > 1e-3))
        return StraightLine(start=draw(vec3(POSITION_BOUND)), direction=direction, length=end)
    n = draw(st.integers(2, 8))
    origin = np.array(draw(vec3(POSITION_BOUND / 2)))
    scale = draw(log_uniform(0.1, 1e3))
    steps = draw(arrays(np.float64, (n - 1, 3), elements=st.floats(-1.0, 1.0)))
    steps[:, 0] = np.abs(steps[:, 0]) + 0.05  # distinct consecutive waypoints
    return Spline(origin + scale * np.vstack([np.zeros(3), np.cumsum(steps, axis=0)]))


@st.composite
def env_kwargs(draw):
    """Valid keyword arguments of `AUVPath3DEnv` across the documented ranges, and the number of
    control steps to max_time (bounded so that an episode costs <= 20 000 physics steps)."""
    kw: dict = {"path": draw(paths())}
    physics_dt = draw(log_uniform(*PHYSICS_DT_RANGE))
    substeps = int(draw(log_uniform(1, MAX_SUBSTEPS)))
    control_dt = substeps * physics_dt
    n_steps = draw(st.integers(1, max(1, min(60, PHYSICS_STEPS_PER_EXAMPLE // substeps))))
    fraction = 1.0 if n_steps == 1 else draw(st.floats(0.01, 1.0))
    kw.update(
        physics_dt=physics_dt, control_dt=control_dt, max_time=control_dt * (n_steps - 1 + fraction)
    )
    hold = draw(st.integers(1, 1000)) * physics_dt
    amplitude = draw(st.one_of(st.just(0.0), log_uniform(1e-3, MAX_NOISE_AMPLITUDE)))
    noises = [
        {"disturbance": "paper"},
        {"disturbance": "none"},
        {"disturbance": amplitude, "noise_hold": hold},
        {"disturbance": NoiseConfig((amplitude,) * 5, hold)},
    ]
    kw.update(draw(st.sampled_from(noises)))
    silent = kw["disturbance"] == "none" or kw["disturbance"] == 0.0
    if silent:  # no noise: a hold would hold nothing (refused)
        kw.pop("noise_hold", None)
    elif "noise_hold" not in kw and not isinstance(kw["disturbance"], NoiseConfig):
        whole = abs(0.01 / physics_dt - round(0.01 / physics_dt)) < 1e-9 * (0.01 / physics_dt)
        if not whole or 0.01 < physics_dt:  # the default hold 0.01 s does not fit
            kw["noise_hold"] = hold
    if draw(st.booleans()):
        kw["current"] = CurrentConfig(
            mean=draw(vec3(MAX_CURRENT_SPEED)),
            std=tuple(abs(x) for x in draw(vec3(MAX_CURRENT_SPEED))),
            time_constant=draw(log_uniform(1e-3, MAX_CURRENT_TIME_CONSTANT)),
        )
    kw["param_uncertainty"] = draw(st.one_of(st.just(0.0), st.floats(0.0, 0.999)))
    kw["actuator"] = draw(st.sampled_from(["paper", "fins"]))
    kw["randomize_start"] = draw(st.booleans())
    path = make_path(kw["path"])
    turn = max(path_turn_rates(path))
    # 1 - 1e-12: the env's check 2·u·turn <= bound must not fail by one rounding at u = u_max
    u_max = SPEED_BOUND if turn == 0 else min(SPEED_BOUND, PATH_RATE_BOUND / (2 * turn))
    u_max *= 1 - 1e-12
    kw["u_desired"] = u_max * draw(st.one_of(st.just(1.0), log_uniform(1e-4, 1.0)))
    kw["sigma"] = draw(log_uniform(1e-6, 1e6))
    kw["virtual_point_law"] = draw(st.sampled_from(["corrected", "printed"]))
    kw["corridor"] = draw(log_uniform(MIN_CORRIDOR, ERROR_BOUND))
    kw["max_pitch"] = draw(st.floats(0.01, math.pi / 2 - 1e-6))
    if draw(st.booleans()):
        weight = log_uniform(1e-6, MAX_REWARD_WEIGHT)
        kw["reward_weights"] = {t: draw(st.one_of(st.just(0.0), weight)) for t in REWARD_TERMS}
    if draw(st.booleans()):
        kw["start_heading"] = draw(st.floats(-2 * math.pi, 2 * math.pi))
    if draw(st.booleans()):  # anywhere the errors stay observable, possibly beyond the corridor
        offset = np.array(draw(vec3(1.0)))
        reach = ERROR_BOUND - 2 * math.sqrt(3) - 1e-6
        length = float(np.linalg.norm(offset))
        start = path.evaluate(0.0)[0] + offset / max(length, 1e-9) * draw(st.floats(0, reach))
        if np.abs(start).max() <= POSITION_BOUND:
            kw["start_position"] = tuple(start)
    if draw(st.booleans()):
        kw["params"] = remus100().perturbed(np.random.default_rng(draw(st.integers(0, 99))), 0.5)
    return kw, n_steps


actions_for = arrays(np.float64, (60, 3), elements=st.floats(-3.0, 3.0, allow_nan=False))


OUT_OF_SPACE = "obs returned by the `step()` method is not within the observation space"


def checked_step(env, action):
    """``env.step(action)``, letting through gymnasium's passive-checker warning that the
    observation left the space only on a step that ended the episode with a failure reason
    (the documented terminal observation, e.g. x_e beyond ±500 m when the corridor is left);
    any other warning is re-emitted."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = env.step(action)
    reason = result[4].get("termination_reason", "")
    for warning in caught:
        if OUT_OF_SPACE in str(warning.message):
            assert result[2] and reason in FAILURES, (reason, result[0])
        else:
            warnings.warn_explicit(
                warning.message, warning.category, warning.filename, warning.lineno
            )
    return result


def run_episode(env, seed, actions):
    """(observations, rewards, terminated, truncated, reasons) of one episode, checking every
    step's invariants on the way."""
    space = env.observation_space
    obs, _ = env.reset(seed=seed)
    assert obs.dtype == np.float32 and space.contains(obs), obs
    out = [[obs], [], [], [], []]
    for k, action in enumerate(actions, start=1):
        obs, reward, terminated, truncated, info = checked_step(env, action)
        reason = info.get("termination_reason", "")
        assert obs.dtype == np.float32 and np.all(np.isfinite(obs)), (k, obs)
        assert math.isfinite(reward), (k, reward)
        assert terminated == (reason != ""), (k, reason)
        if not space.contains(obs):
            assert reason in FAILURES, (k, reason, obs)
        for row, value in zip(out, (obs, reward, terminated, truncated, reason), strict=True):
            row.append(value)
        if terminated or truncated:
            break
    return out


@settings(CI, max_examples=200)
@given(env_kwargs(), actions_for, st.integers(0, 2**31 - 1))
def test_episodes_keep_their_invariants(drawn, actions, seed):
    kwargs, n_steps = drawn
    env = gym.make("AUVPath3D-v0", **kwargs)
    config = env.unwrapped.config
    assert config.max_steps == n_steps == math.ceil(config.max_time / config.control_dt - 1e-9)
    assert env.spec.max_episode_steps == n_steps
    obs, rewards, terminated, truncated, reasons = run_episode(env, seed, actions[:n_steps])
    steps = len(rewards)
    assert truncated[-1] == (steps == n_steps)  # truncated exactly at max_time ...
    assert not any(truncated[:-1])
    assert steps == n_steps or terminated[-1]  # ... or terminated before
    t = steps * config.control_dt
    assert (t >= config.max_time * (1 - 1e-9)) == truncated[-1]
    # Same seed ⇒ bit-identical.
    again = run_episode(gym.make("AUVPath3D-v0", **kwargs), seed, actions[:n_steps])
    np.testing.assert_array_equal(np.asarray(obs), np.asarray(again[0]))
    assert rewards == again[1] and reasons == again[4]


@settings(CI, max_examples=60)
@given(env_kwargs(), st.integers(2, 3), st.integers(0, 2**31 - 1), st.integers(0, 2**31 - 1))
def test_vector_env_is_the_single_env(drawn, n, seed, action_seed):
    kwargs, n_steps = drawn
    total = 2 * n_steps + 2  # through at least one autoreset of every vehicle
    actions = np.random.default_rng(action_seed).uniform(-1.5, 1.5, size=(total, n, 3))
    vector = gym.make_vec("AUVPath3D-v0", num_envs=n, **kwargs)
    assert isinstance(vector, AUVPath3DVectorEnv) and vector.spec.max_episode_steps == n_steps
    singles = [AUVPath3DEnv(**kwargs) for _ in range(n)]
    obs, _ = vector.reset(seed=seed)
    assert vector.observation_space.contains(obs)
    done = [False] * n
    for i, env in enumerate(singles):
        np.testing.assert_array_equal(obs[i], env.reset(seed=seed + i)[0])
    for a in actions:
        o, r, term, trunc, info = vector.step(a)
        assert np.all(np.isfinite(o)) and np.all(np.isfinite(r))
        for i, env in enumerate(singles):
            if done[i]:  # NEXT_STEP: this step resets vehicle i, as env.reset() without a seed
                np.testing.assert_array_equal(o[i], env.reset()[0])
                assert (r[i], term[i], trunc[i]) == (0.0, False, False)
                done[i] = False
                continue
            so, sr, sterm, strunc, sinfo = env.step(a[i])
            np.testing.assert_array_equal(o[i], so)
            assert (r[i], term[i], trunc[i]) == (sr, sterm, strunc)
            if sterm:
                assert info["termination_reason"][i] == sinfo["termination_reason"]
            done[i] = sterm or strunc


# ------------------------------------------------------------------------------ bad input
NOT_NUMBERS = st.sampled_from(["1", b"1", None, True, False, [1.0], (1.0,), {"a": 1}, 1j])


def outside(low: float, high: float) -> st.SearchStrategy:
    """Numbers outside [low, high] (NaN and ±inf included) and values that are not numbers."""
    beyond = [st.sampled_from([math.nan, math.inf, -math.inf])]
    if low > -math.inf:
        beyond.append(st.floats(max_value=low, exclude_max=True, allow_nan=False))
    if high < math.inf:
        beyond.append(st.floats(min_value=high, exclude_min=True, allow_nan=False))
    return st.one_of(*beyond, NOT_NUMBERS)


BAD = {
    "physics_dt": outside(*PHYSICS_DT_RANGE),
    "control_dt": st.one_of(outside(0.0, 100.0), st.floats(0.0501, 0.0599), st.just(0.0)),
    "max_time": st.one_of(outside(0.05, 1e6), st.just(0.0)),
    "noise_hold": st.one_of(outside(0.0, 1e6), st.just(0.0), st.just(0.015)).filter(
        lambda v: v is not None
    ),
    "u_desired": st.one_of(outside(0.0, SPEED_BOUND), st.just(0.0)),
    "sigma": st.one_of(outside(0.0, math.inf), st.just(0.0)),
    "param_uncertainty": st.one_of(outside(0.0, 1.0), st.just(1.0)).filter(
        lambda v: v is not None  # None: the preset's (0 outside disturbance="ocean")
    ),
    "corridor": outside(MIN_CORRIDOR, ERROR_BOUND),
    "max_pitch": st.one_of(outside(0.0, math.pi / 2), st.sampled_from([0.0, math.pi / 2])),
    "start_heading": st.one_of(outside(-2 * math.pi, 2 * math.pi).filter(lambda v: v is not None)),
    "disturbance": st.one_of(outside(0.0, MAX_NOISE_AMPLITUDE), st.text(max_size=5)).filter(
        lambda v: v not in ("paper", "none", "ocean")
    ),
    "randomize_start": st.one_of(NOT_NUMBERS, st.integers(), st.text(max_size=5)).filter(
        lambda v: not isinstance(v, bool)
    ),
    "actuator": st.one_of(NOT_NUMBERS, st.text(max_size=6)).filter(
        lambda v: v not in ("paper", "fins")
    ),
    "virtual_point_law": st.one_of(NOT_NUMBERS, st.text(max_size=6)).filter(
        lambda v: v not in ("corrected", "printed")
    ),
    "start_position": st.one_of(
        NOT_NUMBERS.filter(lambda v: v is not None),
        st.lists(st.floats(allow_nan=False), min_size=0, max_size=2),
        st.tuples(st.floats(min_value=1e6, exclude_min=True), st.just(0.0), st.just(0.0)),
        st.tuples(st.just(math.nan), st.just(0.0), st.just(0.0)),
    ),
    "current": st.one_of(
        NOT_NUMBERS.filter(lambda v: v is not None and not isinstance(v, (tuple, list, dict))),
        st.tuples(
            outside(-10.0, 10.0).filter(lambda v: not isinstance(v, (tuple, list))),
            st.just(0.0),
            st.just(0.0),
        ),
        st.fixed_dictionaries({"time_constant": outside(0.0, 1e6)}),
    ),
    "reward_weights": st.one_of(
        NOT_NUMBERS.filter(lambda v: v is not None and not isinstance(v, dict)),
        st.fixed_dictionaries({"progress": outside(0.0, MAX_REWARD_WEIGHT)}),
        st.dictionaries(st.text(min_size=1, max_size=4), st.just(1.0), min_size=1).filter(
            lambda d: not set(d) <= set(REWARD_TERMS)
        ),
    ),
    "path_offset": st.one_of(
        NOT_NUMBERS.filter(lambda v: v is not None),
        st.tuples(st.just(0.0), st.just(0.0), outside(-POSITION_BOUND, POSITION_BOUND)),
    ),
    "depth_envelope": st.one_of(  # and the default helix crosses any surface
        st.fixed_dictionaries({"seabed_depth": outside(4.0, 11_000.0)}),
        st.fixed_dictionaries({"margin": outside(0.0, 1000.0)}),
        st.text(max_size=4),
    ),
    "safety_cost": st.one_of(
        st.fixed_dictionaries({"speed_limit": st.one_of(outside(0.0, 10.0), st.just(0.0))}),
        st.fixed_dictionaries({"pitch_limit": outside(0.0, math.pi / 2)}),
        st.fixed_dictionaries({"depth": outside(0.0, 1e6)}),
        st.text(max_size=4),
    ),
}
NAMES_IN_MESSAGES = {"reward_weights": "reward", "noise_hold": "noise"}


@settings(CI, max_examples=300)
@given(st.sampled_from(sorted(BAD)).flatmap(lambda name: st.tuples(st.just(name), BAD[name])))
def test_bad_arguments_raise_named_errors(bad):
    name, value = bad
    with pytest.raises((TypeError, ValueError)) as caught:
        AUVPath3DEnv(**{name: value})
    assert NAMES_IN_MESSAGES.get(name, name) in str(caught.value), str(caught.value)
