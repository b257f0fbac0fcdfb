"""The real-map benchmark: seeded random problems on Nav2's maps, sphereplan against OMPL BIT* as reference.

``sphereplan bench --suite real`` runs this module (docs/planning.md, "The real-map benchmark"). Problems are
drawn the way Nav2's planner benchmark (``tools/planner_benchmarking/metrics.py``) draws them, with the
robot's real footprint: a uniformly random cell away from the map's border and a uniformly random yaw for the
start, then the same for the goal at least a minimum distance away; a draw is kept only when the padded
footprint polygon (:attr:`~planner.robot.RobotProfile.footprint_polygon`) is free there by the exact check of
:mod:`planner.hybrid_astar.bench_polygon`. Every problem also gets a proof of unreachability where one is
cheap: start and goal in different connected parts of the space the footprint's inscribed disc can reach.

Each problem is given to sphereplan (:func:`planner.hybrid_astar.plan.plan_path`, default options unless told
otherwise) and to OMPL's BIT* on a Dubins and a Reeds–Shepp state space at the robot's minimum turning radius
with the exact polygon validity check, each with the same time limit. BIT* is the solvability and length
reference: its first-solution time is the time to beat, its length after the full time limit the length to
match. Every path (sphereplan's and BIT*'s) is re-checked with the exact polygon on states at most half a
cell apart, and its true footprint clearance is measured with the same polygon.
"""

from __future__ import annotations

import csv
import logging
import math
import re
import statistics
import textwrap
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy import ndimage

from planner.errors import (
    GoalOccupied,
    InvalidInput,
    PlannerTimedOut,
    PlanningError,
    StartOccupied,
)
from planner.hybrid_astar.bench import bounded_to
from planner.hybrid_astar.bench_polygon import PolygonChecker
from planner.hybrid_astar.plan import plan_path, planner_for
from planner.hybrid_astar.search import PlannerOptions
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile

log = logging.getLogger(__name__)

Pose = tuple[float, float, float]

REAL_MAPS = ("warehouse", "depot", "smoothers_world", "100by100_20")
SPHEREPLAN = "sphereplan"
BIT_DUBINS = "bitstar-dubins"
BIT_REEDS_SHEPP = "bitstar-reeds-shepp"
REFERENCE_SPACES = {BIT_DUBINS: "dubins", BIT_REEDS_SHEPP: "reeds-shepp"}
SHORT_NAMES = {SPHEREPLAN: "sp", BIT_DUBINS: "D", BIT_REEDS_SHEPP: "RS"}
BIG_MAP_CELLS = 1_000_000  # maps at least this large get the longer default time limit
DEFAULT_TIME_LIMIT_S = 5.0
DEFAULT_TIME_LIMIT_BIG_S = 10.0
_EXPANSIONS = re.compile(r"\((\d+) expansions\)")


def real_maps_dir() -> Path:
    """The folder of the shipped Nav2 maps, ``<maps>/real`` (see ``maps/real/README.md``)."""
    from planner.maps.catalogue import default_maps_dir

    return default_maps_dir() / "real"


def default_time_limit_s(grid: OccupancyGrid) -> float:
    """The default time limit (s) for a map: 10 s from a million cells up, 5 s below."""
    return DEFAULT_TIME_LIMIT_BIG_S if grid.width * grid.height >= BIG_MAP_CELLS else DEFAULT_TIME_LIMIT_S


# ------------------------------------------------------------------------------------------------ problems


@dataclass(frozen=True)
class DrawSettings:
    """How problems are drawn (Nav2's benchmark, scaled to the map).

    Parameters
    ----------
    border_fraction : float
        Start and goal cells keep this fraction of the map's smaller side (in cells) from every border; Nav2
        uses 100 cells on its 2000-cell field, i.e. 0.05.
    min_distance_fraction : float
        The goal lies at least this fraction of the map's smaller side (m) from the start ...
    min_distance_floor_m : float
        ... and never less than this (m); Nav2 uses 3 m.
    max_draws : int
        Give up (``InvalidInput``) after this many rejected draws for one pose.
    """

    border_fraction: float = 0.05
    min_distance_fraction: float = 0.2
    min_distance_floor_m: float = 3.0
    max_draws: int = 200_000

    def border_cells(self, grid: OccupancyGrid) -> int:
        """Cells kept clear of each border by the drawn cells."""
        return max(1, round(self.border_fraction * min(grid.width, grid.height)))

    def min_distance_m(self, grid: OccupancyGrid) -> float:
        """Smallest start–goal distance (m) on this map."""
        return max(self.min_distance_floor_m, self.min_distance_fraction * min(grid.size_m))


@dataclass(frozen=True)
class RealProblem:
    """One drawn problem. Poses are (x m, y m, yaw rad in [−π, π)) in the map frame.

    ``disconnected`` is a proof that no motion joins start and goal: the positions where even the
    footprint's inscribed disc is free fall apart into pieces, and the two lie in different pieces.
    """

    map_name: str
    index: int
    start: Pose
    goal: Pose
    distance_m: float
    disconnected: bool

    @property
    def name(self) -> str:
        return f"{self.map_name}#{self.index}"


