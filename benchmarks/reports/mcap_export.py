"""A recorded episode as an MCAP file of ROS 2 messages (CDR), for Foxglove and ``ros2 bag``.

`write_episode_mcap` turns a `auv_gym.sim.trajectory.Trajectory` into the topics of `TOPICS`, in
standard message types whose ROS 2 .msg definitions the file carries (`message_definition`,
in the form rosbag2 writes), so Foxglove, ``ros2 bag info``/``play`` and ``mcap`` read it without
a ROS installation. It needs the ``mcap`` and ``mcap-ros2-support`` packages (the mcap extra).

Frames (REP-103, REP-105). The simulator is NED with a forward-starboard-down (FRD) body; the
file is ENU with a forward-left-up (FLU) body, as ROS tools expect:

* ``map``: the world frame, ENU, with the sim's origin: (x, y, z)_map = (y, x, −z)_NED
  (east = the sim's y, north = the sim's x, up = −z, so the height is −depth);
* ``base_link``: the vehicle, FLU: a body vector (a, b, c)_FRD is (a, −b, −c)_FLU; the
  orientation of roll φ, pitch θ (nose up > 0) and heading ψ (from north, clockwise) is the
  ENU rotation of roll φ, pitch −θ, yaw π/2 − ψ. The 5-DOF plant has no roll (φ = 0).

Time. Every stamp and log time is the sim time t (0 at the reset) in ns, the same clock that
``/clock`` publishes: samples (state, errors) at t_0 … t_K, interval values (commands,
disturbance, reward) at the start t_k of the control period [t_k, t_{k+1}) they belong to.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np

from auv_gym.metrics import ROLL_ANGLE
from auv_gym.sim.trajectory import Trajectory
from auv_gym.support.files import json_default, write_atomic

__all__ = [
    "BODY_FRAME",
    "TOPICS",
    "WORLD_FRAME",
    "Topic",
    "enu_orientation",
    "enu_position",
    "flu_vector",
    "message_definition",
    "path_points",
    "sim_time_ns",
    "write_episode_mcap",
]

WORLD_FRAME = "map"  # ENU, the sim's origin
BODY_FRAME = "base_link"  # FLU
METADATA_NAME = "auv_gym.episode"  # the MCAP metadata record of the episode's facts
PATH_SPACING = 0.5  # [m] between the poses of /path (about; at most MAX_PATH_POSES of them)
MAX_PATH_POSES = 20_000

# The ROS 2 .msg fields of every type the file uses (comments and constants left out; names
# fully qualified). Each type's definition in the file is its fields, then its dependencies.
_FIELDS: dict[str, str] = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id",
    "std_msgs/MultiArrayDimension": "string label\nuint32 size\nuint32 stride",
    "std_msgs/MultiArrayLayout": "std_msgs/MultiArrayDimension[] dim\nuint32 data_offset",
    "std_msgs/Float64MultiArray": "std_msgs/MultiArrayLayout layout\nfloat64[] data",
    "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1",
    "geometry_msgs/Pose": "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation",
    "geometry_msgs/PoseStamped": "std_msgs/Header header\ngeometry_msgs/Pose pose",
    "geometry_msgs/PoseWithCovariance": "geometry_msgs/Pose pose\nfloat64[36] covariance",
    "geometry_msgs/Twist": "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular",
    "geometry_msgs/TwistWithCovariance": "geometry_msgs/Twist twist\nfloat64[36] covariance",
    "geometry_msgs/Wrench": "geometry_msgs/Vector3 force\ngeometry_msgs/Vector3 torque",
    "geometry_msgs/WrenchStamped": "std_msgs/Header header\ngeometry_msgs/Wrench wrench",
    "geometry_msgs/Vector3Stamped": "std_msgs/Header header\ngeometry_msgs/Vector3 vector",
    "geometry_msgs/PointStamped": "std_msgs/Header header\ngeometry_msgs/Point point",
    "geometry_msgs/Transform": (
        "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation"
    ),
    "geometry_msgs/TransformStamped": (
        "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform"
    ),
    "tf2_msgs/TFMessage": "geometry_msgs/TransformStamped[] transforms",
    "nav_msgs/Odometry": (
        "std_msgs/Header header\nstring child_frame_id\n"
        "geometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist"
    ),
    "nav_msgs/Path": "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses",
    "rosgraph_msgs/Clock": "builtin_interfaces/Time clock",
}
_SEPARATOR = "=" * 80


def _short(name: str) -> str:
    """The name without its interface kind: nav_msgs/msg/Odometry → nav_msgs/Odometry."""
    package, *_, message = name.split("/")
    return f"{package}/{message}"


def _dependencies(name: str) -> list[str]:
    """The complex types ``name`` uses, depth first, each once."""
    found: list[str] = []

    def visit(type_name: str) -> None:
        for line in _FIELDS[type_name].splitlines():
            field_type = line.split()[0].split("[")[0]
            if "/" in field_type and field_type not in found:
                found.append(field_type)
                visit(field_type)

    visit(name)
    return found


def message_definition(name: str) -> str:
    """The ROS 2 message definition of ``name`` ("nav_msgs/msg/Odometry") as rosbag2 stores it
    in an MCAP schema: its fields, then each type it uses after a separator and ``MSG: type``."""
    short = _short(name)
    parts = [_FIELDS[short]]
    parts += [f"{_SEPARATOR}\nMSG: {dep}\n{_FIELDS[dep]}" for dep in _dependencies(short)]
    return "\n".join(parts) + "\n"


@dataclass(frozen=True)
class Topic:
    """One topic of the file: its name, ROS 2 type, frame and what it holds."""

    name: str
    type: str
    frame: str
    holds: str


TOPICS: tuple[Topic, ...] = (
    Topic("/clock", "rosgraph_msgs/msg/Clock", "", "the sim time t at every sample"),
    Topic(
        "/odom",
        "nav_msgs/msg/Odometry",
        f"{WORLD_FRAME} → {BODY_FRAME}",
        "the vehicle's pose and its velocity through the water in the body frame, at every "
        "sample: linear (u, −v, −w) [m/s], angular (0, −q, −r) [rad/s] (no roll rate: the "
        "5-DOF plant has none, the 6-DOF plant's is not recorded)",
    ),
    Topic("/tf", "tf2_msgs/msg/TFMessage", f"{WORLD_FRAME} → {BODY_FRAME}", "the same pose"),
    Topic(
        "/path",
        "nav_msgs/msg/Path",
        WORLD_FRAME,
        "the desired path p(s) over the s the episode reached (a finite path whole), once at t_0",
    ),
    Topic(
        "/path_following/target",
        "geometry_msgs/msg/PointStamped",
        WORLD_FRAME,
        "the virtual point p(s) the vehicle follows, at every sample",
    ),
    Topic(
        "/path_following/error",
        "geometry_msgs/msg/Vector3Stamped",
        BODY_FRAME,
        "the vehicle's position relative to p(s) in the body frame, (x_e, −y_e, −z_e) of the "
        "sim's FRD errors [m], at every sample",
    ),
    Topic(
        "/path_following/state",
        "std_msgs/msg/Float64MultiArray",
        "",
        "distance to p(s) [m], s [-], ṡ [1/s], the virtual point's speed u_p [m/s], at every "
        "sample (layout label distance,s,s_dot,u_p)",
    ),
    Topic(
        "/cmd/wrench",
        "geometry_msgs/msg/WrenchStamped",
        BODY_FRAME,
        "the applied τ = (X, M, N), averaged over each control period: force (X, 0, 0) [N], "
        "torque (0, −M, −N) [N·m]",
    ),
    Topic(
        "/cmd/action",
        "std_msgs/msg/Float64MultiArray",
        "",
        "the policy's action as it returned it, before saturation to [−1, 1] (layout label "
        "a_X,a_M,a_N)",
    ),
    Topic(
        "/disturbance",
        "geometry_msgs/msg/WrenchStamped",
        BODY_FRAME,
        "the white-noise disturbance averaged over each control period: force (f_u, −f_v, "
        "−f_w) [N], torque (0, −f_q, −f_r) [N·m]",
    ),
    Topic(
        "/reward",
        "std_msgs/msg/Float64MultiArray",
        "",
        "the env's reward and safety cost of each control period (layout label reward,cost)",
    ),
)
_TYPES = {topic.name: topic.type for topic in TOPICS}


def sim_time_ns(t: np.ndarray) -> np.ndarray:
    """Sim times [s] as integer ns (rounded: t = k · control_dt is exact to well under 1 ns)."""
    return np.rint(np.asarray(t, dtype=np.float64) * 1e9).astype(np.int64)


def enu_position(ned: np.ndarray) -> np.ndarray:
    """(n, 3) NED positions → ENU: (y, x, −z)."""
    ned = np.asarray(ned, dtype=np.float64)
    return np.stack([ned[..., 1], ned[..., 0], -ned[..., 2]], axis=-1)


def flu_vector(frd: np.ndarray) -> np.ndarray:
    """(n, 3) body vectors FRD → FLU: (a, −b, −c)."""
    frd = np.asarray(frd, dtype=np.float64)
    return np.stack([frd[..., 0], -frd[..., 1], -frd[..., 2]], axis=-1)


def enu_orientation(phi: np.ndarray, theta: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """(n, 4) quaternions (x, y, z, w) of the FLU body in ENU for NED roll φ, pitch θ and
    heading ψ [rad]: the ZYX rotation of roll φ, pitch −θ, yaw π/2 − ψ."""
    roll = np.asarray(phi, dtype=np.float64) / 2
    pitch = -np.asarray(theta, dtype=np.float64) / 2
    yaw = (math.pi / 2 - np.asarray(psi, dtype=np.float64)) / 2
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    return np.stack(
        [
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ],
        axis=-1,
    )


def _stamp(ns: int) -> dict[str, int]:
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def _header(ns: int, frame: str) -> dict[str, Any]:
    return {"stamp": _stamp(ns), "frame_id": frame}


def _xyz(v: np.ndarray) -> dict[str, float]:
    return {"x": float(v[0]), "y": float(v[1]), "z": float(v[2])}


def _quaternion(q: np.ndarray) -> dict[str, float]:
    return {"x": float(q[0]), "y": float(q[1]), "z": float(q[2]), "w": float(q[3])}


def _array(label: str, values: np.ndarray) -> dict[str, Any]:
    data = [float(v) for v in values]
    dim = [{"label": label, "size": len(data), "stride": len(data)}]
    return {"layout": {"dim": dim, "data_offset": 0}, "data": data}


def _path_pose_orientations(points: np.ndarray) -> np.ndarray:
    """Quaternions of the path's tangent at each point (heading and climb, no roll)."""
    if len(points) < 2:
        return enu_orientation(np.zeros(len(points)), np.zeros(len(points)), np.zeros(len(points)))
    d = np.gradient(points, axis=0)
    psi = np.arctan2(d[:, 1], d[:, 0])
    theta = np.arctan2(-d[:, 2], np.hypot(d[:, 0], d[:, 1]))
    return enu_orientation(np.zeros(len(points)), theta, psi)


