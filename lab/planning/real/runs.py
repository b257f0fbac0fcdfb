"""Running one drawn problem: sphereplan, and OMPL BIT* on Dubins and Reeds–Shepp as the reference.

Every path (sphereplan's and BIT*'s) is re-checked with the referee's exact polygon on states at most half a
cell apart, and its true footprint clearance is measured with the same polygon.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from lab.planning.real.problems import RealProblem
from lab.planning.referee import FootprintReferee
from lab.planning.shipped import bounded_to, ompl_states
from planner.errors import (
    GoalOccupied,
    NoValidPathFound,
    PlannerTimedOut,
    PlanningError,
    StartOccupied,
)
from planner.hybrid_astar.plan import plan_path, planner_for
from planner.hybrid_astar.search import PlannerOptions
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile
from planner.termination import Termination

log = logging.getLogger(__name__)

Pose = tuple[float, float, float]


SPHEREPLAN = "sphereplan"
BIT_DUBINS = "bitstar-dubins"
BIT_REEDS_SHEPP = "bitstar-reeds-shepp"
REFERENCE_SPACES = {BIT_DUBINS: "dubins", BIT_REEDS_SHEPP: "reeds-shepp"}
# The room-matched reference (``bench --suite real --room-reference``): BIT* on sphereplan's space (Reeds–Shepp when it
# may reverse, else Dubins) with the footprint grown by the room sphereplan's path keeps (:func:`room_asked_m`), to its
# first solution. It is no solvability or length reference: only its time is compared (summary.py, ``x room``).
BIT_ROOM_DUBINS = "bitstar-room-dubins"
BIT_ROOM_REEDS_SHEPP = "bitstar-room-reeds-shepp"
ROOM_SPACES = {BIT_ROOM_DUBINS: "dubins", BIT_ROOM_REEDS_SHEPP: "reeds-shepp"}
SHORT_NAMES = {SPHEREPLAN: "sp", BIT_DUBINS: "D", BIT_REEDS_SHEPP: "RS", BIT_ROOM_DUBINS: "roomD",
               BIT_ROOM_REEDS_SHEPP: "roomRS"}
ROOM_SLACK_M = 0.005  # the room-matched reference keeps this much less than sphereplan's path (its grown polygon's
# chords and the densified check's spacing stay within it)


# ------------------------------------------------------------------------------------------------- running


@dataclass(frozen=True)
class RunRecord:
    """One problem × one planner: a row of the CSV (columns in field order; units in the names).

    ``status``: sphereplan ``solved``, ``timeout``, ``no_path``, ``start_refused``, ``goal_refused`` or
    ``error``; BIT* ``solved``, ``unsolved``, ``crashed`` (its child process died, e.g. a segfault inside
    OMPL; see :mod:`lab.planning.real.isolated`) or ``error`` (it raised). ``solved`` additionally needs the
    path to pass the exact polygon check (``valid``). ``time_s``: sphereplan's wall time of the call (success
    or failure); BIT*'s time to its first solution (the whole limit when it found none). ``first_length_m``:
    BIT*'s first solution; ``length_m``: the final path (BIT* after its whole budget). ``reference_length_m``: the
    shortest BIT* path among the spaces allowed to sphereplan's motions (Dubins; also Reeds–Shepp when it
    may reverse); ``length_ratio`` = ``length_m`` / it. ``min_clearance_m``: the padded footprint's exact
    distance to the nearest blocked cell or map edge along the path (capped at 1 m); ``reported_clearance_m``:
    what sphereplan's result says. ``expansions``: sphereplan's, from the result or the failure message (−1
    unknown). ``search_loop_s``: of sphereplan's time, the part in its compiled search loop (NaN unknown), the
    median over the runs as ``time_s`` is.
    ``shift_m``: the sideways shift of the final path's roll changes, radius × the total roll change (eq. 1):
    sphereplan's as it rolls it; for BIT*'s car path what a sphere would pay to roll it
    (:func:`rolled_shift_m`), which the car's length leaves out. ``first_shift_m``: the same of the first solution
    (sphereplan's: its one path's).
    """

    map: str
    problem: int
    start_x: float
    start_y: float
    start_yaw: float
    goal_x: float
    goal_y: float
    goal_yaw: float
    distance_m: float
    disconnected: bool
    planner: str
    status: str
    solved: bool
    time_s: float
    time_limit_s: float
    first_length_m: float
    length_m: float
    reference_length_m: float
    length_ratio: float
    min_clearance_m: float
    reported_clearance_m: float
    valid: bool
    reverses: bool
    expansions: int
    message: str
    search_loop_s: float = math.nan
    shift_m: float = math.nan
    first_shift_m: float = math.nan
    backwards_m: float = math.nan


CSV_COLUMNS = tuple(f.name for f in fields(RunRecord))


def _record(problem: RealProblem, planner: str, status: str, time_s: float, time_limit_s: float, *,
            valid: bool = False, first_length_m: float = math.nan, length_m: float = math.nan,
            min_clearance_m: float = math.nan, reported_clearance_m: float = math.nan, reverses: bool = False,
            expansions: int = -1, message: str = "", search_loop_s: float = math.nan,
            shift_m: float = math.nan, first_shift_m: float = math.nan, backwards_m: float = math.nan) -> RunRecord:
    return RunRecord(
        map=problem.map_name, problem=problem.index, start_x=problem.start[0], start_y=problem.start[1],
        start_yaw=problem.start[2], goal_x=problem.goal[0], goal_y=problem.goal[1], goal_yaw=problem.goal[2],
        distance_m=problem.distance_m, disconnected=problem.disconnected, planner=planner, status=status,
        solved=status == "solved" and valid, time_s=time_s, time_limit_s=time_limit_s,
        first_length_m=first_length_m, length_m=length_m, reference_length_m=math.nan, length_ratio=math.nan,
        min_clearance_m=min_clearance_m, reported_clearance_m=reported_clearance_m, valid=valid,
        reverses=reverses, expansions=expansions, message=message, search_loop_s=search_loop_s, shift_m=shift_m,
        first_shift_m=first_shift_m, backwards_m=backwards_m,
    )


def _wrapped(angles: np.ndarray) -> np.ndarray:
    """Angles (rad) moved by whole turns into [−π, π)."""
    return np.remainder(angles + math.pi, 2 * math.pi) - math.pi


def densify(poses: np.ndarray, spacing_m: float) -> np.ndarray:
    """Poses (n, ≥ 3: x, y, yaw) with extra poses interpolated so consecutive ones are ≤ ``spacing_m`` apart
    (x, y linearly; yaw along the shorter way round). Returns (m, 3)."""
    p = np.asarray(poses, dtype=float)[:, :3]
    if len(p) < 2:
        return p.copy()
    step = np.hypot(np.diff(p[:, 0]), np.diff(p[:, 1]))
    parts = np.maximum(1, np.ceil(step / spacing_m).astype(int))
    d_yaw = _wrapped(np.diff(p[:, 2]))
    out = [p[:1]]
    for i, k in enumerate(parts):
        t = (np.arange(1, k + 1) / k)[:, None]
        seg = p[i] + t * np.array([p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1], d_yaw[i]])
        out.append(seg)
    dense = np.concatenate(out)
    dense[:, 2] = _wrapped(dense[:, 2])
    return dense


def rolled_shift_m(poses: np.ndarray, robot: RobotProfile) -> float:
    """The sideways shift (m) a sphere pays to roll a car's path given as dense poses (x, y, yaw): radius × the
    total change of roll, each step held at the roll that turns with the step's curvature (its heading change ÷
    its signed length, so a step rolled backwards counts with the sign eq. 1 gives it), upright at both ends.
    The car's length leaves these shifts out; a sphere cannot (every turn starts and ends with a roll change)."""
    p = np.asarray(poses, dtype=float)[:, :3]
    if len(p) < 2:
        return 0.0
    d = np.diff(p[:, :2], axis=0)
    step = np.hypot(d[:, 0], d[:, 1])
    along = d[:, 0] * np.cos(p[:-1, 2]) + d[:, 1] * np.sin(p[:-1, 2])
    moving = step > 1e-9
    d_yaw = _wrapped(np.diff(p[:, 2]))
    kappa = d_yaw[moving] / np.where(along[moving] < 0.0, -step[moving], step[moving])
    kappa = np.clip(kappa, -robot.max_curvature, robot.max_curvature)
    return shift_of_rolls(np.asarray(robot.roll_model.roll_for_curvature(kappa), dtype=float), robot.radius_m)


