"""The Zenoh doors of robot sessions, each against a separate client session: the JSON topics
``sphereplan/<id>/live/*``, and ROS 2 over rmw_zenoh with ``zenoh-ros2-sdk`` playing the robot (Odometry and
PointCloud2 in, nav_msgs/Path out). In both, observations that block the path bring a new path."""

from __future__ import annotations

import json
import math
import struct
import threading
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import zenoh

from service.core import PlanningService
from service.ros import typestore
from service.sessions import SessionStore
from service.settings import ServiceSettings
from service.zenoh_live import start_live_doors
from service.zenoh_node import ZenohNode, default_config
from tests.service.service_harness import HALL_GOAL, HALL_START, free_port, make_maps


@pytest.fixture()
def doors(tmp_path: Path) -> Iterator[tuple[SessionStore, list[Any], int]]:
    port = free_port()
    settings = ServiceSettings(maps_dir=make_maps(tmp_path / "maps"), workers=1, warm_up=False, ros2=True,
                               ros2_map="hall", ros2_namespace="/", zenoh_listen=f"tcp/127.0.0.1:{port}")
    service = PlanningService(settings, executor_factory=lambda n: ThreadPoolExecutor(n))
    service.start()
    node = ZenohNode(service, settings, config=default_config(settings.zenoh_listen))
    node.start()
    store = SessionStore()
    live = start_live_doors(service, store, node, settings)
    try:
        yield store, live, port
    finally:
        store.close()
        for door in live:
            door.close()
        node.close()
        service.close()


def client_config(port: int) -> zenoh.Config:
    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([f"tcp/127.0.0.1:{port}"]))
    conf.insert_json5("scouting/multicast/enabled", "false")
    return conf


def put(z: zenoh.Session, key: str, payload: str) -> None:
    """As a robot would send its session messages: congestion control BLOCK (the default may drop one when busy)."""
    z.put(key, payload, congestion_control=zenoh.CongestionControl.BLOCK)


def gap_points(y0: float = 4.4, y1: float = 6.2) -> list[list[float]]:
    return [[5.15, float(y), 0.3] for y in np.arange(y0, y1, 0.05)]


def test_zenoh_topics_replan_when_observations_block_the_path(doors: tuple[SessionStore, list[Any], int]) -> None:
    store, _, port = doors
    paths: list[dict[str, Any]] = []
    statuses: list[dict[str, Any]] = []
    got = threading.Condition()

    def on(sample: zenoh.Sample, into: list[dict[str, Any]]) -> None:
        with got:
            into.append(json.loads(sample.payload.to_bytes()))
            got.notify_all()

    def wait_for(pred: Any, timeout: float = 240) -> None:  # generous: a busy 2-core machine
        with got:
            assert got.wait_for(pred, timeout), f"timed out; statuses: {statuses[-3:]}"

    with zenoh.open(client_config(port)) as z:
        z.declare_subscriber("sphereplan/r1/live/path", lambda s: on(s, paths))
        z.declare_subscriber("sphereplan/r1/live/status", lambda s: on(s, statuses))
        time.sleep(0.5)
        start, goal = (dict(zip(("x", "y", "yaw"), p, strict=True)) for p in (HALL_START, HALL_GOAL))
        put(z, "sphereplan/r1/live/session", json.dumps({"map": "hall", "start": start, "goal": goal}))
        wait_for(lambda: len(paths) >= 1)
        first = paths[0]
        assert first["status"] in ("exact", "approximate") and "r1" in store.ids()
        put(z, "sphereplan/r1/live/pose", json.dumps({"x": 2.2, "y": 2.0, "yaw": 0.0}))
        put(z, "sphereplan/r1/live/observations", json.dumps({"points": {"points": gap_points(),
                                                                        "origin": [3.0, 5.5, 0.3]}}))
        wait_for(lambda: len(paths) >= 2 and sum(s.get("state") == "replanned" for s in statuses) >= 2)
        replanned = [s for s in statuses if s.get("state") == "replanned"]
        assert replanned[-1]["replan"]["reason"] == "blocked"
        # the robot rolls along its path, so the new path keeps the old one from the robot for a stretch and is
        # planned from the end of it (ReplanPolicy.splice_lead_s)
        replan = replanned[-1]["replan"]
        assert replan["spliced_m"] > 0 and replan["start"] != {"x": 2.2, "y": 2.0, "yaw": 0.0}
        head = paths[1]["states"][0]
        assert np.hypot(head["x"] - 2.2, head["y"] - 2.0) < 0.3
        assert paths[1]["states"] != first["states"]
        # a malformed message is answered on the status topic, naming the field
        put(z, "sphereplan/r1/live/observations", json.dumps({"scan": {"ranges": [1.0]}}))
        wait_for(lambda: any(s.get("state") == "invalid" for s in statuses))
        bad = next(s for s in statuses if s.get("state") == "invalid")
        assert bad["topic"] == "observations" and bad["field"].startswith("scan.")


# ---------------------------------------------------------------------------------------------- ROS 2

