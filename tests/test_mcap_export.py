"""`auv-gym record`: an episode as MCAP with ROS 2 messages, read back with mcap's reader and
its ROS 2 decoder and compared with the episode value by value (the mcap extra)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mcap_ros2")

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from auv_gym.rollout import rollout
from benchmarks.cli import main
from benchmarks.reports import mcap_export
from benchmarks.reports.mcap_export import (
    TOPICS,
    enu_orientation,
    enu_position,
    message_definition,
    sim_time_ns,
)
from benchmarks.reports.record import episode_path, parse_args, record

ARGS = ["--policy", "pid_los", "--scenario", "paper", "--seed", "3", "--duration", "4"]


def _read(file: Path) -> tuple[dict[str, list], dict[str, str], dict[str, str]]:
    """(topic → [(log time, message)], topic → schema name, the episode's metadata record)."""
    messages: dict[str, list] = {}
    types = {}
    with open(file, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for schema, channel, message, decoded in reader.iter_decoded_messages(log_time_order=True):
            messages.setdefault(channel.topic, []).append((message.log_time, decoded))
            types[channel.topic] = schema.name
        (meta,) = [m for m in reader.iter_metadata() if m.name == "auv_gym.episode"]
    return messages, types, dict(meta.metadata)


def _ns(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def _xyz(v) -> list[float]:
    return [v.x, v.y, v.z]


def test_recorded_episode_reads_back_value_by_value(tmp_path: Path, capsys) -> None:
    out = tmp_path / "run.mcap"
    assert main(["record", *ARGS, "--out", str(out)]) == 0
    assert "81 samples of a 4-s episode" in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.mcap"]  # no temporary left
    args = parse_args([*ARGS, "--out", str(out)])
    tr = rollout(args.policy_object, 3, **args.env_kwargs)  # the same seeded episode
    messages, types, meta = _read(out)
    assert types == {topic.name: topic.type for topic in TOPICS}
    assert meta["policy"] == "pid_los" and meta["scenario"] == "paper" and meta["seed"] == "3"
    assert meta["termination_reason"] == tr.termination_reason
    assert json.loads(meta["control_dt"]) == tr.control_dt

    ns = sim_time_ns(tr.t)
    assert ns[-1] == 4_000_000_000 and np.all(np.diff(ns) == 50_000_000)
    samples = ns.tolist()
    intervals = samples[:-1]
    assert [t for t, _ in messages["/clock"]] == samples
    assert [_ns(m.clock) for _, m in messages["/clock"]] == samples
    for topic in ("/cmd/wrench", "/cmd/action", "/disturbance", "/reward"):
        assert [t for t, _ in messages[topic]] == intervals, topic
    for topic, frame in (
        ("/odom", "map"),
        ("/path_following/target", "map"),
        ("/path_following/error", "base_link"),
    ):
        assert [t for t, _ in messages[topic]] == samples, topic
        assert all(
            _ns(m.header.stamp) == t and m.header.frame_id == frame for t, m in messages[topic]
        )
    for topic in ("/cmd/wrench", "/disturbance"):
        assert all(_ns(m.header.stamp) == t for t, m in messages[topic])

    odom = [m for _, m in messages["/odom"]]
    assert {m.child_frame_id for m in odom} == {"base_link"}
    enu = np.array([_xyz(m.pose.pose.position) for m in odom])
    # ENU (east, north, up) is NED (y, x, −z): exact, a swap and a sign.
    np.testing.assert_array_equal(enu[:, 1], tr["x"])
    np.testing.assert_array_equal(enu[:, 0], tr["y"])
    np.testing.assert_array_equal(-enu[:, 2], tr["z"])
    quaternions = [m.pose.pose.orientation for m in odom]
    q = np.array([[o.x, o.y, o.z, o.w] for o in quaternions])
    yaw = np.arctan2(
        2 * (q[:, 3] * q[:, 2] + q[:, 0] * q[:, 1]), 1 - 2 * (q[:, 1] ** 2 + q[:, 2] ** 2)
    )
    pitch = np.arcsin(2 * (q[:, 3] * q[:, 1] - q[:, 2] * q[:, 0]))
    np.testing.assert_allclose(-pitch, tr["theta"], atol=1e-12)
    np.testing.assert_allclose(np.angle(np.exp(1j * (np.pi / 2 - yaw - tr["psi"]))), 0, atol=1e-12)
    linear = np.array([_xyz(m.twist.twist.linear) for m in odom])
    angular = np.array([_xyz(m.twist.twist.angular) for m in odom])
    np.testing.assert_array_equal(linear, np.column_stack([tr["u"], -tr["v"], -tr["w"]]))
    np.testing.assert_array_equal(angular[:, 1:], np.column_stack([-tr["q"], -tr["r"]]))
    assert not angular[:, 0].any()
    tf = [m.transforms[0] for _, m in messages["/tf"]]
    assert {(t.header.frame_id, t.child_frame_id) for t in tf} == {("map", "base_link")}
    np.testing.assert_array_equal([_xyz(t.transform.translation) for t in tf], enu)

    error = np.array([_xyz(m.vector) for _, m in messages["/path_following/error"]])
    np.testing.assert_array_equal(error, np.column_stack([tr["x_e"], -tr["y_e"], -tr["z_e"]]))
    target = np.array([_xyz(m.point) for _, m in messages["/path_following/target"]])
    np.testing.assert_array_equal(target, enu_position(tr.point))
    state = [m for _, m in messages["/path_following/state"]]
    assert state[0].layout.dim[0].label == "distance,s,s_dot,u_p"
    np.testing.assert_array_equal(
        [list(m.data) for m in state],
        np.column_stack([tr["distance"], tr["s"], tr["s_dot"], tr["u_p"]]),
    )

    wrench = [m.wrench for _, m in messages["/cmd/wrench"]]
    np.testing.assert_array_equal([w.force.x for w in wrench], tr["X"])
    np.testing.assert_array_equal([-w.torque.y for w in wrench], tr["M"])
    np.testing.assert_array_equal([-w.torque.z for w in wrench], tr["N"])
    assert not any([w.force.y, w.force.z, w.torque.x] != [0, 0, 0] for w in wrench)
    np.testing.assert_array_equal([list(m.data) for _, m in messages["/cmd/action"]], tr.actions)
    noise = [m.wrench for _, m in messages["/disturbance"]]
    np.testing.assert_array_equal(
        [[w.force.x, -w.force.y, -w.force.z, -w.torque.y, -w.torque.z] for w in noise],
        np.column_stack([tr[k] for k in ("f_u", "f_v", "f_w", "f_q", "f_r")]),
    )
    assert np.abs(tr["f_u"]).max() > 1.0  # the paper scenario's noise is in the file
    np.testing.assert_array_equal(
        [list(m.data) for _, m in messages["/reward"]],
        np.column_stack([tr["reward"], tr["cost"]]),
    )

    ((t0, path),) = messages["/path"]
    assert t0 == 0 and path.header.frame_id == "map"
    poses = np.array([_xyz(p.pose.position) for p in path.poses])
    drawn = episode_path(args.env_kwargs, 3)
    np.testing.assert_allclose(poses[0], enu_position(drawn.evaluate(np.array([0.0]))[0][0]))
    # Every virtual point the vehicle followed lies on the published path (poses ≤ 0.5 m apart).
    gaps = np.linalg.norm(target[:, None, :] - poses[None, :, :], axis=2).min(axis=1)
    assert gaps.max() <= mcap_export.PATH_SPACING


def test_orientation_points_the_body_x_axis_along_the_ned_heading_and_pitch() -> None:
    theta, psi = np.meshgrid(np.linspace(-1.2, 1.2, 7), np.linspace(-3.1, 3.1, 9))
    theta, psi = theta.ravel(), psi.ravel()
    q = enu_orientation(np.zeros_like(theta), theta, psi)
    x, y, z, w = q.T
    # The FLU body x-axis rotated into ENU (first column of the rotation matrix).
    forward = np.column_stack([1 - 2 * (y**2 + z**2), 2 * (x * y + w * z), 2 * (x * z - w * y)])
    ned = np.column_stack(
        [np.cos(theta) * np.cos(psi), np.cos(theta) * np.sin(psi), -np.sin(theta)]
    )
    np.testing.assert_allclose(forward, enu_position(ned), atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0)
    # Roll φ > 0 (starboard down, NED) lowers the body's right side: FLU's left axis rises.
    x, y, z, w = enu_orientation(np.array([0.3]), np.zeros(1), np.zeros(1))[0]
    left_up = 2 * (y * z + w * x)  # z component of the rotated FLU y axis
    assert math.isclose(left_up, math.sin(0.3))


def test_message_definitions_carry_every_type_they_use() -> None:
    text = message_definition("nav_msgs/msg/Odometry")
    assert text.startswith("std_msgs/Header header\nstring child_frame_id\n")
    for used in ("std_msgs/Header", "builtin_interfaces/Time", "geometry_msgs/PoseWithCovariance",
                 "geometry_msgs/Pose", "geometry_msgs/Point", "geometry_msgs/Quaternion",
                 "geometry_msgs/TwistWithCovariance", "geometry_msgs/Twist",
                 "geometry_msgs/Vector3"):  # fmt: skip
        assert text.count(f"\nMSG: {used}\n") == 1, used


def test_bad_outputs_are_refused_in_one_line_naming_the_path(tmp_path: Path, capsys) -> None:
    (tmp_path / "a_file").write_text("")
    (tmp_path / "folder.mcap").mkdir()
    for out, message in (
        (tmp_path / "missing" / "run.mcap", "folder"),
        (tmp_path / "a_file" / "run.mcap", "is a file"),
        (tmp_path / "folder.mcap", "it is a folder"),
        (tmp_path / "run.bag", "must name an .mcap file"),
    ):
        assert main(["record", *ARGS, "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1 and message in err and str(out) in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file", "folder.mcap"]


def test_an_episode_that_fails_leaves_no_file(tmp_path: Path, monkeypatch, capsys) -> None:
    (tmp_path / "broken_policy.py").write_text(
        "class Broken:\n"
        "    def predict(self, obs, state=None, episode_start=None, deterministic=True):\n"
        "        raise ArithmeticError('no action')\n"
        "policy = Broken()\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    out = tmp_path / "out" / "run.mcap"
    out.parent.mkdir()
    out.write_bytes(b"an earlier recording")
    assert main(["record", "--policy", "broken_policy:policy", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and str(out) in err and "no action" in err, err
    assert out.read_bytes() == b"an earlier recording"  # untouched
    assert sorted(p.name for p in out.parent.iterdir()) == ["run.mcap"]


def test_a_write_that_fails_midway_leaves_no_partial_file(tmp_path: Path, monkeypatch) -> None:
    args = parse_args([*ARGS, "--duration", "1", "--out", str(tmp_path / "run.mcap")])

    def half_then_full_disk(fh, *rest):
        fh.write(b"\x89MCAP0\r\n" + bytes(1000))
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(mcap_export, "_write", half_then_full_disk)
    with pytest.raises(RuntimeError, match=r"run\.mcap.*not written: No space left"):
        record(args.policy_object, args.env_kwargs, args.out, 3)
    assert not list(tmp_path.iterdir())


def test_record_help_shows_every_default(capsys) -> None:
    with pytest.raises(SystemExit) as stop:
        main(["record", "--help"])
    assert stop.value.code == 0
    text = capsys.readouterr().out
    assert text.startswith("usage: auv-gym record")
    for flag in ("--policy", "--scenario", "--seed", "--duration", "--out"):
        assert flag in text
    assert text.count("(default:") >= 6