def disc_components(grid: OccupancyGrid, checker: PolygonChecker) -> np.ndarray:
    """Labels (height, width) of the 8-connected pieces of cells that may hold a free inscribed-disc centre.

    A cell is kept when its centre is at least ``r_in − res·√2/2`` from every blocked cell centre and from
    the map's outside (``r_in``: the polygon's inradius). That is a superset of the cells containing a
    position where the disc — and so a fortiori the footprint — is free, and any continuous motion passes
    through 8-adjacent kept cells; so different labels at start and goal prove the problem unsolvable.
    Label 0 is "not kept".
    """
    padded = np.pad(checker.blocked, 1, constant_values=True)
    dist = ndimage.distance_transform_edt(~padded)[1:-1, 1:-1] * grid.resolution_m
    kept = dist >= checker.inradius_m - grid.resolution_m * math.sqrt(0.5)
    labels, _ = ndimage.label(kept, structure=np.ones((3, 3), dtype=bool))
    return np.asarray(labels)


def _cell_of(grid: OccupancyGrid, pose: Pose) -> tuple[int, int]:
    ix, iy = grid.world_to_cell(pose[0], pose[1])
    return iy, ix


def _draw_pose(grid: OccupancyGrid, checker: PolygonChecker, rng: np.random.Generator, border: int,
               settings: DrawSettings, away_from: Pose | None = None, min_distance_m: float = 0.0) -> Pose:
    """A uniformly random free cell centre inside the border band with a uniformly random yaw whose padded
    footprint is free (and, with ``away_from``, at least ``min_distance_m`` from it)."""
    res = grid.resolution_m
    ox, oy = grid.origin[0], grid.origin[1]
    blocked = checker.blocked
    for _ in range(settings.max_draws):
        row = int(rng.integers(border, grid.height - border))
        col = int(rng.integers(border, grid.width - border))
        yaw = float(rng.uniform(-math.pi, math.pi))
        if blocked[row, col]:
            continue
        x, y = ox + (col + 0.5) * res, oy + (row + 0.5) * res
        if away_from is not None and math.hypot(x - away_from[0], y - away_from[1]) < min_distance_m:
            continue
        if not checker.collides(x, y, yaw):
            return x, y, yaw
    what = "a goal" if away_from is not None else "a start"
    raise InvalidInput("maps", f"could not draw {what} with a free footprint on {grid.name!r} in "
                               f"{settings.max_draws} draws (map too small or too full?)")


def draw_problems(grid: OccupancyGrid, robot: RobotProfile, n: int, rng: np.random.Generator, *,
                  map_name: str | None = None, allow_unknown: bool = False,
                  settings: DrawSettings | None = None,
                  checker: PolygonChecker | None = None) -> list[RealProblem]:
    """Draw ``n`` problems on ``grid`` with ``rng`` (the same generator state gives the same problems).

    Parameters
    ----------
    grid : the map.
    robot : its footprint polygon (padding included) must be free at every start and goal.
    n : number of problems.
    rng : the only source of randomness.
    map_name : label of the problems (default ``grid.name``).
    allow_unknown : unknown cells do not block (the planner's option of the same name).
    settings : border, minimum distance, draw cap (default :class:`DrawSettings`).
    checker : a :class:`PolygonChecker` for this grid and robot, if one exists already.
    """
    if n < 1:
        raise InvalidInput("--per-map", f"must be ≥ 1, got {n}")
    s = settings or DrawSettings()
    check = checker or PolygonChecker.for_robot(grid, robot, allow_unknown)
    border = s.border_cells(grid)
    if 2 * border >= min(grid.width, grid.height):
        raise InvalidInput("maps", f"{grid.name!r} is too small for a {border}-cell border")
    min_d = s.min_distance_m(grid)
    labels = disc_components(grid, check)
    out: list[RealProblem] = []
    for i in range(n):
        start = _draw_pose(grid, check, rng, border, s)
        goal = _draw_pose(grid, check, rng, border, s, away_from=start, min_distance_m=min_d)
        disconnected = bool(labels[_cell_of(grid, start)] != labels[_cell_of(grid, goal)])
        out.append(RealProblem(map_name or grid.name, i, start, goal,
                               math.hypot(goal[0] - start[0], goal[1] - start[1]), disconnected))
    return out


# ------------------------------------------------------------------------------------------------- running


