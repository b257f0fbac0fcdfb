"""The real-map benchmark's run: draw the problems on each map, run every planner, summarise."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from lab.planning.real.isolated import ReferenceWorker
from lab.planning.real.problems import DrawSettings, RealProblem, default_time_limit_s, draw_problems, resolve_map
from lab.planning.real.runs import (
    BIT_DUBINS,
    BIT_REEDS_SHEPP,
    RunRecord,
    allows_reverse,
    room_asked_m,
    room_space,
    run_sphereplan,
    with_reference_lengths,
)
from lab.planning.real.summary import MapSummary, summarise
from lab.planning.referee import DEFAULT_REACH_M, FootprintReferee, grown_polygon
from planner.errors import (
    PlanningError,
)
from planner.hybrid_astar.plan import plan_path, planner_for
from planner.hybrid_astar.search import PlannerOptions
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile
from planner.termination import Termination

log = logging.getLogger(__name__)

Pose = tuple[float, float, float]


@dataclass(frozen=True)
class RealBenchResult:
    """Everything one run produced: the rows, the per-map summaries, the problems and the settings."""

    records: tuple[RunRecord, ...]
    summaries: tuple[MapSummary, ...]
    problems: tuple[RealProblem, ...]
    robot: str
    seed: int
    reverse_allowed: bool


def _warm_up(robot: RobotProfile, options: PlannerOptions) -> None:
    """Compile the planner and checker kernels on a small open map, so no timed call pays for it."""
    grid = OccupancyGrid.from_occupied(np.zeros((120, 160), dtype=bool), 0.05, name="warm-up")
    checker = FootprintReferee.for_robot(grid, robot)
    checker.collides_many(np.array([[4.0, 3.0, 0.0]]))
    checker.clearances(np.array([[4.0, 3.0, 0.0]]))
    try:
        plan_path(grid, robot, (1.5, 3.0, 0.0), (6.0, 3.0, 0.0), options, Termination(60.0))
    except PlanningError as exc:  # only compilation matters here
        log.warning("warm-up plan failed: %s", exc)


DEFAULT_REFERENCE_S = 3.0  # BIT*'s budget per space and problem: first solution, then optimising, in all


def run_real_bench(
    maps: Sequence[str | Path], robot: RobotProfile, per_map: int, seed: int, *,
    time_limit_s: float | None = None, options: PlannerOptions | None = None, reference: bool = True,
    reference_s: float | None = DEFAULT_REFERENCE_S, settings: DrawSettings | None = None,
    progress: Callable[[str], None] | None = None, repeat: int = 1, room_reference: bool = False,
) -> RealBenchResult:
    """Draw ``per_map`` problems on each map (one ``numpy.random.default_rng(seed)`` for the whole run, maps
    in the given order) and run sphereplan and, with ``reference``, BIT* on Dubins and Reeds–Shepp.

    ``time_limit_s`` None gives each map :func:`default_time_limit_s`; it bounds sphereplan and BIT*'s search
    for a first solution alike. BIT* then optimises until ``reference_s`` in all (None: until the time limit);
    its final length is the reference's best. Each BIT* run happens in a child process
    (:class:`~lab.planning.real.isolated.ReferenceWorker`): a crash inside OMPL is recorded, not fatal.
    ``progress`` is called after every single planner run with a short label.

    ``repeat`` > 1 times every solved problem that many times and keeps the median: sphereplan's plan (each as
    the first towards its goal), and BIT*'s first solution (the extra runs stop at it; OMPL's random numbers
    go on, so each run samples afresh). The lengths are the first run's. Single runs of a few milliseconds vary
    by a third from one run of the bench to the next; the per-problem time ratios inherit that.

    ``room_reference`` (with ``reference``) also runs, on every problem sphereplan solved, BIT* on sphereplan's space
    with the footprint grown by the room sphereplan's path keeps (:func:`~lab.planning.real.runs.room_asked_m`; a
    convex footprint only), to its first solution (timed as the others, ``repeat`` times): how long a sampling
    planner takes to a first path as roomy. Its rows' ``reported_clearance_m`` is that room and ``min_clearance_m``
    its path's true clearance (the grown polygon's plus the room).
    """
    if repeat < 1:
        raise ValueError(f"repeat must be at least 1, not {repeat}")
    if room_reference:
        check_room_reference(robot, reference)
    from planner.maps.nav2 import load_map

    opts = options or PlannerOptions()
    reverse_allowed = allows_reverse(opts, robot)
    rng = np.random.default_rng(seed)
    _warm_up(robot, opts)
    records: list[RunRecord] = []
    drawn: list[RealProblem] = []
    checkers: dict[str, FootprintReferee] = {}
    setup: dict[str, float] = {}
    cells: dict[str, str] = {}
    worker = ReferenceWorker(ompl_seed=seed + 1) if reference else None
    try:
        for spec in maps:
            path = spec if isinstance(spec, Path) else resolve_map(spec)
            grid = load_map(path)
            name = grid.name
            checker = FootprintReferee.for_robot(grid, robot, opts.allow_unknown)
            checkers[name] = checker
            cells[name] = f"{grid.width}×{grid.height}"
            limit = time_limit_s if time_limit_s is not None else default_time_limit_s(grid)
            problems = draw_problems(grid, robot, per_map, rng, map_name=name, allow_unknown=opts.allow_unknown,
                                     settings=settings, checker=checker)
            drawn.extend(problems)
            setup[name] = prepare_planner(grid, robot, opts)
            log.info("%s: %d problems drawn, planner set up in %.3f s, limit %.1f s", name, len(problems),
                     setup[name], limit)
            optimise = None if reference_s is None else max(reference_s, 0.0)
            for problem in problems:
                mine = run_sphereplan(problem, grid, robot, checker, opts, limit, repeat)
                records.append(mine)
                if progress:
                    progress(f"{problem.name} sphereplan")
                if worker is not None:
                    for planner in (BIT_DUBINS, BIT_REEDS_SHEPP):
                        records.append(_timed_reference(worker, problem, grid, robot, checker, planner, limit,
                                                        optimise, str(path), repeat))
                        if progress:
                            progress(f"{problem.name} {planner}")
                if worker is not None and room_reference and mine.solved:
                    room = room_asked_m(mine, robot)
                    record = _timed_reference(worker, problem, grid, robot, checker, room_space(reverse_allowed),
                                              limit, 0.0, str(path), repeat, room)
                    if record.solved:  # the grown polygon's clearance is the true one less the room (both capped)
                        record = replace(record, min_clearance_m=min(record.min_clearance_m + room, DEFAULT_REACH_M))
                    records.append(replace(record, reported_clearance_m=room))
                    if progress:
                        progress(f"{problem.name} {record.planner}")
    finally:
        if worker is not None:
            worker.close()
    final = with_reference_lengths(records, reverse_allowed)
    summaries = summarise(final, checkers, reverse_allowed, setup, cells)
    return RealBenchResult(tuple(final), tuple(summaries), tuple(drawn), robot.name, seed, reverse_allowed)


def check_room_reference(robot: RobotProfile, reference: bool) -> None:
    """Refuse (ValueError, saying why) a room-matched reference that cannot run: it needs the reference's worker,
    and a footprint that can be grown by a pad (a convex one: :func:`~lab.planning.referee.grown_polygon`)."""
    if not reference:
        raise ValueError("it runs with the reference (BIT*): leave the reference on")
    try:
        grown_polygon(robot.footprint_polygon, 0.0)  # refuses a footprint it cannot grow
    except ValueError as exc:
        raise ValueError(f"robot {robot.name!r}: {exc}") from None


def _timed_reference(worker: ReferenceWorker, problem: RealProblem, grid: OccupancyGrid, robot: RobotProfile,
                     checker: FootprintReferee, planner: str, limit: float, optimise: float | None, map_key: str,
                     repeat: int, room_m: float = 0.0) -> RunRecord:
    """One BIT* run in the worker (its polygon grown by ``room_m``); when it solved and ``repeat`` > 1, its first
    solution timed that many times in all (the extra runs stop at it) and the median kept."""
    record = worker.run(problem, grid, robot, checker, planner, limit, optimise, map_key=map_key, room_m=room_m)
    if record.status == "solved" and repeat > 1:
        times = [record.time_s] + [worker.run(problem, grid, robot, checker, planner, limit, 0.0, map_key=map_key,
                                              room_m=room_m).time_s for _ in range(repeat - 1)]
        record = replace(record, time_s=float(np.median(times)))
    return record


def prepare_planner(grid: OccupancyGrid, robot: RobotProfile, options: PlannerOptions) -> float:
    """Seconds to get sphereplan ready for a map it has not seen: its planner (distance field, cost grid,
    heuristic grid) and the reachability labels of the refusal check, as the service does once per map."""
    t0 = time.perf_counter()
    planner = planner_for(grid, robot, options)
    from planner.maps.reachability import prepare

    prepare(planner.clearance, planner.polygon)
    return time.perf_counter() - t0