def shift_of_rolls(rolls: np.ndarray, radius_m: float) -> float:
    """Sideways shift (m) of a sphere of ``radius_m`` holding ``rolls`` (rad) in turn, upright before and after:
    radius × the total roll change (eq. 1)."""
    held = np.asarray(rolls, dtype=float).reshape(-1)
    return float(radius_m * np.abs(np.diff(np.concatenate(([0.0], held, [0.0])))).sum())


def _reverses(poses: np.ndarray) -> bool:
    """Does the path move against its heading anywhere (by more than a millimetre)?"""
    d = np.diff(poses[:, :2], axis=0)
    along = d[:, 0] * np.cos(poses[:-1, 2]) + d[:, 1] * np.sin(poses[:-1, 2])
    return bool((along < -1e-3).any())


def room_asked_m(sphereplan: RunRecord, robot: RobotProfile) -> float:
    """The room the room-matched reference must keep on a problem sphereplan solved: what its path keeps (its true
    clearance), at most the robot's ``preferred_clearance_m`` (the room sphereplan asks for), less ROOM_SLACK_M;
    0 when that is negative or unknown."""
    keep = min(robot.preferred_clearance_m, sphereplan.min_clearance_m) - ROOM_SLACK_M
    return keep if math.isfinite(keep) and keep > 0 else 0.0