@dataclass(frozen=True)
class RunRecord:
    """One problem × one planner: a row of the CSV (columns in field order; units in the names).

    ``status``: sphereplan ``solved``, ``timeout``, ``no_path``, ``start_refused``, ``goal_refused`` or
    ``error``; BIT* ``solved`` or ``unsolved``. ``solved`` additionally needs the path to pass the exact
    polygon check (``valid``). ``time_s``: sphereplan's wall time of the call (success or failure); BIT*'s
    time to its first solution (the whole limit when it found none). ``first_length_m``: BIT*'s first
    solution; ``length_m``: the final path (BIT* after the whole limit). ``reference_length_m``: the
    shortest BIT* path among the spaces allowed to sphereplan's motions (Dubins; also Reeds–Shepp when it
    may reverse); ``length_ratio`` = ``length_m`` / it. ``min_clearance_m``: the padded footprint's exact
    distance to the nearest blocked cell or map edge along the path (capped at 1 m); ``reported_clearance_m``:
    what sphereplan's result says. ``expansions``: sphereplan's, from the result or the failure message (−1
    unknown).
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


CSV_COLUMNS = tuple(f.name for f in fields(RunRecord))


def _record(problem: RealProblem, planner: str, status: str, time_s: float, time_limit_s: float, *,
            valid: bool = False, first_length_m: float = math.nan, length_m: float = math.nan,
            min_clearance_m: float = math.nan, reported_clearance_m: float = math.nan, reverses: bool = False,
            expansions: int = -1, message: str = "") -> RunRecord:
    return RunRecord(
        map=problem.map_name, problem=problem.index, start_x=problem.start[0], start_y=problem.start[1],
        start_yaw=problem.start[2], goal_x=problem.goal[0], goal_y=problem.goal[1], goal_yaw=problem.goal[2],
        distance_m=problem.distance_m, disconnected=problem.disconnected, planner=planner, status=status,
        solved=status == "solved" and valid, time_s=time_s, time_limit_s=time_limit_s,
        first_length_m=first_length_m, length_m=length_m, reference_length_m=math.nan, length_ratio=math.nan,
        min_clearance_m=min_clearance_m, reported_clearance_m=reported_clearance_m, valid=valid,
        reverses=reverses, expansions=expansions, message=message,
    )


def densify(poses: np.ndarray, spacing_m: float) -> np.ndarray:
    """Poses (n, ≥ 3: x, y, yaw) with extra poses interpolated so consecutive ones are ≤ ``spacing_m`` apart
    (x, y linearly; yaw along the shorter way round). Returns (m, 3)."""
    p = np.asarray(poses, dtype=float)[:, :3]
    if len(p) < 2:
        return p.copy()
    step = np.hypot(np.diff(p[:, 0]), np.diff(p[:, 1]))
    parts = np.maximum(1, np.ceil(step / spacing_m).astype(int))
    d_yaw = np.remainder(np.diff(p[:, 2]) + math.pi, 2 * math.pi) - math.pi
    out = [p[:1]]
    for i, k in enumerate(parts):
        t = (np.arange(1, k + 1) / k)[:, None]
        seg = p[i] + t * np.array([p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1], d_yaw[i]])
        out.append(seg)
    dense = np.concatenate(out)
    dense[:, 2] = np.remainder(dense[:, 2] + math.pi, 2 * math.pi) - math.pi
    return dense


def _reverses(poses: np.ndarray) -> bool:
    """Does the path move against its heading anywhere (by more than a millimetre)?"""
    d = np.diff(poses[:, :2], axis=0)
    along = d[:, 0] * np.cos(poses[:-1, 2]) + d[:, 1] * np.sin(poses[:-1, 2])
    return bool((along < -1e-3).any())


def allows_reverse(options: PlannerOptions, robot: RobotProfile) -> bool:
    """Whether sphereplan may reverse with these options (``allow_reverse``; None means the profile's
    ``reversible``)."""
    value = getattr(options, "allow_reverse", False)
    return bool(robot.reversible if value is None else value)


def run_sphereplan(problem: RealProblem, grid: OccupancyGrid, robot: RobotProfile, checker: PolygonChecker,
                   options: PlannerOptions, time_limit_s: float) -> RunRecord:
    """One ``plan_path`` call, timed by the wall clock; the path re-checked and measured with the polygon."""
    t0 = time.perf_counter()
    try:
        result = plan_path(grid, robot, problem.start, problem.goal, options, time_limit_s=time_limit_s)
    except PlanningError as exc:
        elapsed = time.perf_counter() - t0
        if isinstance(exc, StartOccupied):
            status = "start_refused"
        elif isinstance(exc, GoalOccupied):
            status = "goal_refused"
        elif isinstance(exc, PlannerTimedOut):
            status = "timeout"
        elif exc.code == 208:
            status = "no_path"
        else:
            status = "error"
        found = _EXPANSIONS.search(exc.msg)
        log.info("%s sphereplan %s after %.3f s: %s", problem.name, status, elapsed, exc.msg)
        return _record(problem, SPHEREPLAN, status, elapsed, time_limit_s,
                       expansions=int(found.group(1)) if found else -1, message=exc.msg)
    elapsed = time.perf_counter() - t0
    dense = densify(result.states[:, :3], 0.5 * grid.resolution_m)
    hits = checker.collides_many(dense)
    valid = not bool(hits.any())
    message = "" if valid else f"the padded footprint meets an obstacle at {int(hits.sum())} of {len(dense)} poses"
    log.info("%s sphereplan solved in %.3f s, %.2f m%s", problem.name, elapsed, result.length_m,
             "" if valid else " (" + message + ")")
    return _record(problem, SPHEREPLAN, "solved", elapsed, time_limit_s, valid=valid,
                   first_length_m=result.length_m, length_m=result.length_m,
                   min_clearance_m=checker.min_clearance(dense), reported_clearance_m=result.min_clearance_m,
                   reverses=bool((result.states[:, 4] < 0).any()), expansions=int(result.expansions),
                   message=message)


def run_reference(problem: RealProblem, grid: OccupancyGrid, robot: RobotProfile, checker: PolygonChecker,
                  planner: str, time_limit_s: float) -> RunRecord:
    """OMPL BIT* (``planner`` = :data:`BIT_DUBINS` or :data:`BIT_REEDS_SHEPP`) at the robot's minimum turning
    radius with the exact polygon validity check: time to the first solution, then optimising until
    ``time_limit_s``; motions are checked every half cell of arc length."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    from planner.hybrid_astar.bench_polygon import _collides_pose

    ou.setLogLevel(ou.LOG_ERROR)
    rho = robot.min_turning_radius_m
    space = bounded_to(ob.DubinsStateSpace(rho) if planner == BIT_DUBINS else ob.ReedsSheppStateSpace(rho), grid)
    setup = og.SimpleSetup(space)
    poly, blocked = checker.polygon, checker.blocked
    ox, oy, res, reach = checker.origin_xy[0], checker.origin_xy[1], checker.resolution_m, checker.circumradius_m

    def valid(state: Any) -> bool:
        return not _collides_pose(poly, state.getX(), state.getY(), state.getYaw(), blocked, ox, oy, res, reach)

    setup.setStateValidityChecker(valid)
    info = setup.getSpaceInformation()
    info.setStateValidityCheckingResolution(0.5 * res / space.getMaximumExtent())
    start, goal = space.allocState(), space.allocState()
    for st, pose in ((start, problem.start), (goal, problem.goal)):
        st.setX(pose[0])
        st.setY(pose[1])
        st.setYaw(math.remainder(pose[2], 2 * math.pi) if pose[2] < math.pi else -math.pi)  # OMPL: [−π, π)
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
    bit.setStopOnSolnImprovement(False)
    if time_limit_s - first > 0.05:
        setup.solve(time_limit_s - first)
    path = setup.getSolutionPath()
    length = float(path.length())
    path.interpolate(max(2, math.ceil(length / (0.5 * res)) + 1))
    poses = np.array([[path.getState(i).getX(), path.getState(i).getY(), path.getState(i).getYaw()]
                      for i in range(path.getStateCount())])
    dense = densify(poses, 0.5 * res)
    hits = checker.collides_many(dense)
    ok = not bool(hits.any())
    log.info("%s %s: first %.3f s (%.2f m), final %.2f m", problem.name, planner, first, first_length, length)
    return _record(problem, planner, "solved", first, time_limit_s, valid=ok, first_length_m=first_length,
                   length_m=length, min_clearance_m=checker.min_clearance(dense), reverses=_reverses(dense),
                   message="" if ok else f"path meets an obstacle at {int(hits.sum())} interpolated poses")


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


