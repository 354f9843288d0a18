"""The native vector env: registration, parity with the single env, autoreset, bad input."""

from __future__ import annotations

import inspect
import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode, SyncVectorEnv
from gymnasium.wrappers import TimeLimit

import auv_gym  # noqa: F401  (registers the ids)
from auv_gym import AUVPath3DEnv
from auv_gym.envs.vector_env import PARALLEL_MIN_VEHICLES, AUVPath3DVectorEnv, parse_autoreset_mode
from auv_gym.sim.config import SimConfig

# Episodes that end within a few dozen steps: a corridor just above the initial 17.7 m distance,
# a short horizon, and random actions (as tests/test_env.py bounds them).
SHORT = {"corridor": 18.0, "max_time": 2.5}
DISTURBED = {
    **SHORT,
    "current": {"mean": (0.1, -0.05, 0.0), "std": (0.1, 0.1, 0.02), "time_constant": 5.0},
    "param_uncertainty": 0.2,
    "randomize_start": True,
}
MODES = (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP)


def random_actions(seed: int, steps: int, n: int) -> np.ndarray:
    a = np.random.default_rng(seed).uniform(-1, 1, size=(steps, n, 3)).astype(np.float32)
    a[..., 0] = 0.6 * a[..., 0] - 0.1  # often astern: the corridor ends some episodes
    a[..., 1:] *= 0.6
    return a


def reference(n: int, mode: AutoresetMode, max_episode_steps: int | None = None, **kwargs):
    """n single envs in gymnasium's SyncVectorEnv: the semantics the native env must reproduce."""

    def make():
        env = AUVPath3DEnv(**kwargs)
        return env if max_episode_steps is None else TimeLimit(env, max_episode_steps)

    return SyncVectorEnv([make for _ in range(n)], autoreset_mode=mode)


def assert_infos_equal(got: dict, want: dict, where: str = "") -> None:
    assert sorted(got) == sorted(want), where
    for key, value in want.items():
        if isinstance(value, dict):
            assert_infos_equal(got[key], value, f"{where}/{key}")
        elif value.dtype == object:
            assert got[key].dtype == object, key
            for g, w in zip(got[key], value, strict=True):
                if w is None or isinstance(w, str):
                    assert g == w, (where, key)
                else:
                    np.testing.assert_array_equal(g, w, err_msg=f"{where}/{key}")
        else:
            assert got[key].dtype == value.dtype, (where, key, got[key].dtype, value.dtype)
            np.testing.assert_array_equal(got[key], value, err_msg=f"{where}/{key}")


def run_parity(n, mode, steps, seed, max_episode_steps=None, **kwargs) -> dict[str, int]:
    """Step the native env and the reference side by side; everything must be bit-identical."""
    native = AUVPath3DVectorEnv(
        n, autoreset_mode=mode, max_episode_steps=max_episode_steps, **kwargs
    )
    ref = reference(n, mode, max_episode_steps, **kwargs)
    obs, info = native.reset(seed=seed)
    ref_obs, ref_info = ref.reset(seed=seed)
    np.testing.assert_array_equal(obs, ref_obs)
    assert obs.dtype == np.float32
    assert_infos_equal(info, ref_info, "reset")
    counts = {"terminated": 0, "truncated": 0}
    for t, a in enumerate(random_actions(seed, steps, n)):
        out = native.step(a)
        want = ref.step(a)
        for name, g, w in zip(
            ("obs", "reward", "terminated", "truncated"), out, want, strict=False
        ):
            assert g.dtype == w.dtype, (name, g.dtype, w.dtype)
            np.testing.assert_array_equal(g, w, err_msg=f"{name} at step {t}")
        assert_infos_equal(out[4], want[4], f"step {t}")
        counts["terminated"] += int(out[2].sum())
        counts["truncated"] += int(out[3].sum())
    return counts


@pytest.mark.parametrize("mode", MODES, ids=lambda m: m.name)
@pytest.mark.parametrize("n", [1, 3, 8])
def test_parity_with_single_envs_including_autoresets(n, mode):
    counts = run_parity(n, mode, steps=120, seed=11, **SHORT)
    # Every vehicle lives through several episodes.
    assert counts["terminated"] >= 1
    assert counts["terminated"] + counts["truncated"] >= 2 * n