def room_space(reverse_allowed: bool) -> str:
    """The room-matched reference's planner name for sphereplan's motions."""
    return BIT_ROOM_REEDS_SHEPP if reverse_allowed else BIT_ROOM_DUBINS


def allows_reverse(options: PlannerOptions, robot: RobotProfile) -> bool:
    """Whether sphereplan may reverse with these options (``allow_reverse``; None means the profile's
    ``reversible``)."""
    value = getattr(options, "allow_reverse", False)
    return bool(robot.reversible if value is None else value)


def run_sphereplan(problem: RealProblem, grid: OccupancyGrid, robot: RobotProfile, checker: FootprintReferee,
                   options: PlannerOptions, time_limit_s: float, repeat: int = 1) -> RunRecord:
    """A ``plan_path`` call, timed by the wall clock, as the first plan towards its goal (the planner's cached
    holonomic tables dropped first); the path re-checked and measured with the polygon. With ``repeat`` > 1 a
    solved problem is planned that many times in all and its time is the median (the path is the first's: the
    search is deterministic), and so is the time in its compiled search loop."""
    planner_for(grid, robot, options).forget_heuristics()
    t0 = time.perf_counter()
    try:
        result = plan_path(grid, robot, problem.start, problem.goal, options, Termination(time_limit_s))
    except PlanningError as exc:
        elapsed = time.perf_counter() - t0
        if isinstance(exc, StartOccupied):
            status = "start_refused"
        elif isinstance(exc, GoalOccupied):
            status = "goal_refused"
        elif isinstance(exc, PlannerTimedOut):
            status = "timeout"
        elif isinstance(exc, NoValidPathFound):
            status = "no_path"
        else:
            status = "error"
        log.info("%s sphereplan %s after %.3f s: %s", problem.name, status, elapsed, exc.msg)
        return _record(problem, SPHEREPLAN, status, elapsed, time_limit_s,
                       expansions=exc.expansions, message=exc.msg)
    times = [time.perf_counter() - t0]
    loops = [float(result.extra.get("search_loop_time_s", math.nan))]
    for _ in range(repeat - 1):
        planner_for(grid, robot, options).forget_heuristics()
        t0 = time.perf_counter()
        try:  # the search is deterministic, but a repeat near the time limit can run out of it
            again = plan_path(grid, robot, problem.start, problem.goal, options, Termination(time_limit_s))
            loops.append(float(again.extra.get("search_loop_time_s", math.nan)))
        except PlanningError as exc:
            log.warning("%s sphereplan: repeat %d of %d failed (%s); its time counts", problem.name, len(times) + 1,
                        repeat, exc.msg)
        times.append(time.perf_counter() - t0)
    elapsed = float(np.median(times))
    # the loop's time as the call's: the median over the runs (the first alone runs with the caches as the reference
    # planner left them, and the expansions are the same in every run)
    known = [s for s in loops if math.isfinite(s)]
    loop_s = float(np.median(known)) if known else math.nan
    dense = densify(result.states[:, :3], 0.5 * grid.resolution_m)
    hits = checker.collides_many(dense)
    valid = not bool(hits.any())
    message = "" if valid else f"the padded footprint meets an obstacle at {int(hits.sum())} of {len(dense)} poses"
    shift = shift_of_rolls(result.states[:, 3], robot.radius_m)
    log.info("%s sphereplan solved in %.3f s, %.2f m%s", problem.name, elapsed, result.length_m,
             "" if valid else " (" + message + ")")
    return _record(problem, SPHEREPLAN, "solved", elapsed, time_limit_s, valid=valid,
                   first_length_m=result.length_m, length_m=result.length_m,
                   min_clearance_m=checker.min_clearance(dense), reported_clearance_m=result.min_clearance_m,
                   reverses=bool((result.states[:, 4] < 0).any()), expansions=int(result.expansions),
                   message=message, search_loop_s=loop_s, shift_m=shift, first_shift_m=shift,
                   backwards_m=float(result.extra.get("reverse_length_m", math.nan)))  # as the plan reports it


