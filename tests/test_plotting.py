"""benchmarks.reports.plotting, .episode_figures and benchmarks.reports.paper_figures: PNGs, tables,
CLI."""

from __future__ import annotations

import json
import math
import os
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from auv_gym import OBS_INDEX, make_path
from auv_gym.rollout import rollouts
from auv_gym.sim.trajectory import Trajectory
from benchmarks.reports.episode_figures import PAPER_FIGURES, paper_figures
from benchmarks.reports.plotting import metrics_table, save_figure

ROOT = Path(__file__).resolve().parents[1]
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


class LOSPolicy:
    """LOS + PD test policy (θ_d = θ_F + atan(0.5 z_e), ψ_d = ψ_F − atan(0.1 y_e))."""

    name = "plain"

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        o = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        i = OBS_INDEX
        theta_d = o[:, i["theta_F"]] + np.arctan(0.5 * o[:, i["z_e"]])
        psi_error_d = -np.arctan(0.1 * o[:, i["y_e"]])  # ψ_d − ψ_F
        x = (20.0 * (o[:, i["u_D"]] - o[:, i["u"]]) + 1.6) / 50.0
        m = (4.0 * (theta_d - o[:, i["theta"]]) - 8.0 * o[:, i["q"]]) / 10.0
        n = (-4.0 * (o[:, i["psi_error"]] - psi_error_d) - 8.0 * o[:, i["r"]]) / 10.0
        action = np.clip(np.column_stack([x, m, n]), -1.0, 1.0)
        return action, (theta_d, psi_error_d)


class AdaptiveLOSPolicy(LOSPolicy):
    """Integrates |x_e| in its state and exposes "norm_*", "theta_d" and "psi_d_rel" through
    the diagnostics hook, as the FBSM may."""

    name = "adaptive"

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        o = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        action, (theta_d, psi_error_d) = super().predict(o)
        weights = np.zeros(o.shape[0]) if state is None else state[0]
        weights = weights + 0.05 * np.abs(o[:, OBS_INDEX["x_e"]])
        return action, (weights, theta_d, psi_error_d)

    def diagnostics(self, state):
        weights, theta_d, psi_error_d = state
        return {
            "norm_theta_f_surge": weights,
            "norm_pair": np.column_stack([weights, theta_d]),
            "theta_d": theta_d,
            "psi_d_rel": psi_error_d,
        }


def png_size(file: Path) -> tuple[int, int]:
    """(width, height) in pixels from the PNG header."""
    data = file.read_bytes()[:24]
    assert data[:8] == PNG_SIGNATURE
    return struct.unpack(">II", data[16:24])


@pytest.fixture(scope="module")
def episodes() -> dict[str, Trajectory]:
    (plain,) = rollouts(LOSPolicy(), [0], max_time=20.0)
    (adaptive,) = rollouts(AdaptiveLOSPolicy(), [0], max_time=20.0)
    return {"plain": plain, "adaptive": adaptive}


def test_paper_figures_write_pngs_of_the_documented_size(episodes, tmp_path):
    written = paper_figures(episodes, tmp_path, path=make_path("helix"), dpi=100, zoom_from=10.0)
    assert list(written) == list(PAPER_FIGURES)
    expected_inches = {
        "fig3_path_3d": (7.0, 5.5),
        "fig4_horizontal": (7.0, 5.5),
        "fig5_vertical": (7.0, 5.5),
        "fig6_errors": (10.0, 6.0),  # with the zoomed column
        "fig7_surge": (7.0, 4.5),
        "fig8_attitude": (7.0, 5.5),
        "fig9_controls": (7.0, 6.0),
        "fig10_adaptive_norms": (7.0, 1.6 + 1.3 * 2),
        "fig11_distance": (7.0, 4.5),
    }
    for stem, file in written.items():
        assert file == tmp_path / f"{stem}.png"
        width, height = expected_inches[stem]
        assert png_size(file) == (round(width * 100), round(height * 100)), stem
        assert file.stat().st_size > 15_000, stem  # axes, text and curves, not a blank canvas
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(f"{s}.png" for s in written)