# ----------------------------------------------------------------------------------------------- summaries


@dataclass(frozen=True)
class MapSummary:
    """The per-map line of the table (times in s, lengths as ratios, clearances in m; nan where empty).

    ``bit_solved``: solved by BIT* on either space; ``missed``: solved by the reference for sphereplan's
    motions (Dubins, plus Reeds–Shepp when it may reverse) but not by sphereplan; ``refused_free``: starts or
    goals sphereplan called "in collision" although the padded polygon is free there (all drawn poses are);
    ``unsolved_*``: problems nobody solved and sphereplan did not refuse (``unsolved_time_p50_s``: how long
    sphereplan took to give up on them: timeout, no path or another planning error); ``time_*``: sphereplan
    on the problems it solved; ``both_*``: medians over the problems both sphereplan and the reference solved;
    ``clearance_*``: medians over sphereplan's solved problems of the path's least clearance, true (polygon)
    and as reported.
    """

    map: str
    cells: str
    time_limit_s: float
    setup_s: float
    problems: int
    disconnected: int
    bit_dubins: int
    bit_reeds_shepp: int
    bit_solved: int
    sphereplan: int
    missed: int
    refused_free: int
    timeouts: int
    bad_paths: int
    time_p50_s: float
    time_p95_s: float
    both_sphereplan_p50_s: float
    both_bit_first_p50_s: float
    unsolved: int
    unsolved_time_p50_s: float
    length_ratio_median: float
    length_ratio_max: float
    clearance_median_m: float
    reported_clearance_median_m: float


def _median(values: Sequence[float]) -> float:
    return float(statistics.median(values)) if values else math.nan


def _p95(values: Sequence[float]) -> float:
    return float(np.percentile(values, 95)) if values else math.nan


