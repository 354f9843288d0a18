"""The SB3 adapter's reduced infos and the training harness's speed options: same steps as the
full path, the keys SB3 reads on every autoreset, and the training-speed benchmark's plumbing."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")
pytestmark = pytest.mark.rl

from stable_baselines3.common.vec_env import VecMonitor, VecNormalize  # noqa: E402

from auv_gym.envs.sb3 import SB3VecEnv, _info_dicts, make_sb3_vec_env  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
# Short episodes that end both ways: astern actions leave the corridor, the rest time out.
SHORT = {
    "corridor": 18.0,
    "max_time": 2.5,
    "randomize_start": True,
    "random_current": 0.3,
    "actuator": "random",
    "path": {"families": ["helix", "line", "spline"]},
}


def random_actions(seed: int, steps: int, n: int) -> np.ndarray:
    a = np.random.default_rng(seed).uniform(-1, 1, size=(steps, n, 3)).astype(np.float32)
    a[..., 0] = 0.6 * a[..., 0] - 0.1
    a[..., 1:] *= 0.6
    return a


def test_minimal_infos_carry_the_full_infos_sb3_keys_on_every_step_and_autoreset():
    n, steps = 6, 120
    full = make_sb3_vec_env(n, seed=3, **SHORT)
    minimal = make_sb3_vec_env(n, seed=3, infos="minimal", **SHORT)
    assert (full.info_mode, minimal.info_mode) == ("full", "minimal")
    np.testing.assert_array_equal(full.reset(), minimal.reset())
    assert minimal.reset_infos == [{}] * n
    ended = {"terminated": 0, "truncated": 0}
    for t, a in enumerate(random_actions(5, steps, n)):
        obs, rew, dones, infos = full.step(a)
        m_obs, m_rew, m_dones, m_infos = minimal.step(a)
        np.testing.assert_array_equal(obs, m_obs, err_msg=f"step {t}")
        np.testing.assert_array_equal(rew, m_rew)
        np.testing.assert_array_equal(dones, m_dones)
        assert m_rew.dtype == np.float32 and m_dones.dtype == np.bool_
        for i, (info, m_info) in enumerate(zip(infos, m_infos, strict=True)):
            want = {"TimeLimit.truncated"} | ({"terminal_observation"} if dones[i] else set())
            assert set(m_info) == want, (t, i)
            assert type(m_info["TimeLimit.truncated"]) is bool
            assert m_info["TimeLimit.truncated"] == info["TimeLimit.truncated"]
            if dones[i]:
                np.testing.assert_array_equal(
                    m_info["terminal_observation"], info["terminal_observation"]
                )
                assert m_info["terminal_observation"].dtype == np.float32
                ended["truncated" if info["TimeLimit.truncated"] else "terminated"] += 1
                assert minimal.reset_infos[i] == {}
    assert ended["terminated"] >= n and ended["truncated"] >= n


def test_vec_monitor_and_vec_normalize_see_the_same_episodes_with_minimal_infos():
    n, steps = 4, 80
    kwargs = {"max_time": 1.0, "randomize_start": True}
    envs = [
        VecNormalize(VecMonitor(make_sb3_vec_env(n, seed=1, infos=mode, **kwargs)))
        for mode in ("full", "minimal")
    ]
    for env in envs:
        env.reset()
    episodes = 0
    for a in random_actions(2, steps, n):
        (obs, rew, dones, infos), (m_obs, m_rew, m_dones, m_infos) = (e.step(a) for e in envs)
        np.testing.assert_array_equal(obs, m_obs)
        np.testing.assert_array_equal(rew, m_rew)
        np.testing.assert_array_equal(dones, m_dones)
        for i in np.flatnonzero(dones):
            assert m_infos[i]["episode"]["r"] == infos[i]["episode"]["r"]
            assert m_infos[i]["episode"]["l"] == infos[i]["episode"]["l"] == 20
            np.testing.assert_array_equal(
                m_infos[i]["terminal_observation"], infos[i]["terminal_observation"]
            )
            episodes += 1
    assert episodes == n * (steps // 20)


def test_info_dicts_keep_the_masked_keys_in_order():
    info = {
        "a": np.array([1.0, 2.0]),
        "_a": np.array([True, True]),
        "b": np.array([[1, 2], [3, 4]]),
        "_b": np.array([False, True]),
        "c": np.array(["x", None], dtype=object),
        "_c": np.array([True, False]),
    }
    rows = _info_dicts(info, 2)
    assert list(rows[0]) == ["a", "c"] and list(rows[1]) == ["a", "b"]
    assert rows[0] == {"a": 1.0, "c": "x"} and type(rows[0]["a"]) is float
    np.testing.assert_array_equal(rows[1]["b"], [3, 4])
    assert _info_dicts({}, 3) == [{}, {}, {}]


def test_unknown_info_mode_is_refused():
    with pytest.raises(ValueError, match="infos must be one of"):
        make_sb3_vec_env(2, infos="none")
    assert SB3VecEnv.__init__.__defaults__ == ("full",)


def test_training_env_uses_minimal_infos_and_the_serial_kernel():
    from benchmarks.training.train import make_training_env

    venv = make_training_env(300, 0, {"max_time": 5.0}, env_id="AUVPath3DSpeedLimit-v0", threads=1)
    adapter = venv.venv
    assert adapter.info_mode == "minimal" and adapter.core.threads == 1
    from auv_gym.sim.simulator import _step_one

    assert adapter.core.sim._kernel is _step_one


def test_update_threads_callback_switches_torch_threads_per_phase():
    import torch

    from benchmarks.training.callbacks import UpdateThreads

    before = torch.get_num_threads()
    try:
        callback = UpdateThreads(collect=1, update=2)
        callback.on_rollout_end()
        assert torch.get_num_threads() == 2
        callback.on_rollout_start()
        assert torch.get_num_threads() == 1
        callback.on_rollout_end()
        callback.on_training_end()
        assert torch.get_num_threads() == 1
    finally:
        torch.set_num_threads(before)


def test_update_threads_option_is_checked():
    from benchmarks.training.train import TrainOptions, check_options

    with pytest.raises(ValueError, match="update_threads"):
        check_options(TrainOptions(update_threads=-1))


@pytest.mark.integration
def test_speed_training_extracts_a_baseline_and_runs_a_tiny_budget(tmp_path):
    import json

    from benchmarks.speed.training import extract

    tree = extract("HEAD", tmp_path)
    committed = subprocess.run(
        ["git", "show", "HEAD:auv_gym/envs/sb3.py"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    assert (tree / "auv_gym" / "envs" / "sb3.py").read_text() == committed
    assert extract("HEAD", tmp_path) == tree  # cached
    out = tmp_path / "speed.json"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "benchmarks.speed.training",
            "--quick",
            "--baseline",
            "none",
            "--json",
            str(out),
        ],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    )
    runs = json.loads(out.read_text())["runs"]
    assert [(r["side"], r["n_envs"], r["steps"]) for r in runs] == [("new", 8, 8 * 16)]
    r = runs[0]
    assert r["total_per_s"] == pytest.approx(r["steps"] / (r["collect_s"] + r["update_s"]))
    assert 0 < r["total_per_s"] < min(r["collect_per_s"], r["update_per_s"])
    assert math.isfinite(r["floor_update_per_s"]) and r["floor_update_per_s"] > 0


@pytest.mark.integration
def test_speed_training_times_each_number_of_epochs_it_is_given(tmp_path):
    import json

    out = tmp_path / "speed.json"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "benchmarks.speed.training",
            "--quick",
            "--baseline",
            "none",
            "--n-epochs",
            "1",
            "3",
            "--json",
            str(out),
        ],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    )
    runs = json.loads(out.read_text())["runs"]
    # --quick: one warm-up and one timed rollout, each followed by an update of n_epochs epochs
    assert sorted((r["n_epochs"], r["epochs_run"]) for r in runs) == [(1, 2), (3, 6)]
    bad = subprocess.run(
        [
            sys.executable,
            "-m",
            "benchmarks.speed.training",
            "--quick",
            "--baseline",
            "none",
            "--n-epochs",
            "0",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert bad.returncode == 2 and "--n-epochs must be >= 1, got [0]" in bad.stderr


def test_update_threads_train_the_same_weights_up_to_float_rounding():
    """Bit for bit on some CPUs, not on all (torch's 2-thread kernels may sum in another
    order): the training is the same, its float rounding may differ."""
    import torch
    from stable_baselines3 import PPO

    from benchmarks.training.callbacks import UpdateThreads

    before = torch.get_num_threads()
    weights = []
    try:
        for update in (1, 2):
            torch.set_num_threads(1)
            env = VecNormalize(make_sb3_vec_env(32, seed=0, infos="minimal", **SHORT))
            model = PPO(
                "MlpPolicy",
                env,
                n_steps=64,
                batch_size=2048,
                n_epochs=2,
                seed=0,
                device="cpu",
                policy_kwargs={"net_arch": [64, 64]},
            )
            model.learn(2 * 32 * 64, callback=UpdateThreads(1, update))
            assert torch.get_num_threads() == 1
            weights.append([p.detach().clone() for p in model.policy.parameters()])
    finally:
        torch.set_num_threads(before)
    for a, b in zip(*weights, strict=True):
        torch.testing.assert_close(a, b, rtol=1e-4, atol=1e-6)


@pytest.mark.parametrize("two_threads_faster", [False, True])
def test_adaptive_update_threads_keeps_the_faster_count_and_backs_off_its_probes(
    two_threads_faster, monkeypatch
):
    import torch

    from benchmarks.training import callbacks as module

    cost = {1: 1.0, 2: 0.7 if two_threads_faster else 20.0}  # [s] per update
    clock = [0.0]
    monkeypatch.setattr(module.time, "perf_counter", lambda: clock[0])
    before = torch.get_num_threads()
    callback = module.AdaptiveUpdateThreads(1, (1, 2))
    try:
        for _ in range(60):
            callback.on_rollout_start()
            callback.on_rollout_end()
            clock[0] += cost[callback.update]  # the update
        callback.on_training_end()
    finally:
        torch.set_num_threads(before)
    used = [threads for threads, _ in callback.history]
    assert used[:2] == [1, 2] and len(used) == 60
    assert all(seconds == pytest.approx(cost[threads]) for threads, seconds in callback.history)
    best, other = (2, 1) if two_threads_faster else (1, 2)
    # After one try each: the faster count, the other probed after 10, then 20 updates (each
    # probe loses, so the interval doubles; the next would come after 40).
    assert [k for k, threads in enumerate(used) if threads == other][1:] == [11, 31]
    assert used[2:11] == [best] * 9 and callback.probe_every == 40


@pytest.mark.integration
def test_speed_training_runs_the_baseline_commit_of_its_default(tmp_path):
    """The default baseline (b8de6c4) predates `benchmarks.options` and `parse_options`: the
    timed run must import nothing of the project at module level to run in it."""
    import json

    from benchmarks.speed.training import DEFAULT_BASELINE

    known = subprocess.run(
        ["git", "cat-file", "-e", f"{DEFAULT_BASELINE}^{{commit}}"], cwd=ROOT, capture_output=True
    )
    if known.returncode != 0:
        pytest.skip(f"{DEFAULT_BASELINE} is not in this clone's history")
    out = tmp_path / "speed.json"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "benchmarks.speed.training",
            "--quick",
            "--cache",
            str(tmp_path / "cache"),
            "--json",
            str(out),
        ],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    )
    runs = json.loads(out.read_text())["runs"]
    assert sorted(r["side"] for r in runs) == ["new", "old"]
    assert all(r["steps"] == 8 * 16 and r["total_per_s"] > 0 for r in runs)
    assert all(r["floor_update_per_s"] > 0 for r in runs)  # timed in the old tree's code too


def test_the_thread_limit_reaches_numpys_blas():
    """Resets solve spline systems through numpy's BLAS: its threads are limited with torch's
    and numba's, and restored after."""
    import numba
    import torch
    from threadpoolctl import threadpool_info

    from benchmarks.training.envs import thread_limit

    def blas_threads() -> list[int]:
        return [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]

    # torch and numba may share one OpenMP runtime: start from the same count in both
    start = (torch.get_num_threads(), numba.get_num_threads())
    two = min(2, numba.config.NUMBA_NUM_THREADS)
    torch.set_num_threads(two)
    numba.set_num_threads(two)
    try:
        blas = blas_threads()
        with thread_limit(1):
            assert blas and set(blas_threads()) == {1}
            assert torch.get_num_threads() == 1 and numba.get_num_threads() == 1
        after = (blas_threads(), torch.get_num_threads(), numba.get_num_threads())
        assert after == (blas, two, two)
    finally:
        numba.set_num_threads(start[1])
        torch.set_num_threads(start[0])
