"""Zenoh door of robot sessions: topics ``sphereplan/<robot_id>/live/*`` over :class:`service.sessions.SessionStore`.

A robot (or its perception, issue 23) publishes, all JSON:

* ``sphereplan/<robot_id>/live/session`` — a :class:`~service.wire_live.SessionCreate` (without ``id``): starts
  (or restarts) the robot's session on a map or an unknown area;
* ``sphereplan/<robot_id>/live/pose`` — a :class:`~service.wire.PoseIn` (odometry, map frame);
* ``sphereplan/<robot_id>/live/goal`` — a :class:`~service.wire.PoseIn`: planned from the latest pose;
* ``sphereplan/<robot_id>/live/observations`` — a :class:`~service.wire_live.ObservationIn` (points + sensor
  origin, a scan, or a region).

The service publishes ``sphereplan/<robot_id>/live/path`` (the plan-result JSON of every successful replan) and
``sphereplan/<robot_id>/live/status`` (``{robot_id, state, replan, status}`` after every replan, with
``state: "replanned"`` or ``"failed"``, or ``{robot_id, state: "invalid", topic, error_code, error_msg,
field}`` when a message is refused). Messages are handled in arrival order by one worker thread (the Zenoh
callback only queues them; a full queue refuses with ``state: "busy"``), bounded like HTTP bodies and by the
store's limits. The robot id is the session id (at most one session per robot).
"""

from __future__ import annotations

import json
import logging
import queue
import threading
from typing import Any

import zenoh

from planner.live import ReplanEvent
from service.auth import token_ok
from service.core import PlanningService
from service.outcome import outcome_of_exception
from service.sessions import Entry, SessionStore, path_json
from service.wire import NAME_PATTERN, PoseIn
from service.wire_live import ObservationIn, SessionCreate
from service.zenoh_entities import RELIABLE, undeclare_all
from service.zenoh_node import JSON, PREFIX, parse

log = logging.getLogger(__name__)

TOPICS = ("session", "pose", "goal", "observations")
QUEUE_MESSAGES = 256