def summarise(records: Sequence[RunRecord], checkers: dict[str, PolygonChecker], reverse_allowed: bool,
              setup_s: dict[str, float], cells: dict[str, str]) -> list[MapSummary]:
    """One :class:`MapSummary` per map (in first-seen order), then one named ``all`` over every map."""
    spaces = {BIT_DUBINS, BIT_REEDS_SHEPP} if reverse_allowed else {BIT_DUBINS}
    maps = list(dict.fromkeys(r.map for r in records))
    out = [_summary(m, [r for r in records if r.map == m], checkers.get(m), spaces, setup_s.get(m, math.nan),
                    cells.get(m, "")) for m in maps]
    if len(maps) > 1:
        out.append(_summary("all", list(records), None, spaces, sum(setup_s.get(m, 0.0) for m in maps), "",
                            checkers))
    return out


def _summary(name: str, records: list[RunRecord], checker: PolygonChecker | None, spaces: set[str],
             setup_s: float, cells: str, checkers: dict[str, PolygonChecker] | None = None) -> MapSummary:
    by_problem: dict[tuple[str, int], dict[str, RunRecord]] = {}
    for r in records:
        by_problem.setdefault((r.map, r.problem), {})[r.planner] = r
    ours = [g[SPHEREPLAN] for g in by_problem.values() if SPHEREPLAN in g]
    solved = [r for r in ours if r.solved]

    def ref_solved(group: dict[str, RunRecord], allowed: set[str]) -> list[RunRecord]:
        return [group[p] for p in allowed if p in group and group[p].solved]

    refused_free = 0
    for r in ours:
        if r.status not in ("start_refused", "goal_refused"):
            continue
        check = checker or (checkers or {}).get(r.map)
        pose = (r.start_x, r.start_y, r.start_yaw) if r.status == "start_refused" else (r.goal_x, r.goal_y, r.goal_yaw)
        if check is None or not check.collides(*pose):
            refused_free += 1
    both_ours, both_bit, unsolved_times = [], [], []
    missed = 0
    for g in by_problem.values():
        mine = g.get(SPHEREPLAN)
        refs = ref_solved(g, spaces)
        if mine is not None and refs and not mine.solved:
            missed += 1
        if mine is not None and refs and mine.solved:
            both_ours.append(mine.time_s)
            both_bit.append(min(r.time_s for r in refs))
        anyone = (mine is not None and mine.solved) or bool(ref_solved(g, set(REFERENCE_SPACES)))
        if not anyone and mine is not None and mine.status in ("timeout", "no_path", "error"):
            unsolved_times.append(mine.time_s)
    ratios = [r.length_ratio for r in solved if math.isfinite(r.length_ratio)]
    limits = sorted({r.time_limit_s for r in records})
    return MapSummary(
        map=name, cells=cells, time_limit_s=limits[0] if len(limits) == 1 else math.nan, setup_s=setup_s,
        problems=len(by_problem), disconnected=sum(1 for g in by_problem.values()
                                                   if next(iter(g.values())).disconnected),
        bit_dubins=sum(1 for g in by_problem.values() if BIT_DUBINS in g and g[BIT_DUBINS].solved),
        bit_reeds_shepp=sum(1 for g in by_problem.values() if BIT_REEDS_SHEPP in g and g[BIT_REEDS_SHEPP].solved),
        bit_solved=sum(1 for g in by_problem.values() if ref_solved(g, set(REFERENCE_SPACES))),
        sphereplan=len(solved), missed=missed, refused_free=refused_free,
        timeouts=sum(1 for r in ours if r.status == "timeout"),
        bad_paths=sum(1 for r in ours if r.status == "solved" and not r.valid),
        time_p50_s=_median([r.time_s for r in solved]), time_p95_s=_p95([r.time_s for r in solved]),
        both_sphereplan_p50_s=_median(both_ours), both_bit_first_p50_s=_median(both_bit),
        unsolved=len(unsolved_times), unsolved_time_p50_s=_median(unsolved_times),
        length_ratio_median=_median(ratios), length_ratio_max=max(ratios) if ratios else math.nan,
        clearance_median_m=_median([r.min_clearance_m for r in solved]),
        reported_clearance_median_m=_median([r.reported_clearance_m for r in solved]),
    )


TABLE_COLUMNS = (
    ("map", "map"), ("cells", "cells"), ("limit s", "time limit given to each planner"),
    ("setup s", "building sphereplan's planner for the map (once, not in the plan times)"),
    ("n", "problems"), ("disc", "proven unreachable (disconnected)"),
    ("BIT*D", "solved by BIT* on Dubins"), ("BIT*RS", "solved by BIT* on Reeds–Shepp"),
    ("BIT*", "solved by BIT* (either)"), ("sp", "solved by sphereplan"),
    ("missed", "solved by the reference for sphereplan's motions, not by sphereplan"),
    ("refused", "free start/goal refused as in collision"), ("t/o", "sphereplan timeouts"),
    ("bad", "sphereplan paths the exact polygon check rejects"),
    ("p50 s", "sphereplan time p50, solved"), ("p95 s", "sphereplan time p95, solved"),
    ("both sp", "sphereplan p50 where both solved"), ("both BIT*", "BIT* first-solution p50 where both solved"),
    ("unsolved", "problems nobody solved (sphereplan timed out or found none)"),
    ("give-up s", "sphereplan p50 time to give up on them"),
    ("len med", "length ÷ reference, median"), ("len max", "length ÷ reference, max"),
    ("clear m", "sphereplan's true footprint clearance, median"),
    ("rep m", "sphereplan's reported min_clearance_m, median"),
)