def test_figures_draw_the_data(episodes, tmp_path):
    from matplotlib.image import imread

    file = paper_figures({"plain": episodes["plain"]}, tmp_path, dpi=100)["fig6_errors"]
    pixels = imread(file)[..., :3]
    colours = np.unique((pixels.reshape(-1, 3) * 255).astype(np.uint8), axis=0)
    assert colours.shape[0] > 50  # anti-aliased lines and text in several colours
    from matplotlib.colors import to_rgb

    from benchmarks.reports.plotting import policy_colours

    colour = np.array(to_rgb(policy_colours(["plain"])["plain"]))  # the policy's own colour
    near = np.all(np.abs(pixels - colour) < 0.05, axis=-1)
    assert near.sum() > 300  # three panels of 20-s error curves


def test_adaptive_figure_only_with_norms(episodes, tmp_path):
    written = paper_figures({"plain": episodes["plain"]}, tmp_path, dpi=50)
    assert "fig10_adaptive_norms" not in written
    assert len(written) == len(PAPER_FIGURES) - 1
    with pytest.raises(ValueError, match="at least one"):
        paper_figures({}, tmp_path)


def test_save_figure_is_atomic_and_follows_the_umask(tmp_path):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(2.0, 1.0), dpi=50)
    fig.add_subplot(1, 1, 1).plot([0, 1], [1, 0])
    target = save_figure(fig, tmp_path / "sub" / "f.png")
    assert png_size(target) == (100, 50)
    assert [p.name for p in target.parent.iterdir()] == ["f.png"]
    mask = os.umask(0)
    os.umask(mask)
    assert target.stat().st_mode & 0o777 == 0o666 & ~mask


def test_render_track_still_renders_the_env():
    from auv_gym import AUVPath3DEnv

    env = AUVPath3DEnv(render_mode="rgb_array", max_time=1.0)
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.array([0.5, 0.0, 0.0]))
    frame = env.render()
    assert frame.shape == (320, 960, 3) and frame.dtype == np.uint8
    assert frame.min() < 100 and frame.max() == 255


def test_metrics_table_marks_the_best_value():
    results = {
        "A": {
            "rms_distance": 0.04,
            "settling_time_0p5": 31.2,
            "success": True,
            "chattering": math.nan,
            "termination_reason": "time_limit",
        },
        "B": {
            "rms_distance": 0.3,
            "settling_time_0p5": math.inf,
            "success": False,
            "chattering": 0.5,
            "termination_reason": "corridor",
        },
    }
    table = metrics_table(
        results,
        ["rms_distance", "settling_time_0p5", "success", "chattering", "termination_reason"],
    )
    lines = table.strip().splitlines()
    assert lines[0] == "| metric | unit | A | B |"
    assert lines[2] == "| RMS distance, t ≥ transient | m | **0.0400** | 0.300 |"
    assert lines[3] == "| settling time to 0.5 m | s | **31.2** | never |"
    assert lines[4] == "| success | - | yes | no |"
    assert lines[5] == "| chattering TV(τ/τ_max) per s | 1/s | — | 0.500 |"  # NaN: no winner
    assert lines[6] == "| episode end | - | time_limit | corridor |"


def test_make_figures_on_test_policies(tmp_path):
    from benchmarks.reports.paper_figures import make_figures

    result = make_figures(
        {"plain": LOSPolicy(), "adaptive": AdaptiveLOSPolicy()},
        tmp_path,
        duration=10.0,
        seed=3,
        dpi=40,
    )
    assert len(result["figures"]) == len(PAPER_FIGURES)
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["seed"] == 3 and metrics["transient"] == 5.0
    assert metrics["metrics"]["plain"]["steps"] == 200
    assert metrics["metrics"]["plain"]["settling_time_0p1"] == "inf"
    table = (tmp_path / "metrics.md").read_text()
    assert "| metric | unit | plain | adaptive |" in table
    back = Trajectory.load(tmp_path / "trajectories" / "adaptive.npz")
    assert back.metadata["seed"] == 3 and back.extras["norm_pair"].shape == (200, 2)
    # Same seed, same disturbance for both policies.
    plain = Trajectory.load(tmp_path / "trajectories" / "plain.npz")
    np.testing.assert_array_equal(plain["f_r"], back["f_r"])


