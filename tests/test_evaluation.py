"""auv_gym.rollout, .metrics and .trajectory: metrics against hand-computed values, .npz round
trip, determinism, and batched rollouts against the single Gymnasium env."""

from __future__ import annotations

import math

import numpy as np
import pytest

import controllers
from auv_gym import OBS_INDEX, AUVPath3DEnv
from auv_gym.metrics import MetricsWindowWarning, compute_metrics
from auv_gym.rollout import evaluate, rollout, rollouts
from auv_gym.sim.trajectory import INTERVAL_FIELDS, SAMPLE_FIELDS, Trajectory


class ProportionalPolicy:
    """A small LOS + PD policy (not the paper's controller), enough to follow the helix roughly.

    X feeds u_D − u back around the 1.6-N drag at 1 m/s; M and N track θ_d = θ_F + atan(k_z z_e)
    and ψ_d = ψ_F − atan(k_y y_e) (docs/model.md §3.4) with rate damping. Row-wise, so batched calls
    equal per-row calls bit for bit.
    """

    name = "proportional"

    def __init__(self, k_y: float = 0.1, k_z: float = 0.5) -> None:
        self.k_y, self.k_z = k_y, k_z

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        o = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        i = OBS_INDEX
        x = (20.0 * (o[:, i["u_D"]] - o[:, i["u"]]) + 1.6) / 50.0
        theta_d = np.clip(o[:, i["theta_F"]] + np.arctan(self.k_z * o[:, i["z_e"]]), -0.7, 0.7)
        m = (4.0 * (theta_d - o[:, i["theta"]]) - 8.0 * o[:, i["q"]]) / 10.0
        n = (
            -4.0 * (o[:, i["psi_error"]] + np.arctan(self.k_y * o[:, i["y_e"]]))
            - 8.0 * o[:, i["r"]]
        ) / 10.0
        return np.clip(np.column_stack([x, m, n]), -1.0, 1.0).astype(np.float32), state


class CountingPolicy(ProportionalPolicy):
    """Carries a step counter in `state` and exposes it and θ_d through `diagnostics`."""

    name = "counting"

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        n = np.atleast_2d(observation).shape[0]
        count = np.zeros(n) if state is None else state.copy()
        if episode_start is not None:
            count[np.asarray(episode_start, dtype=bool)] = 0.0
        action, _ = super().predict(observation)
        return action, count + 1.0

    def diagnostics(self, state):
        return {"count": state, "pair": np.column_stack([state, 2.0 * state])}


class PitchUpPolicy:
    """Full thrust and a pitch moment that depends on y_e: rows fail at different steps."""

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        o = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        m = np.clip(0.3 + 0.5 * o[:, OBS_INDEX["y_e"]] / 8.0, -1.0, 1.0)
        ones = np.ones(o.shape[0])
        return np.column_stack([ones, m, 0.3 * ones]), state


def synthetic_trajectory(**overrides) -> Trajectory:
    """K = 10 control steps of 1 s with values chosen so the metrics are easy by hand."""
    d = np.array([5.0, 4.0, 3.0, 2.0, 0.6, 0.4, 0.3, 0.05, 0.2, 0.08, 0.05])
    u = np.array([0.0, 0.5, 0.9, 1.1, 1.05, 1.0, 1.0, 0.98, 1.02, 1.0, 1.0])
    samples = {name: np.zeros(11) for name in SAMPLE_FIELDS}
    u_p = np.array([1.0, 1.0, 1.0, 1.0, 1.0, 1.2, 1.1, 1.0, 1.0, 0.9, 1.2])
    samples.update(distance=d, x_e=np.zeros(11), y_e=0.6 * d, z_e=0.8 * d, u=u, u_p=u_p)
    x_bar = np.array([1.0, 1.0, 0.5] + [0.2] * 7)
    m_bar = np.array([1.0, -1.0, 0.0, 0.0, 0.0, 0.5, -0.5, 0.5, -0.5, 0.5])
    intervals = {name: np.zeros(10) for name in INTERVAL_FIELDS}
    intervals.update(X=50.0 * x_bar, M=10.0 * m_bar, reward=np.ones(10))
    intervals.update(a_X=np.r_[1.3, x_bar[1:]], a_M=m_bar)
    kwargs = dict(
        t=np.arange(11.0),
        samples=samples,
        intervals=intervals,
        control_dt=1.0,
        u_desired=1.0,
        actuator_limits=(50.0, 10.0, 10.0),
        metadata={"seed": 7, "policy": "hand"},
    )
    kwargs.update(overrides)
    return Trajectory(**kwargs)


