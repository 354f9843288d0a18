"""An agent's stages (`controllers.stages`): the envelope guard and the actuator allocation by
hand, the one pipeline that applies them around the network at inference and around the env in
training (the same commands), the reference generalist's stages from its metadata, and bad
stage lists, settings and former metadata keys named in one line."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path
from types import SimpleNamespace
from typing import ClassVar

import numpy as np
import pytest

from auv_gym.sim.observation import ObservationConfig
from auv_gym.vehicle.actuators import ActuatorParams
from controllers.actuator_allocation import Allocation
from controllers.allocation import allocate
from controllers.envelope_guard import EnvelopeGuard, check_envelope_guard, guard_commands
from controllers.stages import (
    AllocationStage,
    GuardStage,
    StagedPolicy,
    build_stages,
    check_stage_specs,
)

FACTORS = {"x_e": 0.125, "y_e": 0.25, "z_e": 0.25}  # the base scales (2 m) on the fins

ROOT = Path(__file__).resolve().parents[1]
GENERALIST = ROOT / "benchmarks" / "agents" / "ppo_generalist"
INDEX = (0, 1, 2)  # θ, q, u in the hand-made observations below
GUARD = EnvelopeGuard()  # pitch 35°–50°, T = 1 s, surge 1.8–1.95 m/s
NAMES = ObservationConfig.from_spec("preview").names
U, V, W = (NAMES.index(n) for n in ("u", "v", "w"))
PREV = [NAMES.index(n) for n in ("a_X_prev", "a_M_prev", "a_N_prev")]
FIN_GAIN = 6.15 * math.pi / 6  # K·δ_max [kg] of REMUS 100: the fin moment at 1 m/s [N·m]


def _guard_obs(theta_deg: float, q_deg_s: float, u: float) -> np.ndarray:
    return np.array([math.radians(theta_deg), math.radians(q_deg_s), u])


def test_inside_the_soft_limits_the_guard_is_the_identity():
    commands = np.float32([[0.7, 1.0, -0.4], [-1.0, -1.0, 1.0]])
    obs = np.stack(
        [_guard_obs(20.0, 10.0, 1.2), _guard_obs(-30.0, 4.0, 1.79)]
    )  # θ + T·q = 30°, −26°
    np.testing.assert_array_equal(guard_commands(commands, obs, INDEX, GUARD), commands)


def test_the_stern_plane_guard_mirrors_the_moment_command():
    """For the realistic actuator a_M is δ_s, positive nose-down: the same limits, mirrored."""
    stern = EnvelopeGuard(nose_up_command=-1.0)
    cases = [  # (θ [deg], command a_M (δ_s), guarded)
        (42.5, -1.0, 0.0),  # half way up: the nose-up deflection (δ_s < 0) capped at 0
        (42.5, 0.6, 0.6),  # nose-down stays allowed
        (55.0, -0.2, 1.0),  # past the hard limit: full nose-down deflection
        (-55.0, 0.3, -1.0),  # mirrored: full nose-up deflection
    ]
    for theta, command, expected in cases:
        out = guard_commands(
            np.float32([0.5, command, 0.0]), _guard_obs(theta, 0.0, 1.0), INDEX, stern
        )
        np.testing.assert_allclose(out, [0.5, expected, 0.0], atol=1e-6)


def test_hand_computed_guarded_commands():
    cases = [  # (θ [deg], q [deg/s], u [m/s], command, guarded)
        (42.5, 0.0, 1.0, [0.5, 1.0, 0.3], [0.5, 0.0, 0.3]),  # half way: nose-up capped at 0
        (30.0, 10.0, 1.0, [0.5, 1.0, 0.3], [0.5, 1.0 / 3.0, 0.3]),  # θ_p = 40°: 1 − 2·5/15
        (55.0, 0.0, 1.0, [0.5, 0.2, 0.3], [0.5, -1.0, 0.3]),  # past the hard limit: nose down
        (42.5, 0.0, 1.0, [0.5, -0.6, 0.3], [0.5, -0.6, 0.3]),  # nose-down stays allowed
        (-50.0, 0.0, 1.0, [0.5, -1.0, -1.0], [0.5, 1.0, -1.0]),  # mirrored: full nose up
        (0.0, 0.0, 1.875, [0.5, 0.1, 0.0], [0.0, 0.1, 0.0]),  # surge half way: thrust capped
        (0.0, 0.0, 1.875, [-0.3, 0.1, 0.0], [-0.3, 0.1, 0.0]),  # astern stays allowed
        (0.0, 0.0, 2.1, [1.0, 0.1, 0.0], [-1.0, 0.1, 0.0]),  # past u_hard: full astern
    ]
    for theta, q, u, command, expected in cases:
        single = guard_commands(np.float32(command), _guard_obs(theta, q, u), INDEX, GUARD)
        assert single.shape == (3,) and single.dtype == np.float32
        np.testing.assert_allclose(single, expected, atol=1e-6)
    batch = guard_commands(
        np.float32([c[3] for c in cases]),
        np.stack([_guard_obs(*c[:3]) for c in cases]),
        INDEX,
        GUARD,
    )
    np.testing.assert_allclose(batch, [c[4] for c in cases], atol=1e-6)


FLOOR = EnvelopeGuard(surge_floor_soft=1.2, surge_floor_hard=0.9)


def test_hand_computed_low_speed_floor():
    """The floor raises the surge command below u_floor_soft (full ahead from u_floor_hard on)
    and leaves everything else, and every command of a guard without it, as it was."""
    cases = [  # (u [m/s], a_X, guarded a_X)
        (1.5, -1.0, -1.0),  # above the soft floor: astern allowed
        (1.2, -0.7, -0.7),  # at the soft floor: still −1
        (1.05, -1.0, 0.0),  # half way: −1 + 2·0.5
        (1.0, -0.5, 1.0 / 3.0),  # two thirds of the way: floor −1 + 2·(2/3) = 1/3
        (1.0, 0.8, 0.8),  # above the floor stays
        (0.9, -1.0, 1.0),  # at the hard floor: full ahead
        (0.0, 0.2, 1.0),  # stopped: full ahead
        (1.875, 0.5, 0.0),  # the overspeed cap still acts
    ]
    commands = np.float32([[a, 0.3, -0.2] for _, a, _ in cases])
    obs = np.stack([_guard_obs(0.0, 0.0, u) for u, _, _ in cases])
    got = guard_commands(commands, obs, INDEX, FLOOR)
    np.testing.assert_allclose(got[:, 0], [c[2] for c in cases], atol=1e-6)
    np.testing.assert_array_equal(got[:, 1:], commands[:, 1:])
    plain = guard_commands(commands[:7], obs[:7], INDEX, GUARD)
    np.testing.assert_array_equal(plain, commands[:7])  # no floor, below the surge cap


def test_a_guard_records_its_floor_only_when_on():
    assert "surge_floor_soft" not in GUARD.to_dict()  # agents saved before it read the same
    assert FLOOR.to_dict()["surge_floor_soft"] == 1.2
    assert FLOOR.to_dict()["surge_floor_hard"] == 0.9
    assert check_envelope_guard(FLOOR.to_dict(), "here") == FLOOR


class _Constant:
    """A Policy that always commands full nose-up and thrust."""

    path = None
    metadata: ClassVar[dict] = {}

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        n = np.atleast_2d(observation).shape[0]
        out = np.tile(np.float32([1.0, 1.0, 0.5]), (n, 1))
        return (out if np.ndim(observation) == 2 else out[0]), state


def test_a_guard_stage_reads_its_inputs_by_name():
    names = ["x_e", "u", "theta", "q"]
    policy = StagedPolicy(_Constant(), [GuardStage({"pitch_soft_deg": 30.0}, names, "here")])
    obs = np.array([0.0, 1.0, math.radians(40.0), 0.0])  # θ_p = 40° of 30°–50°: cap 0
    command, _ = policy.predict(obs)
    np.testing.assert_allclose(command, [1.0, 0.0, 0.5], atol=1e-6)
    with pytest.raises(ValueError, match=r"here: envelope_guard reads .* lacks \['q'\]"):
        GuardStage(True, ["theta", "u"], "here")


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ({"pitch_soft_deg": 50.0, "pitch_hard_deg": 40.0}, "soft limit must lie below"),
        ({"surge_soft": 2.0}, "soft limit must lie below"),
        ({"pitch_hard_deg": math.nan}, "pitch_hard_deg must be"),
        ({"lookahead_s": -1.0}, "lookahead_s must be"),
        ({"pitch": 40.0}, r"unknown keys \['pitch'\]"),
        ({"nose_up_command": 0.5}, r"nose_up_command must be 1 .* or -1"),
        ({"surge_floor_hard": 0.5}, "surge_floor_hard 0.5 m/s needs a surge_floor_soft"),
        ({"surge_floor_soft": 1.0, "surge_floor_hard": 1.1}, "surge_floor_hard < surge_floor_soft"),
        ({"surge_floor_soft": 1.9}, "< surge_soft, got 0 < 1.9 < 1.8"),
        ({"surge_floor_soft": -0.1}, "surge_floor_soft must be"),
        ("yes", "must be true or a mapping"),
    ],
)
def test_bad_guards_are_named(value, message):
    with pytest.raises(ValueError, match=f"here: .*{message}"):
        check_envelope_guard(value, "here")


class Recorder:
    """An actor that returns fixed commands and keeps the observations it was given."""

    def __init__(self, commands):
        self.commands = np.float32(commands)
        self.seen = []

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        self.seen.append(np.array(observation))
        n = np.atleast_2d(observation).shape[0]
        return np.tile(self.commands, (n, 1)), state


def _obs(u: float, v: float = 0.0, w: float = 0.0, prev=(0.5, 0.5, 0.5)) -> np.ndarray:
    obs = np.zeros(len(NAMES), dtype=np.float32)
    obs[[U, V, W]] = u, v, w
    obs[PREV] = prev  # the env's fin commands: the allocation replaces them
    return obs


def test_fin_commands_and_previous_moments_by_hand():
    actor = Recorder([0.2, 0.1, -0.5])  # X = 10 N, M_d = 1 N·m, N_d = −5 N·m
    policy = StagedPolicy(actor, [AllocationStage(Allocation(NAMES, "fins"))])
    obs = np.stack([_obs(1.0), _obs(2.0), _obs(0.0), _obs(-0.3)])
    first, state = policy.predict(obs, episode_start=np.ones(4, dtype=bool))
    authority = FIN_GAIN * np.array([1.0, 4.0, 0.0, 0.0])  # K·δ_max·max(u|u|, 0) [N·m]
    np.testing.assert_allclose(
        first[:2],
        [[0.2, 1.0 / authority[0], -1.0], [0.2, 1.0 / authority[1], -5.0 / authority[1]]],
        rtol=1e-6,
    )
    np.testing.assert_array_equal(first[2:], np.float32([[0.2, 1.0, -1.0]] * 2))  # no flow: sign
    np.testing.assert_array_equal(actor.seen[0][:, PREV], np.zeros((4, 3)))  # after a reset
    policy.predict(obs, state, episode_start=np.array([False, False, False, True]))
    delivered = np.array(
        [[0.2, 0.1, -authority[0] / 10.0], [0.2, 0.1, -0.5], [0.2, 0.0, 0.0], [0.0, 0.0, 0.0]]
    )
    np.testing.assert_allclose(actor.seen[1][:, PREV], delivered, rtol=1e-6)
    single, _ = policy.predict(_obs(1.0))
    assert single.shape == (3,) and single[1] == pytest.approx(1.0 / authority[0], rel=1e-6)


def test_realistic_actuators_get_the_classical_allocation_of_the_delivered_moments():
    actor = Recorder([0.4, -0.2, 0.9])  # X = 20 N, M_d = −2 N·m, N_d = 9 N·m (beyond the fins)
    policy = StagedPolicy(actor, [AllocationStage(Allocation(NAMES, "realistic"))])
    obs = np.stack([_obs(1.2, 0.05, -0.02), _obs(1.6, -0.1, 0.1)])
    commands, _ = policy.predict(obs)
    u = obs[:, U].astype(np.float64)
    authority = FIN_GAIN * u * u
    tau = np.column_stack([np.full(2, 20.0), np.full(2, -2.0), np.minimum(9.0, authority)])
    expected = allocate(tau, obs[:, [U, V, W]], ActuatorParams())
    np.testing.assert_allclose(commands, expected, rtol=1e-6)


def test_bad_stage_lists_and_settings_are_named():
    guard = {"name": "envelope_guard"}
    alloc = {"name": "actuator_allocation", "commands": "paper"}
    assert check_stage_specs(["envelope_guard", alloc], "f")[0] == {
        "name": "envelope_guard",
        **GUARD.to_dict(),
    }
    cases = [
        (
            [{"name": "lowpass"}],
            r"f: unknown stage 'lowpass'; stages: \['mirror_symmetry', 'envelope_guard'",
        ),
        ([alloc, guard], "must each appear once, in the order"),
        ([guard, guard], "must each appear once"),
        ("envelope_guard", "stages must be a list"),
        ([{"pitch_soft_deg": 3}], "each stage is a mapping with a 'name'"),
        ([{"name": "actuator_allocation", "commands": "fins"}], "must be 'paper'"),
        ([{"name": "actuator_allocation", "gain": 2}], r"unknown keys \['gain'\]"),
        ([{"name": "envelope_guard", "surge_soft": 3.0}], "soft limit must lie below"),
    ]
    for specs, message in cases:
        with pytest.raises(ValueError, match=message):
            check_stage_specs(specs, "f")
    with pytest.raises(ValueError, match=r"the allocation flies \['fins', 'realistic'\]"):
        Allocation(NAMES, "paper")
    with pytest.raises(ValueError, match=r"lacks \['v', 'w'\]"):
        Allocation(["u", "a_X_prev", "a_M_prev", "a_N_prev"], "fins")
    # On the actuator the agent commands, or one drawn per episode, the allocation is left out.
    for actuator in ("paper", "random", None):
        built = build_stages(check_stage_specs([alloc], "f"), NAMES, {"actuator": actuator})
        assert built == []


def test_observation_factors_scale_what_the_network_sees_on_the_allocated_actuator_only():
    """x_e, y_e, z_e seen at 1/8, 1/4, 1/4 on the fins, the commands allocated as without the
    factors; on the paper's actuator the allocation, and with it the factors, is left out."""
    spec = {"name": "actuator_allocation", "observation_factors": FACTORS}
    specs = check_stage_specs([spec], "f")
    assert specs == ({"name": "actuator_allocation", "commands": "paper", **spec},)
    stages = build_stages(specs, NAMES, {"actuator": "fins"})
    assert stages[0].to_dict() == specs[0]  # what the exported metadata lists
    plain, factored = Recorder([0.2, 0.1, -0.5]), Recorder([0.2, 0.1, -0.5])
    obs = np.stack([_obs(1.0), _obs(1.5)])
    errors = [NAMES.index(n) for n in FACTORS]
    obs[:, errors] = [[2.0, -0.4, 0.8], [-1.0, 0.3, 0.1]]  # x_e, y_e, z_e [m]
    expected, _ = StagedPolicy(
        plain,
        build_stages(check_stage_specs(["actuator_allocation"], "f"), NAMES, {"actuator": "fins"}),
    ).predict(obs)
    commands, _ = StagedPolicy(factored, stages).predict(obs)
    np.testing.assert_array_equal(commands, expected)
    seen = factored.seen[0]
    np.testing.assert_array_equal(seen[:, errors], obs[:, errors] * np.float32([0.125, 0.25, 0.25]))
    others = [k for k in range(len(NAMES)) if k not in errors]
    np.testing.assert_array_equal(seen[:, others], plain.seen[0][:, others])
    assert build_stages(specs, NAMES, {"actuator": "paper"}) == []


