"""The Zenoh node: queryables and pub/sub over :class:`service.core.PlanningService`.

Key expressions (payloads are the same JSON as the HTTP API, encoding ``application/json``):

* queryable ``sphereplan/plan`` — payload a :class:`~service.wire.PlanRequest`; replies the plan result
  with ``reply``, or the error / failed-result JSON with ``reply_err``. Queryables are declared complete,
  so a query with the default target reaches one instance however many serve. Queries go to the process pool:
  the callback only validates and submits, the reply is sent when the job finishes, so a slow plan
  never blocks other queries. Every query is finalised (``drop``) once answered.
* queryables ``sphereplan/reconfigure`` and ``sphereplan/simulate`` — payloads a
  :class:`~service.wire.ReconfigureIn` / :class:`~service.wire.SimulateRequest`, replying what
  ``/v1/reconfigure`` / ``/v1/simulate`` answer.
* ``sphereplan/*/pose`` (a :class:`~service.wire.PoseIn`) and ``sphereplan/*/goal`` (a
  :class:`~service.wire.GoalMessage`), taken by one subscriber so that a pose published just before a
  goal is always applied first: each new goal is planned from that robot's latest pose; the
  service publishes the plan result on ``sphereplan/<robot_id>/path`` and ``{robot_id, goal_id, state,
  error_code, error_msg, ...}`` on ``sphereplan/<robot_id>/status`` (``planning``, then ``succeeded``
  or ``failed``). The newest goal wins: a new goal cancels the plan in flight for the robot's previous
  one (freeing its slot first, so a goal is never refused because of the goals it replaces); the
  superseded goal publishes ``superseded`` and no path.
* Every payload is bounded like an HTTP body (``max_body_bytes``, checked by length before it is read)
  and a malformed or too deeply nested one is answered with the error JSON naming ``body`` (a query's
  ``reply_err``; on the topics an ``invalid_pose`` / ``invalid_goal`` status). A large one is parsed in a
  parse process (:mod:`service.limits`), robot samples are handled off the callback thread in order per
  robot, so one slow payload holds no other.
* With a token (``--token-file``, :mod:`service.auth`) every query and pose/goal put must carry the
  attachment ``Bearer <token>``: a query without it is answered ``reply_err`` naming ``attachment``, a sample
  without it is dropped. ``settings.zenoh_robots`` (``--robots``) says which robots' topics this instance
  plans, so that instances serving one fleet each plan a disjoint set.
* a liveliness token ``sphereplan/planner/<zid>`` announces the planner while it runs.

Default session: peer mode, listening on ``tcp/127.0.0.1:7447`` only, multicast scouting off, so the
node is reachable from this machine and nothing else. A standard Zenoh config file (``--zenoh-config``)
replaces that for router or multi-host deployments. ``close()`` undeclares everything and closes the
session: a live session keeps callback threads that would keep the process alive.
"""

from __future__ import annotations

import json
import logging
import threading
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any, TypeVar

import zenoh
from pydantic import BaseModel

from planner.errors import InvalidInput, StartOutsideMap
from service.auth import token_ok
from service.core import PlanningService
from service.limits import SMALL_BODY_BYTES, KeyedSerialExecutor, ParseGate, parse_json_model
from service.outcome import Outcome, Unauthorized, error_outcome, outcome_of_exception
from service.settings import ServiceSettings
from service.wire import (
    GoalMessage,
    PlanRequest,
    PoseIn,
    PoseMessage,
    ReconfigureIn,
    SimulateRequest,
)
from service.zenoh_entities import RELIABLE, undeclare_all

log = logging.getLogger(__name__)

PREFIX = "sphereplan"
JSON = zenoh.Encoding.APPLICATION_JSON
M = TypeVar("M", bound=BaseModel)


def default_config(listen: str = "tcp/127.0.0.1:7447") -> zenoh.Config:
    """Peer mode, listening on ``listen`` only, no multicast scouting, no outgoing connections."""
    conf = zenoh.Config()
    conf.insert_json5("mode", json.dumps("peer"))
    conf.insert_json5("listen/endpoints", json.dumps([listen]))
    conf.insert_json5("connect/endpoints", "[]")
    conf.insert_json5("scouting/multicast/enabled", "false")
    return conf


