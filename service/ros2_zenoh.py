"""ROS 2 over Zenoh, natively: the robot-facing topics in rmw_zenoh's wire format, no bridge.

With ``rmw_zenoh_cpp`` a ROS 2 node publishes CDR payloads on the key expression
``<domain_id>/<topic without leading '/'>/<DDS type name>/<RIHS01 type hash>`` (the DDS type name of
``geometry_msgs/msg/PoseStamped`` is ``geometry_msgs::msg::dds_::PoseStamped_``) with an attachment
``u64 sequence number, u64 source timestamp (ns), u8 GID length, GID`` (little-endian), and announces
itself with liveliness tokens ``@ros2_lv/<domain>/<zid>/<node id>/<entity id>/<NN|MP|MS>/<enclave>/
<namespace>/<node>[/<topic>/<type>/<hash>/<qos>]`` (``/`` in names mangled to ``%``). This module speaks
that on the Zenoh node's own session when ``sphereplan serve --ros2`` is given:

* subscribes ``<ns>/goal_pose`` (``geometry_msgs/msg/PoseStamped``, RViz's "2D Goal Pose"),
  ``<ns>/pose`` (``geometry_msgs/msg/PoseStamped``, the robot's pose in ``map``) and ``<ns>/map``
  (``nav_msgs/msg/OccupancyGrid``, optional: without it ``--ros2-map`` names the map);
* publishes the plan on ``<ns>/plan`` (``nav_msgs/msg/Path``, poses stamped with the plan's times from
  when it was published).

CDR is encoded and decoded with ``mcap-ros2-support``'s dynamic (de)serialiser from the ROS 2 Humble
message definitions of the ``rosbags`` type store, whose ``hash_rihs01`` gives the type hashes. A goal
that cannot be planned (no pose yet, wrong frame, no path) is logged and publishes no path.
"""

from __future__ import annotations

import logging
import os
import struct
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any

import zenoh

from service.core import PlanningService
from service.outcome import Outcome
from service.ros import OCCUPANCY_GRID, PATH, POSE_STAMPED, msgdef, path_msg, typestore
from service.wire import MAP_FRAMES, InlineGrid, PlanRequest, PoseIn
from service.zenoh_entities import undeclare_all

log = logging.getLogger(__name__)

ADMIN_SPACE = "@ros2_lv"
#: rmw_zenoh's QoS token for the default profile (reliable, volatile, keep last 10)
DEFAULT_QOS = "::,10:,:,:,,"
CDR = zenoh.Encoding("application/cdr")


def dds_type_name(typename: str) -> str:
    """``pkg/msg/Name`` → ``pkg::msg::dds_::Name_`` (what rmw_zenoh puts in key expressions)."""
    pkg, kind, name = typename.split("/")
    return f"{pkg}::{kind}::dds_::{name}_"


def mangle(name: str) -> str:
    return "%" if name in ("", "/") else name.replace("/", "%")


def fully_qualified(namespace: str, topic: str) -> str:
    ns = "/" + namespace.strip("/") if namespace.strip("/") else ""
    return f"{ns}/{topic.lstrip('/')}"


def topic_key(domain_id: int, topic: str, typename: str) -> str:
    """The data key expression of ``topic`` (fully qualified) carrying ``typename``."""
    return f"{domain_id}/{topic.lstrip('/')}/{dds_type_name(typename)}/{type_hash(typename)}"


def type_hash(typename: str) -> str:
    return str(typestore().hash_rihs01(typename))


def attachment(sequence: int, timestamp_ns: int, gid: bytes) -> bytes:
    return struct.pack("<QQB", sequence, timestamp_ns, len(gid)) + gid


_codecs: dict[str, tuple[Callable[[bytes], Any], Callable[[Any], bytes]]] = {}


def codec(typename: str) -> tuple[Callable[[bytes], Any], Callable[[Any], bytes]]:
    """(decode, encode) of ``typename``'s CDR, built by mcap-ros2-support from its message definition."""
    if typename not in _codecs:
        from mcap_ros2._dynamic import generate_dynamic, serialize_dynamic

        text = msgdef(typename)
        _codecs[typename] = (generate_dynamic(typename, text)[typename], serialize_dynamic(typename, text)[typename])
    return _codecs[typename]


@dataclass(frozen=True)
class Ros2Options:
    """How the node appears to ROS 2: domain, namespace of its topics, and what goals are planned on."""

    domain_id: int = 0
    namespace: str = "/"
    map_name: str | None = None
    robot: str | None = None
    node_name: str = "sphereplan"


