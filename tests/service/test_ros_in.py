"""ROS messages in: ``nav_msgs/OccupancyGrid`` JSON as the map and ``geometry_msgs/Pose``/``PoseStamped`` as
start and goal, over HTTP (a real ``sphereplan serve``) — the same plan as the native request."""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import httpx
import numpy as np
import pytest

from tests.service import service_harness as harness
from tests.service.service_harness import HALL_GOAL, HALL_START, hall_grid, plan_body, strip_timing


@pytest.fixture(scope="module")
def client() -> Iterator[httpx.Client]:
    """A client of the session's shared ``sphereplan serve`` (tests/service/service_harness.py)."""
    server = harness.acquire()
    try:
        with httpx.Client(base_url=server.url, timeout=60) as c:
            yield c
    finally:
        harness.release()


def ros_grid(frame: str = "map") -> dict[str, Any]:
    """The hall map as ``ros2 topic echo --json /map`` / rosbridge would spell it."""
    grid = hall_grid()
    ox, oy, _ = grid.origin
    return {
        "header": {"stamp": {"sec": 1700000000, "nanosec": 5}, "frame_id": frame},
        "info": {"map_load_time": {"sec": 1700000000, "nanosec": 0}, "resolution": grid.resolution_m,
                 "width": grid.width, "height": grid.height,
                 "origin": {"position": {"x": ox, "y": oy, "z": 0.0},
                            "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}},
        "data": np.asarray(grid.data, dtype=int).ravel().tolist(),
    }


def ros_pose(x: float, y: float, yaw: float) -> dict[str, Any]:
    return {"position": {"x": x, "y": y, "z": 0.0},
            "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}}


def stamped(x: float, y: float, yaw: float, frame: str = "map") -> dict[str, Any]:
    return {"header": {"stamp": {"sec": 1, "nanosec": 0}, "frame_id": frame}, "pose": ros_pose(x, y, yaw)}


def test_ros_map_and_poses_plan_like_the_native_request(client: httpx.Client) -> None:
    native = client.post("/v1/plan", json=plan_body())
    assert native.status_code == 200, native.text
    body = {"map": ros_grid(), "start": stamped(*HALL_START), "goal": ros_pose(*HALL_GOAL)}
    ros = client.post("/v1/plan", json=body)
    assert ros.status_code == 200, ros.text
    a, b = strip_timing(native.json()), strip_timing(ros.json())
    assert a.pop("map") == "hall" and b.pop("map") == "occupancy_grid"
    assert a == b


def test_ros_map_for_simulate_and_reconfigure(client: httpx.Client) -> None:
    plan = client.post("/v1/plan", json=plan_body()).json()
    sim = client.post("/v1/simulate", json={"map": ros_grid(), "path": plan, "noise": "none", "tracker": "pursuit"})
    assert sim.status_code == 200, sim.text
    assert sim.json()["metrics"]["min_clearance_m"] > 0
    rec = client.post("/v1/reconfigure", json={"start": [2.0, 2.0], "goal": [3.5, 3.0], "map": ros_grid()})
    assert rec.status_code == 200, rec.text


def _bad(**change: Any) -> dict[str, Any]:
    grid = ros_grid()
    for path, value in change.items():
        node = grid
        *parents, last = path.split("__")
        for key in parents:
            node = node[key]
        node[last] = value
    return {"map": grid, "start": stamped(*HALL_START), "goal": stamped(*HALL_GOAL)}


ROS_BAD: list[tuple[str, dict[str, Any], str]] = [
    ("map in another frame", _bad(header__frame_id="odom"), "map.header.frame_id"),
    ("data too short", _bad(data=[0] * 10), "map"),
    ("cell value", _bad(data=[0] * 7999 + [127]), "map.data[7999]"),
    ("zero resolution", _bad(info__resolution=0.0), "map.info.resolution"),
    ("width missing", _bad(info__width=None), "map.info.width"),
    ("zero quaternion", _bad(info__origin__orientation={"x": 0, "y": 0, "z": 0, "w": 0}),
     "map.info.origin.orientation"),
    ("pose in another frame", {**_bad(), "start": stamped(*HALL_START, frame="base_link")}, "start.header.frame_id"),
    ("pose without position", {**_bad(), "goal": {"orientation": {"w": 1.0}, "position": {"x": 1.0}}},
     "goal.position.y"),
    ("stamped pose string x", {**_bad(), "goal": {"pose": {"position": {"x": "1", "y": 2.0}}}}, "goal.pose.position.x"),
    ("unknown field", {**_bad(), "goal": {**stamped(*HALL_GOAL), "twist": {}}}, "goal.twist"),
]


@pytest.mark.parametrize(("case", "body", "field"), ROS_BAD, ids=[c[0] for c in ROS_BAD])
def test_bad_ros_messages_name_the_field(client: httpx.Client, case: str, body: dict[str, Any], field: str) -> None:
    response = client.post("/v1/plan", json=body)
    assert response.status_code == 422, response.text
    assert response.json()["field"] == field, response.json()