def test_cli_end_to_end(tmp_path):
    out = tmp_path / "figs"
    spec = "tests.test_plotting:LOSPolicy"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "benchmarks.reports.paper_figures",
            "--out",
            str(out),
            "--duration",
            "5",
            "--seed",
            "1",
            "--policies",
            spec,
            "--dpi",
            "30",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert "wrote 8 figures" in proc.stdout  # no adaptive norms for this policy
    assert png_size(out / "fig3_path_3d.png") == (210, 165)
    assert (out / "metrics.md").read_text().count("| plain |") == 1
    bad = subprocess.run(
        [
            sys.executable,
            "-m",
            "benchmarks.reports.paper_figures",
            "--out",
            str(out),
            "--duration",
            "-1",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert bad.returncode == 2 and "--duration must be a finite number in (0, " in bad.stderr


def test_cli_with_the_paper_controllers(tmp_path):
    out = tmp_path / "paper"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "benchmarks.reports.paper_figures",
            "--out",
            str(out),
            "--duration",
            "8",
            "--dpi",
            "30",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    assert "wrote 9 figures" in proc.stdout  # FBSM exposes its adaptive-parameter norms
    assert "| metric | unit | FBSM | backstepping |" in (out / "metrics.md").read_text()
    fbsm = Trajectory.load(out / "trajectories" / "FBSM.npz")
    backstepping = Trajectory.load(out / "trajectories" / "backstepping.npz")
    assert fbsm.steps == backstepping.steps == 160
    assert {"theta_d", "psi_d_rel"} <= set(fbsm.extras) and any(
        k.startswith("norm_") for k in fbsm.extras
    )
    np.testing.assert_array_equal(fbsm["f_u"], backstepping["f_u"])  # the same noise
    assert np.abs(fbsm["f_u"]).max() <= 35.0 and np.abs(fbsm["f_u"]).max() > 5.0


def test_a_policy_has_one_colour_in_every_figure():
    from matplotlib.colors import to_hex

    from auv_gym.paths import Helix
    from benchmarks.analysis.stats_figures import learning_curve_figure
    from benchmarks.reports.plotting import new_figure, plot_track, policy_colours

    names = ["fbsm", "my_agent", "ppo_helix", "other_agent"]
    colours = policy_colours(names)
    assert len(set(colours.values())) == len(names)
    # Fixed for shipped names, stable for others, whatever else is drawn and in which order.
    assert policy_colours(["ppo_helix", "fbsm"]) == {
        "ppo_helix": colours["ppo_helix"],
        "fbsm": colours["fbsm"],
    }
    assert policy_colours(["my_agent"])["my_agent"] == policy_colours(["x", "my_agent"])["my_agent"]

    fig = new_figure(9, 3, 60)
    tracks = {n: np.column_stack([np.arange(5.0), np.zeros(5), np.zeros(5)]) for n in names}
    plot_track(fig, Helix(), tracks, s_max=10.0)
    track_colours = {line.get_label(): to_hex(line.get_color()) for line in fig.axes[0].lines}
    curve = {"x": [0.0, 1.0], "iqm": [2.0, 1.0], "low": [1.5, 0.5], "high": [2.5, 1.5], "n_runs": 2}
    curves = learning_curve_figure({"env steps": {n: curve for n in reversed(names)}})
    curve_colours = {
        line.get_label().split(" (")[0]: to_hex(line.get_color()) for line in curves.axes[0].lines
    }
    for name in names:
        assert track_colours[name] == curve_colours[name] == to_hex(colours[name])


def test_every_shipped_policy_has_a_fixed_colour_of_its_own():
    """A shipped name without a fixed colour takes one by hash, which can sit next to a
    look-alike (an agent once drew in another's orange in the suite's learning curves)."""
    from benchmarks.catalog.policies import REFERENCE_AGENTS
    from benchmarks.reports.plotting import POLICY_COLOURS
    from controllers import CLASSICAL

    names = [*CLASSICAL, *REFERENCE_AGENTS]
    assert [n for n in names if n not in POLICY_COLOURS] == []
    assert len({POLICY_COLOURS[n] for n in names}) == len(names)
