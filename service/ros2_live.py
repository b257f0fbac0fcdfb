"""ROS 2 door of robot sessions over rmw_zenoh: odometry, laser scans and point clouds in; the path and the live
map out (``sphereplan serve --ros2``; wire format as :mod:`service.ros2_zenoh`).

Topics, under the node's namespace and ``live/`` (remap your robot's topics onto them):

==========================  ==============================  ==================================================
``<ns>/live/odom``          ``nav_msgs/msg/Odometry``       the robot's pose; the first one starts the session
``<ns>/live/scan``          ``sensor_msgs/msg/LaserScan``   ranges from the sensor on the robot
``<ns>/live/points``        ``sensor_msgs/msg/PointCloud2`` obstacle points (x, y, z float32/float64 fields)
``<ns>/live/goal_pose``     ``geometry_msgs/msg/PoseStamped`` the goal (map frame), planned at once
``<ns>/live/plan``          ``nav_msgs/msg/Path``           out: every successful replan
``<ns>/live/map``           ``nav_msgs/msg/OccupancyGrid``  out: the live map after a replan (at most every 2 s)
==========================  ==============================  ==================================================

No TF: odometry is taken as the robot's pose in ``map`` (``odom`` = ``map``), and a scan or a cloud not in the
``map`` frame is taken to be in the robot's frame at the pose of the latest odometry, ``sensor_height_m`` above
the ground (default: the sphere's centre). The session starts on the ``--ros2-map`` map, the last
``<ns>/map`` received, or else an unknown 60 m × 60 m area at 0.05 m centred on the first pose. Everything is
bounded by the session store (points per cloud, beams per scan, update rate).
"""

from __future__ import annotations

import logging
import math
import os
import threading
import time
from typing import Any

import numpy as np
import zenoh

from planner.live import PointObservation, ScanObservation, SensorPose
from planner.live.session import ReplanEvent
from planner.occupancy import UNKNOWN, OccupancyGrid
from service.core import PlanningService
from service.ros import OCCUPANCY_GRID, PATH, POSE_STAMPED, occupancy_grid_msg, path_msg
from service.ros2_zenoh import (
    ADMIN_SPACE,
    CDR,
    DEFAULT_QOS,
    Ros2Options,
    attachment,
    codec,
    dds_type_name,
    fully_qualified,
    mangle,
    topic_key,
    type_hash,
)
from service.sessions import Entry, SessionStore
from service.zenoh_entities import undeclare_all

log = logging.getLogger(__name__)

ODOMETRY = "nav_msgs/msg/Odometry"
LASER_SCAN = "sensor_msgs/msg/LaserScan"
POINT_CLOUD2 = "sensor_msgs/msg/PointCloud2"
UNKNOWN_AREA_M = 60.0
UNKNOWN_RES_M = 0.05
MAP_PERIOD_S = 2.0
_FLOAT_TYPES = {7: "<f4", 8: "<f8"}  # sensor_msgs/PointField FLOAT32, FLOAT64


def yaw_of(q: Any) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def cloud_points(msg: Any, max_points: int) -> np.ndarray:
    """The x, y, z of a ``sensor_msgs/PointCloud2`` as an (n, 3) float array (NaN points dropped)."""
    n = int(msg.width) * int(msg.height)
    if n > max_points:
        raise ValueError(f"cloud of {n} points; at most {max_points} per observation")
    fields = {f.name: f for f in msg.fields}
    if not all(k in fields for k in "xyz"):
        raise ValueError("PointCloud2 needs x, y and z fields")
    step = int(msg.point_step)
    raw = bytes(msg.data)
    if len(raw) < n * step:
        raise ValueError(f"PointCloud2 data has {len(raw)} bytes, fewer than width × height × point_step")
    buf = np.frombuffer(raw, dtype=np.uint8, count=n * step).reshape(n, step)
    cols = []
    for k in "xyz":
        f = fields[k]
        kind = _FLOAT_TYPES.get(int(f.datatype))
        if kind is None:
            raise ValueError(f"PointCloud2 field {k} must be FLOAT32 or FLOAT64")
        dtype = np.dtype(kind).newbyteorder(">" if msg.is_bigendian else "<")
        size = dtype.itemsize
        off = int(f.offset)
        cols.append(np.ascontiguousarray(buf[:, off:off + size]).view(dtype).reshape(n).astype(float))
    pts = np.stack(cols, axis=1)
    return pts[np.all(np.isfinite(pts), axis=1)]


