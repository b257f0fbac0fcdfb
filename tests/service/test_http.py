"""The HTTP API against a real ``sphereplan serve`` (uvicorn on a free port), driven with httpx."""

from __future__ import annotations

import asyncio
import base64
import gzip
import io
import json
import math
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pytest
import schemathesis
from hypothesis import HealthCheck, Phase, given, settings
from PIL import Image
from schemathesis import GenerationMode
from schemathesis.checks import not_a_server_error
from schemathesis.specs.openapi.checks import (
    content_type_conformance,
    response_schema_conformance,
    status_code_conformance,
)

from service.cli import main as cli_main
from tests.service import service_harness as harness
from tests.service.service_harness import (
    HALL_GOAL,
    HALL_START,
    SLOT_GOAL,
    SLOW,
    Server,
    plan_body,
    strip_sim_timing,
    strip_timing,
)


def cli_plan(server: Server, tmp_path: Path, start: tuple[float, ...], goal: tuple[float, ...],
             *extra: str) -> tuple[int, dict[str, Any]]:
    out = tmp_path / "cli.json"
    code = cli_main(["plan", "--map", str(server.maps_dir / "hall.yaml"), "--start", *map(str, start),
                     "--goal", *map(str, goal), "--out", str(out), *extra])
    return code, json.loads(out.read_text())


def test_plan_equals_cli(client: httpx.Client, server: Server, tmp_path: Path) -> None:
    response = client.post("/v1/plan", json=plan_body())
    assert response.status_code == 200, response.text
    assert response.headers["content-type"] == "application/json"
    body = response.json()
    assert body["status"] == "exact" and body["error_code"] == 0
    states = body["states"]
    assert math.dist((states[0]["x"], states[0]["y"]), HALL_START[:2]) < 1e-9
    assert math.dist((states[-1]["x"], states[-1]["y"]), HALL_GOAL[:2]) <= 0.1
    code, cli = cli_plan(server, tmp_path, HALL_START, HALL_GOAL)
    assert code == 0
    assert strip_timing(body) == strip_timing(cli)


def test_failed_plan_equals_cli(client: httpx.Client, server: Server, tmp_path: Path) -> None:
    occupied_start = (5.1, 2.0, 0.0)  # inside the wall
    response = client.post("/v1/plan", json=plan_body(start=occupied_start))
    assert response.status_code == 422
    body = response.json()
    assert body["status"] == "failed" and body["error_code"] == 205 and "collision" in body["error_msg"]
    code, cli = cli_plan(server, tmp_path, occupied_start, HALL_GOAL)
    assert code == 2
    assert strip_timing(body) == strip_timing(cli)


def test_robot_and_options_are_used(client: httpx.Client, server: Server, tmp_path: Path) -> None:
    body = plan_body(robot="zju-80", options={"greed": 1.0})
    response = client.post("/v1/plan", json=body)
    assert response.status_code == 200, response.text
    result = response.json()
    assert result["robot"]["name"] == "zju-80"
    code, cli = cli_plan(server, tmp_path, HALL_START, HALL_GOAL, "--robot", "zju-80", "--options", '{"greed": 1.0}')
    assert code == 0
    assert strip_timing(result) == strip_timing(cli)


def test_inline_grid_plans_like_the_named_map(client: httpx.Client) -> None:
    grid = harness.hall_grid()
    inline = {"data": grid.data.tolist(), "resolution_m": grid.resolution_m, "origin": list(grid.origin),
              "name": "hall"}
    named = client.post("/v1/plan", json=plan_body())
    sent = client.post("/v1/plan", json={**plan_body(), "map": inline})
    assert named.status_code == sent.status_code == 200, sent.text
    assert strip_timing(named.json()) == strip_timing(sent.json())


