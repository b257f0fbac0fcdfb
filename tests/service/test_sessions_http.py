"""The HTTP door of robot sessions (``/v1/sessions``) on the real app: create on a map, observations that block
the path get a new path (also on the Server-Sent Events stream), bad input names its field, limits hold."""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fastapi.testclient import TestClient

from planner.maps.clearance import least_footprint_distance
from planner.robot import load_robot
from service.http import create_app
from service.sessions import SessionLimits, SessionStore
from service.settings import ServiceSettings
from tests.service.service_harness import HALL_GOAL, HALL_START, hall_grid, make_maps


def pose(p: tuple[float, float, float]) -> dict[str, float]:
    return dict(zip(("x", "y", "yaw"), p, strict=True))


def gap_wall(y0: float = 4.4, y1: float = 6.2) -> list[list[float]]:
    """Points of an obstacle in the hall's only gap (above its wall at x = 5 m), leaving the top of the gap open."""
    return [[5.15, float(y), 0.3] for y in np.arange(y0, y1, 0.05)]


@pytest.fixture()
def client(tmp_path: Path) -> Iterator[TestClient]:
    settings = ServiceSettings(maps_dir=make_maps(tmp_path / "maps"), workers=1, warm_up=False, zenoh=False)
    app = create_app(settings)
    with TestClient(app) as c:  # one unwarmed pool worker; sessions plan in the server process itself
        yield c


@pytest.fixture()
def session(client: TestClient) -> dict[str, Any]:
    r = client.post("/v1/sessions", json={"map": "hall", "start": pose(HALL_START), "goal": pose(HALL_GOAL)})
    assert r.status_code == 201, r.text
    return r.json()


def test_observations_that_block_the_path_give_a_new_path(client: TestClient, session: dict[str, Any]) -> None:
    sid = session["id"]
    first = session["path"]
    assert session["replan"]["reason"] == "goal" and first["status"] in ("exact", "approximate")
    r = client.post(f"/v1/sessions/{sid}/observations",
                    json={"points": {"points": gap_wall(), "origin": [3.0, 5.5, 0.3]}})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["update"]["cells_changed"] > 0
    assert body["replan"]["reason"] == "blocked" and body["replan"]["ok"]
    new = client.get(f"/v1/sessions/{sid}/path").json()
    assert new["states"] != first["states"]
    xy = np.array([[s["x"], s["y"], s["yaw"]] for s in new["states"]])
    live = hall_grid()
    data = live.data.copy()
    for x, y, _ in gap_wall():
        data[int(y / 0.1), int(x / 0.1)] = 100
    blocked_hall = type(live)(data, live.resolution_m, live.origin)
    assert least_footprint_distance(blocked_hall, load_robot(), xy) > 0  # clear of what was observed
    assert xy[np.abs(xy[:, 0] - 5.15) < 0.3, 1].min() > 6.2  # through what is left of the gap
    status = client.get(f"/v1/sessions/{sid}").json()["status"]
    assert status["replans"] == 2 and status["last_replan"]["reason"] == "blocked"
    grid = client.get(f"/v1/sessions/{sid}/map").json()
    assert grid["info"]["width"] == 100 and len(grid["data"]) == 100 * 80
    assert client.get(f"/v1/sessions/{sid}/map.png").headers["content-type"] == "image/png"


def test_event_stream_carries_the_new_path(client: TestClient, session: dict[str, Any]) -> None:
    sid = session["id"]

    def block_later() -> None:
        time.sleep(0.5)
        client.post(f"/v1/sessions/{sid}/observations",
                    json={"points": {"points": gap_wall(), "origin": [3.0, 5.5, 0.3]}})

    threading.Thread(target=block_later).start()
    events = []
    with client.stream("GET", f"/v1/sessions/{sid}/events?max_events=2") as stream:
        assert stream.headers["content-type"].startswith("text/event-stream")
        name = None
        for line in stream.iter_lines():
            if line.startswith("event: "):
                name = line[7:]
            elif line.startswith("data: "):
                events.append((name, json.loads(line[6:])))
    kinds = [k for k, _ in events]
    assert "replan" in kinds
    replan = dict(events)["replan"]
    assert replan["replan"]["reason"] == "blocked" and len(replan["path"]["states"]) > 2