def _fmt(value: float, digits: int = 2) -> str:
    return "–" if not math.isfinite(value) else f"{value:.{digits}f}"


def format_real_table(summaries: Sequence[MapSummary]) -> str:
    """The per-map table (fixed-width text) with a legend of the columns."""
    rows = []
    for s in summaries:
        rows.append([
            s.map, s.cells, _fmt(s.time_limit_s, 0), _fmt(s.setup_s, 2), str(s.problems), str(s.disconnected),
            str(s.bit_dubins), str(s.bit_reeds_shepp), str(s.bit_solved), str(s.sphereplan), str(s.missed),
            str(s.refused_free), str(s.timeouts), str(s.bad_paths), _fmt(s.time_p50_s, 3), _fmt(s.time_p95_s, 3),
            _fmt(s.both_sphereplan_p50_s, 3), _fmt(s.both_bit_first_p50_s, 3), str(s.unsolved),
            _fmt(s.unsolved_time_p50_s, 3), _fmt(s.length_ratio_median, 3), _fmt(s.length_ratio_max, 3),
            _fmt(s.clearance_median_m, 3), _fmt(s.reported_clearance_median_m, 3),
        ])
    head = [c[0] for c in TABLE_COLUMNS]
    widths = [max(len(head[i]), *(len(r[i]) for r in rows)) for i in range(len(head))]
    line = "  ".join(h.ljust(widths[i]) if i < 2 else h.rjust(widths[i]) for i, h in enumerate(head))
    out = [line, "-" * len(line)]
    for r in rows:
        out.append("  ".join(v.ljust(widths[i]) if i < 2 else v.rjust(widths[i]) for i, v in enumerate(r)))
    out.append("")
    out.extend(f"  {short:9s} {long}" for short, long in TABLE_COLUMNS[2:])
    return "\n".join(out)


def write_real_csv(records: Sequence[RunRecord], path: str | Path) -> None:
    """One row per problem × planner, columns :data:`CSV_COLUMNS`."""
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(CSV_COLUMNS))
        writer.writeheader()
        for r in records:
            writer.writerow(asdict(r))


def read_real_csv(path: str | Path) -> list[RunRecord]:
    """The records of a CSV written by :func:`write_real_csv` (to re-plot or re-summarise a run)."""
    types = {f.name: f.type for f in fields(RunRecord)}
    out = []
    with open(path, newline="") as fh:
        for row in csv.DictReader(fh):
            values: dict[str, Any] = {}
            for key, text in row.items():
                kind = types[key]
                if kind == "bool":
                    values[key] = text == "True"
                elif kind == "int":
                    values[key] = int(text)
                elif kind == "float":
                    values[key] = float(text)
                else:
                    values[key] = text
            out.append(RunRecord(**values))
    return out


def plot_real(records: Sequence[RunRecord], summaries: Sequence[MapSummary], path: str | Path, title: str) -> None:
    """A PNG summary: outcomes per map and planner, time per problem (failures drawn at the time limit),
    length ÷ reference, and the true footprint clearance of each path (style: :mod:`planner.plotstyle`)."""
    from planner.plotstyle import save

    save(real_figure(records, summaries, title), path, dpi=90)


