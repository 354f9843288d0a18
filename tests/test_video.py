"""Videos: `auv-gym video` writes an MP4 of an episode; gymnasium's RecordVideo works on the env
(both need the video extra)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from benchmarks.cli import main

imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")


def _frames(file: Path) -> tuple[dict, list[np.ndarray]]:
    reader = imageio_ffmpeg.read_frames(str(file))
    meta = next(reader)
    width, height = meta["size"]
    return meta, [np.frombuffer(f, np.uint8).reshape(height, width, 3) for f in reader]


def test_video_command_writes_every_kth_frame(tmp_path: Path, capsys) -> None:
    out = tmp_path / "videos" / "run.mp4"
    assert (
        main(
            [
                "video",
                "--policy",
                "backstepping",
                "--scenario",
                "nominal",
                "--duration",
                "4",
                "--every",
                "4",
                "--fps",
                "10",
                "--out",
                str(out),
                "--quiet",
            ]
        )
        == 0
    )
    meta, frames = _frames(out)
    assert meta["size"] == (960, 320) and meta["fps"] == 10
    assert len(frames) == 1 + 80 // 4  # the reset frame, then every 4th of 80 control steps
    assert frames[-1].std() > 10 and not np.array_equal(frames[1], frames[-1])
    assert "21 frames at 10 fps" in capsys.readouterr().out
    assert sorted(p.name for p in out.parent.iterdir()) == ["run.mp4"]  # no temporary left


def test_video_command_names_bad_arguments(tmp_path: Path, capsys) -> None:
    for args, message in (
        (["--out", str(tmp_path / "x.gif")], "--out must name an .mp4"),
        (["--every", "0"], "--every must be in"),
        (["--scenario", "nowhere"], "unknown scenario"),
    ):
        assert main(["video", *args]) == 2
        assert message in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_record_video_wrapper_works_on_the_env(tmp_path: Path) -> None:
    pytest.importorskip("moviepy")
    import gymnasium as gym
    from gymnasium.wrappers import RecordVideo

    import auv_gym  # noqa: F401

    env = gym.make("AUVPath3D-v0", render_mode="rgb_array", max_time=1.0, disturbance="none")
    env = RecordVideo(
        env, str(tmp_path / "videos"), episode_trigger=lambda episode: True, disable_logger=True
    )
    env.reset(seed=0)
    done = False
    while not done:
        _, _, terminated, truncated, _ = env.step(np.array([0.5, 0.0, 0.0], dtype=np.float32))
        done = terminated or truncated
    env.close()
    (video,) = (tmp_path / "videos").glob("*.mp4")
    meta, frames = _frames(video)
    assert meta["fps"] == 20 and len(frames) == 21  # reset + 20 steps of 0.05 s