@pytest.mark.parametrize("mode", MODES, ids=lambda m: m.name)
def test_parity_under_current_parameter_uncertainty_and_random_starts(mode):
    counts = run_parity(5, mode, steps=110, seed=3, **DISTURBED)
    assert counts["terminated"] >= 1 and counts["truncated"] >= 1


def test_parity_with_time_limit_shorter_than_max_time():
    # gym.make's TimeLimit truncates at max_episode_steps, also on a terminal step.
    counts = run_parity(4, AutoresetMode.NEXT_STEP, 90, seed=5, max_episode_steps=17, **SHORT)
    assert counts["truncated"] >= 4 * 4


def test_vehicle_i_is_a_single_env_reset_with_seed_k_plus_i():
    """The contract stated directly, without SyncVectorEnv: vehicle i ≡ env.reset(seed=k + i)."""
    n, k, steps = 4, 100, 80
    native = AUVPath3DVectorEnv(n, **DISTURBED)
    actions = random_actions(1, steps, n)
    obs, _ = native.reset(seed=k)
    history = [native.step(a) for a in actions]
    for i in range(n):
        env = AUVPath3DEnv(**DISTURBED)
        single_obs, _ = env.reset(seed=k + i)
        np.testing.assert_array_equal(obs[i], single_obs)
        done = False
        for t, a in enumerate(actions):
            o, r, term, trunc, info = history[t]
            if done:  # NEXT_STEP: this step is vehicle i's reset, as env.reset() without seed
                expected, _ = env.reset()
                np.testing.assert_array_equal(o[i], expected)
                assert (r[i], term[i], trunc[i]) == (0.0, False, False)
                done = False
                continue
            so, sr, sterm, strunc, sinfo = env.step(a[i])
            np.testing.assert_array_equal(o[i], so)
            assert (r[i], term[i], trunc[i]) == (sr, sterm, strunc)
            for key in ("x_e", "y_e", "z_e", "distance", "s", "u_p", "t", "reward_progress"):
                assert info[key][i] == sinfo[key], key
            np.testing.assert_array_equal(info["tau"][i], sinfo["tau"])
            np.testing.assert_array_equal(info["disturbance"][i], sinfo["disturbance"])
            if sterm:
                assert info["termination_reason"][i] == sinfo["termination_reason"]
            done = sterm or strunc


def test_make_vec_returns_the_native_env_with_registered_limits():
    env = gym.make_vec("AUVPath3D-v0", num_envs=6, disturbance="none", max_time=1.0)
    assert isinstance(env, AUVPath3DVectorEnv)
    assert env.num_envs == 6
    assert env.max_episode_steps is None  # the registration has no TimeLimit ...
    assert env.spec.max_episode_steps == 20  # ... the env truncates at max_time = 1 s itself
    assert env.metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP
    assert env.config.noise.amplitude == (0.0,) * 5
    single = gym.make("AUVPath3D-v0")
    assert env.single_observation_space == single.observation_space
    assert env.single_action_space == single.action_space
    assert env.observation_space.shape == (6, 15)
    assert env.action_space.shape == (6, 3)
    assert env.observation_space.dtype == np.float32
    env.reset(seed=0)
    ends = []
    for _ in range(21):
        _, _, terminated, truncated, _ = env.step(np.zeros((6, 3), np.float32))
        ends.append(truncated.copy())
        assert not terminated.any()
    assert np.asarray(ends).nonzero()[0].tolist() == [19] * 6  # 1 s = 20 steps of 0.05 s
    variant = gym.make_vec("AUVPath3DFins-v0", num_envs=2, autoreset_mode="SameStep")
    assert variant.config.actuator == "fins"
    assert variant.metadata["autoreset_mode"] is AutoresetMode.SAME_STEP


def test_constructor_accepts_exactly_the_single_env_arguments():
    single = set(inspect.signature(AUVPath3DEnv.__init__).parameters) - {"self"}
    config = set(inspect.signature(SimConfig.from_kwargs).parameters)
    assert single - {"render_mode"} == config
    # The env spells its arguments out for help() and IDEs; SimConfig.from_kwargs is the one that
    # uses them. Their defaults and annotations must never drift apart.
    env_params = inspect.signature(AUVPath3DEnv.__init__).parameters
    for name, param in inspect.signature(SimConfig.from_kwargs).parameters.items():
        assert env_params[name].default == param.default, name
        assert env_params[name].annotation == param.annotation, name
    env = AUVPath3DVectorEnv(2, path="line", u_desired=1.5, corridor=12.0, render_mode=None)
    assert env.config.u_desired == 1.5
    assert env.config.limits.corridor == 12.0
    with pytest.raises(TypeError, match="not_an_argument"):
        AUVPath3DVectorEnv(2, not_an_argument=1)