def path_points(path: Any, trajectory: Trajectory) -> np.ndarray:
    """(n, 3) NED points of ``path`` (an `auv_gym.paths.Path`) for /path: s from 0 (or the
    episode's smallest s) to the path's end if finite, else to the furthest s the episode reached,
    about `PATH_SPACING` m apart."""
    s = trajectory["s"]
    s0 = min(0.0, float(np.nanmin(s)))
    s1 = float(path.s_end) if math.isfinite(path.s_end) else float(np.nanmax(s))
    s1 = max(s1, s0 + 1e-6)
    coarse = path.evaluate(np.linspace(s0, s1, 1001))[0]
    length = float(np.sum(np.linalg.norm(np.diff(coarse, axis=0), axis=1)))
    count = int(min(MAX_PATH_POSES, max(2, math.ceil(length / PATH_SPACING) + 1)))
    return np.asarray(path.evaluate(np.linspace(s0, s1, count))[0], dtype=np.float64)


def write_episode_mcap(
    trajectory: Trajectory,
    out: str | os.PathLike,
    *,
    path: np.ndarray | None = None,
    facts: Mapping[str, Any] | None = None,
) -> Path:
    """Write ``trajectory`` to ``out`` as MCAP with ROS 2 messages (`TOPICS`), atomically
    (`auv_gym.support.files.write_atomic`: readers see no file or the complete one).

    ``path``: (n, 3) NED points of the desired path for /path (`path_points`); None: the locus
    of the virtual point p(s) over the episode. ``facts``: JSON-serialisable values added to
    the MCAP metadata record ``auv_gym.episode`` (policy, scenario, env id…), beside the
    trajectory's end, control period, frames and metadata.
    """
    points = trajectory.point if path is None else np.asarray(path, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or not len(points):
        raise ValueError(f"path must be an (n, 3) array of points, got shape {points.shape}")
    target = Path(out)
    write_atomic(target, lambda fh: _write(fh, trajectory, points, facts or {}))
    return target


def _metadata(trajectory: Trajectory, facts: Mapping[str, Any]) -> dict[str, str]:
    record = {
        **facts,
        "termination_reason": trajectory.termination_reason,
        "control_dt": trajectory.control_dt,
        "steps": trajectory.steps,
        "frames": f"{WORLD_FRAME}: ENU (x east = sim y, y north = sim x, z up = -sim z); "
        f"{BODY_FRAME}: FLU (sim FRD body with y and z negated); sim time from 0 at the reset",
        "trajectory": trajectory.metadata,
    }
    return {
        k: v if isinstance(v, str) else json.dumps(v, default=json_default)
        for k, v in record.items()
    }


def _write(fh: IO[bytes], tr: Trajectory, points: np.ndarray, facts: Mapping[str, Any]) -> None:
    from mcap_ros2.writer import Writer

    writer = Writer(fh)
    schemas = {
        type_name: writer.register_msgdef(type_name, message_definition(type_name))
        for type_name in dict.fromkeys(_TYPES.values())
    }

    def put(topic: str, ns: int, message: dict[str, Any], sequence: int) -> None:
        writer.write_message(
            topic, schemas[_TYPES[topic]], message, log_time=ns, publish_time=ns, sequence=sequence
        )

    ns = sim_time_ns(tr.t)
    steps = tr.steps
    position = enu_position(tr.position)
    phi = np.zeros(steps + 1)
    if ROLL_ANGLE in tr.extras:  # the 6-DOF plant's roll at each interval's end (0 at reset)
        phi[1:] = tr.extras[ROLL_ANGLE]
    orientation = enu_orientation(phi, tr["theta"], tr["psi"])
    linear = flu_vector(np.column_stack([tr["u"], tr["v"], tr["w"]]))
    angular = flu_vector(np.column_stack([np.zeros(steps + 1), tr["q"], tr["r"]]))
    error = flu_vector(np.column_stack([tr["x_e"], tr["y_e"], tr["z_e"]]))
    target = enu_position(tr.point)
    state = np.column_stack([tr["distance"], tr["s"], tr["s_dot"], tr["u_p"]])
    force = flu_vector(np.column_stack([tr["X"], np.zeros(steps), np.zeros(steps)]))
    torque = flu_vector(np.column_stack([np.zeros(steps), tr["M"], tr["N"]]))
    noise_force = flu_vector(np.column_stack([tr["f_u"], tr["f_v"], tr["f_w"]]))
    noise_torque = flu_vector(np.column_stack([np.zeros(steps), tr["f_q"], tr["f_r"]]))
    actions = tr.actions
    zeros36 = [0.0] * 36  # ground truth: no uncertainty

    path_ned = points
    path_enu = enu_position(path_ned)
    path_q = _path_pose_orientations(path_ned)
    start = int(ns[0])
    put(
        "/path",
        start,
        {
            "header": _header(start, WORLD_FRAME),
            "poses": [
                {
                    "header": _header(start, WORLD_FRAME),
                    "pose": {"position": _xyz(p), "orientation": _quaternion(q)},
                }
                for p, q in zip(path_enu, path_q, strict=True)
            ],
        },
        0,
    )
    for k in range(steps + 1):
        t = int(ns[k])
        pose = {"position": _xyz(position[k]), "orientation": _quaternion(orientation[k])}
        put("/clock", t, {"clock": _stamp(t)}, k)
        put(
            "/odom",
            t,
            {
                "header": _header(t, WORLD_FRAME),
                "child_frame_id": BODY_FRAME,
                "pose": {"pose": pose, "covariance": zeros36},
                "twist": {
                    "twist": {"linear": _xyz(linear[k]), "angular": _xyz(angular[k])},
                    "covariance": zeros36,
                },
            },
            k,
        )
        transform = {"translation": pose["position"], "rotation": pose["orientation"]}
        put(
            "/tf",
            t,
            {
                "transforms": [
                    {
                        "header": _header(t, WORLD_FRAME),
                        "child_frame_id": BODY_FRAME,
                        "transform": transform,
                    }
                ]
            },
            k,
        )
        put(
            "/path_following/target",
            t,
            {"header": _header(t, WORLD_FRAME), "point": _xyz(target[k])},
            k,
        )
        put(
            "/path_following/error",
            t,
            {"header": _header(t, BODY_FRAME), "vector": _xyz(error[k])},
            k,
        )
        put("/path_following/state", t, _array("distance,s,s_dot,u_p", state[k]), k)
        if k == steps:
            break
        put(
            "/cmd/wrench",
            t,
            {
                "header": _header(t, BODY_FRAME),
                "wrench": {"force": _xyz(force[k]), "torque": _xyz(torque[k])},
            },
            k,
        )
        put("/cmd/action", t, _array("a_X,a_M,a_N", actions[k]), k)
        put(
            "/disturbance",
            t,
            {
                "header": _header(t, BODY_FRAME),
                "wrench": {"force": _xyz(noise_force[k]), "torque": _xyz(noise_torque[k])},
            },
            k,
        )
        put("/reward", t, _array("reward,cost", [tr["reward"][k], tr["cost"][k]]), k)
    writer.add_metadata(METADATA_NAME, _metadata(tr, facts))
    writer.finish()
