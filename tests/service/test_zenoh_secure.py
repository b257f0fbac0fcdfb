"""The shipped multi-host Zenoh configuration (deploy/zenoh/service.json5) run for real on loopback: TLS,
user/password authentication and the access-control list (issue 12, row 11). Only file locations, the
listen address and the service's password are replaced; every rule is the shipped one."""

from __future__ import annotations

import json
import shutil
import subprocess
import threading
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest
import zenoh

from service.core import PlanningService
from service.settings import ServiceSettings
from service.zenoh_node import ZenohNode
from tests.service import service_harness as harness
from tests.service.service_harness import HALL_GOAL, HALL_START, plan_body

pytestmark = pytest.mark.faults

REPO = Path(__file__).resolve().parents[2]
SHIPPED = REPO / "deploy" / "zenoh" / "service.json5"
USERS = {"sphereplan": "service-password-1", "r1": "r1-password-0001", "operator": "operator-password-1",
         "mallory": "mallory-password-1"}


def make_certificates(folder: Path) -> dict[str, Path]:
    """A throw-away CA and a certificate for localhost / 127.0.0.1 signed by it."""
    if shutil.which("openssl") is None:
        pytest.skip("openssl is needed to make the test certificates")
    files = {name: folder / name for name in ("ca.key", "ca.pem", "server.key", "server.csr", "server.pem", "ext")}
    files["ext"].write_text("subjectAltName=DNS:localhost,IP:127.0.0.1\n")

    def openssl(*args: str) -> None:
        subprocess.run(["openssl", *args], check=True, capture_output=True, timeout=60)

    openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", str(files["ca.key"]), "-out",
            str(files["ca.pem"]), "-days", "2", "-subj", "/CN=sphereplan-test-ca")
    openssl("req", "-newkey", "rsa:2048", "-nodes", "-keyout", str(files["server.key"]), "-out",
            str(files["server.csr"]), "-subj", "/CN=localhost")
    openssl("x509", "-req", "-in", str(files["server.csr"]), "-CA", str(files["ca.pem"]), "-CAkey",
            str(files["ca.key"]), "-CAcreateserial", "-out", str(files["server.pem"]), "-days", "2",
            "-extfile", str(files["ext"]))
    return files


@pytest.fixture(scope="module")
def secure(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    tmp = tmp_path_factory.mktemp("secure")
    certs = make_certificates(tmp)
    users = tmp / "users.txt"
    users.write_text("".join(f"{user}:{password}\n" for user, password in USERS.items()))
    endpoint = f"tls/127.0.0.1:{harness.free_port()}"
    config = zenoh.Config.from_file(str(SHIPPED))
    config.insert_json5("listen/endpoints", json.dumps([endpoint]))
    config.insert_json5("transport/link/tls/listen_certificate", json.dumps(str(certs["server.pem"])))
    config.insert_json5("transport/link/tls/listen_private_key", json.dumps(str(certs["server.key"])))
    config.insert_json5("transport/link/tls/root_ca_certificate", json.dumps(str(certs["ca.pem"])))
    config.insert_json5("transport/auth/usrpwd/dictionary_file", json.dumps(str(users)))
    config.insert_json5("transport/auth/usrpwd/password", json.dumps(USERS["sphereplan"]))
    service = PlanningService(ServiceSettings(maps_dir=harness.make_maps(tmp / "maps"), zenoh=False,
                                              warm_up=False), ThreadPoolExecutor)
    service.start()
    node = ZenohNode(service, config=config)
    node.start()
    yield {"endpoint": endpoint.replace("127.0.0.1", "localhost"), "ca": certs["ca.pem"]}
    node.close()
    service.close()


def open_client(secure: dict[str, Any], user: str | None, password: str | None = None) -> zenoh.Session:
    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([secure["endpoint"]]))
    conf.insert_json5("scouting/multicast/enabled", "false")
    conf.insert_json5("transport/link/tls/root_ca_certificate", json.dumps(str(secure["ca"])))
    if user is not None:
        conf.insert_json5("transport/auth/usrpwd", json.dumps({"user": user, "password": password or USERS[user]}))
    return zenoh.open(conf)


