"""Command-filtered backstepping (controllers.command_filtered, docs/model.md §4.10)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import controllers
from auv_gym import AUVPath3DEnv
from auv_gym.sim.observation import OBS_INDEX
from auv_gym.vehicle import remus100
from auv_gym.vehicle.actuators import ACTUATOR_STATE
from benchmarks.catalog.scenarios import load_scenarios


def _fly(policy, env, seed, steps):
    obs, _ = env.reset(seed=seed)
    state, start = None, True
    diagnostics, rate_limited, distance = [], [], []
    for _ in range(steps):
        action, state = policy.predict(obs, state=state, episode_start=np.array([start]))
        start = False
        diagnostics.append((*state["diag"][0], obs[OBS_INDEX["u"]]))
        obs, _, terminated, _, info = env.step(action)
        rate_limited.append(env.unwrapped.sim.actuator_state[0, ACTUATOR_STATE.rate_limited])
        distance.append(info["distance"])
        assert not terminated, info.get("termination_reason")
    return state, np.array(rate_limited), np.array(distance), diagnostics


def test_moments_stay_inside_the_fins_magnitude_and_rate_limits():
    """From the paper's start (90° off the path) the law asks for far more than the fins give;
    the applied moments stay within K·δ_max·u|u| and change by at most the fins' moment rate."""
    env = AUVPath3DEnv(actuator="fins", disturbance="none")
    policy = controllers.make("command_filtered", actuator="fins")
    _, _, _, diagnostics = _fly(policy, env, 0, 600)
    diagnostics = np.array(diagnostics)
    moments, u = diagnostics[:, 1:3], diagnostics[:, 5]
    params = remus100()
    authority = params.fin_moment_coeff * params.fin_max * u * np.abs(u)
    assert (np.abs(moments) <= authority[:, None] * (1 + 1e-12)).all()
    assert (np.abs(moments) >= 0.999 * authority[:, None]).any()  # the limits are met
    # Per control step the filter moves at most the fins' moment rate at the larger u of the two.
    rate = math.radians(60.0) / params.fin_max * np.maximum(authority[1:], authority[:-1])
    steps = np.abs(np.diff(moments, axis=0))
    assert (steps <= 1.02 * rate[:, None] * 0.05).all(), (steps / (rate[:, None] * 0.05)).max()


def test_as_built_it_saturates_the_fin_rate_less_than_backstepping():
    """On the as-built helix (seed 3, 150 s) the fin servos are rate-limited in a fraction of
    the physics steps several times smaller than with backstepping (measured 0.07 against
    0.35-0.51 on seeds 0-2 of the three as-built scenarios), and it stays on the path."""
    scenario = load_scenarios()["as_built_helix"]
    env = AUVPath3DEnv(**scenario.env)
    limited = {}
    for name in ("command_filtered_colos", "backstepping_colos"):
        policy = controllers.make(name, **scenario.controller)
        _, rate_limited, distance, _ = _fly(policy, env, 3, 3000)
        limited[name] = rate_limited.mean()
        assert math.sqrt(np.mean(distance[2000:] ** 2)) < 1.5
    assert limited["command_filtered_colos"] < 0.5 * limited["backstepping_colos"], limited


def test_the_compensation_decays_once_the_limits_release():
    """After the start's large errors, on the fin-limited vehicle without noise, ξ decays: the
    compensated errors become the true ones and the law is backstepping's."""
    env = AUVPath3DEnv(actuator="fins", disturbance="none")
    policy = controllers.make("command_filtered", actuator="fins")
    state, _, distance, _ = _fly(policy, env, 0, 4000)
    diagnostics = policy.diagnostics(state)
    assert max(abs(float(diagnostics[f"xi_{j}"][0])) for j in range(1, 5)) < 1e-3
    assert distance[-200:].max() < 0.1


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"actuator": "paper"}, r"give actuator='fins' or 'realistic', got 'paper'"),
        ({"filter_wn": 0.0}, r"filter_wn must be in \(0, 20.0\], got 0.0"),
        ({"filter_zeta": math.nan}, r"filter_zeta must be in"),
        ({"fin_rate_max": -1.0}, r"fin_rate_max must be > 0 rad/s, got -1.0"),
        (
            {"k9": 1.0},
            r"unknown command_filtered keyword arguments \[.k9.\]; valid: .* "
            r"and its gains \[.*.k2.",
        ),
    ],
)
def test_bad_settings_raise_one_named_line(kwargs, message):
    with pytest.raises(ValueError, match=message):
        controllers.make("command_filtered", **{"actuator": "fins", **kwargs})