@pytest.mark.parametrize(
    ("factors", "message"),
    [
        ({}, "observation_factors must be a non-empty mapping"),
        ([0.5], "observation_factors must be a non-empty mapping"),
        ({"y_e": 0.0}, r"observation_factors\['y_e'\] must be a finite number > 0, got 0.0"),
        ({"y_e": -1}, r"observation_factors\['y_e'\] must be a finite number > 0"),
        ({"y_e": float("nan")}, r"observation_factors\['y_e'\] must be a finite number > 0"),
        ({"y_e": True}, r"observation_factors\['y_e'\] must be a finite number > 0"),
        ({"y_e": "0.5"}, r"observation_factors\['y_e'\] must be a finite number > 0"),
    ],
)
def test_bad_observation_factors_are_named(factors, message):
    spec = {"name": "actuator_allocation", "observation_factors": factors}
    with pytest.raises(ValueError, match=f"^f: stage actuator_allocation: {message}"):
        check_stage_specs([spec], "f")


@pytest.mark.parametrize(
    ("factors", "message"),
    [
        (
            {"depth": 0.5},
            r"observation_factors name \['depth'\], which the agent's observation lacks",
        ),
        (
            {"u": 0.5, "y_e": 0.5},
            r"observation_factors cannot scale \['u'\], which the stages read",
        ),
        (
            {"a_M_prev": 2.0},
            r"observation_factors cannot scale \['a_M_prev'\], which the stages read",
        ),
        ({"theta": 2.0}, r"observation_factors cannot scale \['theta'\], which the stages read"),
    ],
)
def test_factors_on_entries_the_agent_lacks_or_the_stages_read_are_named(factors, message):
    specs = check_stage_specs(
        [{"name": "actuator_allocation", "observation_factors": factors}], "f"
    )
    with pytest.raises(ValueError, match=f"^agent: actuator_allocation's {message}"):
        build_stages(specs, NAMES, {"actuator": "fins"}, "agent")


