"""A robot session: a live map, the goal, the robot's pose and its path, replanned when the path is blocked.

:class:`LiveSession` is the transport-free loop every door drives (HTTP session resource, Zenoh topics,
ROS 2 over rmw_zenoh, ``sphereplan explore``): the door hands it poses (odometry), observations and goals;
the session updates its :class:`~planner.live.live_map.LiveMap`, refreshes its planner for the changed cells
(:mod:`planner.live.refresh`), checks the rest of the path with the robot's real footprint (covering circles,
then the exact polygon: :meth:`planner.maps.clearance.ClearanceMap.footprint_margins`) and replans from the
current pose when it is blocked, when the goal changes, when a failed plan may now succeed (the map changed)
or on a timer (``ReplanPolicy.period_s``). Each replan is a :class:`ReplanEvent` saying why and how long it
took; listeners get every event (the doors publish the new path from there).
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from planner.angles import check_angle
from planner.errors import BadEndpoint, GoalOccupied, InvalidInput, PlannerCancelled, PlanningError, StartOccupied
from planner.hybrid_astar.search import HybridAStar, PlannerOptions, Pose
from planner.kinematics import wrap
from planner.live.guide import WIDE_M, guided_plan
from planner.live.live_map import CellRect, LiveMap, MapUpdate
from planner.live.observations import Observation
from planner.live.refresh import capped, refresh
from planner.result import PlanResult
from planner.robot import RobotProfile
from planner.termination import Termination

EVENTS_KEPT = 256
"""Replan events a session remembers (older ones are dropped)."""

MAX_PENDING_REGIONS = 256
"""Changed rectangles a session collects before refreshing; beyond that they are merged into one."""

LIVE_OPTION_DEFAULTS: dict[str, Any] = {"allow_unknown": True, "greed": 2.0, "open_step_factor": 1}
"""Planner options a live session uses unless told otherwise: unknown space is traversable (Nav2's default,
what exploring needs), and the search is greedier than a one-off plan's (f = g + 3·h instead of g + 2·h): a
replan must come back while the robot is still driving, and the smoothing recovers the length. On the explore
sweep's slow replans (long detours round a blocked garage aisle) this cut the expansions about twentyfold with
paths no longer (``sphereplan bench --suite explore`` measures both). Every step is one step long
(``open_step_factor`` 1): with the one-off planner's long steps in the open, two of the sweep's worlds
(``smoothers-boxes``, ``smoothers-door``) collided, where one-step replans reach the goal; why is not yet known
(``tests/planner/live/test_session.py`` keeps the default)."""


def live_options(given: dict[str, Any] | None = None) -> PlannerOptions:
    """:data:`LIVE_OPTION_DEFAULTS` overridden by the ``given`` planner options (a JSON object, checked by name)."""
    return PlannerOptions.from_dict({**LIVE_OPTION_DEFAULTS, **(given or {})})


REASONS = ("goal", "blocked", "timer", "map_changed", "request")
"""Why a session replans: a new goal, the path ahead is blocked, the replan timer, a failed plan retried
after the map changed, or a caller asked."""


@dataclass(frozen=True)
class ReplanPolicy:
    """When to replan. ``period_s``: also replan this often while a goal is active (None = only when needed,
    as Nav2's planner server with ``expected_planner_frequency`` 0); ``time_limit_s``: each plan's limit;
    ``arrival_tolerance_m``: the goal counts as reached (no more replans) this close; ``retry_period_s``: after a
    failed plan, a map change triggers a new attempt at most this often (a stopped robot's flickering sensor
    noise must not replan at the sensor's rate); ``splice_lead_s``: a robot rolling along its path is not
    replanned from where it is (a new path may start against its motion, and it cannot stop on the spot) but from
    the state of its path it reaches after rolling ``splice_lead_s`` at its speed and then braking, when that is
    short of the blockage; the new path keeps the old one up to there (0 = always from the current pose);
    ``guided``: search first with the guides of
    :mod:`planner.live.guide` (gaps the robot cannot roll through closed; then gaps up to ``guide_levels_m``
    wider), each for at most ``guide_expansions`` expansions and all of them for at most ``guide_share`` of the
    time limit, then, if they found nothing, with the planner's own heuristic for the rest of it."""

    period_s: float | None = None
    time_limit_s: float = 2.0
    arrival_tolerance_m: float = 0.25
    retry_period_s: float = 1.0
    splice_lead_s: float = 0.5
    guided: bool = True
    guide_levels_m: tuple[float, ...] = (0.0, WIDE_M)
    guide_expansions: int = 6000
    guide_share: float = 0.5

    def __post_init__(self) -> None:
        if self.period_s is not None and not (math.isfinite(self.period_s) and self.period_s > 0):
            raise InvalidInput("replan_period_s", f"must be a finite number of seconds > 0, got {self.period_s!r}")
        if not (math.isfinite(self.time_limit_s) and 0 < self.time_limit_s <= 60):
            raise InvalidInput("time_limit_s", f"must be in (0, 60] s, got {self.time_limit_s!r}")
        if not (math.isfinite(self.arrival_tolerance_m) and self.arrival_tolerance_m > 0):
            raise InvalidInput("arrival_tolerance_m", "must be a finite number > 0")
        if not (math.isfinite(self.retry_period_s) and self.retry_period_s >= 0):
            raise InvalidInput("retry_period_s", "must be a finite number of seconds ≥ 0")
        if not (math.isfinite(self.splice_lead_s) and 0 <= self.splice_lead_s <= 10):
            raise InvalidInput("splice_lead_s", f"must be in [0, 10] s, got {self.splice_lead_s!r}")
        if not (math.isfinite(self.guide_share) and 0 < self.guide_share < 1):
            raise InvalidInput("guide_share", f"must be in (0, 1), got {self.guide_share!r}")
        if not all(math.isfinite(w) and 0 <= w <= 1 for w in self.guide_levels_m):
            raise InvalidInput("guide_levels_m", f"must be widenings in [0, 1] m, got {self.guide_levels_m!r}")
        if not 0 < self.guide_expansions <= 1_000_000:
            raise InvalidInput("guide_expansions", f"must be in [1, 1000000], got {self.guide_expansions!r}")


@dataclass(frozen=True)
class ReplanEvent:
    """One replan: ``seq`` counts the session's plans from 1; ``reason`` is one of :data:`REASONS`;
    ``latency_s`` runs from the trigger (observation applied, pose or goal received) to the new path, and
    splits into ``refresh_s`` (bringing the planner's distance field and heuristic up to date) and
    ``planning_time_s`` (the search); ``blocked_at`` is the first blocked pose of the old path; ``method`` says
    which search gave the answer: ``"guided"`` (:mod:`planner.live.guide`), ``"guided+0.15m"`` (the guide for gaps
    that much wider) or ``"ordinary"`` (the planner's own heuristic, alone or after guided searches that found
    nothing); ``spliced_m`` is how much of the old path, from the robot on, the new one keeps (``start`` is then
    the state it was planned from, at the end of that stretch)."""

    seq: int
    reason: str
    ok: bool
    error_code: int
    error_msg: str
    latency_s: float
    refresh_s: float
    planning_time_s: float
    length_m: float
    start: Pose
    blocked_at: tuple[float, float] | None = None
    refresh_mode: str = ""
    method: str = ""
    spliced_m: float = 0.0

    def to_json(self) -> dict[str, Any]:
        return {
            "seq": self.seq, "reason": self.reason, "ok": self.ok, "error_code": self.error_code,
            "error_msg": self.error_msg, "latency_s": round(self.latency_s, 6), "refresh_s": round(self.refresh_s, 6),
            "planning_time_s": round(self.planning_time_s, 6), "length_m": self.length_m,
            "start": {"x": self.start[0], "y": self.start[1], "yaw": self.start[2]},
            "blocked_at": None if self.blocked_at is None else {"x": self.blocked_at[0], "y": self.blocked_at[1]},
            "refresh_mode": self.refresh_mode, "method": self.method, "spliced_m": round(self.spliced_m, 3),
        }


SPLICE_CLEAR_M = 1.0
"""A replan is spliced onto the old path only where that leaves at least this much of it before the blockage."""
SPLICE_SHARE = 0.75
"""A spliced replan's search from the splice point gets this share of the time limit; when it finds nothing the
search from the robot gets what is left (at least the rest of the share), so that the replan as a whole keeps
about its limit (it took up to 1.25 × the limit when the first search ran out of time)."""


def _spliced(prefix: np.ndarray, result: PlanResult) -> PlanResult:
    """``result`` (planned from the last state of ``prefix``) with ``prefix`` (the old path's states from the robot
    on) put in front of it, time and arc length counted from the robot."""
    head = prefix.copy()
    head[:, 5] -= head[0, 5]
    head[:, 6] -= head[0, 6]
    tail = result.states[1:].copy()
    tail[:, 5] += head[-1, 5]
    tail[:, 6] += head[-1, 6]
    x, y, yaw = (float(v) for v in head[0, :3])
    return replace(result, states=np.vstack([head, tail]), start=(x, y, yaw),
                   extra={**result.extra, "spliced_m": float(head[-1, 6])})


def _pose(value: Any, field_name: str) -> Pose:
    try:
        x, y, yaw = (float(v) for v in value)
    except (TypeError, ValueError):
        raise InvalidInput(field_name, f"must be three numbers x, y, yaw, got {value!r}") from None
    if not all(math.isfinite(v) for v in (x, y, yaw)):
        raise InvalidInput(field_name, "must be finite numbers")
    return x, y, wrap(check_angle(f"{field_name}.yaw", yaw, "degrees converted to radians"))


@dataclass
class _Progress:
    index: int = 0


class LiveSession:
    """Live map + goal + pose + path for one robot (see the module docstring).

    Parameters
    ----------
    live_map : the robot's :class:`LiveMap` (the session owns it from now on).
    robot : the robot profile whose padded footprint is checked.
    options : planner options; default :func:`live_options` (unknown space traversable, a greedier search).
    policy : when to replan.
    clock : seconds on a monotonic scale (the simulation passes its own time).
    """

    def __init__(self, live_map: LiveMap, robot: RobotProfile, options: PlannerOptions | None = None,
                 policy: ReplanPolicy | None = None, clock: Callable[[], float] = time.monotonic) -> None:
        self.map = live_map
        self.robot = robot
        self.options = options or live_options()
        self.policy = policy or ReplanPolicy()
        self.clock = clock
        self.pose: Pose | None = None
        self.goal: Pose | None = None
        self.path: PlanResult | None = None
        self.last_failure: ReplanEvent | None = None
        self.events: deque[ReplanEvent] = deque(maxlen=EVENTS_KEPT)
        self.listeners: list[Callable[[ReplanEvent], None]] = []
        self.arrived = False
        self._planner: HybridAStar | None = None
        self._pending: list[CellRect] = []
        self._progress = _Progress()
        self._seq = 0
        self._last_plan_t = -math.inf
        self._sync_s = 0.0  # refresh time not yet reported by a replan
        self._sync_mode = ""
        self._blocked: int | None = None  # the blocked state of the path, for the replan it triggers

    # ------------------------------------------------------------------ inputs

    def set_pose(self, pose: Any, now_s: float | None = None, field: str = "pose") -> ReplanEvent | None:
        """The robot's current pose (x, y, yaw in the map frame, from odometry); replans on the timer. A bad pose
        is refused naming ``field``."""
        self.pose = _pose(pose, field)
        self._advance()
        if self.goal is not None and not self.arrived and self.policy.period_s is not None:
            now = self.clock() if now_s is None else now_s
            if now - self._last_plan_t >= self.policy.period_s:
                self._sync_s, self._sync_mode = 0.0, ""
                return self.replan("timer", time.perf_counter())
        return None

    def set_goal(self, goal: Any) -> ReplanEvent:
        """A new goal: plan to it from the current pose at once."""
        if self.pose is None:
            raise InvalidInput("pose", "the session has no pose yet: send the robot's pose before its goal")
        self.goal = _pose(goal, "goal")
        self.arrived = False
        self._sync_s, self._sync_mode = 0.0, ""
        return self.replan("goal", time.perf_counter())

    def observe(self, observation: Observation) -> tuple[MapUpdate, ReplanEvent | None]:
        """Apply an observation to the live map; replan when it blocks the rest of the path (or when the last
        plan failed and the map changed). Returns the map update and the replan, if one happened."""
        t0 = time.perf_counter()
        self._sync_s, self._sync_mode = 0.0, ""
        update = self.map.apply(observation)
        if update.changed is None:
            return update, None
        self._pending.extend(update.regions)
        if len(self._pending) > MAX_PENDING_REGIONS:
            union = self._pending[0]
            for rect in self._pending[1:]:
                union = union.union(rect)
            self._pending = [union]
        if self.goal is None or self.pose is None or self.arrived:
            return update, None
        if self.path is None:
            if self.clock() - self._last_plan_t < self.policy.retry_period_s:
                return update, None
            return update, self.replan("map_changed", t0)
        blocked = self.blocked_index()
        if blocked is None:
            return update, None
        xy = (float(self.path.states[blocked, 0]), float(self.path.states[blocked, 1]))
        self._blocked = blocked
        return update, self.replan("blocked", t0, blocked_at=xy)

    # ------------------------------------------------------------------ state

    @property
    def planner(self) -> HybridAStar:
        """The session's planner, refreshed for every map change so far."""
        self._sync()
        assert self._planner is not None
        return self._planner

    def _sync(self) -> None:
        """Build the planner, or refresh it for the cells changed since; the time is reported by the next replan."""
        if self._planner is None:
            t0 = time.perf_counter()
            self._planner = capped(HybridAStar(self.map.grid, self.robot, self.options))
            self._pending = []
            self._sync_s += time.perf_counter() - t0
            self._sync_mode = "built"
            return
        if not self._pending:
            return
        self._planner, took, how = refresh(self._planner, self._pending)
        self._pending = []
        self._sync_s += took
        self._sync_mode = how

    def remaining_states(self) -> np.ndarray:
        """The path's states (rows of ``planner.result.STATE_FIELDS``) from the robot's progress on."""
        if self.path is None:
            return np.zeros((0, 8))
        return self.path.states[self._progress.index:]

    def blocked_index(self) -> int | None:
        """Index (into the path's states) of the first state ahead whose footprint meets a blocked cell of the
        live map, or None while the rest of the path is free."""
        if self.path is None:
            return None
        planner = self.planner
        rest = self.remaining_states()
        if len(rest) == 0:
            return None
        margins = planner.clearance.footprint_margins(planner.footprint, planner.polygon, rest[:, :3])
        bad = np.flatnonzero(margins < 0)
        return None if bad.size == 0 else self._progress.index + int(bad[0])

    def _advance(self) -> None:
        """Move the progress index to the path state nearest the pose (never backwards by more than 1 m)."""
        if self.path is None or self.pose is None:
            return
        st = self.path.states
        i0 = self._progress.index
        s0 = st[i0, 6] - 1.0
        lo = int(np.searchsorted(st[:, 6], s0))
        d = np.hypot(st[lo:, 0] - self.pose[0], st[lo:, 1] - self.pose[1])
        self._progress.index = lo + int(np.argmin(d))
        if self.goal is not None and math.hypot(self.pose[0] - self.goal[0], self.pose[1] - self.goal[1]) <= \
                self.policy.arrival_tolerance_m and self._progress.index >= len(st) - 2:
            self.arrived = True

    # ------------------------------------------------------------------ planning

    def replan(self, reason: str, t_trigger: float | None = None,
               blocked_at: tuple[float, float] | None = None, time_limit_s: float | None = None) -> ReplanEvent:
        """Plan from the current pose to the goal now (within ``time_limit_s``, default the policy's); the event
        goes to every listener."""
        if reason not in REASONS:
            raise InvalidInput("reason", f"must be one of {', '.join(REASONS)}, got {reason!r}")
        if self.pose is None or self.goal is None:
            raise InvalidInput("goal" if self.goal is None else "pose", "the session needs a pose and a goal to plan")
        t0 = time.perf_counter() if t_trigger is None else t_trigger
        self._sync()
        assert self._planner is not None
        refresh_s, mode = self._sync_s, self._sync_mode
        self._sync_s, self._sync_mode = 0.0, ""
        self._seq += 1
        self._last_plan_t = self.clock()
        start = self.pose
        limit = self.policy.time_limit_s if time_limit_s is None else time_limit_s
        t_search = time.perf_counter()
        method = "ordinary"
        blocked, self._blocked = self._blocked, None
        splice = self._splice_index(blocked) if reason in ("blocked", "timer") else None
        spliced_m = 0.0
        try:
            if splice is not None:
                assert self.path is not None
                old, i = self.path.states, self._progress.index
                try:
                    x, y, yaw = (float(v) for v in old[splice, :3])
                    result, method = self._search((x, y, yaw), self.goal, SPLICE_SHARE * limit)
                except (BadEndpoint, PlannerCancelled, InvalidInput):
                    raise
                except PlanningError:
                    splice = None  # from the splice point nothing was found: try from where the robot is
                    left = max(limit - (time.perf_counter() - t_search), (1.0 - SPLICE_SHARE) * limit)
                    result, method = self._search(start, self.goal, left)
                else:
                    start = result.start
                    result = _spliced(old[i:splice + 1], result)
                    spliced_m = float(old[splice, 6] - old[i, 6])
            else:
                result, method = self._search(start, self.goal, limit)
        except PlanningError as exc:
            self.path = None
            self._progress = _Progress()
            event = ReplanEvent(self._seq, reason, False, exc.code, exc.msg, time.perf_counter() - t0, refresh_s,
                                time.perf_counter() - t_search, 0.0, start, blocked_at, mode, method)
            self.last_failure = event
        else:
            self.path = result
            self._progress = _Progress()
            self.last_failure = None
            event = ReplanEvent(self._seq, reason, True, 0, "", time.perf_counter() - t0, refresh_s,
                                time.perf_counter() - t_search, result.length_m, start, blocked_at, mode, method,
                                spliced_m)
        self.events.append(event)
        for listener in list(self.listeners):
            listener(event)
        return event

    def _splice_index(self, blocked: int | None) -> int | None:
        """The state of the path to plan from instead of the current pose (see ``ReplanPolicy.splice_lead_s``):
        ``splice_lead_s`` at the path's speed at the robot, then the braking distance, ahead; None when the robot
        is (nearly) still, the path stops on the way there, or that state is less than :data:`SPLICE_CLEAR_M`
        short of the blocked one."""
        if self.path is None or self.policy.splice_lead_s <= 0:
            return None
        st = self.path.states
        i = self._progress.index
        v = abs(float(st[i, 4]))
        ahead = v * self.policy.splice_lead_s + v * v / (2.0 * self.robot.max_accel_m_s2)
        if ahead < 0.05:
            return None
        end = float(st[-1, 6]) if blocked is None else float(st[blocked, 6]) - SPLICE_CLEAR_M
        target = float(st[i, 6]) + ahead
        if target > end:
            return None
        k = int(np.searchsorted(st[:, 6], target))
        if not i < k < len(st) - 1:
            return None
        # only across a stretch the robot rolls without stopping: a stop (a cusp, or the roll-in at the head of a
        # path spliced before) is where a new path may start from the robot itself, and splices must not pile up
        return k if bool(np.all(np.abs(st[i:k + 1, 4]) > 1e-6)) else None

    def _search(self, start: Pose, goal: Pose, limit: float) -> tuple[PlanResult, str]:
        """One search within ``limit`` seconds in all: the guided ones first (when the policy says so), then the
        ordinary one. Returns the path and the method that found it; raises the last search's error."""
        assert self._planner is not None
        pol = self.policy
        t0 = time.perf_counter()
        if pol.guided:
            for widen in pol.guide_levels_m:
                budget = limit * pol.guide_share - (time.perf_counter() - t0)
                if budget <= 0:
                    break
                try:
                    result = guided_plan(self._planner, start, goal,
                                         Termination(budget, max_iterations=pol.guide_expansions), widen)
                except (BadEndpoint, PlannerCancelled, InvalidInput):
                    raise  # the ordinary search would say the same
                except PlanningError:
                    continue  # proves nothing: a guide is not admissible everywhere
                return result, "guided" if widen == 0 else f"guided+{widen:g}m"
        rest = max(limit - (time.perf_counter() - t0), limit * (1.0 - pol.guide_share))
        return self._planner.plan(start, goal, Termination(rest)), "ordinary"

    def status(self) -> dict[str, Any]:
        """The session's state as JSON: pose, goal, path length and progress, the last replan, map knowledge."""
        last = self.events[-1].to_json() if self.events else None
        state = ("arrived" if self.arrived else "idle" if self.goal is None else
                 "following" if self.path is not None else
                 "blocked" if self.last_failure is not None and self.last_failure.error_code in
                 (StartOccupied.code, GoalOccupied.code) else "no_path")
        return {
            "state": state,
            "pose": None if self.pose is None else dict(zip(("x", "y", "yaw"), self.pose, strict=True)),
            "goal": None if self.goal is None else dict(zip(("x", "y", "yaw"), self.goal, strict=True)),
            "path_length_m": None if self.path is None else self.path.length_m,
            "path_index": self._progress.index,
            "replans": self._seq,
            "last_replan": last,
            "known_fraction": self.map.known_fraction(),
            "map_updates": self.map.updates,
        }


__all__ = ["LIVE_OPTION_DEFAULTS", "REASONS", "LiveSession", "ReplanEvent", "ReplanPolicy", "live_options"]