def test_partial_reset_with_reset_mask_matches_sync_vector_env():
    n, kwargs = 4, {"max_time": 10.0}
    native = AUVPath3DVectorEnv(n, **kwargs)
    ref = reference(n, AutoresetMode.NEXT_STEP, **kwargs)
    native.reset(seed=20)
    ref.reset(seed=20)
    actions = random_actions(2, 30, n)
    for a in actions[:10]:
        native.step(a)
        ref.step(a)
    mask = np.array([False, True, False, True])
    seeds = [None, 7, None, None]  # vehicle 3 continues its own generator
    obs, info = native.reset(seed=seeds, options={"reset_mask": mask})
    ref_obs, ref_info = ref.reset(seed=seeds, options={"reset_mask": mask.copy()})
    np.testing.assert_array_equal(obs, ref_obs)
    assert_infos_equal(info, ref_info)
    assert info["_x_e"].tolist() == mask.tolist()
    np.testing.assert_array_equal(info["t"][mask], 0.0)
    for t, a in enumerate(actions[10:]):
        out, want = native.step(a), ref.step(a)
        for g, w in zip(out[:4], want[:4], strict=True):
            np.testing.assert_array_equal(g, w, err_msg=f"step {t}")
    assert native.sim.steps.tolist() == [30, 20, 30, 20]
    single = AUVPath3DEnv(**kwargs)
    np.testing.assert_array_equal(obs[1], single.reset(seed=7)[0])


def test_disabled_autoreset_keeps_vehicles_until_reset_mask():
    n = 3
    native = AUVPath3DVectorEnv(n, autoreset_mode=AutoresetMode.DISABLED, **SHORT)
    ref = reference(n, AutoresetMode.DISABLED, **SHORT)
    native.reset(seed=9)
    ref.reset(seed=9)
    assert native.metadata["autoreset_mode"] is AutoresetMode.DISABLED
    resets = 0
    for t, a in enumerate(random_actions(4, 100, n)):
        out, want = native.step(a), ref.step(a)
        for g, w in zip(out[:4], want[:4], strict=True):
            np.testing.assert_array_equal(g, w, err_msg=f"step {t}")
        assert_infos_equal(out[4], want[4])
        done = out[2] | out[3]
        if done.any():
            resets += int(done.sum())
            obs, info = native.reset(options={"reset_mask": done})
            ref_obs, ref_info = ref.reset(options={"reset_mask": done.copy()})
            np.testing.assert_array_equal(obs, ref_obs)
            assert_infos_equal(info, ref_info)
    assert resets >= n


def test_same_step_reports_final_observation_and_info():
    n = 3
    env = AUVPath3DVectorEnv(n, autoreset_mode="same_step", max_time=0.5, disturbance="none")
    env.reset(seed=1)
    ahead = np.tile([0.8, 0.0, 0.1], (n, 1))
    for _ in range(9):
        _, _, _, truncated, info = env.step(ahead)
        assert not truncated.any() and "final_obs" not in info
    obs, reward, terminated, truncated, info = env.step(ahead)
    assert truncated.all() and not terminated.any()
    assert info["_final_obs"].all() and info["_final_info"].all()
    np.testing.assert_array_equal(info["final_info"]["t"], 0.5)
    np.testing.assert_array_equal(info["t"], 0.0)  # already the next episode
    assert "reward_progress" in info["final_info"] and "reward_progress" not in info
    fresh = AUVPath3DVectorEnv(n, max_time=0.5, disturbance="none")
    first, _ = fresh.reset(seed=1)
    assert not np.array_equal(info["final_obs"][0], first[0])
    # disturbance="none" and the paper start: every episode starts identically.
    np.testing.assert_array_equal(obs, first)
    assert np.isfinite(reward).all()