ALLOCATED_FLOOR = {"surge_floor_soft": 1.2, "surge_floor_hard": 0.9}  # [m/s]


def test_the_allocations_surge_floor_guards_its_actuator_only():
    """On the fins the guard floors the surge command (−1 at 1.2 m/s, 0 at 1.05, +1 from
    0.9 m/s down: the ramp of `test_hand_computed_low_speed_floor`), before the allocation; on
    the paper's actuator the guard is the one without a floor, command for command."""
    specs = check_stage_specs(
        ["envelope_guard", {"name": "actuator_allocation", **ALLOCATED_FLOOR}], "f"
    )
    assert specs[1] == {"name": "actuator_allocation", "commands": "paper", **ALLOCATED_FLOOR}
    assert "surge_floor_soft" not in specs[0]  # the guard's own settings are unchanged
    fins = build_stages(specs, NAMES, {"actuator": "fins"})
    assert fins[0].guard.surge_floor_soft == 1.2 and fins[0].guard.surge_floor_hard == 0.9
    assert fins[1].to_dict() == specs[1]  # what an export for the fins lists
    paper = build_stages(specs, NAMES, {"actuator": "paper"})
    assert [s.name for s in paper] == ["envelope_guard"] and not paper[0].guard.has_floor
    speeds = [1.5, 1.2, 1.05, 0.9, 0.3]  # [m/s]
    obs = np.stack([_obs(u) for u in speeds])
    commands = np.float32([[-1.0, 0.0, 0.0]] * len(speeds))
    floored = fins[0].act(commands, obs, None)[0]
    np.testing.assert_allclose(floored[:, 0], [-1.0, -1.0, 0.0, 1.0, 1.0], atol=1e-6)
    plain = build_stages(check_stage_specs(["envelope_guard"], "f"), NAMES, {"actuator": "fins"})
    np.testing.assert_array_equal(paper[0].act(commands, obs, None)[0], commands)
    np.testing.assert_array_equal(plain[0].act(commands, obs, None)[0], commands)


