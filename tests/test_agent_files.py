"""A saved agent's files are validated completely on load (issue 11, item 5).

Each test damages one file of a copy of the shipped agent (benchmarks/agents/ppo_generalist) and
expects an error naming that file and the problem, raised by `controllers.agent.check_agent`
before torch is imported, and by `load_policy`, which calls it first. Was, e.g.: a
vecnormalize.npz with NaN clip_obs or negative epsilon loaded, then failed deep in torch or
predicted NaN actions.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from controllers.agent import check_agent

ROOT = Path(__file__).resolve().parent.parent
SHIPPED = ROOT / "benchmarks" / "agents" / "ppo_generalist"
STATS, MODEL, META = "vecnormalize.npz", "model.zip", "metadata.json"
# The shipped agent's observation: the path preview and the error integrals (49 values).
OBS_NAMES = json.loads((SHIPPED / META).read_text())["obs_names"]
OBS_DIM = len(OBS_NAMES)
FEWER, MORE = OBS_DIM - 1, OBS_DIM + 1


def edit_stats(**changes: object) -> Callable[[Path], None]:
    """Rewrite vecnormalize.npz with keys replaced (a value of None removes the key)."""

    def damage(agent: Path) -> None:
        with np.load(agent / STATS) as data:
            stats = dict(data)
        for key, value in changes.items():
            if value is None:
                stats.pop(key)
            else:
                stats[key] = np.asarray(value)
        np.savez(agent / STATS, **stats)

    return damage


def edit_meta(**changes: object) -> Callable[[Path], None]:
    def damage(agent: Path) -> None:
        meta = json.loads((agent / META).read_text())
        (agent / META).write_text(json.dumps({**meta, **changes}))

    return damage


def write_bytes(name: str, content: Callable[[bytes], bytes]) -> Callable[[Path], None]:
    def damage(agent: Path) -> None:
        (agent / name).write_bytes(content((agent / name).read_bytes()))

    return damage


def rezip(drop: str = "", data: Callable[[dict], dict] | None = None) -> Callable[[Path], None]:
    """Rewrite model.zip without member ``drop`` and with its ``data`` JSON transformed."""

    def damage(agent: Path) -> None:
        with zipfile.ZipFile(agent / MODEL) as archive:
            members = {name: archive.read(name) for name in archive.namelist() if name != drop}
        if data is not None:
            members["data"] = json.dumps(data(json.loads(members["data"]))).encode()
        with zipfile.ZipFile(agent / MODEL, "w") as archive:
            for name, content in members.items():
                archive.writestr(name, content)

    return damage


def flip_a_byte_of_policy(agent: Path) -> None:
    """Corrupt policy.pth's stored bytes in place; the zip's directory stays intact."""
    with zipfile.ZipFile(agent / MODEL) as archive:
        info = archive.getinfo("policy.pth")
    raw = bytearray((agent / MODEL).read_bytes())
    name_len, extra_len = (
        int.from_bytes(raw[info.header_offset + k : info.header_offset + k + 2], "little")
        for k in (26, 28)
    )
    start = info.header_offset + 30 + name_len + extra_len
    raw[start + info.compress_size // 2] ^= 0xFF
    (agent / MODEL).write_bytes(bytes(raw))


def shape_fewer(data: dict) -> dict:
    return {**data, "observation_space": {**data["observation_space"], "_shape": [FEWER]}}


nan, inf = float("nan"), float("inf")
DAMAGES = {
    "clip_obs NaN": (edit_stats(clip_obs=nan), STATS, r"clip_obs is not finite"),
    "clip_obs inf": (edit_stats(clip_obs=inf), STATS, r"clip_obs is not finite"),
    "clip_obs 0": (edit_stats(clip_obs=0.0), STATS, r"clip_obs must be > 0, got 0.0"),
    "clip_obs < 0": (edit_stats(clip_obs=-10.0), STATS, r"clip_obs must be > 0, got -10.0"),
    "epsilon < 0": (edit_stats(epsilon=-1e-8), STATS, r"epsilon must be > 0, got -1e-08"),
    "epsilon 0": (edit_stats(epsilon=0.0), STATS, r"epsilon must be > 0, got 0.0"),
    "epsilon NaN": (edit_stats(epsilon=nan), STATS, r"epsilon is not finite"),
    "epsilon array": (
        edit_stats(epsilon=[1e-8, 1e-8]),
        STATS,
        r"statistics of shape \(2,\) for epsilon, expected \(\)",
    ),
    "mean (N - 1,)": (
        edit_stats(mean=np.zeros(FEWER)),
        STATS,
        rf"statistics of shape \({FEWER},\) for mean, expected \({OBS_DIM},\)",
    ),
    "var (N, 1)": (
        edit_stats(var=np.ones((OBS_DIM, 1))),
        STATS,
        rf"shape \({OBS_DIM}, 1\) for var",
    ),
    "mean NaN": (edit_stats(mean=[nan] + [0.0] * FEWER), STATS, r"mean is not finite"),
    "var inf": (edit_stats(var=[inf] + [1.0] * FEWER), STATS, r"var is not finite"),
    "var < 0": (edit_stats(var=[-1.0] + [1.0] * FEWER), STATS, r"var must be >= 0"),
    "mean text": (
        edit_stats(mean=np.array(["a"] * OBS_DIM)),
        STATS,
        r"mean must hold real numbers",
    ),
    "no epsilon": (edit_stats(epsilon=None), STATS, r"missing statistics \['epsilon'\]"),
    "no mean, var": (
        edit_stats(mean=None, var=None),
        STATS,
        r"missing statistics \['mean', 'var'\]",
    ),
    "other obs_names": (
        edit_stats(obs_names=np.array([*OBS_NAMES[:-1], "depth"])),
        STATS,
        r"statistics for observation layout",
    ),
    "stats garbage": (write_bytes(STATS, lambda b: b"garbage" * 50), STATS, r"are unreadable"),
    "stats truncated": (write_bytes(STATS, lambda b: b[: len(b) // 2]), STATS, r"are unreadable"),
    "model garbage": (
        write_bytes(MODEL, lambda b: b"not a zip" * 100),
        MODEL,
        r"not a valid zip file \(corrupt or truncated\)",
    ),
    "model truncated": (
        write_bytes(MODEL, lambda b: b[: len(b) // 2]),
        MODEL,
        r"not a valid zip file \(corrupt or truncated\)",  # the directory at its end is gone
    ),
    "model cut short": (
        write_bytes(MODEL, lambda b: b[:-30]),
        MODEL,
        r"damaged \(truncated, or not an SB3 model\)",
    ),
    "model empty": (write_bytes(MODEL, lambda b: b""), MODEL, r"not a valid zip file"),
    "model bit flip": (flip_a_byte_of_policy, MODEL, r"policy\.pth"),
    "model no policy": (rezip(drop="policy.pth"), MODEL, r"no \['policy.pth'\]"),
    "model no data": (rezip(drop="data"), MODEL, r"no \['data'\]"),
    "model obs (N - 1,)": (
        rezip(data=shape_fewer),
        MODEL,
        rf"observation space shape \({FEWER},\), expected \({OBS_DIM},\)",
    ),
    "meta garbage": (write_bytes(META, lambda b: b"{not json"), META, r"is unreadable"),
    "meta truncated": (write_bytes(META, lambda b: b[: len(b) // 2]), META, r"is unreadable"),
    "meta list": (
        write_bytes(META, lambda b: b"[1, 2]"),
        META,
        r"must be a JSON object, got a list",
    ),
    "meta obs size": (
        edit_meta(observation_shape=[MORE]),
        META,
        rf"observation_shape is \[{MORE}\], expected \[{OBS_DIM}\]",
    ),
    "meta action size": (
        edit_meta(action_shape=[4]),
        META,
        r"action_shape is \[4\], expected \[3\]",
    ),
    "meta algo": (
        edit_meta(algo="dqn"),
        META,
        r"algo is 'dqn', expected one of \['crossq', 'ppo', 'sac', 'tqc'\]",
    ),
    "meta version": (
        edit_meta(auv_gym_version="1.0.0"),
        META,
        r"trained with auv-gym 1.0.0, this is auv-gym 0\.\d+\.\d+",
    ),
    "meta bad version": (edit_meta(auv_gym_version="abc"), META, r"'abc' is not a version"),
    "meta obs_names": (edit_meta(obs_names=list(OBS_NAMES[::-1])), META, r"observation layout"),
}


@pytest.fixture
def agent_copy(tmp_path: Path) -> Path:
    return shutil.copytree(SHIPPED, tmp_path / "agent")


@pytest.mark.parametrize("case", DAMAGES)
def test_a_damaged_agent_file_is_named_with_its_problem(case: str, agent_copy: Path) -> None:
    damage, file, message = DAMAGES[case]
    damage(agent_copy)
    with pytest.raises(ValueError, match=message) as caught:
        check_agent(agent_copy)
    assert str(agent_copy / file) in str(caught.value)
    assert "\n" not in str(caught.value)


@pytest.mark.rl
@pytest.mark.parametrize("case", ["clip_obs NaN", "epsilon < 0", "model bit flip", "meta obs size"])
def test_load_policy_refuses_the_same_files(case: str, agent_copy: Path) -> None:
    from controllers.loader import load_policy

    damage, _, message = DAMAGES[case]
    damage(agent_copy)
    with pytest.raises(ValueError, match=message):
        load_policy(agent_copy)


def test_missing_files_are_named(agent_copy: Path) -> None:
    (agent_copy / STATS).unlink()
    (agent_copy / "vecnormalize.pkl").unlink(missing_ok=True)  # the fallback, for SB3 / RL Zoo
    with pytest.raises(FileNotFoundError, match=r"normalisation statistics missing"):
        check_agent(agent_copy)
    (agent_copy / MODEL).unlink()
    with pytest.raises(FileNotFoundError, match=rf"agent directory {agent_copy} has no model\.zip"):
        check_agent(agent_copy)


def test_the_shipped_agent_passes_and_its_statistics_are_returned() -> None:
    files = check_agent(SHIPPED)
    assert files.obs_mean.shape == files.obs_var.shape == (OBS_DIM,)
    assert files.clip_obs == 10.0 and files.epsilon == 1e-8
    assert files.metadata["obs_names"] == list(OBS_NAMES)
    assert np.all(files.obs_var > 0)


def test_checking_an_agent_does_not_import_torch(tmp_path: Path) -> None:
    agent = shutil.copytree(SHIPPED, tmp_path / "agent")
    DAMAGES["epsilon < 0"][0](agent)
    code = (
        "import sys\n"
        "from controllers.agent import check_agent\n"
        f"check_agent({str(SHIPPED)!r})\n"
        "try:\n"
        f"    check_agent({str(agent)!r})\n"
        "except ValueError as error:\n"
        "    print(error)\n"
        "print('torch' in sys.modules)\n"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run(
        [sys.executable, "-c", code],
        env=env,
        capture_output=True,
        text=True,
        check=True,
        timeout=300,
    )
    lines = done.stdout.splitlines()
    assert "epsilon must be > 0" in lines[0] and lines[1] == "False"


def test_an_off_policy_agent_with_n_step_returns_loads_without_warnings() -> None:
    """SAC saved with `n_steps` 3 names SB3's NStepReplayBuffer; loading it for inference used
    to warn that `n_steps` "is ignored" (no buffer is built), on every load."""
    import warnings

    from controllers.agent import observation_layout
    from controllers.loader import load_policy

    agent = ROOT / "benchmarks" / "agents" / "sac_generalist"  # trained with n_steps 3
    assert json.loads((agent / META).read_text())["algo"] == "sac"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        policy = load_policy(agent)
    observation = np.zeros((2, len(observation_layout(policy.metadata))), np.float32)
    action, _ = policy.predict(observation, deterministic=True)
    assert action.shape == (2, 3) and np.all(np.isfinite(action))


@pytest.mark.parametrize("name", ["ppo_as_built", "ppo_residual_as_built"])
def test_an_agent_for_the_propeller_and_fins_is_refused_on_another_actuator(name):
    """Was: controllers.make("agent", env=...) flew `ppo_as_built`'s shaft-speed and fin-angle
    commands as the paper's forces, silently, and the residual ensemble failed inside its base's
    envelope guard without naming the agent or the actuator."""
    import controllers
    from benchmarks.catalog.policies import check_policy_for_env

    folder = ROOT / "benchmarks" / "agents" / name
    refused = (
        rf"^agent {folder} commands the propeller and fins \(shaft speed and fin angles, "
        r"actuator='realistic'\); this env's actuator is 'paper': fly it on an env with "
        r"actuator='realistic'$"
    )
    with pytest.raises(ValueError, match=refused):
        controllers.make("agent", path=folder, env={"actuator": "paper"})
    with pytest.raises(ValueError, match=rf"^policy 'agent:{folder}': " + refused[1:]):
        check_policy_for_env(f"agent:{folder}", {"actuator": "paper"})
    policy = controllers.make("agent", path=folder, env={"actuator": "realistic"})
    assert policy.env_kwargs["actuator"] == "realistic"
