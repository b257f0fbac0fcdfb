"""Exploration in simulation: roll the sphere through a true world the planner only partly knows.

:func:`explore` is the loop a robot session runs, closed in simulation (issue 22). The planner starts from
KNOWN (a map with some of the world's obstacles missing: boxes, a blocked aisle, a closed door) and learns
the rest from a simulated range sensor (:class:`planner.live.range_sensor.RangeSensor`) ray-cast in TRUE
from the sphere's *true* pose at ``sensor_rate_hz``, through Nav2's obstacle-layer filters with paper 001's
height and range limits. Each sweep goes to a :class:`planner.live.session.LiveSession`, which replans from
the current pose when the rest of the path is blocked. Between sweeps the tracker (paper 001's eq. 15 MPC
with its pure-pursuit fallback, or pure pursuit alone) rolls the sphere along the current path through the
eq. 1 simulator with its actuator limits (:class:`planner.closed_loop.simulator.SphereSimulator`); the
tracker is given the true pose (localisation is :func:`planner.closed_loop.simulate.simulate_plan`'s
subject, not this one's).

Outcomes: ``reached`` (the true centre ends within ``goal_tolerance_m`` of the goal), ``collided`` (the
true footprint met a blocked cell of TRUE: the run stops there), ``no_path`` (the planner found no path on
what it knows and nothing new can be seen from where the robot stopped) or ``timeout`` (simulated time ran
out). Every random draw (sensor noise) comes from ``seed``.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from planner.closed_loop.simulator import SphereSimulator
from planner.closed_loop.tracker import (
    Command,
    Estimate,
    MPCTracker,
    ObstacleCircles,
    PurePursuitTracker,
    ReferencePath,
)
from planner.errors import InvalidInput, PlannerTimedOut, PlanningError
from planner.hybrid_astar.search import HybridAStar, PlannerOptions, Pose
from planner.kinematics import SphereState, wrap
from planner.live.live_map import LiveMap
from planner.live.obstacle_layer import ObstacleLayerParams
from planner.live.range_sensor import RangeSensor
from planner.live.session import LiveSession, ReplanEvent, ReplanPolicy, live_options
from planner.maps.clearance import ClearanceMap, least_footprint_distance
from planner.occupancy import OccupancyGrid
from planner.result import STATE_FIELDS
from planner.robot import RobotProfile
from planner.termination import Termination

OUTCOMES = ("reached", "collided", "no_path", "timeout")
MAX_SNAPSHOTS = 6
"""Live-map pictures kept for the plot (the first, the last and evenly chosen replans between)."""


@dataclass(frozen=True)
class ExploreOptions:
    """Settings of one exploration run. ``time_limit_s`` None = 3 × the straight start–goal distance at
    cruise speed + 60 s of simulated time; ``max_stalled_sweeps``: sweeps the robot may stand still
    without a path (each failed replan retried when the map changed) before the run ends as ``no_path``; a
    replan that ran out of its ``plan_time_limit_s`` (which proves nothing) is first retried up to
    ``timeout_retries`` times with twice, four times ... the limit."""

    sensor: RangeSensor = field(default_factory=RangeSensor)
    sensor_rate_hz: float = 5.0
    control_rate_hz: float = 20.0
    tracker: str = "mpc"
    time_limit_s: float | None = None
    replan_period_s: float | None = None
    plan_time_limit_s: float = 5.0
    goal_tolerance_m: float = 0.25
    max_stalled_sweeps: int = 10
    timeout_retries: int = 2
    planner: PlannerOptions = field(default_factory=live_options)

    def __post_init__(self) -> None:
        if self.tracker not in ("mpc", "pursuit"):
            raise InvalidInput("tracker", f"must be 'mpc' or 'pursuit', got {self.tracker!r}")
        for name in ("sensor_rate_hz", "control_rate_hz", "plan_time_limit_s", "goal_tolerance_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise InvalidInput(name, f"must be a finite number > 0, got {value!r}")
        if self.control_rate_hz < self.sensor_rate_hz:
            raise InvalidInput("control_rate_hz", "must be at least the sensor rate")
        if self.time_limit_s is not None and not (math.isfinite(self.time_limit_s) and 0 < self.time_limit_s <= 7200):
            raise InvalidInput("time_limit_s", f"must be in (0, 7200] s of simulated time, got {self.time_limit_s!r}")


def same_geometry(a: OccupancyGrid, b: OccupancyGrid) -> bool:
    """Do two grids cover the same cells (size, resolution, origin)?"""
    return a.data.shape == b.data.shape and math.isclose(a.resolution_m, b.resolution_m) and \
        bool(np.allclose(a.origin, b.origin))


def _percentile(values: list[float], q: float) -> float | None:
    return float(np.percentile(values, q)) if values else None


def known_world_length(world: OccupancyGrid, robot: RobotProfile, start: Pose, goal: Pose,
                       options: PlannerOptions, time_limit_s: float) -> float | None:
    """Length (m) of the plan with TRUE known from the start (the yardstick of the driven length), or None
    when TRUE has no path (or the planner gave up): ``options`` with the one-off planner's settings where a live
    session's differ (no unknown space, the default ``greed``), so a faster replan search cannot move it."""
    opts = replace(options, allow_unknown=False, greed=PlannerOptions().greed)
    try:
        return HybridAStar(world, robot, opts).plan(start, goal, Termination(time_limit_s)).length_m
    except PlanningError:
        return None