@pytest.mark.parametrize(
    ("stages", "message"),
    [
        (
            ["envelope_guard", {"name": "actuator_allocation", "surge_floor_soft": 1.2}],
            r"the surge floor needs both \['surge_floor_soft', 'surge_floor_hard'\], missing "
            r"\['surge_floor_hard'\]",
        ),
        (
            [
                "envelope_guard",
                {"name": "actuator_allocation", **ALLOCATED_FLOOR, "surge_floor_soft": 0.8},
            ],
            "surge_floor_hard must lie below surge_floor_soft, got 0.9 and 0.8 m/s",
        ),
        (
            [
                "envelope_guard",
                {
                    "name": "actuator_allocation",
                    **ALLOCATED_FLOOR,
                    "surge_floor_hard": float("nan"),
                },
            ],
            "surge_floor_hard",
        ),
        (
            [{"name": "actuator_allocation", **ALLOCATED_FLOOR}],
            "actuator_allocation's surge floor is the envelope guard's on its actuator; add an "
            "envelope_guard stage",
        ),
        (
            [
                {"name": "envelope_guard", "surge_soft": 1.0, "surge_hard": 1.5},
                {"name": "actuator_allocation", **ALLOCATED_FLOOR},
            ],
            r"surge_floor_hard < surge_floor_soft < surge_soft, got 0.9 < 1.2 < 1 m/s",
        ),
        (
            ["envelope_guard", {"name": "actuator_allocation", "surge_floor": 1.2}],
            r"unknown keys \['surge_floor'\]; valid: \['commands', 'observation_factors'",
        ),
    ],
)
def test_bad_allocation_floors_are_named(stages, message):
    with pytest.raises(ValueError, match=f"^f: .*{message}"):
        check_stage_specs(stages, "f")