class Ros2LiveFace:
    """The rmw_zenoh session topics on an open Zenoh session (see the module docstring)."""

    def __init__(self, service: PlanningService, store: SessionStore, session: zenoh.Session,
                 options: Ros2Options, sensor_height_m: float | None = None) -> None:
        self.service = service
        self.store = store
        self.session = session
        self.options = options
        self.sensor_height_m = sensor_height_m
        self.zid = str(session.zid())
        self.sid = f"ros2-{options.domain_id}-{mangle(options.namespace).strip('%') or 'root'}"
        self.topic = {name: fully_qualified(options.namespace, f"live/{name}")
                      for name in ("odom", "scan", "points", "goal_pose", "plan", "map")}
        self.in_map = fully_qualified(options.namespace, "map")
        self._entities: list[Any] = []
        self._lock = threading.Lock()
        self._pose: tuple[float, float, float] | None = None
        self._grid: OccupancyGrid | None = None
        self._gid = os.urandom(16)
        self._sequence = 0
        self._next_entity = 1
        self._last_map_t = -math.inf
        self.published = 0

    def _node_prefix(self, entity_id: int, kind: str) -> str:
        o = self.options
        return (f"{ADMIN_SPACE}/{o.domain_id}/{self.zid}/1/{entity_id}/{kind}/%/{mangle(o.namespace)}/"
                f"{o.node_name}_live")

    def _announce(self, kind: str, topic: str, typename: str) -> None:
        entity_id, self._next_entity = self._next_entity, self._next_entity + 1
        token = (f"{self._node_prefix(entity_id, kind)}/{mangle(topic)}/{dds_type_name(typename)}/"
                 f"{type_hash(typename)}/{DEFAULT_QOS}")
        self._entities.append(self.session.liveliness().declare_token(token))

    def start(self) -> None:
        d = self.options.domain_id
        self._entities.append(self.session.liveliness().declare_token(self._node_prefix(0, "NN")))
        inputs = (("odom", ODOMETRY, self._on_odom), ("scan", LASER_SCAN, self._on_scan),
                  ("points", POINT_CLOUD2, self._on_points), ("goal_pose", POSE_STAMPED, self._on_goal))
        for name, typename, handler in inputs:
            key = topic_key(d, self.topic[name], typename)
            self._entities.append(self.session.declare_subscriber(key, self._guarded(name, typename, handler)))
            self._announce("MS", self.topic[name], typename)
        self._entities.append(self.session.declare_subscriber(topic_key(d, self.in_map, OCCUPANCY_GRID),
                                                              self._guarded("map", OCCUPANCY_GRID, self._on_map)))
        self._publishers = {
            "plan": self.session.declare_publisher(topic_key(d, self.topic["plan"], PATH), encoding=CDR),
            "map": self.session.declare_publisher(topic_key(d, self.topic["map"], OCCUPANCY_GRID), encoding=CDR),
        }
        self._entities.extend(self._publishers.values())
        self._announce("MP", self.topic["plan"], PATH)
        self._announce("MP", self.topic["map"], OCCUPANCY_GRID)
        log.info("ROS 2 (rmw_zenoh) live session topics up under %s", fully_qualified(self.options.namespace, "live"))

    def close(self) -> None:
        undeclare_all(self._entities)

    # ------------------------------------------------------------------ in

    def _guarded(self, name: str, typename: str, handler: Any) -> Any:
        decode = codec(typename)[0]

        def on_sample(sample: zenoh.Sample) -> None:
            try:
                handler(decode(sample.payload.to_bytes()))
            except Exception as exc:  # a bad message must not kill the subscriber
                log.warning("ROS 2 live %s: message refused: %s", name, exc)

        return on_sample

    def _on_map(self, msg: Any) -> None:
        info = msg.info
        o = info.origin
        w, h = int(info.width), int(info.height)
        if w * h > self.store.limits.max_cells or len(msg.data) != w * h:
            raise ValueError(f"map of {w}×{h} cells refused")
        data = np.asarray(msg.data, dtype=np.int8).reshape(h, w)
        grid = OccupancyGrid(data, float(info.resolution), (o.position.x, o.position.y, yaw_of(o.orientation)),
                             name="ros2_map")
        with self._lock:
            self._grid = grid

    def _session(self) -> Entry:
        """The face's session, created at the first pose."""
        if self.sid in self.store.ids():
            return self.store.get(self.sid)
        pose = self._pose
        if pose is None:
            raise ValueError(f"no odometry on {self.topic['odom']} yet")
        robot = self.service.robot_profile(self.options.robot)
        name = self.options.map_name
        if self._grid is not None:
            grid = self._grid
        elif name is not None:
            from service.grids import load_map_file

            grid = load_map_file(self.service.resolve_map(name), robot)
        else:
            n = int(UNKNOWN_AREA_M / UNKNOWN_RES_M)
            origin = (pose[0] - UNKNOWN_AREA_M / 2, pose[1] - UNKNOWN_AREA_M / 2, 0.0)
            grid = OccupancyGrid(np.full((n, n), UNKNOWN, dtype=np.int8), UNKNOWN_RES_M, origin, name="unknown")
        entry, _ = self.store.create(f"ros2:{self.sid}", grid, robot, pose, name=grid.name, session_id=self.sid)
        entry.on_event.append(self._publish)
        return entry

    def _on_odom(self, msg: Any) -> None:
        p = msg.pose.pose.position
        pose = (float(p.x), float(p.y), yaw_of(msg.pose.pose.orientation))
        with self._lock:
            self._pose = pose
            self._session()
            self.store.pose(self.sid, pose)

    def _sensor(self, entry: Entry) -> SensorPose:
        assert self._pose is not None
        h = self.sensor_height_m if self.sensor_height_m is not None else entry.session.robot.radius_m
        return SensorPose(self._pose[0], self._pose[1], h, self._pose[2])

    def _on_scan(self, msg: Any) -> None:
        with self._lock:
            entry = self._session()
            sensor = self._sensor(entry)
            if msg.header.frame_id in ("map", "/map"):
                raise ValueError("a LaserScan is in its sensor's frame, not 'map'")
            ranges = np.asarray(msg.ranges, dtype=float)
            scan = ScanObservation(ranges, float(msg.angle_min), float(msg.angle_increment), float(msg.range_min),
                                   float(msg.range_max), sensor)
            self.store.observe(self.sid, scan)

    def _on_points(self, msg: Any) -> None:
        with self._lock:
            entry = self._session()
            pts = cloud_points(msg, self.store.limits.max_points)
            sensor = self._sensor(entry)
            if msg.header.frame_id in ("map", "/map"):
                obs = PointObservation(pts, np.array([sensor.x, sensor.y, sensor.z]))
            else:
                obs = PointObservation.in_sensor_frame(pts, sensor)
            self.store.observe(self.sid, obs)

    def _on_goal(self, msg: Any) -> None:
        if msg.header.frame_id not in ("", "map", "/map"):
            raise ValueError(f"goal in frame {msg.header.frame_id!r}; sphereplan plans in 'map'")
        p = msg.pose.position
        goal = (float(p.x), float(p.y), yaw_of(msg.pose.orientation))
        with self._lock:
            self._session()
            self.store.goal(self.sid, goal)

    # ------------------------------------------------------------------ out

    def _put(self, which: str, payload: bytes, now: float) -> None:
        seq, self._sequence = self._sequence, self._sequence + 1
        self._publishers[which].put(payload, encoding=CDR, attachment=attachment(seq, int(now * 1e9), self._gid))

    def _publish(self, entry: Entry, event: ReplanEvent) -> None:
        now = time.time()
        if event.ok and entry.session.path is not None:
            st = entry.session.path.states
            self._put("plan", codec(PATH)[1](path_msg(st[:, [5, 0, 1, 2]], now)), now)
            self.published += 1
        if now - self._last_map_t >= MAP_PERIOD_S:
            self._last_map_t = now
            self._put("map", codec(OCCUPANCY_GRID)[1](occupancy_grid_msg(entry.session.map.grid, now)), now)