def test_simulate_equals_cli(client: httpx.Client, server: Server, tmp_path: Path) -> None:
    plan = client.post("/v1/plan", json=plan_body()).json()
    response = client.post("/v1/simulate", json={"map": "hall", "path": plan, "seed": 3})
    assert response.status_code == 200, response.text
    sim = response.json()
    assert sim["metrics"]["reached_goal"] and not sim["metrics"]["collided"]
    (tmp_path / "plan.json").write_text(json.dumps(plan))
    out = tmp_path / "sim.json"
    assert cli_main(["simulate", "--map", str(server.maps_dir / "hall.yaml"), "--path", str(tmp_path / "plan.json"),
                     "--seed", "3", "--out", str(out)]) == 0
    assert strip_sim_timing(sim) == strip_sim_timing(json.loads(out.read_text()))


def test_bad_simulate_requests(client: httpx.Client) -> None:
    plan = client.post("/v1/plan", json=plan_body()).json()
    cases: list[tuple[dict[str, Any], int, str]] = [
        ({"map": "hall", "path": {**plan, "states": plan["states"][:1]}}, 422, "path.states"),
        ({"map": "hall", "path": {**plan, "robot": {"name": "../robots/x"}}}, 422, "path.robot.name"),
        ({"map": "hall", "path": {**plan, "robot": {"name": "wheelie"}}}, 404, "path.robot.name"),
        ({"map": "hall", "path": plan, "tracker": "lqr"}, 422, "tracker"),
        ({"map": "hall", "path": plan, "seed": -1}, 422, "seed"),
        ({"map": "nowhere", "path": plan}, 404, "map"),
    ]
    for body, status, field in cases:
        response = client.post("/v1/simulate", json=body)
        assert response.status_code == status, (field, response.text)
        assert response.json()["field"] == field
    nan = json.dumps({"map": "hall", "path": plan}).replace(str(plan["states"][3]["x"]), "NaN", 1)
    response = client.post("/v1/simulate", content=nan, headers={"content-type": "application/json"})
    assert response.status_code == 422 and response.json()["field"] == "path.states[3].x"


def test_tensegrity_static_equals_cli(client: httpx.Client, tmp_path: Path) -> None:
    response = client.post("/v1/tensegrity/static", json={"theta1": 30, "theta2": 60, "degrees": True})
    assert response.status_code == 200, response.text
    out = tmp_path / "static.json"
    assert cli_main(["tensegrity", "static", "--theta1", "30", "--theta2", "60", "--degrees", "--out", str(out)]) == 0
    assert response.json() == json.loads(out.read_text())
    bad = client.post("/v1/tensegrity/static", json={"theta1": "30", "theta2": 0.6})
    assert bad.status_code == 422 and bad.json()["field"] == "theta1"
    unknown = client.post("/v1/tensegrity/static", json={"theta1": 0.1, "theta2": 0.2, "robot": "nobody"})
    assert unknown.status_code == 404


RECONFIGURE = {"start": [2.0, 2.0], "start_tilt": [30.0, 75.0], "goal": [3.5, 3.0], "degrees": True, "map": "hall"}


def test_reconfigure_equals_cli(client: httpx.Client, server: Server, tmp_path: Path) -> None:
    response = client.post("/v1/reconfigure", json=RECONFIGURE)
    assert response.status_code == 200, response.text
    out = tmp_path / "reconf.json"
    assert cli_main(["reconfigure", "--start", "2", "2", "--start-tilt", "30", "75", "--goal", "3.5", "3",
                     "--degrees", "--map", str(server.maps_dir / "hall.yaml"), "--out", str(out)]) == 0
    assert strip_timing(response.json()) == strip_timing(json.loads(out.read_text()))
    occupied = client.post("/v1/reconfigure", json={**RECONFIGURE, "goal": [5.1, 2.0]})
    assert occupied.status_code == 422 and occupied.json()["error_code"] == 206
    assert occupied.json()["status"] == "failed"
    bad = client.post("/v1/reconfigure", json={**RECONFIGURE, "start_tilt": [30.0]})
    assert bad.status_code == 422 and bad.json()["field"] == "start_tilt"
    assert client.post("/v1/reconfigure", json={**RECONFIGURE, "method": "spiral"}).json()["field"] == "method"