def test_the_allocations_floor_is_refused_in_training_on_drawn_actuators():
    specs = check_stage_specs(
        ["envelope_guard", {"name": "actuator_allocation", **ALLOCATED_FLOOR}], "f"
    )
    with pytest.raises(
        ValueError, match=r"^cfg: actuator_allocation's surge floor guards a deployed"
    ):
        build_stages(specs, NAMES, {"actuator": "random"}, "cfg", drawn="fins")


@pytest.mark.parametrize("kind", ["native", "dummy"])
def test_training_scales_the_fin_episodes_and_their_final_observations_only(kind):
    """On drawn actuators the factors scale what the network sees of the fin episodes, and the
    final observation of each fin episode that ends (the value bootstrap of a truncation); the
    paper episodes, and everything else, are seen as without the factors, step for step."""
    from benchmarks.training.agent_interface import wrap_actions
    from benchmarks.training.train import make_training_env

    kwargs = {"actuator": "random", "disturbance": "none", "max_time": 2.0}
    errors = [NAMES.index(n) for n in FACTORS]
    values = np.float32([0.125, 0.25, 0.25])
    runs = []
    for stage in (
        "actuator_allocation",
        {"name": "actuator_allocation", "observation_factors": FACTORS},
    ):
        inner = make_training_env(4, 3, kwargs, kind=kind, env_id="AUVPath3DPreview-v0")
        cfg = SimpleNamespace(
            stages=check_stage_specs([stage], "t"), action_bounds=None, vehicle_share=None
        )
        venv = wrap_actions(inner, cfg, NAMES, {**kwargs, "observation": "preview"})
        rng = np.random.default_rng(1)
        seen, finals = [venv.reset()], []
        drawn = [np.array(venv.venv.get_attr("actuator"))]
        for _ in range(90):
            obs, _, dones, infos = venv.step(rng.uniform(-1, 1, size=(4, 3)).astype(np.float32))
            seen.append(obs)
            finals.append({i: infos[i]["terminal_observation"] for i in np.flatnonzero(dones)})
            drawn.append(np.array(venv.venv.get_attr("actuator")))
        venv.close()
        runs.append((seen, finals, drawn))
    (plain, plain_finals, drawn), (scaled, scaled_finals, _) = runs
    factor = np.ones(len(NAMES), np.float32)
    factor[errors] = values
    ended_on = {"fins": 0, "paper": 0}
    for k in range(len(plain)):
        on_fins = drawn[k] == "fins"
        np.testing.assert_array_equal(scaled[k][on_fins], plain[k][on_fins] * factor)
        np.testing.assert_array_equal(scaled[k][~on_fins], plain[k][~on_fins])
        if k == 0:
            continue
        assert plain_finals[k - 1].keys() == scaled_finals[k - 1].keys()
        for i, final in plain_finals[k - 1].items():
            actuator = drawn[k - 1][i]  # the ended episode's
            want = final * factor if actuator == "fins" else final
            np.testing.assert_array_equal(scaled_finals[k - 1][i], want)
            ended_on[actuator] += 1
    assert ended_on["fins"] > 0 and ended_on["paper"] > 0  # both kinds of episode ended