def real_figure(records: Sequence[RunRecord], summaries: Sequence[MapSummary], title: str) -> Any:
    """The figure :func:`plot_real` writes: legends beside the panels, proved-unsolvable problems shaded and
    labelled, failures as × at the time they gave up."""
    from planner.plotstyle import legend_right, pyplot

    plt = pyplot()

    planners = [p for p in (SPHEREPLAN, BIT_DUBINS, BIT_REEDS_SHEPP) if any(r.planner == p for r in records)]
    colours = {SPHEREPLAN: "tab:blue", BIT_DUBINS: "tab:orange", BIT_REEDS_SHEPP: "tab:green"}
    maps = list(dict.fromkeys(r.map for r in records))
    problems = list(dict.fromkeys((r.map, r.problem) for r in records))
    labels = [f"{m}#{i}" for m, i in problems]
    fig, axes = plt.subplots(4, 1, figsize=(max(10.0, 0.28 * len(problems) + 4), 15))
    fig.suptitle(textwrap.fill(title, 110), fontsize=10)

    ax = axes[0]  # outcomes
    outcomes = ("solved", "timeout", "no_path", "start_refused", "goal_refused", "error", "unsolved", "invalid")
    hatch_colours = {"solved": "tab:green", "timeout": "tab:red", "no_path": "tab:purple",
                     "start_refused": "tab:brown", "goal_refused": "tab:pink", "error": "black",
                     "unsolved": "tab:gray", "invalid": "gold"}
    width = 0.8 / len(planners)
    for k, planner in enumerate(planners):
        bottom = np.zeros(len(maps))
        for outcome in outcomes:
            counts = np.array([sum(1 for r in records if r.map == m and r.planner == planner and
                                   ("invalid" if r.status == "solved" and not r.valid else r.status) == outcome)
                               for m in maps], dtype=float)
            if not counts.any():
                continue
            ax.bar(np.arange(len(maps)) + k * width, counts, width, bottom=bottom, color=hatch_colours[outcome],
                   edgecolor=colours[planner], linewidth=1.5, label=outcome if k == 0 or outcome == "unsolved"
                   else None)
            bottom += counts
        for j in range(len(maps)):  # name each bar: sp, D (BIT* Dubins), RS (BIT* Reeds–Shepp)
            ax.text(j + k * width, bottom[j] + 0.1, SHORT_NAMES[planner], ha="center", va="bottom", fontsize=7)
    ax.set_xticks(np.arange(len(maps)) + 0.4 - width / 2)
    ax.set_xticklabels(maps, fontsize=8)
    per_map = max(sum(1 for r in records if r.map == m and r.planner == planners[0]) for m in maps)
    ax.set_ylim(0, per_map * 1.45)
    ax.set_ylabel("problems")
    ax.set_title("outcome per map and planner (sp = sphereplan, D = BIT* Dubins, RS = BIT* Reeds–Shepp)")
    handles, names = ax.get_legend_handles_labels()
    unique = dict(zip(names, handles, strict=True))
    legend_right(ax, list(unique.values()))
    ax.get_legend().set_title("outcome", prop={"size": 7})

    x = np.arange(len(problems))
    lookup = {(r.map, r.problem, r.planner): r for r in records}
    unsolvable = {(r.map, r.problem) for r in records if r.disconnected}
    labels = [f"{lab} (unsolvable)" if key in unsolvable else lab for key, lab in zip(problems, labels, strict=True)]
    for a in axes[1:]:
        for i, key in enumerate(problems):
            if key in unsolvable:
                a.axvspan(i - 0.5, i + 0.5, color="0.9", zorder=0)
    ax = axes[1]  # times
    for k, planner in enumerate(planners):
        offs = (k - (len(planners) - 1) / 2) * 0.2
        ok = [(i, lookup[(m, p, planner)]) for i, (m, p) in enumerate(problems) if (m, p, planner) in lookup]
        good = [(i, r.time_s) for i, r in ok if r.solved]
        bad = [(i, r.time_s) for i, r in ok if not r.solved]
        if good:
            ax.plot([i + offs for i, _ in good], [t for _, t in good], "o", color=colours[planner],
                    label=f"{planner} (BIT*: first solution)" if planner != SPHEREPLAN else planner)
        if bad:
            ax.plot([i + offs for i, _ in bad], [max(t, 1e-3) for _, t in bad], "x", color=colours[planner], ms=9,
                    mew=2, label=f"{planner}: failed / unsolved")
    ax.set_yscale("log")
    ax.set_ylabel("time (s, log)")
    ax.set_title("time per problem (× = failed or unsolved, at the time it gave up; grey: proved unsolvable)")
    handles, _ = ax.get_legend_handles_labels()
    if unsolvable:
        from matplotlib.patches import Patch

        handles.append(Patch(fc="0.9", label="unsolvable (start and goal in different\nfree components)"))
    legend_right(ax, handles)

    ax = axes[2]  # length ratio
    ratios = [(i, lookup[(m, p, SPHEREPLAN)].length_ratio) for i, (m, p) in enumerate(problems)
              if (m, p, SPHEREPLAN) in lookup and math.isfinite(lookup[(m, p, SPHEREPLAN)].length_ratio)]
    if ratios:
        ax.bar([i for i, _ in ratios], [v for _, v in ratios], 0.6, color=colours[SPHEREPLAN])
        ax.set_ylim(min(0.9, min(v for _, v in ratios) - 0.05), max(1.3, max(v for _, v in ratios) + 0.05))
    ax.axhline(1.05, color="k", lw=0.8, ls="--", label="5 % longer than the reference")
    ax.axhline(1.0, color="k", lw=0.5)
    ax.set_ylabel("length ÷ BIT* reference")
    ax.set_title("sphereplan's length over the reference's final length (problems both solved; gaps: not both)")
    legend_right(ax)

    ax = axes[3]  # clearance
    for k, planner in enumerate(planners):
        offs = (k - (len(planners) - 1) / 2) * 0.2
        pts = [(i + offs, lookup[(m, p, planner)].min_clearance_m) for i, (m, p) in enumerate(problems)
               if (m, p, planner) in lookup and lookup[(m, p, planner)].solved]
        if pts:
            ax.plot([a for a, _ in pts], [b for _, b in pts], "o", color=colours[planner], label=planner)
    rep = [(i, lookup[(m, p, SPHEREPLAN)].reported_clearance_m) for i, (m, p) in enumerate(problems)
           if (m, p, SPHEREPLAN) in lookup and lookup[(m, p, SPHEREPLAN)].solved]
    if rep:
        ax.plot([a for a, _ in rep], [b for _, b in rep], "_", color="k", ms=10, label="sphereplan reported")
    ax.set_ylabel("least footprint clearance (m)")
    ax.set_title("true padded-footprint clearance along each solved path")
    legend_right(ax)
    for a in axes[1:]:
        a.set_xticks(x)
        a.set_xticklabels(labels, rotation=70, ha="right", fontsize=7)
        a.set_xlim(-0.7, len(problems) - 0.3)
        a.set_xlabel("problem (map#index)")
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    return fig


