"""ROS 2 messages out of sphereplan's results, and MCAP files of them (Foxglove, ``ros2 bag play``).

Every builder returns a message as a plain dict in the ROS 2 field layout (``nav_msgs/msg/OccupancyGrid``,
``nav_msgs/msg/Path``, ``visualization_msgs/msg/MarkerArray``, ``geometry_msgs/msg/PoseStamped``,
``sensor_msgs/msg/JointState``, ``sensor_msgs/msg/PointCloud2``). CDR serialisation is left to the ecosystem's
libraries: the MCAP writer is ``mcap-ros2-support``'s, and the message definitions it embeds as schemas are ROS 2
Humble's,
taken from the ``rosbags`` type store (not typed in here). Reading a map back (``--map run.mcap``) uses
``mcap-ros2-support``'s decoder for an MCAP file and ``rosbags`` for a rosbag2 folder (sqlite3 or mcap).

Stamps: a result is written as if it started at ``t0`` (default: now); a plan pose at plan time ``t``
is stamped ``t0 + t`` and every message is logged at its stamp, so ``ros2 bag play`` replays it in time.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable, Mapping, Sequence
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from planner.errors import InvalidInput
from planner.maps.nav2 import snap_resolution
from planner.occupancy import OccupancyGrid

FRAME = "map"

#: topics of a plan MCAP
MAP_TOPIC, PLAN_TOPIC, FOOTPRINTS_TOPIC = "/map", "/plan", "/plan/footprints"
START_TOPIC, GOAL_TOPIC = "/plan/start", "/plan/goal"

OCCUPANCY_GRID = "nav_msgs/msg/OccupancyGrid"
PATH = "nav_msgs/msg/Path"
MARKER_ARRAY = "visualization_msgs/msg/MarkerArray"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
JOINT_STATE = "sensor_msgs/msg/JointState"
POINT_CLOUD2 = "sensor_msgs/msg/PointCloud2"
POINT_STAMPED = "geometry_msgs/msg/PointStamped"

#: topics of a perception MCAP
POINTS_TOPIC, SENSOR_ORIGIN_TOPIC, ROBOT_POSE_TOPIC = "/perception/obstacles", "/perception/origin", "/perception/pose"
#: sensor_msgs/PointField datatype FLOAT32
FLOAT32 = 7

#: visualization_msgs/Marker constants
LINE_STRIP, ADD = 4, 0


@cache
def typestore() -> Any:
    """The ROS 2 Humble type store of ``rosbags`` (message definitions of the standard interfaces)."""
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_HUMBLE)


def msgdef(typename: str) -> str:
    """The ROS 2 ``.msg`` text (with its dependencies) of ``typename``, as rosbag2 stores it in MCAP."""
    text, _ = typestore().generate_msgdef(typename, ros_version=2)
    return str(text)


# ------------------------------------------------------------------------------------------- builders


def stamp(t: float) -> dict[str, int]:
    sec = math.floor(t)
    return {"sec": int(sec), "nanosec": min(int(round((t - sec) * 1e9)), 999_999_999)}


def header(t: float, frame_id: str = FRAME) -> dict[str, Any]:
    return {"stamp": stamp(t), "frame_id": frame_id}


def yaw_quaternion(yaw: float) -> dict[str, float]:
    return {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}


def pose(x: float, y: float, yaw: float, z: float = 0.0) -> dict[str, Any]:
    return {"position": {"x": float(x), "y": float(y), "z": float(z)}, "orientation": yaw_quaternion(float(yaw))}


def pose_stamped(t: float, x: float, y: float, yaw: float) -> dict[str, Any]:
    return {"header": header(t), "pose": pose(x, y, yaw)}


def occupancy_grid_msg(grid: OccupancyGrid, t: float) -> dict[str, Any]:
    """``nav_msgs/OccupancyGrid`` of ``grid``: row-major, row 0 at the origin (the grid's own layout)."""
    ox, oy, oyaw = grid.origin
    return {
        "header": header(t),
        "info": {"map_load_time": stamp(t), "resolution": float(grid.resolution_m), "width": int(grid.width),
                 "height": int(grid.height), "origin": pose(ox, oy, oyaw)},
        "data": np.asarray(grid.data, dtype=np.int8).ravel().tolist(),
    }


def path_msg(rows: Iterable[Sequence[float]], t0: float) -> dict[str, Any]:
    """``nav_msgs/Path`` from rows ``(t, x, y, yaw)``: each pose stamped ``t0 + t``."""
    poses = [pose_stamped(t0 + t, x, y, yaw) for t, x, y, yaw in rows]
    return {"header": header(t0), "poses": poses}


def point_cloud2_msg(points: np.ndarray, t: float, frame_id: str = FRAME) -> dict[str, Any]:
    """``sensor_msgs/PointCloud2`` of (N, 3) points (m): an unordered cloud (height 1), fields x, y, z as
    little-endian float32, 12 bytes a point."""
    xyz = np.ascontiguousarray(np.asarray(points, dtype="<f4").reshape(-1, 3))
    fields = [{"name": name, "offset": 4 * i, "datatype": FLOAT32, "count": 1} for i, name in enumerate("xyz")]
    return {"header": header(t, frame_id), "height": 1, "width": len(xyz), "fields": fields, "is_bigendian": False,
            "point_step": 12, "row_step": 12 * len(xyz), "data": xyz.tobytes(), "is_dense": True}


def roll_colour(roll: float, max_roll: float) -> dict[str, float]:
    """Blue (rolled right) through green (upright) to red (rolled left): the viewer's colour map."""
    u = max(-1.0, min(1.0, roll / max_roll)) if max_roll > 0 else 0.0
    return {"r": max(0.0, u), "g": 1.0 - abs(u), "b": max(0.0, -u), "a": 1.0}


def footprint_markers(states: np.ndarray, polygon: np.ndarray, max_roll: float, t0: float,
                      spacing_m: float = 0.25) -> dict[str, Any]:
    """``visualization_msgs/MarkerArray``: the robot's (padded) footprint polygon (n, 2; robot frame) every
    ``spacing_m`` along the path (and at both ends) as closed LINE_STRIPs coloured by roll, plus the path
    itself as one LINE_STRIP with a colour per point."""
    markers: list[dict[str, Any]] = []
    picked: list[int] = []
    last_s = -math.inf
    for i, s in enumerate(states[:, 6]):
        if s - last_s >= spacing_m or i == len(states) - 1:
            picked.append(i)
            last_s = s
    corners = np.vstack([polygon, polygon[:1]])
    for k, i in enumerate(picked):
        x, y, yaw, roll, t = states[i, 0], states[i, 1], states[i, 2], states[i, 3], states[i, 5]
        c, s = math.cos(yaw), math.sin(yaw)
        points = [{"x": float(x + c * px - s * py), "y": float(y + s * px + c * py), "z": 0.0} for px, py in corners]
        markers.append({
            "header": header(t0 + t), "ns": "footprints", "id": k, "type": LINE_STRIP, "action": ADD,
            "pose": pose(0, 0, 0), "scale": {"x": 0.01, "y": 0.0, "z": 0.0},
            "color": roll_colour(roll, max_roll), "frame_locked": False, "points": points,
        })
    markers.append({
        "header": header(t0), "ns": "path", "id": 0, "type": LINE_STRIP, "action": ADD, "pose": pose(0, 0, 0),
        "scale": {"x": 0.03, "y": 0.0, "z": 0.0}, "color": {"r": 1.0, "g": 1.0, "b": 1.0, "a": 1.0},
        "points": [{"x": float(x), "y": float(y), "z": 0.0} for x, y in states[:, :2]],
        "colors": [roll_colour(float(r), max_roll) for r in states[:, 3]],
    })
    return {"markers": markers}


# --------------------------------------------------------------------------------------------- writing


class McapOut:
    """An MCAP file of ROS 2 CDR messages (``ros2`` profile), written with ``mcap-ros2-support``."""

    def __init__(self, path: str | Path) -> None:
        from mcap_ros2.writer import Writer

        self.path = Path(path)
        self._file = self.path.open("wb")
        self._writer = Writer(self._file)
        self._schemas: dict[str, Any] = {}

    def write(self, topic: str, typename: str, message: Mapping[str, Any], t: float) -> None:
        schema = self._schemas.get(typename)
        if schema is None:
            schema = self._schemas[typename] = self._writer.register_msgdef(typename, msgdef(typename))
        ns = int(round(t * 1e9))
        self._writer.write_message(topic, schema, dict(message), log_time=ns, publish_time=ns)

    def close(self) -> None:
        try:
            self._writer.finish()
        finally:
            self._file.close()

    def __enter__(self) -> McapOut:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _states(result: Mapping[str, Any]) -> np.ndarray:
    from planner.result import STATE_FIELDS

    return np.array([[float(st[k]) for k in STATE_FIELDS] for st in result.get("states") or []]).reshape(-1, 8)


def _write_plan(out: McapOut, plan: Mapping[str, Any], t0: float, topic: str = PLAN_TOPIC) -> None:
    states = _states(plan)
    if len(states) == 0:
        return
    out.write(topic, PATH, path_msg(states[:, [5, 0, 1, 2]], t0), t0)
    robot = plan.get("robot") or {}
    if "footprint" in robot:
        out.write(f"{topic}/footprints", MARKER_ARRAY,
                  footprint_markers(states, np.asarray(robot["footprint"], float),
                                    float(robot.get("max_roll_rad") or 0.0), t0), t0)


def write_plan_mcap(path: str | Path, plan: Mapping[str, Any], grid: OccupancyGrid | None,
                    t0: float | None = None) -> None:
    """A plan result (docs/contracts.md) as MCAP: ``/map``, ``/plan`` (poses stamped with the plan's times),
    ``/plan/footprints`` and the start and goal as ``PoseStamped`` (a failed plan: map, start, goal only)."""
    t0 = time.time() if t0 is None else t0
    with McapOut(path) as out:
        if grid is not None:
            out.write(MAP_TOPIC, OCCUPANCY_GRID, occupancy_grid_msg(grid, t0), t0)
        for topic, key in ((START_TOPIC, "start"), (GOAL_TOPIC, "goal")):
            p = plan.get(key)
            if isinstance(p, Mapping):
                out.write(topic, POSE_STAMPED, pose_stamped(t0, p["x"], p["y"], p["yaw"]), t0)
        _write_plan(out, plan, t0)


def write_simulation_mcap(path: str | Path, plan: Mapping[str, Any], sim: Mapping[str, Any],
                          grid: OccupancyGrid | None, t0: float | None = None) -> None:
    """A closed-loop run as MCAP: the map and the plan it tracked (as a plan MCAP), the executed
    trajectory and the fused estimate over time (``/sim/pose``, ``/sim/estimate`` PoseStamped at every
    control step) and whole (``/sim/trajectory``, ``/sim/estimate/path`` Path, written at the end)."""
    t0 = time.time() if t0 is None else t0
    with McapOut(path) as out:
        if grid is not None:
            out.write(MAP_TOPIC, OCCUPANCY_GRID, occupancy_grid_msg(grid, t0), t0)
        _write_plan(out, plan, t0)
        rows = {name: [(r["t"], r["x"], r["y"], r["yaw"]) for r in sim.get(name) or []]
                for name in ("trajectory", "estimate")}
        for name, topic in (("trajectory", "/sim/pose"), ("estimate", "/sim/estimate")):
            for t, x, y, yaw in rows[name]:
                out.write(topic, POSE_STAMPED, pose_stamped(t0 + t, x, y, yaw), t0 + t)
        end = t0 + max((r[0] for r in rows["trajectory"]), default=0.0)
        out.write("/sim/trajectory", PATH, path_msg(rows["trajectory"], t0), end)
        out.write("/sim/estimate/path", PATH, path_msg(rows["estimate"], t0), end)


def write_reconfiguration_mcap(path: str | Path, result: Mapping[str, Any], grid: OccupancyGrid | None,
                               t0: float | None = None) -> None:
    """A Spherobot reconfiguration as MCAP: the sphere's centre and full body orientation over time on
    ``/reconfigure/pose`` (PoseStamped, z = radius) and whole on ``/reconfigure/path`` (Path)."""
    t0 = time.time() if t0 is None else t0
    radius = float(result.get("radius_m") or 0.0)
    poses = []
    for s in result.get("samples") or []:
        poses.append({"header": header(t0 + s["t"]), "pose": {
            "position": {"x": float(s["x"]), "y": float(s["y"]), "z": radius},
            "orientation": {"x": float(s["qx"]), "y": float(s["qy"]), "z": float(s["qz"]), "w": float(s["qw"])}}})
    with McapOut(path) as out:
        if grid is not None:
            out.write(MAP_TOPIC, OCCUPANCY_GRID, occupancy_grid_msg(grid, t0), t0)
        for p in poses:
            stamp_s = p["header"]["stamp"]["sec"] + p["header"]["stamp"]["nanosec"] * 1e-9
            out.write("/reconfigure/pose", POSE_STAMPED, p, stamp_s)
        out.write("/reconfigure/path", PATH, {"header": header(t0), "poses": poses}, t0)


def write_schedule_mcap(path: str | Path, plan: Mapping[str, Any], schedule: Mapping[str, Any],
                        t0: float | None = None) -> None:
    """A VPIP schedule as MCAP: the plan it follows, and per 100 Hz tick the rod lengths (``/vpip/rods``, m)
    and the plane angles and roll (``/vpip/plane``, rad) as ``sensor_msgs/JointState`` (names + positions,
    Foxglove plots them), and the rolled pose (``/vpip/pose``, PoseStamped)."""
    t0 = time.time() if t0 is None else t0
    series = schedule["series"]
    rods = [f"rod_{r['index']}_{r['side']}" for r in schedule.get("rods") or []]
    angles = [k for k in ("roll_desired_rad", "roll_rad", "phi_vpip_rad", "theta_vpip_rad", "pitch_phase_rad")
              if k in series]
    with McapOut(path) as out:
        _write_plan(out, plan, t0)
        for i, t in enumerate(series["t"]):
            lengths = [float(v) for v in series["rod_length_m"][i]]
            names = rods if len(rods) == len(lengths) else [f"rod_{j}" for j in range(len(lengths))]
            out.write("/vpip/rods", JOINT_STATE, {"header": header(t0 + t, "base_link"), "name": names,
                                                   "position": lengths}, t0 + t)
            out.write("/vpip/plane", JOINT_STATE, {"header": header(t0 + t, "base_link"), "name": angles,
                                                    "position": [float(series[k][i]) for k in angles]}, t0 + t)
            out.write("/vpip/pose", POSE_STAMPED,
                      pose_stamped(t0 + t, series["x"][i], series["y"][i], series["yaw"][i]), t0 + t)


def write_perception_mcap(path: str | Path, scan: Mapping[str, Any], t0: float | None = None) -> None:
    """A ``sphereplan perceive`` result as MCAP: the kept obstacle points (``/perception/obstacles``,
    ``sensor_msgs/PointCloud2`` in ``map``), the sensor origin the rays start from (``/perception/origin``,
    ``geometry_msgs/PointStamped``) and the sphere's pose (``/perception/pose``, PoseStamped), all at ``t0``."""
    t0 = time.time() if t0 is None else t0
    ox, oy, oz = (float(v) for v in scan["origin_map"])
    p = scan["pose"]
    with McapOut(path) as out:
        out.write(POINTS_TOPIC, POINT_CLOUD2, point_cloud2_msg(np.asarray(scan["points_map"], float), t0), t0)
        out.write(SENSOR_ORIGIN_TOPIC, POINT_STAMPED,
                  {"header": header(t0), "point": {"x": ox, "y": oy, "z": oz}}, t0)
        out.write(ROBOT_POSE_TOPIC, POSE_STAMPED, pose_stamped(t0, p["x"], p["y"], p["yaw"]), t0)


# --------------------------------------------------------------------------------------------- reading


def grid_from_msg(msg: Any, name: str) -> OccupancyGrid:
    """A planner grid from a decoded ``nav_msgs/OccupancyGrid`` (attribute access, any decoder)."""
    info = msg.info
    width, height = int(info.width), int(info.height)
    data = np.asarray(msg.data, dtype=np.int8)
    if width <= 0 or height <= 0 or data.size != width * height:
        raise InvalidInput("--map", f"the OccupancyGrid has {data.size} cells for {width} x {height}")
    q = info.origin.orientation
    yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
    origin = (float(info.origin.position.x), float(info.origin.position.y), yaw)
    return OccupancyGrid(data=data.reshape(height, width), resolution_m=snap_resolution(float(info.resolution)),
                         origin=origin, name=name)


def read_map_from_bag(path: str | Path, topic: str = MAP_TOPIC) -> OccupancyGrid:
    """The last ``nav_msgs/OccupancyGrid`` on ``topic`` of an MCAP file or a rosbag2 folder.

    Raises :class:`InvalidInput` (``--map`` / ``--map-topic``) when the file cannot be read or has no such
    message."""
    p = Path(path)
    if not p.exists():
        raise InvalidInput("--map", f"{p} does not exist")
    last: Any = None
    seen: dict[str, str] = {}
    try:
        if p.is_dir():
            from rosbags.highlevel import AnyReader

            with AnyReader([p], default_typestore=typestore()) as reader:
                seen = {c.topic: c.msgtype for c in reader.connections}
                conns = [c for c in reader.connections if c.topic == topic and c.msgtype == OCCUPANCY_GRID]
                # (no connections would mean every connection to rosbags)
                for conn, _, raw in reader.messages(connections=conns) if conns else ():
                    last = reader.deserialize(raw, conn.msgtype)
        else:
            from mcap.reader import make_reader
            from mcap_ros2.decoder import DecoderFactory

            with p.open("rb") as f:
                mcap = make_reader(f, decoder_factories=[DecoderFactory()])
                summary = mcap.get_summary()
                if summary is not None:
                    seen = {c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()
                            if c.schema_id in summary.schemas}
                for schema, _, _, decoded in mcap.iter_decoded_messages(topics=[topic]):
                    if schema is not None and schema.name in (OCCUPANCY_GRID, "nav_msgs/OccupancyGrid"):
                        last = decoded
    except InvalidInput:
        raise
    except Exception as exc:  # a file that is not MCAP / rosbag2, or a corrupt one
        raise InvalidInput("--map", f"{p} is not a readable MCAP file or rosbag2 folder: {exc}") from None
    if last is None:
        shown = ", ".join(f"{t} ({ty})" for t, ty in sorted(seen.items())) or "none"
        raise InvalidInput("--map-topic", f"no {OCCUPANCY_GRID} on {topic} in {p} (topics: {shown})")
    return grid_from_msg(last, f"{p.stem}{topic.replace('/', '_')}")