def _reference(session: LiveSession) -> ReferencePath | None:
    if session.path is None:
        return None
    states = session.path.states
    rows = [dict(zip(STATE_FIELDS, map(float, row), strict=True)) for row in states]
    return ReferencePath(rows)


def explore(known: OccupancyGrid, world: OccupancyGrid, robot: RobotProfile, start: Pose, goal: Pose,
            options: ExploreOptions | None = None, seed: int = 0) -> dict[str, Any]:
    """Run one exploration (see the module docstring); returns the EXPLORE.json dict (``metrics``,
    ``outcome``, ``replans``, ``trajectory``, ``paths``) and, under ``"_snapshots"``, the live map at a few
    moments as (t, int8 array) pairs for the plot (not JSON: :func:`explore_json` drops it)."""
    opts = options or ExploreOptions()
    if not same_geometry(known, world):
        raise InvalidInput("world", f"must cover the same cells as the known map ({known.width}×{known.height} at "
                                    f"{known.resolution_m} m, origin {list(known.origin)}); got {world.width}×"
                                    f"{world.height} at {world.resolution_m} m, origin {list(world.origin)}")
    for name, pose in (("start", start), ("goal", goal)):
        if not world.contains(pose[0], pose[1]):
            raise InvalidInput(name, f"({pose[0]}, {pose[1]}) is outside the world map")
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    t_sim = 0.0
    layer = ObstacleLayerParams.for_robot(robot, opts.sensor.range_m)
    live = LiveMap(known, layer)
    session = LiveSession(live, robot, opts.planner,
                          ReplanPolicy(opts.replan_period_s, opts.plan_time_limit_s, opts.goal_tolerance_m),
                          clock=lambda: t_sim)
    truth = ClearanceMap(world)
    polygon = robot.footprint_polygon
    length_known = known_world_length(world, robot, start, goal, opts.planner, max(5.0, opts.plan_time_limit_s))

    dt = 1.0 / opts.control_rate_hz
    sweep_every = max(1, round(opts.control_rate_hz / opts.sensor_rate_hz))
    cruise = robot.max_speed_m_s
    limit = opts.time_limit_s if opts.time_limit_s is not None else \
        3.0 * math.hypot(goal[0] - start[0], goal[1] - start[1]) / cruise + 60.0
    sim = SphereSimulator(robot)
    pursuit = PurePursuitTracker(robot)
    state = SphereState(float(start[0]), float(start[1]), wrap(float(start[2])), 0.0, 0.0)

    events: list[tuple[float, ReplanEvent]] = []
    paths: list[dict[str, Any]] = []
    snapshots: list[tuple[float, np.ndarray]] = [(0.0, live.data.copy())]
    update_s: list[float] = []
    traj: list[tuple[float, ...]] = []
    ref: ReferencePath | None = None
    mpc: MPCTracker | None = None
    seg_i = 0
    s_proj = 0.0
    stalled = 0
    retries = 0
    outcome = "timeout"

    def adopt(event: ReplanEvent | None) -> None:
        nonlocal ref, mpc, seg_i, s_proj
        if event is None:
            return
        events.append((t_sim, event))
        if snapshots[-1][0] == t_sim:
            snapshots.pop()
        snapshots.append((t_sim, live.data.copy()))
        ref = _reference(session)
        seg_i, s_proj = 0, 0.0
        if ref is not None:
            xy = session.path.states[:, :2] if session.path is not None else np.zeros((0, 2))
            paths.append({"t": round(t_sim, 3), "seq": event.seq, "reason": event.reason,
                          "xy": np.round(xy[:: max(1, len(xy) // 400)], 3).tolist()})
            if opts.tracker == "mpc":
                mpc = MPCTracker(robot, obstacles=ObstacleCircles(live.snapshot()))

    def sweep() -> None:
        pose = (state.x, state.y, wrap(state.yaw))
        scan = opts.sensor.scan(world, pose, rng)
        session.set_pose(pose, t_sim)
        update, event = session.observe(scan)
        update_s.append(update.time_s)
        adopt(event)

    sweep()
    adopt(session.set_goal(goal))
    k = 0
    while True:
        t_sim = k * dt
        traj.append((t_sim, state.x, state.y, state.yaw, state.roll, state.v))
        if float(truth.footprint_distances(polygon, np.array([[state.x, state.y, state.yaw]]), 0.05)[0]) <= 0.0:
            outcome = "collided"
            break
        if math.hypot(state.x - goal[0], state.y - goal[1]) <= opts.goal_tolerance_m and abs(state.v) < 1e-3 and \
                (ref is None or seg_i == len(ref.segments) - 1):
            outcome = "reached"
            break
        if t_sim >= limit:
            break
        if k > 0 and k % sweep_every == 0:
            sweep()
            adopt(session.set_pose((state.x, state.y, wrap(state.yaw)), t_sim))
            failure = session.last_failure
            stopped = ref is None and abs(state.v) < 1e-3
            if stopped and failure is not None and failure.error_code == PlannerTimedOut.code and \
                    retries < opts.timeout_retries:
                # the search ran out of time, which proves nothing: try again with twice the time
                retries += 1
                adopt(session.replan("request", time_limit_s=opts.plan_time_limit_s * 2 ** retries))
                stopped = ref is None
            if ref is not None:
                retries = 0
            stalled = stalled + 1 if stopped else 0
            if stalled >= opts.max_stalled_sweeps:
                outcome = "no_path"
                break
        cmd = Command(0.0, 0.0)
        if ref is not None:
            seg = ref.segments[seg_i]
            est = Estimate(state.x, state.y, state.yaw, state.roll, state.v)
            s_proj = seg.project(est.x, est.y, s_proj)
            to_go = seg.length_m - s_proj
            if to_go <= 0.01 or (to_go < 0.5 and seg.remaining(est.x, est.y) <= 0.01):
                cmd = Command(0.0, float(seg.roll[-1]))
                if abs(state.v) < 1e-3 and seg_i + 1 < len(ref.segments):
                    seg_i += 1
                    s_proj = 0.0
                    if mpc is not None:
                        mpc.reset()
            elif mpc is not None:
                cmd = mpc.command(est, seg, s_proj)
                if not cmd.ok:
                    cmd = pursuit.command(est, seg, s_proj)
            else:
                cmd = pursuit.command(est, seg, s_proj)
        state = sim.step(state, cmd.v, cmd.roll, dt).state
        k += 1

    tr = np.array(traj)
    driven = float(np.hypot(*np.diff(tr[:, 1:3], axis=0).T).sum()) if len(tr) > 1 else 0.0
    replans = [e for _, e in events if e.reason != "goal"]
    latencies = [e.latency_s for e in replans]
    snapshots.append((t_sim, live.data.copy()))
    if len(snapshots) > MAX_SNAPSHOTS:
        pick = np.unique(np.linspace(0, len(snapshots) - 1, MAX_SNAPSHOTS).round().astype(int))
        snapshots = [snapshots[i] for i in pick]
    clearance = least_footprint_distance(world, robot, tr[:, 1:4]) if len(tr) else 0.0
    final = events[-1][1] if events else None
    metrics = {
        "reached_goal": outcome == "reached",
        "collided": outcome == "collided" or clearance <= 0.0,
        "no_path": outcome == "no_path",
        "replans": len(replans),
        "replan_latency_p50_s": _percentile(latencies, 50),
        "replan_latency_p95_s": _percentile(latencies, 95),
        "replan_latency_max_s": max(latencies) if latencies else None,
        "replan_reasons": dict(Counter(e.reason for e in replans)),
        "replans_failed": sum(not e.ok for e in replans),
        "replan_methods": dict(Counter(e.method for e in replans if e.ok)),
        "map_update_p50_s": _percentile(update_s, 50),
        "map_update_p95_s": _percentile(update_s, 95),
        "sweeps": len(update_s),
        "length_m": driven,
        "length_known_world_m": length_known,
        "length_ratio": driven / length_known if length_known and outcome == "reached" else None,
        "true_world_has_path": length_known is not None,
        "min_clearance_m": clearance,
        "duration_s": float(tr[-1, 0]) if len(tr) else 0.0,
        "final_distance_to_goal_m": float(math.hypot(state.x - goal[0], state.y - goal[1])),
        "known_fraction": live.known_fraction(),
    }
    return {
        "outcome": outcome,
        "error_msg": "" if final is None or final.ok else final.error_msg,
        "robot": robot.to_json(),
        "seed": seed,
        "tracker": opts.tracker,
        "sensor": {"range_m": opts.sensor.range_m, "n_beams": opts.sensor.n_beams, "rate_hz": opts.sensor_rate_hz,
                   "height_m": opts.sensor.height_m, "noise_m": opts.sensor.noise_m},
        "start": {"x": start[0], "y": start[1], "yaw": start[2]},
        "goal": {"x": goal[0], "y": goal[1], "yaw": goal[2]},
        "metrics": metrics,
        "replans": [{"t": round(t, 3), **e.to_json()} for t, e in events],
        "paths": paths,
        "trajectory": [dict(zip(("t", "x", "y", "yaw", "roll", "v"), (round(float(v), 4) for v in row), strict=True))
                       for row in tr[:: max(1, sweep_every // 2)]],
        "_snapshots": snapshots,
    }


def explore_json(result: dict[str, Any]) -> dict[str, Any]:
    """The JSON part of an :func:`explore` result (without the map snapshots)."""
    return {k: v for k, v in result.items() if not k.startswith("_")}


__all__ = ["OUTCOMES", "ExploreOptions", "explore", "explore_json", "known_world_length", "same_geometry"]
