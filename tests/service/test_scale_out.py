"""Two instances serving one fleet (issue 25, findings 5 and 6), on the real engines: HAProxy (Debian package) in
front of two HTTP instances with the shipped ``deploy/haproxy/sphereplan.cfg``; a Zenoh router as a Python
process (``service.zenoh_router``) with two token-protected instances behind it. Robust on a slow, busy machine:
generous timeouts, polling, and no timing assertions.
"""

from __future__ import annotations

import asyncio
import shutil
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from lab.fleet import Fleet, Process
from tests.service import service_harness as harness
from tests.service.service_harness import HALL_START, plan_body

pytestmark = pytest.mark.faults

TOKEN = "fleet-token-for-tests-0001"
BEARER = f"Bearer {TOKEN}"
WAIT_S = 300.0


class _Endpoint:
    """What ``zenoh_steps`` needs of a server: the endpoint its client connects to."""

    def __init__(self, endpoint: str) -> None:
        self.zenoh_endpoint = endpoint


@pytest.fixture(scope="module")
def zenoh_fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Fleet, str, list[Process]]]:
    folder = tmp_path_factory.mktemp("zenoh-fleet")
    maps_dir = harness.make_maps(folder / "maps")
    fleet = Fleet(folder, token=TOKEN)
    try:
        router, endpoint = fleet.router()
        fleet.wait_log(router, "listening")
        config = {"mode": "peer", "connect": {"endpoints": [endpoint]}, "listen": {"endpoints": []},
                  "scouting": {"multicast": {"enabled": False}}}
        # robots partitioned by id: a* on the first instance, b* on the second
        # Zenoh sends each query to one complete queryable (the nearest), not round-robin: room for all 100
        instances = [fleet.instance(f"z{i}", maps_dir, zenoh_config=config,
                                    extra=("--robots", robots, "--max-in-flight", "120"))
                     for i, robots in enumerate(("a$*", "b$*"))]
        for instance in instances:
            fleet.wait_ready(instance)
        yield fleet, endpoint, instances
    finally:
        fleet.close()


def _steps(endpoint: str, steps: list[dict[str, Any]], timeout_s: float = WAIT_S) -> list[dict[str, Any]]:
    return harness.zenoh_steps(_Endpoint(endpoint), steps, timeout_s)  # type: ignore[arg-type]


def test_a_plan_query_is_answered_exactly_once_by_two_instances(zenoh_fleet: tuple[Fleet, str, list[Process]]
                                                                ) -> None:
    _, endpoint, _ = zenoh_fleet
    queries = [{"query": "sphereplan/plan", "payload": plan_body(goal=(8.0, 1.5 + 0.01 * i, 0.0)),
                "attachment": BEARER, "consolidation": "none", "timeout_s": 240} for i in range(100)]
    answer = _steps(endpoint, [{"sleep": 1.0}, {"queries": queries}])[1]
    counts = Counter(len(replies) for replies in answer["all_replies"])
    assert counts == {1: 100}, counts  # no query unanswered, none answered twice
    assert all(replies[0]["ok"] and replies[0]["payload"]["status"] == "exact" for replies in answer["all_replies"])


def test_zenoh_without_the_token_gets_nothing_planned(zenoh_fleet: tuple[Fleet, str, list[Process]]) -> None:
    """Finding 5: the Zenoh door ignored --token-file."""
    _, endpoint, instances = zenoh_fleet
    pose = dict(zip(("x", "y", "yaw"), HALL_START, strict=True))
    answers = _steps(endpoint, [
        {"subscribe": "sphereplan/*/*"},
        {"sleep": 1.0},
        {"query": "sphereplan/plan", "payload": plan_body(), "consolidation": "none"},
        {"query": "sphereplan/plan", "payload": plan_body(), "attachment": "Bearer wrong-token-000000000",
         "consolidation": "none"},
        {"put": "sphereplan/a-stranger/pose", "payload": pose},
        {"put": "sphereplan/a-stranger/goal", "payload": {"map": "hall", "goal": {"x": 8.0, "y": 2.0, "yaw": 0.0}}},
        {"put": "sphereplan/a-stranger/pose", "payload": pose, "attachment": "Bearer wrong-token-000000000"},
        {"put": "sphereplan/a-stranger/goal", "payload": {"map": "hall", "goal": {"x": 8.0, "y": 2.0, "yaw": 0.0}},
         "attachment": "Bearer wrong-token-000000000"},
        {"sleep": 3.0},
        {"wait": "/status", "until": {"never": True}, "timeout_s": 0},
    ])
    for index in (2, 3):
        (reply,) = answers[index]["replies"]
        assert not reply["ok"] and reply["payload"]["field"] == "attachment", reply
    published = [s for s in answers[-1]["samples"] if s["key"].endswith(("/path", "/status"))]
    assert not published, published  # nothing planned, nothing published for the stranger
    assert "without a valid token" in instances[0].log_path.read_text()  # robots a* are the first instance's