def test_a_peer_without_valid_credentials_cannot_connect(secure: dict[str, Any]) -> None:
    for user, password in ((None, None), ("r1", "wrong-password-1"), ("nobody", "no-such-user-1")):
        with pytest.raises(zenoh.ZError):
            open_client(secure, user, password)
    plain = zenoh.Config()  # nor without TLS
    plain.insert_json5("mode", '"client"')
    plain.insert_json5("connect/endpoints", json.dumps([secure["endpoint"].replace("tls/", "tcp/")]))
    plain.insert_json5("scouting/multicast/enabled", "false")
    with pytest.raises(zenoh.ZError):
        zenoh.open(plain)


def test_only_operators_may_query(secure: dict[str, Any]) -> None:
    with open_client(secure, "operator") as operator:
        replies = list(operator.get("sphereplan/plan", payload=json.dumps(plan_body()).encode(), timeout=60))
    assert len(replies) == 1 and replies[0].ok is not None
    assert json.loads(replies[0].ok.payload.to_bytes())["status"] == "exact"
    for user in ("r1", "mallory"):
        with open_client(secure, user) as other:
            denied = list(other.get("sphereplan/plan", payload=json.dumps(plan_body()).encode(), timeout=3))
        assert not [r for r in denied if r.ok is not None]


def test_a_forged_pose_or_path_does_not_get_through(secure: dict[str, Any]) -> None:
    received: list[tuple[str, Any]] = []
    arrived = threading.Condition()

    def on_sample(sample: zenoh.Sample) -> None:
        with arrived:
            received.append((str(sample.key_expr), sample.payload.to_string()))
            arrived.notify_all()

    def wait_for(predicate: Any, timeout_s: float = 60) -> None:
        end = time.monotonic() + timeout_s
        with arrived:
            while not predicate() and time.monotonic() < end:
                arrived.wait(timeout=0.1)

    def pose(x: float, y: float, yaw: float) -> bytes:
        return json.dumps({"x": x, "y": y, "yaw": yaw}).encode()

    with open_client(secure, "r1") as robot, open_client(secure, "mallory") as mallory:
        subscribers = [robot.declare_subscriber("sphereplan/r1/path", on_sample),
                       robot.declare_subscriber("sphereplan/r1/status", on_sample)]
        time.sleep(0.5)  # let the subscriptions reach the router
        robot.put("sphereplan/r1/pose", pose(*HALL_START))
        mallory.put("sphereplan/r1/pose", pose(8.0, 6.0, 3.0))  # forged: would be planned from if let through
        mallory.put("sphereplan/r1/path", b'{"forged": true}')
        mallory.put("sphereplan/r1/goal", json.dumps({"map": "hall", "goal": {"x": 2.0, "y": 6.0, "yaw": 0.0}}))
        time.sleep(0.5)
        robot.put("sphereplan/r1/goal", json.dumps({"map": "hall", "goal": dict(zip(("x", "y", "yaw"), HALL_GOAL,
                                                                                    strict=True))}))
        wait_for(lambda: any(k.endswith("/status") and '"succeeded"' in p for k, p in received))
        for subscriber in subscribers:
            subscriber.undeclare()
    paths = [json.loads(p) for k, p in received if k.endswith("/path")]
    assert len(paths) == 1 and "forged" not in paths[0], paths
    first, last = paths[0]["states"][0], paths[0]["states"][-1]
    assert (round(first["x"], 3), round(first["y"], 3)) == HALL_START[:2]  # r1's own pose, not the forged one
    assert abs(last["x"] - HALL_GOAL[0]) < 0.15 and abs(last["y"] - HALL_GOAL[1]) < 0.15
    statuses = [json.loads(p) for k, p in received if k.endswith("/status")]
    assert [s["goal_id"] for s in statuses if s["state"] == "succeeded"] == [1]  # mallory's goal never counted


# ------------------------------------------------------------------------------------ issue 25: a fleet

ROUTER = REPO / "deploy" / "zenoh" / "router.json5"
INSTANCE = REPO / "deploy" / "zenoh" / "instance.json5"
FLEET_USERS = {**USERS, "router": "router-password-01", "sphereplan-1": "instance-1-password",
               "sphereplan-2": "instance-2-password"}