TYPES = ("geometry_msgs/msg/PoseStamped", "geometry_msgs/msg/Pose", "geometry_msgs/msg/Point",
         "geometry_msgs/msg/Quaternion", "std_msgs/msg/Header", "builtin_interfaces/msg/Time", "nav_msgs/msg/Path",
         "nav_msgs/msg/Odometry", "geometry_msgs/msg/PoseWithCovariance", "geometry_msgs/msg/TwistWithCovariance",
         "geometry_msgs/msg/Twist", "geometry_msgs/msg/Vector3", "sensor_msgs/msg/PointCloud2",
         "sensor_msgs/msg/PointField")


def write_msg_files(folder: Path) -> Path:
    """The ``.msg`` files the SDK reads (ROS 2 Humble definitions), as ``<pkg>/msg/<Name>.msg``."""
    for typename in TYPES:
        text = typestore().generate_msgdef(typename, ros_version=2)[0]
        own = text.split("=" * 80)[0].strip() + "\n"
        path = folder.joinpath(*typename.split("/")).with_suffix(".msg")
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(own)
    return folder


def test_ros2_odometry_and_pointcloud_replan(doors: tuple[SessionStore, list[Any], int], tmp_path: Path) -> None:
    import zenoh_ros2_sdk as sdk
    from zenoh_ros2_sdk import message_registry
    from zenoh_ros2_sdk.session import ZenohSession

    store, live, port = doors
    face = live[1]
    message_registry._registry = None
    message_registry.get_registry(str(write_msg_files(tmp_path / "msgs")))
    ZenohSession._instance = None
    received: list[Any] = []
    got = threading.Event()

    def on_path(msg: Any) -> None:
        received.append(msg)
        got.set()

    path_sub = sdk.ROS2Subscriber("/live/plan", "nav_msgs/msg/Path", on_path, router_port=port, node_name="robot")
    odom_pub = sdk.ROS2Publisher("/live/odom", "nav_msgs/msg/Odometry", router_port=port, node_name="robot")
    goal_pub = sdk.ROS2Publisher("/live/goal_pose", "geometry_msgs/msg/PoseStamped", router_port=port,
                                 node_name="robot")
    cloud_pub = sdk.ROS2Publisher("/live/points", "sensor_msgs/msg/PointCloud2", router_port=port, node_name="robot")
    try:
        ts = message_registry.get_registry().session.store.types
        header_t, time_t = ts["std_msgs/msg/Header"], ts["builtin_interfaces/msg/Time"]
        pose_t, point_t, quat_t = (ts[f"geometry_msgs/msg/{n}"] for n in ("Pose", "Point", "Quaternion"))
        pwc_t, twc_t = ts["geometry_msgs/msg/PoseWithCovariance"], ts["geometry_msgs/msg/TwistWithCovariance"]
        twist_t, vec_t = ts["geometry_msgs/msg/Twist"], ts["geometry_msgs/msg/Vector3"]
        field_t = ts["sensor_msgs/msg/PointField"]

        def header(frame: str) -> Any:
            return header_t(stamp=time_t(sec=0, nanosec=0), frame_id=frame)

        def ros_pose(p: tuple[float, float, float]) -> Any:
            return pose_t(position=point_t(x=p[0], y=p[1], z=0.0),
                          orientation=quat_t(x=0.0, y=0.0, z=math.sin(p[2] / 2), w=math.cos(p[2] / 2)))

        def odom(p: tuple[float, float, float]) -> dict[str, Any]:
            zero = vec_t(x=0.0, y=0.0, z=0.0)
            return {"header": header("map"), "child_frame_id": "base_link",
                    "pose": pwc_t(pose=ros_pose(p), covariance=np.zeros(36)),
                    "twist": twc_t(twist=twist_t(linear=zero, angular=zero), covariance=np.zeros(36))}

        def cloud(points: list[list[float]]) -> dict[str, Any]:
            data = b"".join(struct.pack("<fff", *p) for p in points)
            fields = [field_t(name=n, offset=4 * i, datatype=7, count=1) for i, n in enumerate("xyz")]
            return {"header": header("map"), "height": 1, "width": len(points), "fields": fields,
                    "is_bigendian": False, "point_step": 12, "row_step": 12 * len(points),
                    "data": np.frombuffer(data, dtype=np.uint8), "is_dense": True}

        deadline = time.monotonic() + 180
        while not got.is_set() and time.monotonic() < deadline:
            odom_pub.publish(**odom(HALL_START))
            time.sleep(0.3)
            goal_pub.publish(header=header("map"), pose=ros_pose(HALL_GOAL))
            got.wait(timeout=10)
        assert received, "no nav_msgs/Path arrived on /live/plan"
        sid = face.sid
        first = store.get(sid).session.path
        assert first is not None
        n_before = len(received)
        odom_pub.publish(**odom((2.2, 2.0, 0.0)))
        time.sleep(0.3)
        got.clear()
        deadline = time.monotonic() + 60
        while len(received) == n_before and time.monotonic() < deadline:
            cloud_pub.publish(**cloud(gap_points()))
            got.wait(timeout=5)
        assert len(received) > n_before, "no new path after the PointCloud2 blocked the old one"
        event = store.get(sid).session.events[-1]
        assert event.reason == "blocked" and event.ok and event.spliced_m > 0  # odometry on the path, rolling
        path = received[-1]
        xy = np.array([[p.pose.position.x, p.pose.position.y] for p in path.poses])
        assert np.hypot(xy[0, 0] - 2.2, xy[0, 1] - 2.0) < 0.3  # the published path starts at the robot
        assert xy[np.abs(xy[:, 0] - 5.15) < 0.3, 1].min() > 6.2  # around what the cloud showed
    finally:
        for entity in (path_sub, odom_pub, goal_pub, cloud_pub):
            entity.close()
        ZenohSession.get_instance().close()