class RmwZenohFace:
    """The ROS 2 (rmw_zenoh) face of the Zenoh node on an open session."""

    def __init__(self, service: PlanningService, session: zenoh.Session, options: Ros2Options) -> None:
        self.service = service
        self.session = session
        self.options = options
        self.zid = str(session.zid())
        self._entities: list[Any] = []
        self._lock = threading.Lock()
        self._pose: PoseIn | None = None
        self._grid: InlineGrid | None = None
        self._goal_id = 0
        self._sequence = 0
        self._gid = os.urandom(16)
        self._next_entity = 1
        self.topic = {name: fully_qualified(options.namespace, name) for name in ("goal_pose", "pose", "map", "plan")}
        self.plan_key = topic_key(options.domain_id, self.topic["plan"], PATH)
        self.published = 0

    # ------------------------------------------------------------------------------ graph

    def _node_prefix(self, entity_id: int, kind: str) -> str:
        o = self.options
        return f"{ADMIN_SPACE}/{o.domain_id}/{self.zid}/0/{entity_id}/{kind}/%/{mangle(o.namespace)}/{o.node_name}"

    def _announce(self, kind: str, topic: str, typename: str) -> None:
        entity_id, self._next_entity = self._next_entity, self._next_entity + 1
        token = (f"{self._node_prefix(entity_id, kind)}/{mangle(topic)}/{dds_type_name(typename)}/"
                 f"{type_hash(typename)}/{DEFAULT_QOS}")
        self._entities.append(self.session.liveliness().declare_token(token))

    def start(self) -> None:
        o = self.options
        self._entities.append(self.session.liveliness().declare_token(self._node_prefix(0, "NN")))
        inputs = (("goal_pose", POSE_STAMPED, self._on_goal), ("pose", POSE_STAMPED, self._on_pose),
                  ("map", OCCUPANCY_GRID, self._on_map))
        for name, typename, handler in inputs:
            key = topic_key(o.domain_id, self.topic[name], typename)
            self._entities.append(self.session.declare_subscriber(key, self._guarded(name, typename, handler)))
            self._announce("MS", self.topic[name], typename)
        self._publisher = self.session.declare_publisher(self.plan_key, encoding=CDR)
        self._entities.append(self._publisher)
        self._announce("MP", self.topic["plan"], PATH)
        log.info("ROS 2 (rmw_zenoh) face up: domain %d, %s in, %s out", o.domain_id,
                 ", ".join(self.topic[n] for n in ("goal_pose", "pose", "map")), self.topic["plan"])

    def close(self) -> None:
        undeclare_all(self._entities)

    # ------------------------------------------------------------------------------ topics in

    def _guarded(self, name: str, typename: str, handler: Callable[[Any], None]) -> Callable[[zenoh.Sample], None]:
        decode = codec(typename)[0]

        def on_sample(sample: zenoh.Sample) -> None:
            try:
                handler(decode(sample.payload.to_bytes()))
            except Exception as exc:  # a malformed message must not kill the subscriber
                log.warning("ROS 2 %s: message refused: %s", self.topic[name], exc)

        return on_sample

    @staticmethod
    def _planar(msg: Any, topic: str) -> PoseIn:
        if msg.header.frame_id not in MAP_FRAMES:
            raise ValueError(f"{topic} is in frame {msg.header.frame_id!r}; sphereplan plans in 'map'")
        from service.wire import RosPose

        p, q = msg.pose.position, msg.pose.orientation
        ros = RosPose.model_validate({"position": {"x": p.x, "y": p.y, "z": p.z},
                                      "orientation": {"x": q.x, "y": q.y, "z": q.z, "w": q.w}})
        x, y, yaw = ros.as_pose()
        return PoseIn(x=x, y=y, yaw=yaw)

    def _on_pose(self, msg: Any) -> None:
        pose = self._planar(msg, self.topic["pose"])
        with self._lock:
            self._pose = pose

    def _on_map(self, msg: Any) -> None:
        from service.wire import RosOccupancyGrid

        o = msg.info.origin
        grid = RosOccupancyGrid.model_validate({
            "header": {"frame_id": msg.header.frame_id},
            "info": {"resolution": float(msg.info.resolution), "width": int(msg.info.width),
                     "height": int(msg.info.height),
                     "origin": {"position": {"x": o.position.x, "y": o.position.y, "z": o.position.z},
                                "orientation": {"x": o.orientation.x, "y": o.orientation.y, "z": o.orientation.z,
                                                "w": o.orientation.w}}},
            "data": [int(v) for v in msg.data]})
        with self._lock:
            self._grid = grid.as_inline()

    def _on_goal(self, msg: Any) -> None:
        goal = self._planar(msg, self.topic["goal_pose"])
        with self._lock:
            self._goal_id += 1
            goal_id, start, grid = self._goal_id, self._pose, self._grid
        if start is None:
            raise ValueError(f"no pose received on {self.topic['pose']} yet to plan from")
        map_spec: str | InlineGrid | None = grid if grid is not None else self.options.map_name
        if map_spec is None:
            raise ValueError(f"no map: none received on {self.topic['map']} and no --ros2-map given")
        request = PlanRequest(map=map_spec, start=start, goal=goal, robot=self.options.robot)
        future: Future[Outcome] = self.service.submit_plan(request)
        future.add_done_callback(lambda done: self._plan_done(goal_id, done.result()))

    # ------------------------------------------------------------------------------ topic out

    def _plan_done(self, goal_id: int, outcome: Outcome) -> None:
        if goal_id != self._goal_id:
            log.info("ROS 2 goal %d superseded before its plan finished; not published", goal_id)
            return
        if not outcome.ok:
            body = outcome.json()
            log.warning("ROS 2 goal %d: no plan (%s: %s)", goal_id, body.get("error_code"), body.get("error_msg"))
            return
        states = outcome.json()["states"]
        now = time.time()
        msg = path_msg(((s["t"], s["x"], s["y"], s["yaw"]) for s in states), now)
        payload = codec(PATH)[1](msg)
        with self._lock:
            seq = self._sequence
            self._sequence += 1
        try:
            self._publisher.put(payload, encoding=CDR, attachment=attachment(seq, int(now * 1e9), self._gid))
            self.published += 1
        except Exception as exc:  # closing
            log.warning("could not publish %s: %s", self.topic["plan"], exc)
