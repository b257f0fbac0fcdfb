"""Robot sessions on every door: a store of :class:`planner.live.session.LiveSession` s, bounded, transport-free.

HTTP (:mod:`service.http_sessions`), Zenoh and ROS 2 over rmw_zenoh (:mod:`service.zenoh_live`) all drive a
:class:`SessionStore`: create a session (a map or an unknown area, a robot, a start pose, optionally a goal),
send it poses, observations and goals, read its path and status, and subscribe to its replans. Planning runs
in the caller's thread (the HTTP routes call from a worker thread, Zenoh from its callback thread), one
operation per session at a time (a lock per session), so a session's planner stays warm and is refreshed only
where its map changed.

Bounds (:class:`SessionLimits`), each refused naming the field: sessions in all and per client, cells of a
session's map (its memory: the live map and the planner's distance field grow with it), points per
observation, beams per scan, cells per region update, and the update rate of a session (a faster sender is
answered 429 with ``Retry-After``, :class:`service.outcome.RateLimited`). Sessions idle longer than
``idle_timeout_s`` are dropped.
"""

from __future__ import annotations

import logging
import math
import queue
import secrets
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from planner.errors import InvalidInput, NotFound
from planner.hybrid_astar.search import PlannerOptions
from planner.live import (
    LiveMap,
    LiveSession,
    Observation,
    ObstacleLayerParams,
    PointObservation,
    RegionUpdate,
    ReplanEvent,
    ReplanPolicy,
    ScanObservation,
    live_options,
)
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile
from service.outcome import RateLimited, ServiceBusy

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SessionLimits:
    """Hard limits of the session store (see the module docstring)."""

    max_sessions: int = 16
    max_sessions_per_client: int = 4
    max_cells: int = 4_200_000
    max_points: int = 100_000
    max_beams: int = 10_000
    max_region_cells: int = 250_000
    min_update_interval_s: float = 0.02
    idle_timeout_s: float = 900.0
    max_time_limit_s: float = 10.0
    queue_events: int = 64


@dataclass
class Entry:
    """One stored session: the live session, who made it, its lock, its subscribers."""

    id: str
    client: str
    session: LiveSession
    name: str
    lock: threading.Lock = field(default_factory=threading.Lock)
    last_update: float = -math.inf
    last_used: float = field(default_factory=time.monotonic)
    subscribers: list[queue.Queue[dict[str, Any]]] = field(default_factory=list)
    on_event: list[Callable[[Entry, ReplanEvent], None]] = field(default_factory=list)


def path_json(entry: Entry) -> dict[str, Any] | None:
    """The session's current path as the plan-result JSON (docs/contracts.md), or None."""
    path = entry.session.path
    if path is None:
        return None
    out = path.to_json()
    out["map"] = entry.name
    return out