def test_vpip_rods_and_schedule_equal_cli(client: httpx.Client, tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    rods = client.post("/v1/vpip/rods", json={"phi_vpip": 5, "theta_vpip": 10, "roll": 2, "degrees": True})
    assert rods.status_code == 200, rods.text
    capsys.readouterr()
    assert cli_main(["vpip", "rods", "--phi-vpip", "5", "--theta-vpip", "10", "--roll", "2", "--degrees"]) == 0
    assert rods.json() == json.loads(capsys.readouterr().out)
    assert client.post("/v1/vpip/rods", json={"phi_vpip": 0.1, "theta_vpip": 0.1, "robot": "nobody"}).status_code == 404

    plan = client.post("/v1/plan", json=plan_body(robot="daedalus")).json()
    schedule = client.post("/v1/vpip/schedule", json={"path": plan})
    assert schedule.status_code == 200, schedule.text[:300]
    (tmp_path / "plan.json").write_text(json.dumps(plan))
    out = tmp_path / "schedule.json"
    assert cli_main(["vpip", "schedule", "--path", str(tmp_path / "plan.json"), "--out", str(out)]) == 0
    assert schedule.json() == json.loads(out.read_text())
    no_rods = client.post("/v1/vpip/schedule", json={"path": plan, "robot": "zju-60"})
    assert no_rods.status_code == 422 and no_rods.json()["field"] == "robot"


def _huge_grid() -> dict[str, Any]:
    """A nav_msgs/OccupancyGrid of 2001 × 2000 cells: one row more than the 4 M cells a request may carry."""
    cells = base64.b64encode(gzip.compress(bytes(2001 * 2000))).decode()
    return {"info": {"resolution": 0.05, "width": 2001, "height": 2000, "origin": {"position": {"x": 0.0, "y": 0.0}}},
            "data_gzip_b64": cells}


BAD_REQUESTS: list[tuple[str, Any, int, str | None, int]] = [
    # (case, body (dict → JSON; bytes → raw), HTTP status, field named, Nav2 code)
    ("malformed JSON", b'{"map": "hall",', 400, "body", 200),
    ("not an object", [1, 2], 422, "body", 200),
    ("missing goal", {k: v for k, v in plan_body().items() if k != "goal"}, 422, "goal", 200),
    ("unknown field", {**plan_body(), "colour": "red"}, 422, "colour", 200),
    ("string number", plan_body(start=("2", 2.0, 0.0)), 422, "start.x", 200),  # type: ignore[arg-type]
    ("bool number", plan_body(start=(True, 2.0, 0.0)), 422, "start.x", 200),
    ("NaN", b'{"map":"hall","start":{"x":NaN,"y":2,"yaw":0},"goal":{"x":8,"y":2,"yaw":0}}', 422, "start.x", 200),
    ("Infinity", b'{"map":"hall","start":{"x":2,"y":2,"yaw":0},"goal":{"x":Infinity,"y":2,"yaw":0}}', 422,
     "goal.x", 200),
    ("huge number", b'{"map":"hall","start":{"x":1e999,"y":2,"yaw":0},"goal":{"x":8,"y":2,"yaw":0}}', 422,
     "start.x", 200),
    ("negative time limit", plan_body(time_limit_s=-1.0), 422, "time_limit_s", 200),
    ("zero time limit", plan_body(time_limit_s=0), 422, "time_limit_s", 200),
    ("time limit over the server's", plan_body(time_limit_s=30.0), 422, "time_limit_s", 200),
    ("bad option", plan_body(options={"n_rolls": 4}), 422, "options.n_rolls", 200),
    ("unknown option", plan_body(options={"speed": 1}), 422, "options.speed", 200),
    ("map path", {**plan_body(), "map": "../maps/hall"}, 422, "map", 200),
    ("map dot-dot", {**plan_body(), "map": ".."}, 422, "map", 200),
    ("absolute map path", {**plan_body(), "map": "/etc/passwd"}, 422, "map", 200),
    ("map file name", {**plan_body(), "map": "hall.yaml"}, 404, "map", 200),
    ("unknown map", {**plan_body(), "map": "nowhere"}, 404, "map", 200),
    ("unknown robot", plan_body(robot="wheelie"), 404, "robot", 200),
    ("robot path", plan_body(robot="/etc/passwd"), 422, "robot", 200),
    ("ragged inline grid", {**plan_body(), "map": {"data": [[0, 0], [0]], "resolution_m": 0.1}}, 422, "map", 200),
    ("inline value", {**plan_body(), "map": {"data": [[0, 101]], "resolution_m": 0.1}}, 422, "map.data[0][1]", 200),
    ("inline too big", {**plan_body(), "map": _huge_grid()}, 422, "map", 200),
    ("start outside", plan_body(start=(-3.0, 2.0, 0.0)), 422, None, 203),
    ("goal outside", plan_body(goal=(80.0, 2.0, 0.0)), 422, None, 204),
    ("start occupied", plan_body(start=(5.1, 2.0, 0.0)), 422, None, 205),
    ("goal occupied", plan_body(goal=(0.05, 0.05, 0.0)), 422, None, 206),
]


@pytest.mark.parametrize(("case", "body", "status", "field", "code"), BAD_REQUESTS, ids=[c[0] for c in BAD_REQUESTS])
def test_bad_input_gets_its_4xx(client: httpx.Client, case: str, body: Any, status: int, field: str | None,
                                code: int) -> None:
    if isinstance(body, bytes):
        response = client.post("/v1/plan", content=body, headers={"content-type": "application/json"})
    else:
        response = client.post("/v1/plan", json=body)
    assert response.status_code == status, response.text
    error = response.json()
    assert error["error_code"] == code
    assert isinstance(error["error_msg"], str) and error["error_msg"]
    if field is not None:
        assert error["field"] == field, error
    assert client.get("/healthz").status_code == 200


def test_body_over_the_limit_is_413(client: httpx.Client) -> None:
    big = b" " * 4_100_000
    declared = client.post("/v1/plan", content=big, headers={"content-type": "application/json"})
    assert declared.status_code == 413 and declared.json()["field"] == "body"

    def chunks() -> Iterator[bytes]:  # no Content-Length: counted while streaming
        for _ in range(5):
            yield b" " * 1_000_000

    streamed = client.post("/v1/plan", content=chunks(), headers={"content-type": "application/json"})
    assert streamed.status_code == 413
    assert client.get("/healthz").status_code == 200


def test_non_json_content_type_is_415(client: httpx.Client) -> None:
    response = client.post("/v1/plan", content=json.dumps(plan_body()), headers={"content-type": "text/plain"})
    assert response.status_code == 415 and response.json()["field"] == "content-type"


def test_unknown_route_and_method_are_json_errors(client: httpx.Client) -> None:
    missing = client.get("/v1/nothing")
    assert missing.status_code == 404 and missing.json()["error_code"] == 200
    wrong_method = client.get("/v1/plan")
    assert wrong_method.status_code == 405 and wrong_method.json()["error_msg"]


def test_maps_robots_and_health(client: httpx.Client) -> None:
    maps = client.get("/v1/maps").json()
    assert [m["name"] for m in maps] == ["hall"]
    info = client.get("/v1/maps/hall").json()
    assert (info["width"], info["height"], info["resolution_m"]) == (100, 80, 0.1)
    assert 0 < info["occupied_fraction"] < 1
    png = client.get("/v1/maps/hall.png")
    assert png.status_code == 200 and png.headers["content-type"] == "image/png"
    with Image.open(io.BytesIO(png.content)) as image:
        assert image.size == (100, 80)
        pixels = np.asarray(image)
        assert pixels[79, 51] == 0 and pixels[40, 20] == 254  # the wall (bottom rows) and free floor
    assert client.get("/v1/maps/nowhere").status_code == 404
    assert client.get("/v1/maps/nowhere.png").status_code == 404
    assert client.get("/v1/maps/..%2F..%2Fetc%2Fpasswd").status_code in (404, 422)
    assert client.get("/v1/maps/.hidden").status_code == 422
    robots = {r["name"] for r in client.get("/v1/robots").json()}
    assert {"zju-60", "zju-80", "daedalus"} <= robots
    assert client.get("/healthz").json()["status"] == "ok"
    assert client.get("/readyz").status_code == 200
    assert "/v1/plan" in client.get("/openapi.json").json()["paths"]
    assert client.get("/docs").status_code == 200


def test_twenty_concurrent_plans_while_healthz_answers(server: Server) -> None:
    goals = [(8.0, 2.0 + 0.1 * (i % 5), 0.0) for i in range(20)]

    async def run() -> tuple[list[httpx.Response], list[dict[str, Any]]]:
        async with httpx.AsyncClient(base_url=server.url, timeout=120) as client:
            plans = [asyncio.create_task(client.post("/v1/plan", json=plan_body(goal=g))) for g in goals]
            health: list[dict[str, Any]] = []
            while not all(p.done() for p in plans):
                reply = await client.get("/healthz")
                assert reply.status_code == 200
                health.append(reply.json())
                await asyncio.sleep(0.02)
            return [p.result() for p in plans], health

    responses, health = asyncio.run(run())
    assert [r.status_code for r in responses] == [200] * 20, [r.text[:200] for r in responses]
    assert all(r.json()["status"] == "exact" for r in responses)
    # /healthz kept answering while plans were queued or running in the pool
    assert any(h["in_flight"] > 0 for h in health)


def test_full_pool_gives_503_and_recovers(client: httpx.Client, server: Server) -> None:
    slow = plan_body(goal=SLOT_GOAL, options=SLOW, time_limit_s=0.3)  # times out: holds a job for 0.3 s

    async def burst() -> list[httpx.Response]:
        async with httpx.AsyncClient(base_url=server.url, timeout=120) as c:
            return list(await asyncio.gather(*(c.post("/v1/plan", json=slow) for _ in range(40))))

    responses = asyncio.run(burst())
    statuses = [r.status_code for r in responses]
    assert set(statuses) <= {422, 503}, statuses
    busy = [r for r in responses if r.status_code == 503]
    assert busy, "24 jobs in flight at most: 40 at once must overflow"
    assert all(int(r.headers["retry-after"]) >= 1 and r.json()["error_code"] == 200 for r in busy)
    assert all(r.json()["error_code"] == 207 for r in responses if r.status_code == 422)
    assert client.get("/healthz").json()["in_flight"] == 0
    assert client.post("/v1/plan", json=plan_body()).status_code == 200


# per operation and mode: bounded so the suite stays quick (raise it for a deeper run)
FUZZ_EXAMPLES = int(os.environ.get("SPHEREPLAN_FUZZ_EXAMPLES", "12"))
# per request: schemathesis's default (10 s) is a latency check in disguise, and a shared CI box can be 5x
# slower than an idle one; what this test checks is the answer (no 5xx, documented shape), not the speed
FUZZ_REQUEST_TIMEOUT_S = float(os.environ.get("SPHEREPLAN_FUZZ_TIMEOUT_S", "120"))


@pytest.mark.parametrize("mode", [GenerationMode.POSITIVE, GenerationMode.NEGATIVE])
def test_openapi_fuzz_finds_no_server_error(server: Server, mode: GenerationMode) -> None:
    """schemathesis over /openapi.json: no 5xx, statuses/content types/bodies as documented."""
    api = schemathesis.openapi.from_url(server.url + "/openapi.json")
    operations = [result.ok() for result in api.get_all_operations()]  # type: ignore[union-attr]
    assert len(operations) >= 7
    for operation in operations:
        if mode == GenerationMode.NEGATIVE and not (len(operation.body) or len(operation.path_parameters)):
            continue  # nothing to make invalid

        @given(case=operation.as_strategy(generation_mode=mode))
        @settings(max_examples=FUZZ_EXAMPLES, deadline=None, derandomize=True, database=None,
                  suppress_health_check=list(HealthCheck), phases=[Phase.explicit, Phase.generate])
        def check(case: Any) -> None:
            # a generous timeout: a valid tensegrity/static takes ~12 s on a loaded 2-core machine
            case.call_and_validate(checks=[not_a_server_error, status_code_conformance, content_type_conformance,
                                           response_schema_conformance], timeout=FUZZ_REQUEST_TIMEOUT_S)

        check()