def test_goal_pose_and_failures(client: TestClient, session: dict[str, Any]) -> None:
    sid = session["id"]
    r = client.post(f"/v1/sessions/{sid}/pose", json={"x": 2.5, "y": 2.0, "yaw": 0.0})
    assert r.status_code == 200 and r.json()["replan"] is None
    r = client.post(f"/v1/sessions/{sid}/goal", json={"x": 8.0, "y": 6.0, "yaw": 1.57})
    assert r.status_code == 200 and r.json()["replan"]["reason"] == "goal" and r.json()["path"]["states"]
    # close the gap completely: no path, answered as a failed plan
    r = client.post(f"/v1/sessions/{sid}/observations", json={"points": {"points": gap_wall(4.4, 7.95),
                                                                          "origin": [3.0, 5.5, 0.3]}})
    assert r.json()["replan"]["ok"] is False and r.json()["replan"]["error_code"] == 208
    r = client.get(f"/v1/sessions/{sid}/path")
    assert r.status_code == 422 and r.json()["error_code"] == 208
    assert client.delete(f"/v1/sessions/{sid}").status_code == 204
    assert client.get(f"/v1/sessions/{sid}").status_code == 404


@pytest.mark.parametrize(("body", "field"), [
    ({"map": "hall", "start": {"x": 1, "y": 1, "yaw": 99}}, "start.yaw"),
    ({"start": {"x": 1, "y": 1, "yaw": 0}}, "body"),
    ({"map": "nowhere", "start": {"x": 1, "y": 1, "yaw": 0}}, "map"),
    ({"unknown": {"width_m": 5000, "height_m": 10, "resolution_m": 0.05}, "start": {"x": 1, "y": 1, "yaw": 0}},
     "unknown.width_m"),
    ({"unknown": {"width_m": 1000, "height_m": 1000, "resolution_m": 0.05}, "start": {"x": 1, "y": 1, "yaw": 0}},
     "unknown.resolution_m"),
])
def test_bad_sessions_name_the_field(client: TestClient, body: dict[str, Any], field: str) -> None:
    r = client.post("/v1/sessions", json=body)
    assert 400 <= r.status_code < 500 and r.json()["field"] == field, r.text


def test_bad_observations_and_limits(client: TestClient, session: dict[str, Any]) -> None:
    sid = session["id"]
    for obs, field in (({"points": {"points": [[1, 2]], "origin": [0, 0, 0]}}, "points.points[0]"),
                       ({"points": {"points": [[1, 2, 3]], "frame": "sensor"}}, "points"),
                       ({"scan": {"ranges": [1.0], "angle_min": 0, "angle_increment": 0.1, "range_max": 10,
                                  "sensor_pose": {"x": 1, "y": 1, "yaw": 400}}}, "scan.sensor_pose.yaw"),
                       ({"region": {"ix0": 95, "iy0": 0, "data": [[0] * 10]}}, "region.data")):
        r = client.post(f"/v1/sessions/{sid}/observations", json=obs)
        assert r.status_code == 422 and r.json()["field"] == field, r.text
    assert client.post("/v1/sessions/no-such/pose", json=pose(HALL_START)).status_code == 404
    # the update rate and the sessions per client are bounded
    limits = SessionLimits(min_update_interval_s=60, max_sessions_per_client=1)
    client.app.state.sessions = SessionStore(limits)  # type: ignore[attr-defined]
    r = client.post("/v1/sessions", json={"map": "hall", "start": pose(HALL_START)})
    sid = r.json()["id"]
    one = {"points": {"points": [[3, 3, 0.3]], "origin": [2, 2, 0.3]}}
    ok = client.post(f"/v1/sessions/{sid}/observations", json=one)
    assert ok.status_code == 200
    busy = client.post(f"/v1/sessions/{sid}/observations", json=one)
    assert busy.status_code == 429 and "Retry-After" in busy.headers
    second = client.post("/v1/sessions", json={"map": "hall", "start": pose(HALL_START)})
    assert second.status_code == 422 and second.json()["field"] == "session"


def test_sessions_use_the_live_planner_options(client: TestClient) -> None:
    """A session plans with the live defaults (unknown traversable, the greedier search) under what it is given,
    and each replan says which search answered."""
    from planner.live import live_options
    from planner.live.session import LIVE_OPTION_DEFAULTS

    r = client.post("/v1/sessions", json={"map": "hall", "start": pose(HALL_START), "goal": pose(HALL_GOAL),
                                          "options": {"allow_unknown": False}})
    assert r.status_code == 201, r.text
    body = r.json()
    assert body["replan"]["method"] in ("guided", "ordinary")
    options = client.app.state.sessions.get(body["id"]).session.options  # type: ignore[attr-defined]
    assert options.allow_unknown is False and options.greed == LIVE_OPTION_DEFAULTS["greed"]
    plain = client.post("/v1/sessions", json={"map": "hall", "start": pose(HALL_START)}).json()
    assert client.app.state.sessions.get(plain["id"]).session.options == live_options()  # type: ignore[attr-defined]
    bad = client.post("/v1/sessions", json={"map": "hall", "start": pose(HALL_START), "options": {"greedy": 2}})
    assert bad.status_code == 422 and "options.greedy" in bad.text