def map_json(entry: Entry) -> dict[str, Any]:
    """The live map as a ``nav_msgs/OccupancyGrid`` in its ROS JSON form (row-major, row 0 at the origin)."""
    g = entry.session.map.grid
    ox, oy, yaw = g.origin
    return {"header": {"frame_id": "map"},
            "info": {"resolution": g.resolution_m, "width": g.width, "height": g.height,
                     "origin": {"position": {"x": ox, "y": oy, "z": 0.0},
                                "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}}},
            "data": g.data.ravel().tolist()}


class SessionStore:
    """All robot sessions of one server (see the module docstring)."""

    def __init__(self, limits: SessionLimits | None = None, clock: Callable[[], float] = time.monotonic) -> None:
        self.limits = limits or SessionLimits()
        self.clock = clock
        self._sessions: dict[str, Entry] = {}
        self._lock = threading.Lock()

    # ------------------------------------------------------------------ lifecycle

    def create(self, client: str, grid: OccupancyGrid, robot: RobotProfile, start: tuple[float, float, float],
               goal: tuple[float, float, float] | None = None, options: PlannerOptions | None = None,
               policy: ReplanPolicy | None = None, layer: ObstacleLayerParams | None = None,
               name: str | None = None, session_id: str | None = None) -> tuple[Entry, ReplanEvent | None]:
        """A new session on ``grid`` (copied into its live map) with the robot at ``start``; plans at once when
        ``goal`` is given. Raises :class:`InvalidInput` (limits, bad poses) or :class:`ServiceBusy` (full)."""
        lim = self.limits
        if grid.data.size > lim.max_cells:
            raise InvalidInput("map", f"{grid.width}×{grid.height} = {grid.data.size} cells; a session's map may have "
                                      f"at most {lim.max_cells}")
        if policy is not None and policy.time_limit_s > lim.max_time_limit_s:
            raise InvalidInput("time_limit_s", f"must be ≤ {lim.max_time_limit_s:g} s for a session")
        self.expire()
        with self._lock:
            if len(self._sessions) >= lim.max_sessions:
                raise ServiceBusy(len(self._sessions), 5)
            mine = sum(e.client == client for e in self._sessions.values())
            if mine >= lim.max_sessions_per_client:
                raise InvalidInput("session", f"this client has {mine} sessions already (at most "
                                              f"{lim.max_sessions_per_client}); DELETE one first")
            sid = session_id or secrets.token_hex(8)
            if sid in self._sessions:
                raise InvalidInput("session", f"session {sid!r} exists already")
        live = LiveMap(grid, layer or ObstacleLayerParams.for_robot(robot))
        session = LiveSession(live, robot, options or live_options(), policy or ReplanPolicy())
        entry = Entry(sid, client, session, name or grid.name)
        session.listeners.append(lambda event: self._publish(entry, event))
        session.set_pose(start, field="start")
        with self._lock:
            if len(self._sessions) >= lim.max_sessions:
                raise ServiceBusy(len(self._sessions), 5)
            self._sessions[sid] = entry
        event = None
        if goal is not None:
            with entry.lock:
                event = session.set_goal(goal)
        log.info("session %s created on %s (%d×%d cells) for %s", sid, entry.name, grid.width, grid.height, client)
        return entry, event

    def get(self, sid: str) -> Entry:
        with self._lock:
            entry = self._sessions.get(sid)
        if entry is None:
            raise NotFound("session", f"no session {sid!r} (it may have expired after "
                                      f"{self.limits.idle_timeout_s:g} s idle)")
        entry.last_used = self.clock()
        return entry

    def ids(self) -> list[str]:
        with self._lock:
            return list(self._sessions)

    def delete(self, sid: str) -> None:
        entry = self.get(sid)
        with self._lock:
            self._sessions.pop(sid, None)
        for q in list(entry.subscribers):
            _offer(q, {"event": "closed", "data": {"session": sid}})

    def expire(self) -> None:
        """Drop sessions idle longer than the limit."""
        now = self.clock()
        with self._lock:
            old = [sid for sid, e in self._sessions.items() if now - e.last_used > self.limits.idle_timeout_s]
        for sid in old:
            log.info("session %s expired", sid)
            self.delete(sid)

    def close(self) -> None:
        for sid in self.ids():
            self.delete(sid)

    # ------------------------------------------------------------------ updates

    def _throttle(self, entry: Entry) -> None:
        now = self.clock()
        wait = entry.last_update + self.limits.min_update_interval_s - now
        if wait > 0:
            raise RateLimited(f"session {entry.id} takes at most {1 / self.limits.min_update_interval_s:g} updates "
                              f"per second; retry in {wait:.3f} s", max(1, math.ceil(wait)))
        entry.last_update = now

    def pose(self, sid: str, pose: tuple[float, float, float]) -> ReplanEvent | None:
        entry = self.get(sid)
        with entry.lock:
            return entry.session.set_pose(pose)

    def goal(self, sid: str, goal: tuple[float, float, float]) -> ReplanEvent:
        entry = self.get(sid)
        with entry.lock:
            return entry.session.set_goal(goal)

    def observe(self, sid: str, observation: Observation) -> tuple[dict[str, Any], ReplanEvent | None]:
        """Apply an observation (bounded: points, beams, region cells, rate); returns (map update JSON, replan)."""
        entry = self.get(sid)
        self.check_size(observation)
        with entry.lock:
            self._throttle(entry)
            try:
                update, event = entry.session.observe(observation)
            except InvalidInput as exc:
                if isinstance(observation, RegionUpdate) and not exc.field.startswith("region."):
                    raise InvalidInput(f"region.{exc.field}", exc.msg) from None
                raise
        data = update.to_json()
        for q in list(entry.subscribers):
            if update.changed is not None:
                known = entry.session.map.known_fraction()
                _offer(q, {"event": "map", "data": {"update": data, "known_fraction": known}})
        return data, event

    def check_size(self, observation: Observation) -> None:
        lim = self.limits
        if isinstance(observation, PointObservation) and len(observation.points_m) > lim.max_points:
            raise InvalidInput("points", f"{len(observation.points_m)} points; at most {lim.max_points} per "
                                          "observation")
        if isinstance(observation, ScanObservation) and len(observation.ranges_m) > lim.max_beams:
            raise InvalidInput("scan.ranges", f"{len(observation.ranges_m)} beams; at most {lim.max_beams} per scan")
        if isinstance(observation, RegionUpdate) and observation.data.size > lim.max_region_cells:
            raise InvalidInput("region.data", f"{observation.data.size} cells; at most {lim.max_region_cells} "
                                              "per region update")

    # ------------------------------------------------------------------ events

    def subscribe(self, sid: str) -> queue.Queue[dict[str, Any]]:
        """A queue that receives ``{"event": "replan" | "map" | "closed", "data": ...}`` (oldest dropped when full)."""
        entry = self.get(sid)
        q: queue.Queue[dict[str, Any]] = queue.Queue(maxsize=self.limits.queue_events)
        entry.subscribers.append(q)
        return q

    def unsubscribe(self, sid: str, q: queue.Queue[dict[str, Any]]) -> None:
        with self._lock:
            entry = self._sessions.get(sid)
        if entry is not None and q in entry.subscribers:
            entry.subscribers.remove(q)

    def _publish(self, entry: Entry, event: ReplanEvent) -> None:
        message = {"event": "replan", "data": {"replan": event.to_json(), "path": path_json(entry),
                                               "status": entry.session.status()}}
        for q in list(entry.subscribers):
            _offer(q, message)
        for hook in list(entry.on_event):
            try:
                hook(entry, event)
            except Exception:  # a door's publisher must not break the session
                log.exception("session %s: publishing replan %d failed", entry.id, event.seq)


def _offer(q: queue.Queue[dict[str, Any]], item: dict[str, Any]) -> None:
    """Put ``item``; when the queue is full drop its oldest item first (a slow reader loses old events)."""
    while True:
        try:
            q.put_nowait(item)
            return
        except queue.Full:
            try:
                q.get_nowait()
            except queue.Empty:
                pass


def as_array(rows: Any, field: str, width: int) -> np.ndarray:
    """A list of rows of ``width`` finite numbers as a float array, or :class:`InvalidInput` naming ``field``."""
    arr = np.asarray(rows, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != width:
        raise InvalidInput(field, f"must be a list of [{', '.join('xyz'[:width])}] rows")
    return arr
