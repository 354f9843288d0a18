"""A share of the training vehicles on another plant or actuator
(`benchmarks.training.vehicle_share`) and the VecEnv that concatenates one native vector env per
plant or actuator (`benchmarks.training.plant_mix`).

Two concatenated 5-DOF envs are one env of all their vehicles bit for bit; the 6-DOF rows of a
plant share fly the 6-DOF plant (roll) and the 5-DOF rows are a 5-DOF env's; a tiny PPO run with
a plant share trains, resumes exactly and loads; the fins rows of an actuator share fly the fins
and their allocation in training; every bad share is refused in one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("stable_baselines3")
pytestmark = pytest.mark.rl

from auv_gym import VARIANTS  # noqa: E402
from auv_gym.envs.sb3 import make_sb3_vec_env  # noqa: E402
from benchmarks.training.envs import describe_env, make_training_env  # noqa: E402
from benchmarks.training.evaluation import TRAIN_SEED_BASE  # noqa: E402
from benchmarks.training.plant_mix import ConcatVecEnv  # noqa: E402
from benchmarks.training.vehicle_share import VehicleShare  # noqa: E402

ENV_ID = "AUVPath3DSpeedLimit-v0"
# 2.5 s episodes (50 steps) and an 18 m corridor: in 300 steps every vehicle truncates about six
# times and astern commands end some episodes early.
SHORT = {"corridor": 18.0, "max_time": 2.5, "randomize_start": True}
SECTION = {
    "n_envs": 4,
    "n_timesteps": 256,
    "policy": "MlpPolicy",
    "normalize": True,
    "n_steps": 32,
    "batch_size": 64,
    "n_epochs": 1,
    "policy_kwargs": "dict(net_arch=[16, 16])",
    "env_kwargs": {"randomize_start": True, "max_time": 20.0},
    "plant_share": {"6dof": 0.5},
}
HALF = VehicleShare("5dof", (("6dof", 0.5),))


def random_actions(seed: int, steps: int, n: int) -> np.ndarray:
    a = np.random.default_rng(seed).uniform(-1, 1, size=(steps, n, 3)).astype(np.float32)
    a[..., 0] = 0.6 * a[..., 0] - 0.1  # often astern: the corridor ends some episodes
    a[..., 1:] *= 0.6
    return a


def assert_infos_equal(got: list[dict], want: list[dict], where: str) -> None:
    assert len(got) == len(want), where
    for i, (a, b) in enumerate(zip(got, want, strict=True)):
        assert list(a) == list(b), (where, i)
        for key, value in b.items():
            np.testing.assert_array_equal(a[key], value, err_msg=f"{where}/{i}/{key}")


def test_two_concatenated_envs_are_one_env_of_all_vehicles_bit_for_bit():
    """2 + 3 vehicles against 5, seeded alike, over 300 steps of random actions: observations,
    float32 rewards, dones, every info (terminal observations included) and reset infos."""
    whole = make_sb3_vec_env(5, **SHORT)
    parts = ConcatVecEnv([make_sb3_vec_env(2, **SHORT), make_sb3_vec_env(3, **SHORT)])
    assert parts.num_envs == 5
    assert parts.seed(7) == whole.seed(7) == [7, 8, 9, 10, 11]
    np.testing.assert_array_equal(parts.reset(), whole.reset())
    assert_infos_equal(parts.reset_infos, whole.reset_infos, "reset")
    ends, terminal = 0, 0
    for t, action in enumerate(random_actions(0, 300, 5)):
        obs, reward, done, info = parts.step(action)
        obs_w, reward_w, done_w, info_w = whole.step(action)
        np.testing.assert_array_equal(obs, obs_w, err_msg=f"step {t}")
        assert reward.dtype == reward_w.dtype == np.float32
        np.testing.assert_array_equal(reward, reward_w, err_msg=f"step {t}")
        np.testing.assert_array_equal(done, done_w, err_msg=f"step {t}")
        assert_infos_equal(info, info_w, f"step {t}")
        assert_infos_equal(parts.reset_infos, whole.reset_infos, f"reset infos {t}")
        ends += int(done.sum())
        terminal += sum("terminal_observation" in row for row in info)
    assert ends == terminal >= 30  # the comparison covered autoresets of every sub-env
    np.testing.assert_array_equal(
        np.array(parts.get_attr("state", [4, 0, 2])), np.array(whole.get_attr("state", [4, 0, 2]))
    )
    generator = parts.get_attr("np_random", 3)[0].bit_generator.state
    assert generator == whole.get_attr("np_random", 3)[0].bit_generator.state


def test_requests_go_to_the_sub_env_of_each_index_in_the_order_asked():
    first, second = make_sb3_vec_env(2, max_time=5.0), make_sb3_vec_env(3, max_time=5.0)
    env = ConcatVecEnv([first, second])
    assert env.get_attr("num_envs", [4, 1, 2, 0]) == [3, 2, 3, 2]  # each sub-env's own count
    assert [s["num_envs"] for s in env.env_method("snapshot", indices=[3, 0])] == [3, 2]
    assert env.env_is_wrapped(ConcatVecEnv, [1, 4]) == [False, False]
    env.set_attr("render_vehicle", 1, indices=[1, 0])  # every vehicle of the first sub-env
    assert (first.core.render_vehicle, second.core.render_vehicle) == (1, 0)
    env.set_attr("render_vehicle", 1)
    assert second.core.render_vehicle == 1
    with pytest.raises(ValueError, match="shared by all vehicles"):
        env.set_attr("render_vehicle", 0, indices=[2, 3])  # 2 of the second sub-env's 3
    with pytest.raises(ValueError, match=r"env index 5 out of range \[0, 5\)"):
        env.get_attr("state", [0, 5])
    with pytest.raises(ValueError, match=r"one row per vehicle \(5\), got shape \(4, 3\)"):
        env.step_async(np.zeros((4, 3), np.float32))


def test_a_snapshot_continues_bit_for_bit():
    env = ConcatVecEnv([make_sb3_vec_env(2, **SHORT), make_sb3_vec_env(1, **SHORT, plant="6dof")])
    env.seed(3)
    env.reset()
    actions = random_actions(1, 100, 3)
    for action in actions[:40]:
        env.step(action)
    saved = env.snapshot()
    first = [env.step(action)[:3] for action in actions[40:]]
    env.restore(saved)
    again = [env.step(action)[:3] for action in actions[40:]]
    for t, (a, b) in enumerate(zip(first, again, strict=True)):
        for x, y in zip(a, b, strict=True):
            np.testing.assert_array_equal(x, y, err_msg=f"step {t}")
    assert sum(int(done.sum()) for _, _, done in first) >= 3


def test_sub_envs_of_other_spaces_are_refused_naming_the_space():
    from benchmarks.training.action_box import ActionBox

    paper = make_sb3_vec_env(1)
    with pytest.raises(ValueError, match="the observation_space of sub-env 1"):
        ConcatVecEnv([paper, make_sb3_vec_env(1, observation="preview")])
    boxed = ActionBox(make_sb3_vec_env(1), [-0.5, -1.0, -1.0], [0.5, 1.0, 1.0])
    with pytest.raises(ValueError, match="the action_space of sub-env 2"):
        ConcatVecEnv([paper, make_sb3_vec_env(1), boxed])


def test_the_6dof_rows_fly_the_6dof_plant_and_the_5dof_rows_a_5dof_envs():
    """make_training_env with {6dof: 0.5} of 4 vehicles: rows 0-1 are a 2-vehicle 5-DOF
    training env's, rows 2-3 a 6-DOF env's seeded with the seeds of vehicles 2-3 (not a 5-DOF
    env's rows 2-3), and only they roll."""
    seed, kwargs = 3, dict(SHORT)
    mixed = make_training_env(4, seed, kwargs, env_id=ENV_ID, threads=1, vehicle_share=HALF)
    base = make_training_env(2, seed, kwargs, env_id=ENV_ID, threads=1)
    five = make_training_env(4, seed, kwargs, env_id=ENV_ID, threads=1)
    env_seed = TRAIN_SEED_BASE + 1000 * seed
    six = make_sb3_vec_env(
        2, seed=env_seed + 2, infos="minimal", **{**VARIANTS[ENV_ID], **kwargs, "plant": "6dof"}
    )
    assert [config.plant for config in mixed.get_attr("config")] == ["5dof"] * 2 + ["6dof"] * 2
    assert describe_env(mixed) == (
        "VecMonitor<ConcatVecEnv[2×SB3VecEnv<AUVPath3DVectorEnv>, 2×SB3VecEnv<AUVPath3DVectorEnv>]>"
    )
    obs = mixed.reset()
    np.testing.assert_array_equal(obs[:2], base.reset())
    np.testing.assert_array_equal(obs[2:], six.reset())
    np.testing.assert_array_equal(obs[2:], five.reset()[2:])  # the same start, another plant
    rolled, ends = 0.0, 0
    differs = False
    for action in random_actions(2, 200, 4):
        obs, reward, done, _ = mixed.step(action)
        obs_b, reward_b, done_b, _ = base.step(action[:2])
        obs_6, reward_6, done_6, _ = six.step(action[2:])
        obs_5 = five.step(action)[0]
        np.testing.assert_array_equal(obs[:2], obs_b)
        np.testing.assert_array_equal(reward[:2], reward_b)
        np.testing.assert_array_equal(done[:2], done_b)
        np.testing.assert_array_equal(obs[2:], obs_6)
        np.testing.assert_array_equal(reward[2:], reward_6)
        np.testing.assert_array_equal(done[2:], done_6)
        differs |= not np.array_equal(obs[2:], obs_5[2:])
        sims = mixed.get_attr("sim", [0, 2])
        assert not sims[0].roll.any()  # the 5-DOF plant has no roll
        rolled = max(rolled, float(np.abs(sims[1].roll[:, 0]).max()))  # φ [rad]
        ends += int(done.sum())
    assert differs and rolled > 1e-3 and ends >= 8


def test_a_residual_share_is_a_residual_env_per_plant_whose_base_flies_each_hull():
    """make_training_env with a residual section and {6dof: 0.5} of 4 vehicles: rows 2-3 are a
    2-vehicle residual env on the 6-DOF plant seeded with vehicles 2-3's seeds; with c = 0 each
    part's base (the PID on the realistic actuator) flies its own hull, and the 6-DOF rows roll."""
    from benchmarks.training.residual import ResidualTraining
    from benchmarks.training.residual_env import make_residual_sb3_env

    seed, kwargs = 3, {**SHORT, "actuator": "realistic"}
    residual = ResidualTraining(base="pid_as_built", bound=(1.0, 0.5, 0.5))
    mixed = make_training_env(
        4, seed, kwargs, env_id=ENV_ID, threads=1, residual=residual, vehicle_share=HALF
    )
    env_seed = TRAIN_SEED_BASE + 1000 * seed
    six = make_residual_sb3_env(2, residual, **{**VARIANTS[ENV_ID], **kwargs, "plant": "6dof"})
    six.seed(env_seed + 2)
    five = make_training_env(2, seed, kwargs, env_id=ENV_ID, threads=1, residual=residual)
    assert [config.plant for config in mixed.get_attr("config")] == ["5dof"] * 2 + ["6dof"] * 2
    obs = mixed.reset()
    assert obs.shape == (4, 21)
    np.testing.assert_array_equal(obs[:2], five.reset())
    np.testing.assert_array_equal(obs[2:], six.reset())
    rolled = 0.0
    for _ in range(120):
        base = obs[:, 15:18]
        obs, reward, done, _ = mixed.step(np.zeros((4, 3), np.float32))
        for rows, part in ((slice(0, 2), five), (slice(2, 4), six)):
            obs_p, reward_p, done_p, _ = part.step(np.zeros((2, 3), np.float32))
            np.testing.assert_array_equal(obs[rows], obs_p)
            np.testing.assert_array_equal(reward[rows], reward_p)
            np.testing.assert_array_equal(done[rows], done_p)
        # c = 0: the applied action, the next observation's previous one, is the base's
        np.testing.assert_array_equal(obs[~done, 18:21], base[~done])
        rolled = max(rolled, float(np.abs(mixed.get_attr("sim", [2])[0].roll[:, 0]).max()))
    assert rolled > 1e-3


def _config(tmp_path: Path, name: str = "mix.yml", **changes) -> Path:
    section = {**SECTION, **changes}
    path = tmp_path / name
    path.write_text(yaml.safe_dump({ENV_ID: {k: v for k, v in section.items() if v is not None}}))
    return path


def _train(tmp_path: Path, config: Path, out: str, *extra: str) -> Path:
    from benchmarks.training.train_cli import main

    args = ["--config", str(config), "--env-id", ENV_ID, "--out", str(tmp_path / out)]
    main([*args, "--eval-freq", "0", "--checkpoint-freq", "128", "--no-progress-bar", *extra])
    return tmp_path / out


def test_a_tiny_ppo_run_with_a_plant_share_trains_resumes_exactly_and_loads(tmp_path):
    """256 env steps on 2 + 2 vehicles through the CLI; the same run paused at 128 and resumed
    ends with the same weights (the concatenation's snapshot in the checkpoint); the agent
    loads and acts, and its metadata records the share and the env."""
    from controllers.loader import load_policy

    config = _config(tmp_path)
    whole = _train(tmp_path, config, "whole")
    _train(tmp_path, config, "paused", "--stop-at", "128")
    paused = _train(tmp_path, config, "paused", "--resume")
    meta = json.loads((whole / "final" / "metadata.json").read_text())
    assert meta["num_timesteps"] == 256
    assert meta["plant_share"] == {"shares": {"6dof": 0.5}, "vehicles": {"5dof": 2, "6dof": 2}}
    assert meta["config"]["plant_share"] == {"6dof": 0.5}
    assert meta["vec_env"] == (
        "VecNormalize<VecMonitor<ConcatVecEnv[2×SB3VecEnv<AUVPath3DVectorEnv>, "
        "2×SB3VecEnv<AUVPath3DVectorEnv>]>>"
    )
    import torch
    from stable_baselines3 import PPO

    a = PPO.load(whole / "final" / "model.zip", device="cpu").policy.state_dict()
    b = PPO.load(paused / "final" / "model.zip", device="cpu").policy.state_dict()
    assert list(a) == list(b)
    for key in a:
        torch.testing.assert_close(a[key], b[key], rtol=0, atol=0, msg=key)
    policy = load_policy(whole / "final")
    obs = make_sb3_vec_env(2, seed=0, **VARIANTS[ENV_ID]).reset()
    action, _ = policy.predict(obs, deterministic=True)
    assert action.shape == (2, 3) and np.all(np.abs(action) <= 1.0)


def test_a_schedule_phase_sets_changes_and_drops_the_share(tmp_path):
    from benchmarks.training.config import read_zoo_config
    from benchmarks.training.schedule import check_schedule, read_schedule

    section = {k: v for k, v in SECTION.items() if k != "plant_share"}
    phases = [
        {"name": "base"},
        {"name": "mixed", "plant_share": {"6dof": 0.25}},
        {"name": "more", "n_envs": 8, "plant_share": {"6dof": 0.375}},
        {"name": "alone", "plant_share": None},
    ]
    path = tmp_path / "schedule.yml"
    path.write_text(yaml.safe_dump({ENV_ID: section, "schedule": {"phases": phases}}))
    configs = check_schedule(read_schedule(path), "ppo", tmp_path / "out")
    shares = [read_zoo_config(c, ENV_ID).vehicle_share for c in configs]
    assert shares[0] is None and shares[3] is None
    assert shares[1].vehicles(4) == (("5dof", 3), ("6dof", 1))
    assert shares[2].vehicles(8) == (("5dof", 5), ("6dof", 3))


def test_the_section_plant_may_be_the_6dof_one():
    from benchmarks.training.vehicle_share import parse_vehicle_share

    section = {"plant_share": {"5dof": 0.25}}
    share = parse_vehicle_share(section, 8, ENV_ID, {"plant": "6dof"}, "f.yml")
    assert share == VehicleShare("6dof", (("5dof", 0.25),))
    assert share.to_dict(8) == {"shares": {"5dof": 0.25}, "vehicles": {"6dof": 6, "5dof": 2}}
    assert parse_vehicle_share({"plant_share": None}, 8, ENV_ID, {}, "f.yml") is None
    assert parse_vehicle_share({}, 8, ENV_ID, {}, "f.yml") is None


@pytest.mark.parametrize(
    ("changes", "argv", "message"),
    [
        (
            {"plant_share": {"7dof": 0.25}},
            [],
            "mix.yml: AUVPath3DSpeedLimit-v0: plant_share: unknown plant '7dof'; "
            "valid: ['5dof', '6dof']",
        ),
        ({"plant_share": {"5dof": 0.25}}, [], "plant_share: 5dof is the section's own plant"),
        (
            {"plant_share": {"6dof": 0.5}, "env_kwargs": {"plant": "6dof"}},
            [],
            "plant_share: 6dof is the section's own plant",
        ),
        ({"plant_share": {"6dof": float("nan")}}, [], "6dof share must be a number in (0, 1)"),
        ({"plant_share": {"6dof": 0.0}}, [], "6dof share must be a number in (0, 1), got 0.0"),
        ({"plant_share": {"6dof": 1}}, [], "6dof share must be a number in (0, 1), got 1"),
        ({"plant_share": {"6dof": -0.5}}, [], "6dof share must be a number in (0, 1)"),
        ({"plant_share": {"6dof": True}}, [], "6dof share must be a number in (0, 1), got True"),
        ({"plant_share": {"6dof": "1/4"}}, [], "6dof share must be a number in (0, 1)"),
        ({"plant_share": 0.25}, [], "plant_share must be a mapping of plant name to share"),
        (
            {"plant_share": {"6dof": 0.1}},
            [],
            "plant_share: 6dof share 0.1 of n_envs 4 rounds to 0 vehicles",
        ),
        (
            {"plant_share": {"6dof": 0.9}},
            [],
            "plant_share: the shares take all 4 vehicles ({'6dof': 4}) and leave 0 on the "
            "section's plant 5dof",
        ),
        (
            {
                "plant_share": {"5dof": 0.5},
                "env_kwargs": {"vehicle": "torpedo", "plant": "6dof", "actuator": "realistic"},
            },
            [],
            "plant_share: 5dof: env_kwargs: vehicle 'torpedo' has no [model_5dof]",
        ),
        (
            {},
            ["--vec-env", "dummy"],
            "mix.yml: plant_share needs the native vector env (vec_env auto or native), "
            "not vec_env='dummy'",
        ),
        (
            {"actuator_share": {"fins": 0.25}},
            [],
            "mix.yml: AUVPath3DSpeedLimit-v0: give plant_share or actuator_share, not both",
        ),
        (
            {"plant_share": None, "actuator_share": {"realistic": 0.25}},
            [],
            "actuator_share: unknown actuator 'realistic'; valid: ['paper', 'fins']",
        ),
        (
            {"plant_share": None, "actuator_share": {"paper": 0.25}},
            [],
            "actuator_share: paper is the section's own actuator",
        ),
        (
            {
                "plant_share": None,
                "actuator_share": {"fins": 0.25},
                "env_kwargs": {"actuator": "random"},
            },
            [],
            "actuator_share: the section's actuator is drawn per episode (actuator: random)",
        ),
        (
            {"plant_share": None, "actuator_share": {"fins": 0.9}},
            [],
            "actuator_share: the shares take all 4 vehicles ({'fins': 4}) and leave 0 on the "
            "section's actuator paper",
        ),
    ],
)
def test_a_bad_plant_share_is_one_line_exit_2_before_training(
    tmp_path, capsys, changes, argv, message
):
    from benchmarks.training.seeds_cli import main

    config = _config(tmp_path, **changes)
    out = tmp_path / "run"
    code = main(
        ["--config", str(config), "--env-id", ENV_ID, "--seeds", "1", "--out", str(out), *argv]
    )
    assert code == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "Traceback" not in err
    assert not (out / "seed_0").exists()


def test_a_schedule_phase_with_a_bad_share_is_refused_naming_the_phase(tmp_path, capsys):
    from benchmarks.training.seeds_cli import main

    section = {k: v for k, v in SECTION.items() if k != "plant_share"}
    for share, argv, message in (
        ({"6dof": 0.9}, [], "phase 'mixed': AUVPath3DSpeedLimit-v0: plant_share: the shares"),
        (
            {"6dof": 0.5},
            ["--vec-env", "dummy"],
            "phase 'mixed': plant_share needs the native vector env",
        ),
    ):
        phases = [{"name": "base"}, {"name": "mixed", "plant_share": share}]
        path = tmp_path / "schedule.yml"
        path.write_text(yaml.safe_dump({ENV_ID: section, "schedule": {"phases": phases}}))
        assert (
            main(["--config", str(path), "--seeds", "1", "--out", str(tmp_path / "out"), *argv])
            == 2
        )
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err
        assert not (tmp_path / "out" / "phase_1_base").exists()


def test_the_sum_of_the_shares_must_stay_below_1(monkeypatch):
    """With two plants a single share below 1 is the whole check; a third plant name makes the
    sum its own: refused before any env is built."""
    from benchmarks.training import vehicle_share

    monkeypatch.setattr(vehicle_share, "PLANTS", ("5dof", "6dof", "other"))
    with pytest.raises(ValueError, match=r"^f.yml: plant_share: the shares sum to 1.1 >= 1;"):
        section = {"plant_share": {"6dof": 0.6, "other": 0.5}}
        vehicle_share.parse_vehicle_share(section, 8, ENV_ID, {}, "f.yml")


FINS_QUARTER = VehicleShare("paper", (("fins", 0.25),), "actuator")


def test_the_fins_rows_of_an_actuator_share_fly_the_fins_and_the_others_the_paper_actuator():
    """make_training_env with {fins: 0.25} of 8 vehicles: rows 0-5 are a 6-vehicle training
    env's on the paper's actuator, rows 6-7 a fins env's seeded with vehicles 6-7's seeds; the
    env reports each vehicle's actuator (what the allocation stage follows)."""
    seed, kwargs = 5, dict(SHORT)
    mixed = make_training_env(8, seed, kwargs, env_id=ENV_ID, threads=1, vehicle_share=FINS_QUARTER)
    paper = make_training_env(6, seed, kwargs, env_id=ENV_ID, threads=1)
    env_seed = TRAIN_SEED_BASE + 1000 * seed
    fins = make_sb3_vec_env(
        2, seed=env_seed + 6, infos="minimal", **{**VARIANTS[ENV_ID], **kwargs, "actuator": "fins"}
    )
    assert mixed.get_attr("actuator") == ["paper"] * 6 + ["fins"] * 2
    obs = mixed.reset()
    np.testing.assert_array_equal(obs[:6], paper.reset())
    np.testing.assert_array_equal(obs[6:], fins.reset())
    all_paper = make_training_env(8, seed, kwargs, env_id=ENV_ID, threads=1)
    np.testing.assert_array_equal(obs[6:], all_paper.reset()[6:])  # the same starts
    differs = False
    for action in random_actions(4, 120, 8):
        obs, reward, done, _ = mixed.step(action)
        obs_p, reward_p, done_p, _ = paper.step(action[:6])
        obs_f, reward_f, done_f, _ = fins.step(action[6:])
        np.testing.assert_array_equal(obs, np.concatenate([obs_p, obs_f]))
        np.testing.assert_array_equal(reward, np.concatenate([reward_p, reward_f]))
        np.testing.assert_array_equal(done, np.concatenate([done_p, done_f]))
        # the fins' moments are bounded by the flow: the same commands fly another path
        differs |= not np.array_equal(obs[6:], all_paper.step(action)[0][6:])
    assert differs


def test_an_actuator_share_trains_its_fins_vehicles_inside_the_allocation(tmp_path):
    """A tiny PPO run on 2 paper + 2 fins vehicles with the allocation stage: its metadata
    records the share, and the stage allocates the fins rows only (the paper rows' commands are
    the network's, the fins rows' are not)."""
    from benchmarks.training.agent_interface import wrap_actions
    from benchmarks.training.config import read_zoo_config
    from controllers.loader import load_policy

    config = _config(
        tmp_path,
        plant_share=None,
        actuator_share={"fins": 0.5},
        env_kwargs={**SECTION["env_kwargs"], "observation": "preview_integral"},
        stages=[{"name": "actuator_allocation"}],
    )
    run = _train(tmp_path, config, "run")
    meta = json.loads((run / "final" / "metadata.json").read_text())
    assert meta["actuator_share"] == {
        "shares": {"fins": 0.5},
        "vehicles": {"paper": 2, "fins": 2},
    }
    assert load_policy(run / "final").predict(
        make_sb3_vec_env(1, seed=0, **VARIANTS[ENV_ID], observation="preview_integral").reset(),
        deterministic=True,
    )[0].shape == (1, 3)

    cfg = read_zoo_config(config, ENV_ID)
    venv = make_training_env(
        4, 0, cfg.env_kwargs, env_id=ENV_ID, threads=1, vehicle_share=cfg.vehicle_share
    )
    layout_names = json.loads((run / "final" / "metadata.json").read_text())["obs_names"]
    staged = wrap_actions(venv, cfg, layout_names, {**VARIANTS[ENV_ID], **cfg.env_kwargs})
    staged.reset()
    sent = []
    staged.venv.step_async = lambda actions: sent.append(np.array(actions))  # what the env gets
    action = np.tile(np.array([[0.5, 0.8, -0.8]], np.float32), (4, 1))
    staged.step_async(action)
    np.testing.assert_array_equal(sent[0][:2], action[:2])
    assert not np.allclose(sent[0][2:], action[2:])


def test_a_jump_start_with_a_share_is_refused(tmp_path):
    """The jump start's rollouts fly one env: a share in its section would be dropped there."""
    from benchmarks.training.config import read_zoo_config

    config = _config(
        tmp_path,
        plant_share=None,
        actuator_share={"fins": 0.5},
        jump_start={"expert": "fbsm_colos", "steps": 256},
    )
    with pytest.raises(ValueError, match=r"jump_start: the jump start flies the section's own "):
        read_zoo_config(config, ENV_ID)