def test_metrics_match_hand_computed_values():
    m = compute_metrics(synthetic_trajectory(), transient=5.0)
    # Window t >= 5 s: d = 0.4, 0.3, 0.05, 0.2, 0.08, 0.05; Σd² = 0.3014.
    rms_d = math.sqrt(0.3014 / 6)
    expected = {
        "rms_distance": rms_d,
        "rms_x_e": 0.0,
        "rms_y_e": 0.6 * rms_d,
        "rms_z_e": 0.8 * rms_d,
        "max_distance_window": 0.4,
        # Trapezoid sums of neighbouring d: 4.5 + 3.5 + 2.5 + 1.3 + 0.5 + 0.35 + 0.175 + 0.125
        # + 0.14 + 0.065.
        "iae_distance": 13.155,
        "iae_distance_window": 0.35 + 0.175 + 0.125 + 0.14 + 0.065,
        "settling_time_0p5": 5.0,  # last d >= 0.5 at t = 4 s
        "settling_time_0p1": 9.0,  # last d >= 0.1 at t = 8 s
        "surge_overshoot": 0.1,
        "surge_overshoot_percent": 10.0,
        "rms_speed_error": math.sqrt(0.0008 / 6),  # u − u_D = 0, 0, −.02, .02, 0, 0
        "mean_path_speed": 6.4 / 6,  # u_p = 1.2, 1.1, 1.0, 1.0, 0.9, 1.2
        # Σ X̄² = 1 + 1 + 0.25 + 7·0.04 = 2.53; Σ M̄² = 2 + 5·0.25 = 3.25; Δt = 1 s.
        "control_effort": 5.78,
        "control_effort_X": 2.53,
        "control_effort_M": 3.25,
        "control_effort_N": 0.0,
        # Window intervals t = 5..9 s: M̄ = .5, −.5, .5, −.5, .5 → total variation 4 over 5 s.
        "chattering": 0.8,
        "chattering_X": 0.0,
        "chattering_M": 0.8,
        "chattering_N": 0.0,
        "saturation_fraction": 0.2,  # steps 0 (a_X = 1.3, a_M = 1) and 1 (a_X = 1, a_M = −1)
        "saturation_fraction_X": 0.2,
        "saturation_fraction_M": 0.2,
        "saturation_fraction_N": 0.0,
        "final_distance": 0.05,
        "episode_return": 10.0,
        "duration": 10.0,
        "steps": 10,
        "transient": 5.0,
        "window_samples": 6,
    }
    for name, value in expected.items():
        np.testing.assert_allclose(m[name], value, rtol=1e-12, atol=1e-14, err_msg=name)
    assert m["termination_reason"] == "time_limit"
    # Success: RMS d over the final 10 s (t = 1..10 s) is √(29.6614/10) = 1.72 m > 1 m.
    assert m["success"] is False
    # Over the final 3 s (t = 7..10 s) it is √(0.0514/4) = 0.113 m.
    assert compute_metrics(synthetic_trajectory(), final_window=3.0)["success"] is True


def test_metrics_failure_and_never_settling():
    failed = compute_metrics(synthetic_trajectory(termination_reason="corridor"), final_window=3)
    assert failed["success"] is False
    assert failed["settling_time_0p5"] == math.inf and failed["settling_time_0p1"] == math.inf
    tr = synthetic_trajectory()
    tr.samples["distance"][-1] = 0.2
    m = compute_metrics(tr, transient=5.0)
    assert m["settling_time_0p1"] == math.inf
    assert m["settling_time_0p5"] == 5.0
    # A window beyond the episode gives NaN windowed metrics, not an error, and says so.
    with pytest.warns(MetricsWindowWarning, match="holds 0 sample"):
        late = compute_metrics(synthetic_trajectory(), transient=20.0)
    assert math.isnan(late["rms_distance"]) and math.isnan(late["chattering"])
    assert late["window_samples"] == 0
    assert late["iae_distance"] == pytest.approx(13.155)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"t": np.arange(12.0)}, "shape"),
        ({"termination_reason": "exploded"}, "termination_reason"),
        ({"control_dt": 0.0}, "control_dt"),
        ({"extras": {"bad": np.zeros(3)}}, "extras"),
    ],
)
def test_trajectory_rejects_bad_input(change, message):
    with pytest.raises(ValueError, match=message):
        synthetic_trajectory(**change)


def test_trajectory_rejects_missing_series():
    tr = synthetic_trajectory()
    del tr.samples["u"]
    with pytest.raises(ValueError, match="lack"):
        Trajectory(t=tr.t, samples=tr.samples, intervals=tr.intervals)