def test_session_topics_need_the_token_and_follow_the_robot_partition(tmp_path: Path) -> None:
    """The session topics are guarded like the goal topics: with ``--token-file`` a message without the
    attachment ``Bearer <token>`` is dropped, and an instance serving ``--robots r1`` ignores other robots."""
    port = free_port()
    settings = ServiceSettings(maps_dir=make_maps(tmp_path / "maps"), workers=1, warm_up=False,
                               zenoh_listen=f"tcp/127.0.0.1:{port}", http_token="a-token-for-the-test",
                               zenoh_robots=("r1",))
    service = PlanningService(settings, executor_factory=lambda n: ThreadPoolExecutor(n))
    service.start()
    node = ZenohNode(service, settings, config=default_config(settings.zenoh_listen))
    node.start()
    store = SessionStore()
    live = start_live_doors(service, store, node, settings)
    door = live[0]
    try:
        start, goal = (dict(zip(("x", "y", "yaw"), p, strict=True)) for p in (HALL_START, HALL_GOAL))
        body = json.dumps({"map": "hall", "start": start, "goal": goal})
        with zenoh.open(client_config(port)) as z:
            time.sleep(0.5)
            z.put("sphereplan/r1/live/session", body)  # no token
            z.put("sphereplan/r1/live/session", body, attachment=b"Bearer wrong")
            deadline = time.monotonic() + 30
            while door.dropped_unauthorised < 2 and time.monotonic() < deadline:
                time.sleep(0.05)
            assert door.dropped_unauthorised == 2 and "r1" not in store.ids()
            z.put("sphereplan/r2/live/session", body, attachment=b"Bearer a-token-for-the-test")  # not ours
            z.put("sphereplan/r1/live/session", body, attachment=b"Bearer a-token-for-the-test")
            while "r1" not in store.ids() and time.monotonic() < deadline + 30:
                time.sleep(0.05)
            assert "r1" in store.ids() and "r2" not in store.ids()
    finally:
        store.close()
        for d in live:
            d.close()
        node.close()
        service.close()


def test_a_sessions_time_limit_is_the_same_at_the_http_and_zenoh_doors(doors: tuple[SessionStore, list[Any], int],
                                                                      tmp_path: Path) -> None:
    """The replan time limit a robot asks for (``time_limit_s``, which every replan keeps, spliced or not) is the one
    its session gets through HTTP and through Zenoh, and one over the service's bound is refused naming the field at
    both doors."""
    from fastapi.testclient import TestClient

    from service.http import create_app

    store, _, port = doors
    start = dict(zip(("x", "y", "yaw"), HALL_START, strict=True))
    body = {"map": "hall", "start": start, "time_limit_s": 0.7, "replan_period_s": 3.0}
    settings = ServiceSettings(maps_dir=make_maps(tmp_path / "http_maps"), workers=1, warm_up=False, zenoh=False)
    app = create_app(settings)
    with TestClient(app) as client:
        made = client.post("/v1/sessions", json={**body, "id": "h1"})
        assert made.status_code == 201, made.text
        http_policy = app.state.sessions.get("h1").session.policy
        too_long = client.post("/v1/sessions", json={**body, "time_limit_s": 11.0})
        assert too_long.status_code == 422 and "time_limit_s" in too_long.text
    statuses: list[dict[str, Any]] = []
    got = threading.Condition()

    def on(sample: zenoh.Sample) -> None:
        with got:
            statuses.append(json.loads(sample.payload.to_bytes()))
            got.notify_all()

    with zenoh.open(client_config(port)) as z:
        z.declare_subscriber("sphereplan/r1/live/status", on)
        time.sleep(0.5)
        put(z, "sphereplan/r1/live/session", json.dumps(body))
        with got:
            assert got.wait_for(lambda: any(s.get("state") == "created" for s in statuses), 120), statuses
        put(z, "sphereplan/r1/live/session", json.dumps({**body, "time_limit_s": 11.0}))
        with got:
            assert got.wait_for(lambda: any(s.get("state") == "invalid" for s in statuses), 120), statuses
    zenoh_policy = store.get("r1").session.policy
    assert zenoh_policy == http_policy
    assert (zenoh_policy.time_limit_s, zenoh_policy.period_s) == (0.7, 3.0)
    bad = next(s for s in statuses if s.get("state") == "invalid")
    assert bad["field"] == "time_limit_s"