class LiveZenohNode:
    """Subscribes the session topics on an open Zenoh session and publishes paths and statuses."""

    def __init__(self, service: PlanningService, store: SessionStore, session: zenoh.Session,
                 max_body_bytes: int, token: str | None = None, robots: tuple[str, ...] = ("*",)) -> None:
        self.service = service
        self.store = store
        self.session = session
        self.max_body_bytes = max_body_bytes
        self.token = token  # the server's bearer token: a sample without the attachment 'Bearer <token>' is dropped
        self.robots = robots  # the robot-id patterns this instance serves (serve --robots), as the goal topics
        self.dropped_unauthorised = 0
        self._entities: list[Any] = []
        self._queue: queue.Queue[tuple[str, str, zenoh.ZBytes | None] | None] = queue.Queue(maxsize=QUEUE_MESSAGES)
        self._worker = threading.Thread(target=self._run, name="sphereplan-live-zenoh", daemon=True)
        self.handled = 0

    def start(self) -> None:
        for pattern in self.robots:
            self._entities.append(self.session.declare_subscriber(f"{PREFIX}/{pattern}/live/*", self._on_sample,
                                                                  allowed_origin=zenoh.Locality.REMOTE))
        self._worker.start()
        log.info("zenoh live sessions up: %s/<robot_id>/live/{%s}", PREFIX, ",".join(TOPICS))

    def close(self) -> None:
        undeclare_all(self._entities)
        self._queue.put(None)
        self._worker.join(timeout=5)

    # ------------------------------------------------------------------ in

    def _on_sample(self, sample: zenoh.Sample) -> None:
        parts = str(sample.key_expr).split("/")
        if len(parts) != 4 or parts[3] not in TOPICS:
            return
        robot_id, topic = parts[1], parts[3]
        attachment = sample.attachment
        if not token_ok(None if attachment is None else attachment.to_bytes(), self.token):
            self.dropped_unauthorised += 1
            log.warning("dropped a session message on %s without a valid token attachment", sample.key_expr)
            return
        try:
            self._queue.put_nowait((robot_id, topic, sample.payload))
        except queue.Full:
            self._status(robot_id, {"state": "busy", "topic": topic,
                                    "error_msg": f"more than {QUEUE_MESSAGES} session messages waiting; dropped"})

    def _run(self) -> None:
        while True:
            item = self._queue.get()
            if item is None:
                return
            robot_id, topic, payload = item
            try:
                self._handle(robot_id, topic, payload)
            except Exception as exc:
                outcome = outcome_of_exception(exc)
                if outcome.kind == "internal":
                    log.error("live session message on %s/%s failed", robot_id, topic, exc_info=exc)
                self._status(robot_id, {"state": "invalid", "topic": topic, **outcome.json()})
            self.handled += 1

    def _handle(self, robot_id: str, topic: str, payload: zenoh.ZBytes | None) -> None:
        import re

        from service.http_sessions import session_body, session_grid

        if not re.match(NAME_PATTERN, robot_id):
            raise ValueError(f"robot id {robot_id!r} is not a plain name")
        limit = self.max_body_bytes
        if topic == "session":
            body = parse(SessionCreate, payload, limit)
            if body.id is not None and body.id != robot_id:
                from planner.errors import InvalidInput

                raise InvalidInput("id", "is the robot id of the key expression; leave it out")
            if robot_id in self.store.ids():
                self.store.delete(robot_id)
            from planner.live import ObstacleLayerParams, live_options

            robot = self.service.robot_profile(body.robot)
            grid, name = session_grid(self.service, body, robot, self.store.limits.max_cells)
            options = live_options(body.options)
            base = ObstacleLayerParams.for_robot(robot)
            entry, event = self.store.create(
                f"zenoh:{robot_id}", grid, robot, body.start.as_pose(),
                None, options, body.policy(),
                body.layer.params(base) if body.layer is not None else base, name, robot_id)
            entry.on_event.append(self._publish)
            self._status(robot_id, {"state": "created", "session": session_body(entry)})
            if body.goal is not None:
                self.store.goal(robot_id, body.goal.as_pose())
        elif topic == "pose":
            self.store.pose(robot_id, parse(PoseIn, payload, limit).as_pose())
        elif topic == "goal":
            self.store.goal(robot_id, parse(PoseIn, payload, limit).as_pose())
        else:
            self.store.observe(robot_id, parse(ObservationIn, payload, limit).value())

    # ------------------------------------------------------------------ out

    def _publish(self, entry: Entry, event: ReplanEvent) -> None:
        if event.ok:
            path = path_json(entry)
            self.session.put(f"{PREFIX}/{entry.id}/live/path", json.dumps(path, allow_nan=False), encoding=JSON,
                             congestion_control=RELIABLE)
        self._status(entry.id, {"state": "replanned" if event.ok else "failed", "replan": event.to_json(),
                                "status": entry.session.status()})

    def _status(self, robot_id: str, body: dict[str, Any]) -> None:
        try:
            self.session.put(f"{PREFIX}/{robot_id}/live/status", json.dumps({"robot_id": robot_id, **body}),
                             encoding=JSON, congestion_control=RELIABLE)
        except Exception as exc:  # closing
            log.warning("could not publish the status of %s: %s", robot_id, exc)


def start_live_doors(service: PlanningService, store: SessionStore, node: Any, settings: Any) -> list[Any]:
    """Start the session doors on the Zenoh node's open session: the JSON topics, and with ``settings.ros2`` the
    ROS 2 (rmw_zenoh) session topics too; returns them for closing."""
    doors: list[Any] = [LiveZenohNode(service, store, node.session, settings.max_body_bytes, settings.http_token,
                                      tuple(settings.zenoh_robots))]
    if settings.ros2:
        from service.ros2_live import Ros2LiveFace

        doors.append(Ros2LiveFace(service, store, node.session, node.ros2.options))
    for door in doors:
        door.start()
    return doors