def test_non_finite_vehicle_ends_alone_and_does_not_contaminate_others():
    n, kwargs = 5, {"max_time": 10.0}
    env = AUVPath3DVectorEnv(n, **kwargs)
    clean = AUVPath3DVectorEnv(n, **kwargs)
    obs0, _ = env.reset(seed=4)
    clean.reset(seed=4)
    actions = random_actions(5, 12, n)
    for a in actions[:3]:
        env.step(a)
        clean.step(a)
    last_obs = env.step(actions[3])[0][2].copy()
    clean.step(actions[3])
    env.sim.state[2, 5] = np.nan  # surge speed of vehicle 2 becomes NaN
    env.sim.state[4, 6] = 1e300  # sway speed of vehicle 4 overflows in the damping terms
    obs, reward, terminated, _, info = env.step(actions[4])
    want = clean.step(actions[4])
    assert terminated.tolist() == [False, False, True, False, True]
    assert info["termination_reason"].tolist() == [None, None, "non_finite", None, "non_finite"]
    np.testing.assert_array_equal(obs[2], last_obs)  # the last finite observation
    assert np.isfinite(obs[2]).all()
    assert reward[2] == -100.0  # only the termination penalty (RewardWeights.termination)
    keep = [0, 1, 3]
    np.testing.assert_array_equal(obs[keep], want[0][keep])
    np.testing.assert_array_equal(reward[keep], want[1][keep])
    for a in actions[5:]:  # NEXT_STEP resets 2 and 4; the others stay untouched
        out, ref = env.step(a), clean.step(a)
        np.testing.assert_array_equal(out[0][keep], ref[0][keep])
        assert np.isfinite(out[0]).all() and np.isfinite(env.sim.state).all()
    assert env.sim.steps.tolist() == [12, 12, 6, 12, 6]
    assert not np.array_equal(obs0[2], env.sim.obs[2])


def test_bad_input_raises_value_error():
    env = AUVPath3DVectorEnv(4, max_time=5.0)
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros((4, 3)))
    env.reset(seed=0)
    before = env.state
    for shape in [(3,), (4, 2), (5, 3), (4, 3, 1)]:
        with pytest.raises(ValueError, match="shape"):
            env.step(np.zeros(shape))
    for bad in (np.nan, np.inf, -np.inf):
        a = np.zeros((4, 3))
        a[2, 1] = bad
        with pytest.raises(ValueError, match="row 2"):
            env.step(a)
    np.testing.assert_array_equal(env.state, before)  # nothing moved
    for num_envs in (0, -3, 2.5, True, "4"):
        with pytest.raises(ValueError, match="num_envs"):
            AUVPath3DVectorEnv(num_envs)
    with pytest.raises(ValueError, match="autoreset_mode"):
        AUVPath3DVectorEnv(2, autoreset_mode="sometimes")
    with pytest.raises(ValueError, match="max_episode_steps"):
        AUVPath3DVectorEnv(2, max_episode_steps=0)
    with pytest.raises(ValueError, match="render_mode"):
        AUVPath3DVectorEnv(2, render_mode="human")
    with pytest.raises(ValueError, match="render_vehicle"):
        AUVPath3DVectorEnv(2, render_vehicle=2)
    with pytest.raises(ValueError, match="reset_mask"):
        env.reset(options={"reset_mask": np.zeros(4, dtype=bool)})
    with pytest.raises(ValueError, match="reset_mask"):
        env.reset(options={"reset_mask": np.ones(3, dtype=bool)})
    with pytest.raises(ValueError, match="reset_mask"):
        env.reset(options={"reset_mask": [True] * 4})
    with pytest.raises(ValueError, match="seeds"):
        env.reset(seed=[1, 2])
    fresh = AUVPath3DVectorEnv(2)
    with pytest.raises(ValueError, match="first reset"):
        fresh.reset(options={"reset_mask": np.array([True, False])})
    with pytest.raises(ValueError, match="control_dt"):
        AUVPath3DVectorEnv(2, control_dt=0.033)
    for threads in (0, 1.5, True):
        with pytest.raises(ValueError, match="threads"):
            AUVPath3DVectorEnv(2, threads=threads)


def test_parse_autoreset_mode_accepts_enum_value_and_name():
    for mode in AutoresetMode:
        assert parse_autoreset_mode(mode) is mode
        assert parse_autoreset_mode(mode.value) is mode
        assert parse_autoreset_mode(mode.name.lower()) is mode