@pytest.mark.rl
def test_training_and_inference_apply_the_same_stages_to_the_same_commands():
    """The env's commands behind `StagedActions` (training) equal a `StagedPolicy`'s (inference)
    for the same network actions, step for step across an autoreset: one pipeline."""
    from benchmarks.training.stages import StagedActions
    from benchmarks.training.train import make_training_env

    specs = check_stage_specs(["envelope_guard", "actuator_allocation"], "test")
    settings = {"actuator": "fins"}
    kwargs = {"actuator": "fins", "disturbance": "none", "max_time": 3.0}
    venv = StagedActions(
        make_training_env(2, 0, kwargs, kind="dummy", env_id="AUVPath3DPreview-v0"),
        build_stages(specs, NAMES, settings),
        len(NAMES),
    )
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, size=(80, 2, 3)).astype(np.float32)

    class Replay:
        def __init__(self):
            self.k, self.seen = 0, []

        def predict(self, observation, state=None, episode_start=None, deterministic=True):
            self.seen.append(np.array(observation))
            self.k += 1
            return actions[self.k - 1], state

    sent = []
    inner_step = venv.venv.step_async
    venv.venv.step_async = lambda a: (sent.append(np.array(a)), inner_step(a))[1]
    trained_seen, dones_log = [venv.reset()], []
    for k in range(80):
        obs, _, dones, _ = venv.step(actions[k])
        trained_seen.append(obs)
        dones_log.append(dones)
    assert any(d.any() for d in dones_log)  # an episode ended (3 s) and restarted
    venv.close()
    # Inference: the same raw observations, the same episode starts.
    replay = Replay()
    policy = StagedPolicy(replay, build_stages(specs, NAMES, settings))
    raw_env = make_training_env(2, 0, kwargs, kind="dummy", env_id="AUVPath3DPreview-v0")
    raw_obs = raw_env.reset()
    state, start = None, np.ones(2, dtype=bool)
    for k in range(80):
        commands, state = policy.predict(raw_obs, state, episode_start=start)
        np.testing.assert_array_equal(commands, sent[k])
        np.testing.assert_array_equal(replay.seen[k], trained_seen[k])
        raw_obs, _, dones, _ = raw_env.step(commands)
        start = dones
    raw_env.close()