def run_reference(problem: RealProblem, grid: OccupancyGrid, robot: RobotProfile, checker: FootprintReferee,
                  planner: str, time_limit_s: float, optimise_s: float | None = None,
                  on_first: Callable[[float, float], None] | None = None) -> RunRecord:
    """OMPL BIT* (``planner`` = :data:`BIT_DUBINS` or :data:`BIT_REEDS_SHEPP`, or a room-matched one of
    :data:`ROOM_SPACES` with ``checker`` grown by the room: :meth:`FootprintReferee.grown`) at the robot's minimum
    turning radius with the exact polygon validity check of ``checker``: time to the first solution (at most
    ``time_limit_s``), then optimising until ``optimise_s`` in all (default ``time_limit_s``); motions are checked
    every half cell of arc length. ``on_first(time_s, length_m)`` is called as soon as the first solution is known
    (a parent process learns it even if OMPL then crashes while optimising)."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    from lab.planning.referee import _collides_pose

    ou.setLogLevel(ou.LOG_ERROR)
    rho = robot.min_turning_radius_m
    dubins = planner in (BIT_DUBINS, BIT_ROOM_DUBINS)
    space = bounded_to(ob.DubinsStateSpace(rho) if dubins else ob.ReedsSheppStateSpace(rho), grid)
    setup = og.SimpleSetup(space)
    poly, blocked = checker.polygon, checker.blocked
    ox, oy, res, reach = checker.origin_xy[0], checker.origin_xy[1], checker.resolution_m, checker.circumradius_m

    def valid(state: Any) -> bool:
        return not _collides_pose(poly, state.getX(), state.getY(), state.getYaw(), blocked, ox, oy, res, reach)

    setup.setStateValidityChecker(valid)
    info = setup.getSpaceInformation()
    info.setStateValidityCheckingResolution(0.5 * res / space.getMaximumExtent())
    start, goal = ompl_states(space, problem.start, problem.goal)
    setup.setStartAndGoalStates(start, goal, 0.01)
    pdef = setup.getProblemDefinition()
    bit = og.BITstar(info)
    bit.setStopOnSolnImprovement(True)  # BIT* publishes a solution when solve() returns: stop at the first
    setup.setPlanner(bit)
    t0 = time.perf_counter()
    setup.solve(time_limit_s)
    first = time.perf_counter() - t0
    if not pdef.hasExactSolution():
        log.info("%s %s: no solution in %.1f s", problem.name, planner, time_limit_s)
        return _record(problem, planner, "unsolved", time_limit_s, time_limit_s, message="no solution in time")
    first_length = float(setup.getSolutionPath().length())
    if on_first is not None:
        on_first(first, first_length)
    # what a sphere would pay to roll the first solution (after its time was taken; OMPL's own path object is
    # replaced by the optimisation below, so a copy is interpolated)
    first_shift = rolled_shift_m(_dense_poses(og.PathGeometric(setup.getSolutionPath()), res), robot)
    bit.setStopOnSolnImprovement(False)
    budget = time_limit_s if optimise_s is None else optimise_s
    if budget - first > 0.05:
        setup.solve(budget - first)
    path = setup.getSolutionPath()
    length = float(path.length())
    dense = _dense_poses(path, res)
    hits = checker.collides_many(dense)
    ok = not bool(hits.any())
    log.info("%s %s: first %.3f s (%.2f m), final %.2f m", problem.name, planner, first, first_length, length)
    return _record(problem, planner, "solved", first, time_limit_s, valid=ok, first_length_m=first_length,
                   length_m=length, min_clearance_m=checker.min_clearance(dense), reverses=_reverses(dense),
                   message="" if ok else f"path meets an obstacle at {int(hits.sum())} interpolated poses",
                   shift_m=rolled_shift_m(dense, robot), first_shift_m=first_shift)


def _dense_poses(path: Any, res: float) -> np.ndarray:
    """An OMPL geometric path's poses (x, y, yaw) at most half a cell apart (the path is interpolated in place)."""
    path.interpolate(max(2, math.ceil(float(path.length()) / (0.5 * res)) + 1))
    poses = np.array([[path.getState(i).getX(), path.getState(i).getY(), path.getState(i).getYaw()]
                      for i in range(path.getStateCount())])
    return densify(poses, 0.5 * res)


def with_reference_lengths(records: Sequence[RunRecord], reverse_allowed: bool) -> list[RunRecord]:
    """Fill ``reference_length_m`` and ``length_ratio`` of every record of each problem: the shortest solved
    BIT* path among Dubins (and Reeds–Shepp when sphereplan may reverse)."""
    spaces = {BIT_DUBINS, BIT_REEDS_SHEPP} if reverse_allowed else {BIT_DUBINS}
    best: dict[tuple[str, int], float] = {}
    for r in records:
        if r.planner in spaces and r.solved:
            key = (r.map, r.problem)
            best[key] = min(best.get(key, math.inf), r.length_m)
    out = []
    for r in records:
        ref = best.get((r.map, r.problem), math.nan)
        out.append(replace(r, reference_length_m=ref, length_ratio=r.length_m / ref if r.solved else math.nan))
    return out