def node_config(settings: ServiceSettings) -> zenoh.Config:
    """The session config: ``settings.zenoh_config`` (a standard Zenoh JSON5 file) or the default."""
    if settings.zenoh_config is not None:
        return zenoh.Config.from_file(str(settings.zenoh_config))
    return default_config(settings.zenoh_listen)


def check_size(payload: zenoh.ZBytes | None, limit: int) -> int:
    """The payload's length; :class:`InvalidInput` naming ``body`` when it is missing or over ``limit`` bytes
    (the HTTP body limit), checked before it is copied or parsed."""
    if payload is None:
        raise InvalidInput("body", "a JSON payload is required")
    size = len(payload)
    if size > limit:
        raise InvalidInput("body", f"payload of {size} bytes; this server accepts at most {limit}")
    return size


def parse(model: type[M], payload: zenoh.ZBytes | None, limit: int) -> M:
    """Validate a JSON payload against a wire model; raises :class:`InvalidInput` naming the field.

    A payload over ``limit`` bytes is refused by its length, before it is copied or parsed; one nested too
    deeply for the parser is refused like malformed JSON."""
    check_size(payload, limit)
    assert payload is not None
    return parse_json_model(model, payload.to_bytes(), limit)


def refusal(exc: Exception, where: str) -> Outcome:
    """The outcome of a message refused before a job was queued (bad payload or request, busy, or a bug)."""
    outcome = outcome_of_exception(exc)
    if outcome.kind == "internal":
        log.error("%s failed", where, exc_info=exc)
    return outcome