@pytest.mark.parametrize("kind", ["native", "dummy"])
def test_training_on_drawn_actuators_allocates_the_fin_episodes_only(kind):
    """actuator="random" draws the paper's actuator or the fins per episode: behind
    `StagedActions` the allocation flies the fin episodes (their commands and fed-back previous
    action are `Allocation`'s) and passes the paper episodes unchanged, across autoresets."""
    from benchmarks.training.agent_interface import wrap_actions
    from benchmarks.training.stages import StagedActions
    from benchmarks.training.train import make_training_env
    from controllers.stages import DrawnAllocationStage

    kwargs = {"actuator": "random", "disturbance": "none", "max_time": 2.0}
    inner = make_training_env(4, 3, kwargs, kind=kind, env_id="AUVPath3DPreview-v0")
    specs = check_stage_specs(["actuator_allocation"], "test")
    cfg = SimpleNamespace(stages=specs, action_bounds=None, vehicle_share=None)  # what it reads
    venv = wrap_actions(inner, cfg, NAMES, {**kwargs, "observation": "preview"})
    assert isinstance(venv, StagedActions)
    assert [type(stage) for stage in venv.stages] == [DrawnAllocationStage]
    sent = []
    inner_step = venv.venv.step_async
    venv.venv.step_async = lambda a: (sent.append(np.array(a)), inner_step(a))[1]
    fins = Allocation(NAMES, "fins")
    rng = np.random.default_rng(1)
    seen = venv.reset()
    drawn = np.array(venv.venv.get_attr("actuator"))
    draws, delivered_prev = [drawn], None
    for _ in range(100):
        actions = rng.uniform(-1, 1, size=(4, 3)).astype(np.float32)
        on_fins = drawn == "fins"
        if delivered_prev is not None:  # what the network saw: the delivered command on fins
            np.testing.assert_array_equal(seen[on_fins][:, PREV], delivered_prev[on_fins])
        seen_next, _, dones, _ = venv.step(actions)
        allocated, delivered = fins.allocate(actions, seen)
        np.testing.assert_array_equal(sent[-1][on_fins], allocated[on_fins])
        np.testing.assert_array_equal(sent[-1][~on_fins], actions[~on_fins])
        delivered_prev = np.where(dones[:, None], 0.0, delivered).astype(np.float32)
        seen = seen_next
        drawn = np.array(venv.venv.get_attr("actuator"))
        draws.append(drawn)
    venv.close()
    draws = np.array(draws)
    assert {"paper", "fins"} == set(draws.ravel())  # both drawn, some vehicle switched
    assert any(len(set(draws[:, i])) == 2 for i in range(4))


@pytest.mark.rl
def test_the_training_wrapper_guards_the_env_commands():
    """Full nose-up from rest: the wrapper lets it through until θ + T·q passes 35°, then the
    applied moment M (info "tau", N·m) falls to the ramp's value and the pitch stays below 50°."""
    from benchmarks.training.stages import StagedActions
    from benchmarks.training.train import make_training_env

    venv = StagedActions(
        make_training_env(
            2,
            0,
            {"disturbance": "none", "max_time": 60.0},
            kind="dummy",
            env_id="AUVPath3DPreview-v0",
        ),
        [GuardStage(GUARD, NAMES, "test")],
        len(NAMES),
    )
    obs = venv.reset()
    it, iq = NAMES.index("theta"), NAMES.index("q")
    pitch, capped = [], 0
    for _ in range(600):
        predicted = obs[:, it] + obs[:, iq]  # θ + 1 s · q of the observation the guard reads
        obs, _, dones, infos = venv.step(np.float32([[0.05, 1.0, 0.0]] * 2))
        moment = np.array([info["tau"][1] for info in infos]) / 10.0  # normalised M
        expected = 1.0 - 2.0 * np.clip((predicted - math.radians(35.0)) / math.radians(15.0), 0, 1)
        np.testing.assert_allclose(moment, expected, atol=1e-5)
        capped += int((expected < 1.0).sum())
        pitch.append(np.degrees(obs[:, it]).max())
        assert not dones.any()
    assert capped > 100 and 35.0 < max(pitch) < 50.0
    venv.close()