def test_npz_round_trip(tmp_path):
    tr = rollout(CountingPolicy(), 3, max_time=2.0, disturbance=20.0)
    file = tmp_path / "episode.npz"
    tr.save(file)
    assert [p.name for p in tmp_path.iterdir()] == ["episode.npz"]  # no temporary left behind
    back = Trajectory.load(file)
    np.testing.assert_array_equal(back.t, tr.t)
    for name in (*SAMPLE_FIELDS, *INTERVAL_FIELDS, "count", "pair"):
        np.testing.assert_array_equal(back[name], tr[name], err_msg=name)
    assert back.extras["pair"].shape == (40, 2)
    assert back.termination_reason == tr.termination_reason == "time_limit"
    assert (back.control_dt, back.u_desired, back.actuator_limits) == (
        0.05,
        1.0,
        (50.0, 10.0, 10.0),
    )
    assert back.metadata["seed"] == 3 and back.metadata["policy"] == "counting"
    assert back.metadata["env_kwargs"] == {"max_time": 2.0, "disturbance": 20.0}
    assert _same_metrics(back, tr)
    # Saving through a name without the .npz suffix keeps the name (numpy would append one).
    tr.save(tmp_path / "plain.tmp")
    assert (tmp_path / "plain.tmp").exists() and not (tmp_path / "plain.tmp.npz").exists()


def _same_metrics(a: Trajectory, b: Trajectory) -> bool:
    ma, mb = compute_metrics(a, transient=1.0), compute_metrics(b, transient=1.0)
    return ma.keys() == mb.keys() and all(ma[k] == mb[k] for k in ma)


def test_diagnostics_hook_and_episode_start():
    (tr,) = rollouts(CountingPolicy(), [0], max_time=1.0)
    # episode_start is True at the first call only: the counter counts 1..20.
    np.testing.assert_array_equal(tr.extras["count"], np.arange(1.0, 21.0))
    np.testing.assert_array_equal(tr.extras["pair"][:, 1], 2.0 * np.arange(1.0, 21.0))


def test_evaluate_is_deterministic_and_batch_independent():
    seeds = [0, 1, 2]
    first = evaluate(ProportionalPolicy(), seeds, transient=5.0, max_time=10.0)
    again = evaluate(ProportionalPolicy(), seeds, transient=5.0, max_time=10.0)
    one_by_one = evaluate(ProportionalPolicy(), seeds, transient=5.0, batch_size=1, max_time=10.0)
    threaded = evaluate(ProportionalPolicy(), seeds, transient=5.0, threads=2, max_time=10.0)
    assert first == again == one_by_one == threaded
    assert [m["seed"] for m in first] == seeds
    # Different seeds meet different noise.
    assert first[0]["rms_distance"] != first[1]["rms_distance"]
    assert all(m["steps"] == 200 and m["termination_reason"] == "time_limit" for m in first)


def _env_episode(policy, seed: int, **env_kwargs) -> dict[str, np.ndarray]:
    """The same episode through `AUVPath3DEnv`, one `predict` call per step on one row."""
    env = AUVPath3DEnv(**env_kwargs)
    obs, info = env.reset(seed=seed)
    rows = {
        "state": [env.state],
        "x_e": [info["x_e"]],
        "distance": [info["distance"]],
        "u_p": [info["u_p"]],
        "t": [info["t"]],
        "tau": [],
        "f": [],
        "reward": [],
        "action": [],
    }
    reason = "time_limit"
    while True:
        action, _ = policy.predict(obs[None], deterministic=True)
        obs, reward, terminated, truncated, info = env.step(action[0])
        for key in ("x_e", "distance", "u_p", "t"):
            rows[key].append(info[key])
        rows["state"].append(env.state)
        rows["tau"].append(info["tau"])
        rows["f"].append(info["disturbance"])
        rows["reward"].append(reward)
        rows["action"].append(action[0])
        if terminated:
            reason = info["termination_reason"]
        if terminated or truncated:
            break
    out = {k: np.asarray(v) for k, v in rows.items()}
    out["reason"] = reason
    return out