@pytest.fixture(scope="module")
def secure_fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """The shipped router.json5 (TLS, user/password, ACL) as a Python router, and two instances connected with
    the shipped instance.json5 (own users; robots partitioned: r1 on the first, r2 on the second)."""
    tmp = tmp_path_factory.mktemp("secure-fleet")
    certs = make_certificates(tmp)
    users = tmp / "users.txt"
    users.write_text("".join(f"{user}:{password}\n" for user, password in FLEET_USERS.items()))
    endpoint = f"tls/127.0.0.1:{harness.free_port()}"
    config = zenoh.Config.from_file(str(ROUTER))
    config.insert_json5("listen/endpoints", json.dumps([endpoint]))
    config.insert_json5("transport/link/tls/listen_certificate", json.dumps(str(certs["server.pem"])))
    config.insert_json5("transport/link/tls/listen_private_key", json.dumps(str(certs["server.key"])))
    config.insert_json5("transport/link/tls/root_ca_certificate", json.dumps(str(certs["ca.pem"])))
    config.insert_json5("transport/auth/usrpwd/dictionary_file", json.dumps(str(users)))
    config.insert_json5("transport/auth/usrpwd/password", json.dumps(FLEET_USERS["router"]))
    router = zenoh.open(config)
    maps_dir = harness.make_maps(tmp / "maps")
    started = []
    for index, robots in ((1, ("r1",)), (2, ("r2",))):
        conf = zenoh.Config.from_file(str(INSTANCE))
        conf.insert_json5("connect/endpoints", json.dumps([endpoint.replace("127.0.0.1", "localhost")]))
        conf.insert_json5("transport/link/tls/root_ca_certificate", json.dumps(str(certs["ca.pem"])))
        conf.insert_json5("transport/auth/usrpwd/user", json.dumps(f"sphereplan-{index}"))
        conf.insert_json5("transport/auth/usrpwd/password", json.dumps(FLEET_USERS[f"sphereplan-{index}"]))
        conf.insert_json5("transport/auth/usrpwd/dictionary_file", json.dumps(str(users)))
        service = PlanningService(ServiceSettings(maps_dir=maps_dir, zenoh=False, warm_up=False, zenoh_robots=robots),
                                  ThreadPoolExecutor)
        service.start()
        node = ZenohNode(service, config=conf)
        node.start()
        started.append((service, node))
    yield {"endpoint": endpoint.replace("127.0.0.1", "localhost"), "ca": certs["ca.pem"]}
    for service, node in started:
        node.close()
        service.close()
    router.close()


def test_the_shipped_fleet_router_answers_each_query_once_and_plans_each_goal_once(
        secure_fleet: dict[str, Any]) -> None:
    received: list[str] = []
    arrived = threading.Condition()

    def on_sample(sample: zenoh.Sample) -> None:
        with arrived:
            received.append(str(sample.key_expr))
            arrived.notify_all()

    with open_client(secure_fleet, "operator") as operator:
        time.sleep(1.0)  # both instances' queryables reach the router
        for _ in range(5):
            replies = list(operator.get("sphereplan/plan", payload=json.dumps(plan_body()).encode(), timeout=60,
                                        consolidation=zenoh.ConsolidationMode.NONE))
            assert len(replies) == 1 and replies[0].ok is not None, replies
    with open_client(secure_fleet, "mallory") as mallory:
        denied = list(mallory.get("sphereplan/plan", payload=json.dumps(plan_body()).encode(), timeout=3))
        assert not [r for r in denied if r.ok is not None]
    with open_client(secure_fleet, "r1") as robot:
        subscribers = [robot.declare_subscriber(f"sphereplan/r1/{topic}", on_sample) for topic in ("path", "status")]
        time.sleep(0.5)
        robot.put("sphereplan/r1/pose", json.dumps(dict(zip(("x", "y", "yaw"), HALL_START, strict=True))))
        robot.put("sphereplan/r1/goal", json.dumps({"map": "hall", "goal": dict(zip(("x", "y", "yaw"), HALL_GOAL,
                                                                                    strict=True))}))
        end = time.monotonic() + 120
        with arrived:
            while "sphereplan/r1/path" not in received and time.monotonic() < end:
                arrived.wait(timeout=0.1)
        time.sleep(2.0)  # a second instance's (wrong) path would arrive meanwhile
        for subscriber in subscribers:
            subscriber.undeclare()
    assert received.count("sphereplan/r1/path") == 1, received
