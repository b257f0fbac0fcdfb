"""The Zenoh node, driven from a second process over loopback (a free port, never 7447)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import httpx
import pytest

from service.cli import main as cli_main
from tests.service.service_harness import (
    HALL_GOAL,
    HALL_START,
    SLOT_GOAL,
    SLOW,
    Server,
    plan_body,
    strip_sim_timing,
    strip_timing,
    zenoh_steps,
)

RECONFIGURE = {"start": [2.0, 2.0], "start_tilt": [30.0, 75.0], "goal": [3.5, 3.0], "degrees": True, "map": "hall"}


@pytest.fixture(scope="module")
def query_answers(server: Server) -> list[dict[str, Any]]:
    """One client process for every query test below (process start-up is the slow part)."""
    return zenoh_steps(server, [
        {"query": "sphereplan/plan", "payload": plan_body()},
        {"query": "sphereplan/plan", "payload": plan_body(start=(5.1, 2.0, 0.0))},
        {"query": "sphereplan/plan", "payload": '{"map": "hall", "start": {"x": NaN, "y": 2, "yaw": 0}}'},
        {"query": "sphereplan/plan", "payload": '{"map": '},
        {"query": "sphereplan/plan", "payload": {**plan_body(), "map": "../hall"}},
        {"query": "sphereplan/plan", "payload": {**plan_body(), "map": "nowhere"}},
        {"query": "sphereplan/plan", "payload": plan_body(time_limit_s=-1)},
        {"queries": [{"query": "sphereplan/plan",
                      "payload": plan_body(goal=SLOT_GOAL, options=SLOW, time_limit_s=1.5)},
                     {"query": "sphereplan/plan", "payload": plan_body()}]},
        {"liveliness": "sphereplan/planner/**"},
        {"query": "sphereplan/reconfigure", "payload": RECONFIGURE},
    ])


def only_reply(answer: dict[str, Any]) -> dict[str, Any]:
    replies = answer["replies"]
    assert len(replies) == 1, replies
    reply: dict[str, Any] = replies[0]
    assert reply["encoding"].startswith("application/json")
    return reply


def test_plan_query_equals_cli_and_http(query_answers: list[dict[str, Any]], server: Server, tmp_path: Path) -> None:
    reply = only_reply(query_answers[0])
    assert reply["ok"] and reply["payload"]["status"] == "exact"
    out = tmp_path / "cli.json"
    assert cli_main(["plan", "--map", str(server.maps_dir / "hall.yaml"), "--start", *map(str, HALL_START),
                     "--goal", *map(str, HALL_GOAL), "--out", str(out)]) == 0
    assert strip_timing(reply["payload"]) == strip_timing(json.loads(out.read_text()))
    http = httpx.post(server.url + "/v1/plan", json=plan_body(), timeout=60).json()
    assert strip_timing(reply["payload"]) == strip_timing(http)


def test_failed_plan_replies_err_with_the_failed_result(query_answers: list[dict[str, Any]], server: Server) -> None:
    reply = only_reply(query_answers[1])
    assert not reply["ok"]
    assert reply["payload"]["status"] == "failed" and reply["payload"]["error_code"] == 205
    http = httpx.post(server.url + "/v1/plan", json=plan_body(start=(5.1, 2.0, 0.0)), timeout=60)
    assert http.status_code == 422
    assert strip_timing(reply["payload"]) == strip_timing(http.json())


@pytest.mark.parametrize(("index", "field"), [(2, "start.x"), (3, "body"), (4, "map"), (5, "map"),
                                              (6, "time_limit_s")])
def test_bad_query_replies_err_naming_the_field(query_answers: list[dict[str, Any]], index: int, field: str) -> None:
    reply = only_reply(query_answers[index])
    assert not reply["ok"]
    assert reply["payload"]["field"] == field and reply["payload"]["error_code"] == 200
    assert reply["payload"]["error_msg"]


def test_slow_query_does_not_block_a_fast_one(query_answers: list[dict[str, Any]]) -> None:
    answer = query_answers[7]
    slow, fast = answer["replies"]
    assert fast["ok"] and fast["payload"]["status"] == "exact"
    assert not slow["ok"] and slow["payload"]["error_code"] == 207
    assert answer["order"] == [1, 0]  # the fast plan was answered while the slow one was still searching


def test_liveliness_token_announces_the_planner(query_answers: list[dict[str, Any]]) -> None:
    tokens = query_answers[8]["tokens"]
    assert len(tokens) == 1 and tokens[0].startswith("sphereplan/planner/")


def test_reconfigure_query_equals_http(query_answers: list[dict[str, Any]], server: Server) -> None:
    reply = only_reply(query_answers[9])
    assert reply["ok"] and reply["payload"]["status"] == "exact"
    http = httpx.post(server.url + "/v1/reconfigure", json=RECONFIGURE, timeout=60).json()
    assert strip_timing(reply["payload"]) == strip_timing(http)


def test_simulate_query_equals_http(server: Server) -> None:
    plan = httpx.post(server.url + "/v1/plan", json=plan_body(), timeout=60).json()
    request = {"map": "hall", "path": plan, "tracker": "pursuit", "noise": "none"}
    answers = zenoh_steps(server, [{"query": "sphereplan/simulate", "payload": request},
                                   {"query": "sphereplan/simulate", "payload": {**request, "tracker": "lqr"}}])
    reply, bad = only_reply(answers[0]), only_reply(answers[1])
    assert reply["ok"] and reply["payload"]["metrics"]["reached_goal"]
    http = httpx.post(server.url + "/v1/simulate", json=request, timeout=60).json()
    assert strip_sim_timing(reply["payload"]) == strip_sim_timing(http)
    assert not bad["ok"] and bad["payload"]["field"] == "tracker"


def test_goal_and_pose_topics_plan_and_publish(server: Server) -> None:
    goal_msg = {"map": "hall", "goal": dict(zip(("x", "y", "yaw"), HALL_GOAL, strict=True))}
    answers = zenoh_steps(server, [
        {"subscribe": "sphereplan/r1/*"},
        {"sleep": 0.3},
        {"put": "sphereplan/r1/goal", "payload": goal_msg},  # no pose yet
        {"wait": "/status", "until": {"goal_id": 1, "state": "failed"}, "timeout_s": 10},
        {"put": "sphereplan/r1/pose", "payload": {"x": 2.0, "y": "two", "yaw": 0.0}},  # bad pose
        {"wait": "/status", "until": {"state": "invalid_pose"}, "timeout_s": 10},
        {"put": "sphereplan/r1/pose", "payload": dict(zip(("x", "y", "yaw"), HALL_START, strict=True))},
        {"put": "sphereplan/r1/goal", "payload": goal_msg},  # right after the pose: the pose must be used
        {"put": "sphereplan/r1/goal", "payload": {"map": "hall", "goal": {"x": "far"}}},  # garbage: must not cancel
        {"wait": "/status", "until": {"goal_id": 2, "state": "succeeded"}, "timeout_s": 60},
    ])
    samples = answers[-1]["samples"]
    statuses = [s["payload"] for s in samples if s["key"] == "sphereplan/r1/status"]
    assert statuses[0]["goal_id"] == 1 and statuses[0]["state"] == "failed" and statuses[0]["error_code"] == 203
    assert "pose" in statuses[0]["error_msg"]
    assert statuses[1]["state"] == "invalid_pose" and "y" in statuses[1]["error_msg"]
    assert sorted(s["state"] for s in statuses[2:]) == ["invalid_goal", "planning", "succeeded"]
    assert all(s["goal_id"] == 2 for s in statuses[2:])
    paths = [s["payload"] for s in samples if s["key"] == "sphereplan/r1/path"]
    assert len(paths) == 1
    http = httpx.post(server.url + "/v1/plan", json=plan_body(), timeout=60).json()
    assert strip_timing(paths[0]) == strip_timing(http)
    assert statuses[-1]["length_m"] == paths[0]["length_m"]
