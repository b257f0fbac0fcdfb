"""ROS 2 over Zenoh (rmw_zenoh's wire format) against an independent implementation of it: the
``zenoh-ros2-sdk`` package plays the ROS 2 robot. It computes its own type hashes from ``.msg`` files (given
here locally: there is no network, and the SDK would otherwise git-clone ROS's interface repositories),
builds its own key expressions and liveliness tokens, and encodes/decodes CDR with its own type store.

The robot publishes its pose and a ``geometry_msgs/msg/PoseStamped`` goal; sphereplan must answer a
``nav_msgs/msg/Path`` the SDK decodes, equal to the plan the service makes for the same request."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest
import zenoh_ros2_sdk as sdk

from service.core import PlanningService
from service.ros import typestore
from service.settings import ServiceSettings
from service.wire import PlanRequest, PoseIn
from service.zenoh_node import ZenohNode, default_config
from tests.service.service_harness import HALL_GOAL, HALL_START, free_port, make_maps

TYPES = ("geometry_msgs/msg/PoseStamped", "geometry_msgs/msg/Pose", "geometry_msgs/msg/Point",
         "geometry_msgs/msg/Quaternion", "std_msgs/msg/Header", "builtin_interfaces/msg/Time", "nav_msgs/msg/Path")


def write_msg_files(folder: Path) -> Path:
    """The ``.msg`` files the SDK reads, laid out as ``<pkg>/msg/<Name>.msg`` (ROS 2 Humble definitions)."""
    for typename in TYPES:
        text = typestore().generate_msgdef(typename, ros_version=2)[0]
        own = text.split("=" * 80)[0].strip() + "\n"  # the type's own fields, without its dependencies
        path = folder.joinpath(*typename.split("/")).with_suffix(".msg")
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(own)
    return folder


@pytest.fixture()
def node(tmp_path: Path) -> Iterator[tuple[ZenohNode, PlanningService, int]]:
    port = free_port()
    settings = ServiceSettings(maps_dir=make_maps(tmp_path / "maps"), workers=1, warm_up=False, ros2=True,
                               ros2_map="hall", ros2_namespace="/", zenoh_listen=f"tcp/127.0.0.1:{port}")
    service = PlanningService(settings, executor_factory=lambda n: ThreadPoolExecutor(n))
    service.start()
    zenoh_node = ZenohNode(service, settings, config=default_config(settings.zenoh_listen))
    zenoh_node.start()
    try:
        yield zenoh_node, service, port
    finally:
        zenoh_node.close()
        service.close()


def stamped(pose: tuple[float, float, float]) -> dict[str, Any]:
    x, y, yaw = pose
    return {"header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": "map"},
            "pose": {"position": {"x": x, "y": y, "z": 0.0},
                     "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}}}


def test_ros2_goal_over_zenoh_yields_a_ros2_path(node: tuple[ZenohNode, PlanningService, int], tmp_path: Path) -> None:
    zenoh_node, service, port = node
    from zenoh_ros2_sdk import message_registry
    from zenoh_ros2_sdk.discovery import get_topic_names_and_types
    from zenoh_ros2_sdk.session import ZenohSession

    message_registry._registry = None  # a fresh registry reading our local .msg files
    message_registry.get_registry(str(write_msg_files(tmp_path / "msgs")))
    ZenohSession._instance = None
    received: list[Any] = []
    got = threading.Event()

    def on_path(msg: Any) -> None:
        received.append(msg)
        got.set()

    path_sub = sdk.ROS2Subscriber("/plan", "nav_msgs/msg/Path", on_path, router_port=port, node_name="robot")
    pose_pub = sdk.ROS2Publisher("/pose", "geometry_msgs/msg/PoseStamped", router_port=port, node_name="robot")
    goal_pub = sdk.ROS2Publisher("/goal_pose", "geometry_msgs/msg/PoseStamped", router_port=port, node_name="robot")
    try:
        # the SDK's key expressions (its own type hashes) are the ones sphereplan listens and publishes on
        assert path_sub.keyexpr == zenoh_node.ros2.plan_key
        assert goal_pub.keyexpr.split("/")[-1] == typestore().hash_rihs01("geometry_msgs/msg/PoseStamped")

        ts = message_registry.get_registry().session.store.types
        header_t, time_t = ts["std_msgs/msg/Header"], ts["builtin_interfaces/msg/Time"]
        pose_t, point_t, quat_t = (ts[f"geometry_msgs/msg/{n}"] for n in ("Pose", "Point", "Quaternion"))

        def fields(pose: tuple[float, float, float]) -> dict[str, Any]:
            d = stamped(pose)
            p, q = d["pose"]["position"], d["pose"]["orientation"]
            return {"header": header_t(stamp=time_t(sec=0, nanosec=0), frame_id="map"),
                    "pose": pose_t(position=point_t(**p), orientation=quat_t(**q))}

        # discovery and routes take a moment to settle: publish pose + goal until a path arrives
        deadline = time.monotonic() + 180
        while not got.is_set() and time.monotonic() < deadline:
            pose_pub.publish(**fields(HALL_START))
            time.sleep(0.3)
            goal_pub.publish(**fields(HALL_GOAL))
            got.wait(timeout=15)
        assert received, "no nav_msgs/Path arrived on /plan"

        topics = dict(get_topic_names_and_types(router_port=port, timeout=2.0))
        assert "nav_msgs/msg/Path" in topics.get("/plan", [])
        assert "geometry_msgs/msg/PoseStamped" in topics.get("/goal_pose", [])
    finally:
        for entity in (path_sub, pose_pub, goal_pub):
            entity.close()
        ZenohSession.get_instance().close()

    path = received[-1]
    expected = service.plan(PlanRequest(map="hall", start=PoseIn(x=HALL_START[0], y=HALL_START[1], yaw=HALL_START[2]),
                                        goal=PoseIn(x=HALL_GOAL[0], y=HALL_GOAL[1], yaw=HALL_GOAL[2])), timeout_s=120)
    states = expected.json()["states"]
    assert path.header.frame_id == "map"
    assert len(path.poses) == len(states)
    for ps, st in zip(path.poses, states, strict=True):
        assert (ps.pose.position.x, ps.pose.position.y) == pytest.approx((st["x"], st["y"]))
        q = ps.pose.orientation
        yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
        assert math.remainder(yaw - st["yaw"], math.tau) == pytest.approx(0, abs=1e-9)
    t0 = path.header.stamp.sec + path.header.stamp.nanosec * 1e-9
    last = path.poses[-1].header.stamp
    assert last.sec + last.nanosec * 1e-9 - t0 == pytest.approx(states[-1]["t"], abs=1e-6)


def test_zenoh_json_queries_take_ros_messages(node: tuple[ZenohNode, PlanningService, int]) -> None:
    """The native JSON face: a ``sphereplan/plan`` query with a nav_msgs/OccupancyGrid and PoseStamped poses,
    and a robot's ``pose`` topic given as a geometry_msgs/Pose."""
    import json

    import numpy as np
    import zenoh

    from tests.service.service_harness import hall_grid

    zenoh_node, service, port = node
    grid = hall_grid()
    ros_map = {"header": {"frame_id": "map"},
               "info": {"resolution": grid.resolution_m, "width": grid.width, "height": grid.height,
                        "origin": {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": {"w": 1.0}}},
               "data": np.asarray(grid.data, dtype=int).ravel().tolist()}
    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([f"tcp/127.0.0.1:{port}"]))
    conf.insert_json5("scouting/multicast/enabled", "false")
    with zenoh.open(conf) as session:
        body = {"map": ros_map, "start": stamped(HALL_START), "goal": stamped(HALL_GOAL)}
        replies = []
        deadline = time.monotonic() + 120
        while not replies and time.monotonic() < deadline:
            replies = list(session.get("sphereplan/plan", payload=json.dumps(body).encode(), timeout=60))
        assert replies and replies[0].ok is not None, replies
        result = json.loads(replies[0].ok.payload.to_bytes())
        assert result["status"] == "exact" and result["map"] == "occupancy_grid"

        bad = {**body, "goal": {**stamped(HALL_GOAL), "header": {"frame_id": "odom"}}}
        err = next(iter(session.get("sphereplan/plan", payload=json.dumps(bad).encode(), timeout=60))).err
        assert err is not None and json.loads(err.payload.to_bytes())["field"] == "goal.header.frame_id"

        statuses: list[dict[str, Any]] = []
        done = threading.Event()

        def on_status(sample: zenoh.Sample) -> None:
            statuses.append(json.loads(sample.payload.to_bytes()))
            if statuses[-1]["state"] in ("succeeded", "failed"):
                done.set()

        sub = session.declare_subscriber("sphereplan/r1/status", on_status)
        deadline = time.monotonic() + 120
        while not done.is_set() and time.monotonic() < deadline:
            session.put("sphereplan/r1/pose", json.dumps(stamped(HALL_START)["pose"]).encode())
            time.sleep(0.3)
            session.put("sphereplan/r1/goal", json.dumps({"map": "hall", "goal": stamped(HALL_GOAL)}).encode())
            done.wait(timeout=15)
        sub.undeclare()
    assert statuses and statuses[-1]["state"] == "succeeded", statuses
    planning = [s for s in statuses if s["state"] == "planning"][-1]
    assert planning["start"] == pytest.approx({"x": 2.0, "y": 2.0, "yaw": 0.0})