def test_batched_rollouts_equal_single_env():
    kwargs = {"max_time": 4.0}
    seeds = [3, 5, 11]
    batched = rollouts(ProportionalPolicy(), seeds, **kwargs)
    for seed, tr in zip(seeds, batched, strict=True):
        ref = _env_episode(ProportionalPolicy(), seed, **kwargs)
        assert tr.steps == 80 and tr.termination_reason == ref["reason"] == "time_limit"
        np.testing.assert_array_equal(tr.t, ref["t"])
        state = np.column_stack(
            [tr[name] for name in ("x", "y", "z", "theta", "psi", "u", "v", "w", "q", "r", "s")]
        )
        np.testing.assert_array_equal(state, ref["state"])
        for key in ("x_e", "distance", "u_p"):
            np.testing.assert_array_equal(tr[key], ref[key], err_msg=key)
        np.testing.assert_array_equal(tr.tau, ref["tau"])
        np.testing.assert_array_equal(
            np.column_stack([tr[f] for f in ("f_u", "f_v", "f_w", "f_q", "f_r")]), ref["f"]
        )
        np.testing.assert_array_equal(tr["reward"], ref["reward"])
        np.testing.assert_array_equal(tr.actions, ref["action"])
    # Disturbances depend on the seed alone: another policy meets the same noise.
    other = rollouts(PitchUpPolicy(), seeds[:1], **kwargs)[0]
    np.testing.assert_array_equal(other["f_q"][:40], batched[0]["f_q"][:40])


def test_terminated_rows_stop_recording_like_the_env():
    kwargs = {"max_time": 5.0, "randomize_start": True}
    seeds = list(range(6))
    trajectories = rollouts(PitchUpPolicy(), seeds, **kwargs)
    lengths = set()
    for seed, tr in zip(seeds, trajectories, strict=True):
        ref = _env_episode(PitchUpPolicy(), seed, **kwargs)
        assert tr.steps == len(ref["reward"])
        assert tr.termination_reason == ref["reason"]
        np.testing.assert_array_equal(tr["distance"], ref["distance"])
        lengths.add(tr.steps)
    assert len(lengths) >= 3  # rows ended at different steps, one of them at the time limit
    assert {tr.termination_reason for tr in trajectories} == {"pitch", "time_limit"}
    failed = [compute_metrics(tr, transient=1.0) for tr in trajectories]
    assert all(m["success"] is False for m in failed if m["termination_reason"] == "pitch")


def test_virtual_point_position_is_on_the_path():
    tr = rollout(ProportionalPolicy(), 0, max_time=2.0)
    from auv_gym.paths import make_path

    p, _, _ = make_path("helix").evaluate(tr["s"])
    np.testing.assert_allclose(tr.point, p, rtol=0, atol=1e-12)
    # |vehicle − p(s)| is the guidance distance.
    np.testing.assert_allclose(
        np.linalg.norm(tr.position - tr.point, axis=1), tr["distance"], rtol=1e-9, atol=1e-9
    )


class _WrongShape:
    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        return np.zeros((len(observation), 2)), state


@pytest.mark.parametrize(
    ("policy", "seeds", "kwargs", "message"),
    [
        (object(), [0], {}, "predict"),
        (_WrongShape(), [0], {}, "shape"),
        (ProportionalPolicy(), [], {}, "empty"),
        (ProportionalPolicy(), [-1], {}, "non-negative"),
        (ProportionalPolicy(), [0.5], {}, "integers"),
        (ProportionalPolicy(), [0], {"render_mode": "rgb_array"}, "unknown env keyword"),
        (ProportionalPolicy(), [0], {"batch_size": 0}, "batch_size"),
        (ProportionalPolicy(), [0], {"threads": 0}, "threads"),
    ],
)
def test_rollouts_reject_bad_input(policy, seeds, kwargs, message):
    with pytest.raises(ValueError, match=message):
        rollouts(policy, seeds, max_time=0.1, **kwargs)


@pytest.mark.parametrize("name", ["fbsm", "backstepping"])
def test_paper_controllers_batched_equal_alone(name):
    batched = rollouts(controllers.make(name), [0, 4, 7], max_time=10.0)
    alone = rollout(controllers.make(name), 4, max_time=10.0)
    for key in ("distance", "X", "M", "N", *alone.extras):
        np.testing.assert_array_equal(batched[1][key], alone[key], err_msg=key)
    assert not np.array_equal(batched[0]["distance"], batched[1]["distance"])


@pytest.mark.rl
def test_sb3_model_is_a_policy():
    sb3 = pytest.importorskip("stable_baselines3")
    model = sb3.PPO("MlpPolicy", AUVPath3DEnv(max_time=1.0), n_steps=64, seed=0, device="cpu")
    first, second = rollouts(model, [0, 1], max_time=1.0)
    assert first.steps == second.steps == 20
    obs0 = AUVPath3DEnv().reset(seed=0)[0]
    expected, _ = model.predict(obs0, deterministic=True)
    np.testing.assert_allclose(first.actions[0], expected, rtol=1e-6, atol=1e-6)
    assert first.metadata["policy"] == "PPO"