@dataclass(frozen=True)
class RealBenchResult:
    """Everything one run produced: the rows, the per-map summaries, the problems and the settings."""

    records: tuple[RunRecord, ...]
    summaries: tuple[MapSummary, ...]
    problems: tuple[RealProblem, ...]
    robot: str
    seed: int
    reverse_allowed: bool


def resolve_map(spec: str) -> Path:
    """A map by name in :func:`real_maps_dir` (``depot``) or by path to its YAML."""
    path = Path(spec)
    if spec.endswith((".yaml", ".yml")) or path.is_file():
        if not path.is_file():
            raise InvalidInput("--real-maps", f"map file {spec!r} does not exist")
        return path
    candidate = real_maps_dir() / f"{spec}.yaml"
    if not candidate.is_file():
        raise InvalidInput("--real-maps", f"no real map named {spec!r}; shipped: {', '.join(REAL_MAPS)}")
    return candidate


def _warm_up(robot: RobotProfile, options: PlannerOptions) -> None:
    """Compile the planner and checker kernels on a small open map, so no timed call pays for it."""
    grid = OccupancyGrid.from_occupied(np.zeros((120, 160), dtype=bool), 0.05, name="warm-up")
    checker = PolygonChecker.for_robot(grid, robot)
    checker.collides_many(np.array([[4.0, 3.0, 0.0]]))
    checker.clearances(np.array([[4.0, 3.0, 0.0]]))
    try:
        plan_path(grid, robot, (1.5, 3.0, 0.0), (6.0, 3.0, 0.0), options, time_limit_s=60.0)
    except PlanningError as exc:  # only compilation matters here
        log.warning("warm-up plan failed: %s", exc)


def run_real_bench(
    maps: Sequence[str | Path], robot: RobotProfile, per_map: int, seed: int, *,
    time_limit_s: float | None = None, options: PlannerOptions | None = None, reference: bool = True,
    settings: DrawSettings | None = None, progress: Callable[[str], None] | None = None,
) -> RealBenchResult:
    """Draw ``per_map`` problems on each map (one ``numpy.random.default_rng(seed)`` for the whole run, maps
    in the given order) and run sphereplan and, with ``reference``, BIT* on Dubins and Reeds–Shepp.

    ``time_limit_s`` None gives each map :func:`default_time_limit_s`. ``progress`` is called after every
    single planner run with a short label.
    """
    from planner.maps.nav2 import load_map

    opts = options or PlannerOptions()
    reverse_allowed = allows_reverse(opts, robot)
    rng = np.random.default_rng(seed)
    if reference:
        from ompl import util as ou

        ou.setLogLevel(ou.LOG_ERROR)
        ou.RNG.setSeed(seed + 1)  # effective only before OMPL's first random number in this process
    _warm_up(robot, opts)
    records: list[RunRecord] = []
    drawn: list[RealProblem] = []
    checkers: dict[str, PolygonChecker] = {}
    setup: dict[str, float] = {}
    cells: dict[str, str] = {}
    for spec in maps:
        path = spec if isinstance(spec, Path) else resolve_map(spec)
        grid = load_map(path)
        name = grid.name
        checker = PolygonChecker.for_robot(grid, robot, opts.allow_unknown)
        checkers[name] = checker
        cells[name] = f"{grid.width}×{grid.height}"
        limit = time_limit_s if time_limit_s is not None else default_time_limit_s(grid)
        problems = draw_problems(grid, robot, per_map, rng, map_name=name, allow_unknown=opts.allow_unknown,
                                 settings=settings, checker=checker)
        drawn.extend(problems)
        t0 = time.perf_counter()
        planner_for(grid, robot, opts)  # distance transform and heuristic grids, once per map, not timed per plan
        setup[name] = time.perf_counter() - t0
        log.info("%s: %d problems drawn, planner set up in %.2f s, limit %.1f s", name, len(problems),
                 setup[name], limit)
        for problem in problems:
            records.append(run_sphereplan(problem, grid, robot, checker, opts, limit))
            if progress:
                progress(f"{problem.name} sphereplan")
            if reference:
                for planner in (BIT_DUBINS, BIT_REEDS_SHEPP):
                    records.append(run_reference(problem, grid, robot, checker, planner, limit))
                    if progress:
                        progress(f"{problem.name} {planner}")
    final = with_reference_lengths(records, reverse_allowed)
    summaries = summarise(final, checkers, reverse_allowed, setup, cells)
    return RealBenchResult(tuple(final), tuple(summaries), tuple(drawn), robot.name, seed, reverse_allowed)