def test_each_goal_is_planned_by_exactly_one_instance(zenoh_fleet: tuple[Fleet, str, list[Process]]) -> None:
    _, endpoint, instances = zenoh_fleet
    robots = [f"{side}{i}" for side in "ab" for i in range(50)]
    pose = dict(zip(("x", "y", "yaw"), HALL_START, strict=True))
    steps: list[dict[str, Any]] = [{"subscribe": "sphereplan/*/*"}, {"sleep": 1.0}]
    for i, robot in enumerate(robots):
        steps.append({"put": f"sphereplan/{robot}/pose", "payload": pose, "attachment": BEARER})
        steps.append({"put": f"sphereplan/{robot}/goal", "attachment": BEARER,
                      "payload": {"map": "hall", "goal": {"x": 8.0, "y": 1.5 + 0.01 * i, "yaw": 0.0}}})
    # every robot's own success (goals of one instance may finish out of order on a busy machine); a wait returns
    # at once when its sample has already arrived
    # one shared deadline (not 240 s per robot): a lost status ends in the assertion below, naming the robots
    steps.append({"wait_all": [f"/{robot}/status" for robot in robots], "until": {"state": "succeeded"},
                  "timeout_s": 400})
    steps.append({"sleep": 3.0})  # a second instance's (wrong) path would arrive meanwhile
    steps.append({"wait": "/status", "until": {"never": True}, "timeout_s": 0})
    samples = _steps(endpoint, steps, timeout_s=600)[-1]["samples"]
    paths = Counter(s["key"].split("/")[1] for s in samples if s["key"].endswith("/path"))
    succeeded = Counter(s["key"].split("/")[1] for s in samples
                        if s["key"].endswith("/status") and s["payload"]["state"] == "succeeded")
    assert paths == Counter(robots) and succeeded == Counter(robots), (paths, succeeded)
    planning = Counter(s["key"].split("/")[1] for s in samples
                       if s["key"].endswith("/status") and s["payload"]["state"] == "planning")
    assert planning == Counter(robots), planning


# ------------------------------------------------------------------------------------------------ HTTP


@pytest.mark.skipif(shutil.which("haproxy") is None and not Path("/usr/sbin/haproxy").exists(),
                    reason="haproxy is not installed (.ci/run installs the Debian package)")
def test_http_behind_haproxy_loses_no_accepted_request_when_an_instance_is_killed(tmp_path: Path) -> None:
    maps_dir = harness.make_maps(tmp_path / "maps")
    fleet = Fleet(tmp_path, token=TOKEN)
    try:
        instances = [fleet.instance(f"h{i}", maps_dir) for i in range(2)]
        for instance in instances:
            fleet.wait_ready(instance)
        balancer = fleet.haproxy(instances)
        fleet.wait_ready(balancer)  # /readyz through HAProxy: at least one instance is up
        auth = {"authorization": BEARER}

        async def run() -> list[int]:
            async with httpx.AsyncClient(base_url=balancer.url, timeout=WAIT_S, headers=auth) as c:
                done = 0

                async def client(k: int) -> list[int]:
                    nonlocal done
                    statuses = []
                    for i in range(15):
                        body = plan_body(goal=(8.0, 1.5 + 0.01 * (15 * k + i), 0.0))
                        statuses.append((await c.post("/v1/plan", json=body)).status_code)
                        done += 1
                    return statuses

                clients = [asyncio.create_task(client(k)) for k in range(4)]
                while done < 12:
                    await asyncio.sleep(0.05)
                instances[0].kill()  # an instance lost in the middle of the run, with requests on it
                return [s for statuses in await asyncio.gather(*clients) for s in statuses]

        statuses = asyncio.run(run())
        assert not instances[0].alive() and instances[1].alive()
        assert Counter(statuses) == {200: 60}, Counter(statuses)
        # the token is checked behind the balancer too
        assert httpx.post(balancer.url + "/v1/plan", json=plan_body(), timeout=60).status_code == 401
    finally:
        fleet.close()
