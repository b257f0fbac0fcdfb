"""Zenoh under careless and hostile peers (issue 12, rows 4–6): oversized and deeply nested payloads on
the queryables and topics, and a burst of goals for one robot (the newest wins)."""

from __future__ import annotations

import json

import pytest

from tests.service.service_harness import HALL_START, Server, plan_body, zenoh_steps

pytestmark = pytest.mark.faults

NESTED = "[" * 100_000


def test_oversized_and_nested_payloads_get_the_error_json(server: Server) -> None:
    pose = dict(zip(("x", "y", "yaw"), HALL_START, strict=True))
    answers = zenoh_steps(server, [
        {"query": "sphereplan/plan", "payload": NESTED},
        {"query": "sphereplan/plan", "payload": json.dumps({**plan_body(), "pad": " " * 4_100_000})},
        {"query": "sphereplan/reconfigure", "payload": NESTED},
        {"subscribe": "sphereplan/*/status"},
        {"sleep": 0.3},
        {"put": "sphereplan/nest1/pose", "payload": NESTED},
        {"wait": "nest1/status", "until": {"state": "invalid_pose"}, "timeout_s": 30},
        {"put": "sphereplan/nest2/goal", "payload": NESTED},
        {"wait": "nest2/status", "until": {"state": "invalid_goal"}, "timeout_s": 30},
        {"put": "sphereplan/nest3/pose", "payload": json.dumps({**pose, "pad": " " * 4_100_000})},
        {"wait": "nest3/status", "until": {"state": "invalid_pose"}, "timeout_s": 30},
        {"query": "sphereplan/plan", "payload": plan_body()},
    ])
    for index in (0, 2):
        (reply,) = answers[index]["replies"]
        assert not reply["ok"] and reply["payload"]["field"] == "body", reply
        assert "nested too deeply" in reply["payload"]["error_msg"]
    (big,) = answers[1]["replies"]
    assert not big["ok"] and big["payload"]["field"] == "body" and "at most 4000000" in big["payload"]["error_msg"]
    statuses = {s["key"].split("/")[1]: s["payload"] for s in answers[10]["samples"]}
    assert [statuses[k]["state"] for k in ("nest1", "nest2", "nest3")] == ["invalid_pose", "invalid_goal",
                                                                           "invalid_pose"], statuses
    assert "nested too deeply" in statuses["nest1"]["error_msg"] and "at most" in statuses["nest3"]["error_msg"]
    assert all("internal" not in s["error_msg"] for s in statuses.values())
    (ok,) = answers[-1]["replies"]
    assert ok["ok"] and ok["payload"]["status"] == "exact"
    assert "RecursionError" not in server.log_path.read_text()


def test_a_burst_of_goals_ends_with_the_path_of_the_newest(server: Server) -> None:
    goals = [{"map": "hall", "goal": {"x": 8.0, "y": 1.5 + 0.05 * i, "yaw": 0.0}} for i in range(30)]
    answers = zenoh_steps(server, [
        {"subscribe": "sphereplan/burst/*"},
        {"sleep": 0.3},
        {"put": "sphereplan/burst/pose", "payload": dict(zip(("x", "y", "yaw"), HALL_START, strict=True))},
        *({"put": "sphereplan/burst/goal", "payload": goal} for goal in goals),
        {"wait": "/status", "until": {"goal_id": 30, "state": "succeeded"}, "timeout_s": 120},
        {"sleep": 1.0},  # anything a superseded plan might still (wrongly) publish
        {"wait": "/status", "until": {"never": True}, "timeout_s": 0},
    ])
    samples = answers[-1]["samples"]
    statuses = [s["payload"] for s in samples if s["key"].endswith("/status")]
    assert not [s for s in statuses if s["state"] == "failed"], statuses  # none refused as busy
    newest = [s for s in statuses if s["goal_id"] == 30]
    assert [s["state"] for s in newest] == ["planning", "succeeded"]
    paths = [s["payload"] for s in samples if s["key"].endswith("/path")]
    assert len(paths) == 1
    end = paths[0]["states"][-1]
    assert abs(end["x"] - 8.0) < 0.15 and abs(end["y"] - (1.5 + 0.05 * 29)) < 0.15
    superseded = {s["goal_id"] for s in statuses if s["state"] == "superseded"}
    assert superseded == {s["goal_id"] for s in statuses if s["state"] == "planning"} - {30}


def test_large_payloads_do_not_hold_a_small_query(server: Server) -> None:
    """Finding 3: Zenoh callbacks were serialised, so a 4-byte query waited behind 8 × 4 MB ones. Large payloads
    are parsed in the parse pool now; each is answered, and so is the small query sent with them."""
    # ≈ 3 MB each, parsed before they are refused (the resolution is out of range)
    big = json.dumps({**plan_body(), "map": {"data": [[0] * 1000 for _ in range(1000)], "resolution_m": 500.0}})
    answer = zenoh_steps(server, [{"queries": [*({"query": "sphereplan/plan", "payload": big} for _ in range(8)),
                                               {"query": "sphereplan/plan", "payload": plan_body()}]}])[0]
    *large, small = answer["replies"]
    assert small["ok"] and small["payload"]["status"] == "exact", small
    for reply in large:  # refused for its cells (or busy), never an internal error
        assert not reply["ok"] and (reply["payload"]["field"] or "map").startswith("map"), reply
        assert "internal" not in reply["payload"]["error_msg"]