def test_render_draws_the_chosen_vehicle_like_the_single_env():
    kwargs = {"max_time": 20.0}
    env = AUVPath3DVectorEnv(3, render_mode="rgb_array", render_vehicle=2, **kwargs)
    single = AUVPath3DEnv(render_mode="rgb_array", **kwargs)
    env.reset(seed=30)
    single.reset(seed=32)
    for a in random_actions(6, 15, 3):
        env.step(a)
        single.step(a[2])
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    np.testing.assert_array_equal(frame, single.render())
    assert env.metadata["render_fps"] == 20
    assert AUVPath3DVectorEnv(2).render() is None


def test_seeded_runs_are_reproducible_and_batch_size_independent():
    a = AUVPath3DVectorEnv(16, **DISTURBED)
    b = AUVPath3DVectorEnv(7, **DISTURBED)
    a.reset(seed=50)
    b.reset(seed=59)  # b's vehicle j is a's vehicle 9 + j
    for act in random_actions(8, 60, 16):
        out_a = a.step(act)
        out_b = b.step(act[9:])
        np.testing.assert_array_equal(out_a[0][9:], out_b[0])
        np.testing.assert_array_equal(out_a[1][9:], out_b[1])
    assert math.isfinite(float(a.sim.reward.sum()))


def test_gymnasium_vector_wrappers_see_the_same_episodes():
    """RecordEpisodeStatistics reads metadata["autoreset_mode"]; statistics match the reference."""
    from gymnasium.wrappers.vector import RecordEpisodeStatistics

    n = 4
    native = RecordEpisodeStatistics(AUVPath3DVectorEnv(n, **SHORT))
    ref = RecordEpisodeStatistics(reference(n, AutoresetMode.NEXT_STEP, **SHORT))
    native.reset(seed=8)
    ref.reset(seed=8)
    for a in random_actions(9, 120, n):
        native.step(a)
        ref.step(a)
    assert len(native.return_queue) == len(ref.return_queue) >= 2 * n
    assert list(native.return_queue) == list(ref.return_queue)
    assert list(native.length_queue) == list(ref.length_queue)


# Compiles the threaded kernel (about 1.5 min on 2 cores).
@pytest.mark.integration
def test_thread_count_changes_nothing_but_speed():
    import numba

    before = numba.get_num_threads()
    outs = []
    for threads in (1, 2, 3):
        env = AUVPath3DVectorEnv(6, threads=threads, **DISTURBED)
        env.reset(seed=12)
        outs.append([env.step(a)[:4] for a in random_actions(10, 40, 6)])
        assert numba.get_num_threads() == before  # restored after every step
    for other in outs[1:]:
        for got, want in zip(other, outs[0], strict=True):
            for g, w in zip(got, want, strict=True):
                np.testing.assert_array_equal(g, w)
    assert AUVPath3DVectorEnv(2, threads=10_000).threads == numba.config.NUMBA_NUM_THREADS
    assert AUVPath3DVectorEnv(PARALLEL_MIN_VEHICLES - 1).threads == 1
    assert AUVPath3DVectorEnv(PARALLEL_MIN_VEHICLES).threads is None  # numba's setting


def test_batched_row_resets_equal_one_by_one_resets():
    """`Simulator.reset_rows` (autoresets) draws exactly what `reset_row` draws, row by row."""
    from auv_gym.sim.simulator import Simulator

    current = {"mean": (0.1, 0.0, 0.0), "std": (0.05, 0.05, 0.0)}
    config = SimConfig.from_kwargs(param_uncertainty=0.3, randomize_start=True, current=current)
    one, batch = Simulator(config, 6), Simulator(config, 6)
    rows = [4, 1, 3]
    for i in rows:
        one.reset_row(i, np.random.default_rng(100 + i))
    batch.reset_rows(rows, [np.random.default_rng(100 + i) for i in rows])
    for name in ("state", "current", "params", "keys", "guid", "obs", "step_index"):
        np.testing.assert_array_equal(getattr(batch, name), getattr(one, name), err_msg=name)
    assert np.any(batch.params[4] != batch.params[1])  # perturbed per episode
    assert np.all(batch.state[[0, 2, 5]] == 0.0)  # rows not reset are untouched