class ZenohNode:
    """The service's Zenoh face. ``start()`` opens the session and declares everything; ``close()``
    undeclares and closes it."""

    def __init__(self, service: PlanningService, settings: ServiceSettings | None = None,
                 config: zenoh.Config | None = None, parse_gate: ParseGate | None = None) -> None:
        self.service = service
        self.settings = settings or service.settings
        self._config = config
        self.session: zenoh.Session | None = None
        self._entities: list[Any] = []
        self._lock = threading.Lock()
        self._poses: dict[str, PoseIn] = {}
        self._goal_ids: dict[str, int] = {}
        self.ros2: Any = None  # the rmw_zenoh face (service.ros2_zenoh), with settings.ros2
        self._plans: dict[str, Future[Outcome]] = {}  # robot → the plan in flight for its newest goal
        self._token = self.settings.http_token
        # large payloads are parsed in separate processes (the HTTP app's, when it runs the node)
        self._own_gate = parse_gate is None
        self._parse = parse_gate or ParseGate(retry_after_s=self.settings.retry_after_s)
        self._topics = KeyedSerialExecutor()  # robot samples: off the callback, in order per robot
        # one entry per queryable capability: key suffix → (request model, submit)
        self.queryables: dict[str, tuple[type[BaseModel], Callable[[Any], Future[Outcome]]]] = {
            "plan": (PlanRequest, service.submit_plan),
            "reconfigure": (ReconfigureIn, service.submit_reconfigure),
            "simulate": (SimulateRequest, service.submit_simulate),
        }

    # ------------------------------------------------------------------------------ life cycle

    def start(self) -> None:
        session = zenoh.open(self._config or node_config(self.settings))
        self.session = session
        for name, (model, submit) in self.queryables.items():
            key = f"{PREFIX}/{name}"
            # complete: a query with the default target (BEST_MATCHING) goes to one instance however many serve
            self._entities.append(session.declare_queryable(key, self._query_handler(key, model, submit),
                                                            complete=True))
        # one subscriber per robot pattern for both topics, so that a pose published just before a goal is seen
        # first (callbacks of separate subscribers run on separate threads); our own puts are not delivered.
        # Instances serving one fleet take disjoint patterns, so each goal is planned once.
        for pattern in self.settings.zenoh_robots:
            self._entities.append(session.declare_subscriber(f"{PREFIX}/{pattern}/*", self._on_robot_sample,
                                                             allowed_origin=zenoh.Locality.REMOTE))
        self._entities.append(session.liveliness().declare_token(f"{PREFIX}/planner/{session.zid()}"))
        log.info("zenoh node %s up: queryables %s", session.zid(), ", ".join(self.queryables))
        if self.settings.ros2:
            from service.ros2_zenoh import RmwZenohFace, Ros2Options

            s = self.settings
            self.ros2 = RmwZenohFace(self.service, session, Ros2Options(
                domain_id=s.ros2_domain_id, namespace=s.ros2_namespace, map_name=s.ros2_map, robot=s.ros2_robot))
            self.ros2.start()

    def close(self) -> None:
        session, self.session = self.session, None
        if session is None:
            return
        if self.ros2 is not None:
            self.ros2.close()
        undeclare_all(self._entities)
        session.close()
        if self._own_gate:
            self._parse.close()
        self._topics.close()

    # ------------------------------------------------------------------------------ queries

    def _query_handler(self, key: str, model: type[BaseModel],
                       submit: Callable[[Any], Future[Outcome]]) -> Callable[[zenoh.Query], None]:
        limit = self.settings.max_body_bytes

        def handle(query: zenoh.Query, parse: Callable[[], Any]) -> None:
            try:
                future = submit(parse())
            except Exception as exc:
                self._answer(query, key, refusal(exc, f"query on {key}"))
                return
            future.add_done_callback(lambda done: self._answer(query, key, done.result()))

        def on_query(query: zenoh.Query) -> None:
            if not self._authorised(query.attachment):
                self._answer(query, key, self._unauthorised())
                return
            try:
                size = check_size(query.payload, limit)
                assert query.payload is not None
                raw = query.payload.to_bytes()
                if size <= SMALL_BODY_BYTES:
                    handle(query, lambda: parse_json_model(model, raw, limit))
                else:  # a large payload is parsed in a parse process: it holds no other query or sample
                    parsed = self._parse.submit(model, raw, limit)
                    parsed.add_done_callback(lambda done: handle(query, done.result))
            except Exception as exc:
                self._answer(query, key, refusal(exc, f"query on {key}"))

        return on_query

    def _authorised(self, attachment: zenoh.ZBytes | None) -> bool:
        return token_ok(None if attachment is None else attachment.to_bytes(), self._token)

    @staticmethod
    def _unauthorised() -> Outcome:
        return error_outcome(Unauthorized, "this server needs the attachment 'Bearer <token>' on every query and "
                                           "put", "attachment")

    def _answer(self, query: zenoh.Query, key: str, outcome: Outcome) -> None:
        """Reply (or reply_err) and finalise the query, whatever happens."""
        try:
            if outcome.answer.zenoh_reply == "reply":
                query.reply(key, outcome.body, encoding=JSON)
            else:
                query.reply_err(outcome.body, encoding=JSON)
        except Exception as exc:  # the session may be closing
            log.warning("could not answer a query on %s: %s", key, exc)
        finally:
            try:
                query.drop()
            except Exception as exc:
                log.debug("query drop: %s", exc)

    # ------------------------------------------------------------------------------ pub/sub

    @staticmethod
    def _robot_id(sample: zenoh.Sample) -> str:
        return str(sample.key_expr).split("/")[1]

    def _publish(self, robot_id: str, topic: str, data: dict[str, Any] | bytes) -> None:
        session = self.session
        if session is None:
            return
        payload = data if isinstance(data, bytes) else json.dumps(data, allow_nan=False).encode()
        try:
            session.put(f"{PREFIX}/{robot_id}/{topic}", payload, encoding=JSON, congestion_control=RELIABLE)
        except Exception as exc:  # closing
            log.warning("could not publish %s/%s: %s", robot_id, topic, exc)

    def _status(self, robot_id: str, goal_id: int, state: str, outcome: Outcome | None = None,
                **extra: Any) -> None:
        status: dict[str, Any] = {"robot_id": robot_id, "goal_id": goal_id, "state": state,
                                  "error_code": 0, "error_msg": ""}
        if outcome is not None and not outcome.ok:
            body = outcome.json()
            status.update(error_code=body.get("error_code", 200), error_msg=body.get("error_msg", ""))
        status.update(extra)
        self._publish(robot_id, "status", status)

    def _on_robot_sample(self, sample: zenoh.Sample) -> None:
        """The subscriber's callback: check the token, then handle the sample off the callback thread, in order
        per robot (a large goal parses while other robots' samples go on)."""
        topic = str(sample.key_expr).rsplit("/", 1)[-1]
        if topic not in ("pose", "goal"):
            return
        if not self._authorised(sample.attachment):
            log.warning("dropped a %s on %s without a valid token attachment", sample.kind, sample.key_expr)
            return
        if not self._topics.submit(self._robot_id(sample), lambda: self._handle_robot_sample(sample, topic)):
            log.warning("dropped a sample on %s: too many samples waiting", sample.key_expr)

    def _handle_robot_sample(self, sample: zenoh.Sample, topic: str) -> None:
        try:
            if topic == "pose":
                self._on_pose(sample)
            elif topic == "goal":
                self._on_goal(sample)
        except Exception:  # a bug: logged, and the subscriber keeps running
            log.exception("handling a sample on %s failed", sample.key_expr)

    def _on_pose(self, sample: zenoh.Sample) -> None:
        robot_id = self._robot_id(sample)
        try:
            pose = parse(PoseMessage, sample.payload, self.settings.max_body_bytes).as_pose_in()
        except InvalidInput as exc:
            self._status(robot_id, self._goal_ids.get(robot_id, 0), "invalid_pose", outcome_of_exception(exc))
            return
        with self._lock:
            self._poses[robot_id] = pose

    def _on_goal(self, sample: zenoh.Sample) -> None:
        robot_id = self._robot_id(sample)
        try:
            goal = parse(GoalMessage, sample.payload, self.settings.max_body_bytes)
        except InvalidInput as exc:
            # a malformed goal is reported but does not cancel the goal being planned
            self._status(robot_id, self._goal_ids.get(robot_id, 0), "invalid_goal", outcome_of_exception(exc))
            return
        with self._lock:
            goal_id = self._goal_ids.get(robot_id, 0) + 1
            self._goal_ids[robot_id] = goal_id
            pose = self._poses.get(robot_id)
            previous = self._plans.pop(robot_id, None)
        if previous is not None:
            # the newest goal wins: the plan for the one it replaces is cancelled, and its slot freed, first
            self.service.cancel(previous)
        if pose is None:
            self._status(robot_id, goal_id, "failed", error_outcome(
                InvalidInput, f"no pose received yet on {PREFIX}/{robot_id}/pose to plan from", "pose",
                StartOutsideMap.code))
            return
        try:
            future = self.service.submit_plan(goal.plan_request(pose))
        except Exception as exc:
            self._status(robot_id, goal_id, "failed", refusal(exc, f"goal of {robot_id}"))
            return
        with self._lock:
            if self._goal_ids.get(robot_id) == goal_id:
                self._plans[robot_id] = future
                newest = True
            else:
                newest = False  # a newer goal arrived while this one was being submitted
        if not newest:
            self.service.cancel(future)
        goal_pose = dict(zip(("x", "y", "yaw"), goal.goal.as_pose(), strict=True))
        start_pose = dict(zip(("x", "y", "yaw"), pose.as_pose(), strict=True))  # radians, as the goal
        self._status(robot_id, goal_id, "planning", start=start_pose, goal=goal_pose)
        future.add_done_callback(lambda done: self._goal_done(robot_id, goal_id, done, done.result()))

    def _goal_done(self, robot_id: str, goal_id: int, future: Future[Outcome], outcome: Outcome) -> None:
        with self._lock:
            if self._plans.get(robot_id) is future:
                del self._plans[robot_id]
        if self._goal_ids.get(robot_id) != goal_id:
            self._status(robot_id, goal_id, "superseded")  # a newer goal replaced this one: no path published
            return
        if outcome.ok:
            self._publish(robot_id, "path", outcome.body)
            self._status(robot_id, goal_id, "succeeded", length_m=outcome.json().get("length_m"))
        else:
            self._status(robot_id, goal_id, "failed", outcome)