@pytest.mark.rl
def test_the_reference_generalist_loads_with_its_stages_for_the_scenario_actuator():
    """Guarded everywhere, allocated on the fins; ``stages=[]`` gives the bare network. On the
    calm `fins` helix the allocated agent (its errors at the base scales, its surge floored)
    keeps the path within 8 cm (measured 0.063 m over 100-200 s), where the same network
    guarded but unallocated leaves the corridor (measured at 122 s): the shipped seed is one of
    the recipe's seeds that stall on the fins without the allocation's settings
    (docs/results.md, "The generalist's recipe, ten seeds")."""
    import controllers
    from auv_gym.metrics import compute_metrics
    from auv_gym.rollout import rollouts
    from benchmarks.catalog.policies import agent_run
    from controllers.agent import AgentPolicy
    from controllers.loader import load_policy

    paper = load_policy(GENERALIST)
    assert [s.name for s in paper.stages] == ["envelope_guard"]
    fins = controllers.make("agent", path=str(GENERALIST), env={"actuator": "fins"})
    assert [s.name for s in fins.stages] == ["envelope_guard", "actuator_allocation"]
    assert isinstance(load_policy(GENERALIST, stages=[]), AgentPolicy)
    _, _, agent_env = agent_run("test", GENERALIST)
    env = {**agent_env, "surge_limit": "vehicle", "disturbance": "none", "actuator": "fins"}
    before, after = (
        compute_metrics(rollouts(p, [0], max_time=200.0, **env)[0]) for p in (paper, fins)
    )
    assert after["termination_reason"] == "time_limit" and after["rms_distance"] < 0.08
    assert before["termination_reason"] == "corridor"


@pytest.mark.rl
def test_a_file_trains_inside_its_stages_and_exports_them(tmp_path, train_tiny_preview_agent):
    import yaml

    from benchmarks.training.config import read_zoo_config
    from controllers.loader import load_policy

    guard = {"name": "envelope_guard", "pitch_soft_deg": 30.0, "pitch_hard_deg": 45.0}
    agent = train_tiny_preview_agent(tmp_path, stages=[guard])
    recorded = json.loads((agent / "metadata.json").read_text())["stages"]
    assert recorded == [{**GUARD.to_dict(), **guard}]
    policy = load_policy(agent)
    assert isinstance(policy, StagedPolicy) and policy.stages[0].guard.pitch_soft_deg == 30.0
    section = {"n_envs": 2, "n_timesteps": 64, "policy": "MlpPolicy", "normalize": True}
    for key, value, message in (
        ("stages", [{"name": "envelope_guard", "surge_soft": 3.0}], "soft limit must lie below"),
        ("envelope_guard", True, "envelope_guard is now a stage: stages: "),
    ):
        config = tmp_path / "bad.yml"
        config.write_text(yaml.safe_dump({"AUVPath3DPreview-v0": {**section, key: value}}))
        with pytest.raises(ValueError, match=f"bad.yml: AUVPath3DPreview-v0: .*{message}"):
            read_zoo_config(config, "AUVPath3DPreview-v0", "ppo")


@pytest.mark.rl
def test_an_agent_trained_on_drawn_actuators_exports_its_allocation(
    tmp_path, train_tiny_preview_agent
):
    """Trained inside the allocation on actuator="random": the exported agent lists the
    allocation, flies the fins allocated and the paper's actuator as its network commands."""
    import controllers

    env = {"randomize_start": True, "max_time": 20.0, "actuator": "random"}
    agent = train_tiny_preview_agent(tmp_path, env_kwargs=env, stages=["actuator_allocation"])
    recorded = json.loads((agent / "metadata.json").read_text())["stages"]
    assert recorded == [{"name": "actuator_allocation", "commands": "paper"}]
    fins = controllers.make("agent", path=str(agent), env={"actuator": "fins"})
    paper = controllers.make("agent", path=str(agent), env={"actuator": "paper"})
    assert [type(s) for s in fins.stages] == [AllocationStage] and not getattr(paper, "stages", [])


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"envelope_guard": {}}, "'envelope_guard' is now a stage"),
        ({"actuator_allocation": "paper"}, "'actuator_allocation' is now a stage"),
        ({"stages": [{"name": "envelope_guard", "pitch_soft_deg": 60.0}]}, "soft limit"),
        ({"stages": [{"name": "guard"}]}, "unknown stage 'guard'"),
    ],
)
def test_bad_stages_in_metadata_are_named_before_torch_loads(tmp_path, change, message):
    from controllers.agent import check_agent

    agent = tmp_path / "agent"
    shutil.copytree(GENERALIST, agent)
    meta = json.loads((agent / "metadata.json").read_text())
    (agent / "metadata.json").write_text(json.dumps({**meta, **change}))
    with pytest.raises(ValueError, match=f"metadata.json: .*{message}"):
        check_agent(agent)
