"""Benchmark of the spherical Hybrid A* against OMPL's BIT* and RRT* on the shipped problem sets.

The OMPL planners get a Dubins state space with the robot's minimum turning radius and the very same
three-circle validity check (:class:`planner.maps.clearance.ClearanceMap`), so the comparison is about the
search, not the collision model. BIT* given ``ompl_time_s`` (10 s by default) is the length reference.
"""

from __future__ import annotations

import math
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from planner.errors import PlanningError
from planner.hybrid_astar.plan import plan_path
from planner.maps.clearance import CircleFootprint, ClearanceMap
from planner.maps.load import load_any
from planner.maps.problems import Problem
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile


@dataclass
class BenchRow:
    problem: str
    planner: str
    solvable: bool
    success: bool
    time_median_s: float
    time_p95_s: float
    length_m: float
    length_ratio: float
    min_clearance_m: float
    max_curvature: float
    expansions: int
    note: str = ""


def _p95(values: list[float]) -> float:
    return float(np.percentile(values, 95)) if values else math.nan


def _max_curvature(xy_yaw: np.ndarray) -> float:
    d_s = np.hypot(np.diff(xy_yaw[:, 0]), np.diff(xy_yaw[:, 1]))
    d_yaw = np.abs(np.remainder(np.diff(xy_yaw[:, 2]) + np.pi, 2 * np.pi) - np.pi)
    moving = d_s > 1e-6
    return float((d_yaw[moving] / d_s[moving]).max()) if moving.any() else 0.0


def bench_hybrid(problem: Problem, grid: OccupancyGrid, robot: RobotProfile, runs: int) -> BenchRow:
    """Median/p95 of ``runs`` plans after one warm-up plan (compilation, distance transform)."""
    times: list[float] = []
    result = None
    note = ""
    for i in range(runs + 1):
        t0 = time.perf_counter()
        try:
            result = plan_path(grid, robot, problem.start, problem.goal, time_limit_s=problem.time_limit_s)
        except PlanningError as exc:
            result = None
            note = f"{exc.code}: {exc.msg[:60]}"
        if i > 0:
            times.append(time.perf_counter() - t0)
    ok = result is not None
    return BenchRow(
        problem=problem.name, planner="sphere-hybrid-a*", solvable=problem.solvable, success=ok == problem.solvable,
        time_median_s=statistics.median(times), time_p95_s=_p95(times),
        length_m=result.length_m if result else math.nan, length_ratio=math.nan,
        min_clearance_m=result.min_clearance_m if result else math.nan,
        max_curvature=_max_curvature(result.states[:, :3]) if result else math.nan,
        expansions=result.expansions if result else 0, note=note,
    )



def bounded_to(space: Any, grid: OccupancyGrid) -> Any:
    """An OMPL SE(2)-like state space (Dubins, Reeds–Shepp) bounded to the grid's extent."""
    from ompl import base as ob

    bounds = ob.RealVectorBounds(2)
    bounds.setLow(0, grid.origin[0])
    bounds.setLow(1, grid.origin[1])
    bounds.setHigh(0, grid.origin[0] + grid.size_m[0])
    bounds.setHigh(1, grid.origin[1] + grid.size_m[1])
    space.setBounds(bounds)
    return space


def bench_ompl(problem: Problem, grid: OccupancyGrid, robot: RobotProfile, planner_name: str,
               time_s: float) -> BenchRow:
    """One OMPL run: time to the first exact solution, then optimise until ``time_s``; final length."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    ou.setLogLevel(ou.LOG_ERROR)
    footprint = CircleFootprint.for_robot(robot)
    clearance = ClearanceMap(grid)
    space = bounded_to(ob.DubinsStateSpace(robot.min_turning_radius_m), grid)
    setup = og.SimpleSetup(space)

    def valid(state: Any) -> bool:
        pose = np.array([[state.getX(), state.getY(), state.getYaw()]])
        return bool(clearance.pose_margin(footprint, pose)[0] >= 0.0)

    setup.setStateValidityChecker(valid)
    info = setup.getSpaceInformation()
    extent = max(grid.size_m)
    info.setStateValidityCheckingResolution(0.5 * grid.resolution_m / extent)
    start, goal = space.allocState(), space.allocState()
    for st, pose in ((start, problem.start), (goal, problem.goal)):
        st.setX(pose[0])
        st.setY(pose[1])
        st.setYaw(math.remainder(pose[2], 2 * math.pi) if pose[2] < math.pi else -math.pi)  # OMPL: [−π, π)
    setup.setStartAndGoalStates(start, goal, 0.1)
    pdef = setup.getProblemDefinition()
    t0 = time.perf_counter()
    if planner_name == "BIT*":
        # BIT* publishes its solution only when solve() returns: ask it to return on the first one.
        bit = og.BITstar(info)
        bit.setStopOnSolnImprovement(True)
        setup.setPlanner(bit)
        setup.solve(time_s)
        first = time.perf_counter() - t0
        bit.setStopOnSolnImprovement(False)
    else:
        setup.setPlanner(og.RRTstar(info))
        setup.solve(ob.plannerOrTerminationCondition(
            ob.timedPlannerTerminationCondition(time_s), ob.exactSolnPlannerTerminationCondition(pdef)))
        first = time.perf_counter() - t0
    solved = pdef.hasExactSolution()
    if solved and time_s - first > 0.05:
        setup.solve(time_s - first)
    length = math.nan
    clearance_m = math.nan
    curvature = math.nan
    if pdef.hasExactSolution():
        path = setup.getSolutionPath()
        length = float(path.length())
        path.interpolate(max(2, int(length / 0.02)))
        poses = np.array([[path.getState(i).getX(), path.getState(i).getY(), path.getState(i).getYaw()]
                          for i in range(path.getStateCount())])
        clearance_m = float(clearance.pose_margin(footprint, poses).min())
        curvature = _max_curvature(poses)
    return BenchRow(
        problem=problem.name, planner=f"ompl-{planner_name}", solvable=problem.solvable,
        success=solved == problem.solvable, time_median_s=first, time_p95_s=first, length_m=length,
        length_ratio=math.nan, min_clearance_m=clearance_m, max_curvature=curvature, expansions=0,
        note="time = first solution" if solved else "no solution in time",
    )


def run_bench(problems: list[Problem], robot: RobotProfile, runs: int, ompl_time_s: float, rrt_time_s: float,
              progress: Callable[[str], None] | None = None) -> list[BenchRow]:
    """Every problem × every planner; fills ``length_ratio`` against the best length any planner found."""
    rows: list[BenchRow] = []
    grids: dict[Path, OccupancyGrid] = {}
    for problem in problems:
        grid = grids.setdefault(problem.map_path, load_any(problem.map_path, robot))
        group = [bench_hybrid(problem, grid, robot, runs)]
        if progress:
            progress(f"{problem.name}: hybrid")
        if ompl_time_s > 0:
            group.append(bench_ompl(problem, grid, robot, "BIT*", ompl_time_s))
            if progress:
                progress(f"{problem.name}: BIT*")
        if rrt_time_s > 0:
            group.append(bench_ompl(problem, grid, robot, "RRT*", rrt_time_s))
            if progress:
                progress(f"{problem.name}: RRT*")
        lengths = [r.length_m for r in group if math.isfinite(r.length_m)]
        best = min(lengths) if lengths else math.nan
        for r in group:
            r.length_ratio = r.length_m / best if lengths else math.nan
        rows.extend(group)
    return rows


def format_table(rows: list[BenchRow]) -> str:
    head = (f"{'problem':28s} {'planner':18s} {'ok':>3s} {'t_med ms':>9s} {'t_p95 ms':>9s} {'length m':>9s} "
            f"{'ratio':>6s} {'clear m':>8s} {'max k':>6s} {'exp':>7s}")
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(
            f"{r.problem[:28]:28s} {r.planner:18s} {'yes' if r.success else 'NO':>3s} {r.time_median_s * 1e3:9.1f} "
            f"{r.time_p95_s * 1e3:9.1f} {r.length_m:9.2f} {r.length_ratio:6.3f} {r.min_clearance_m:8.3f} "
            f"{r.max_curvature:6.3f} {r.expansions:7d}"
        )
    return "\n".join(lines)


def write_csv(rows: list[BenchRow], path: str | Path) -> None:
    import csv

    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(asdict(rows[0])))
        writer.writeheader()
        for r in rows:
            writer.writerow(asdict(r))


def plot_bench(rows: list[BenchRow], path: str | Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    problems = list(dict.fromkeys(r.problem for r in rows if r.solvable))
    planners = list(dict.fromkeys(r.planner for r in rows))
    fig, axes = plt.subplots(2, 1, figsize=(12, 7), sharex=True)
    width = 0.8 / len(planners)
    for k, name in enumerate(planners):
        sel = {r.problem: r for r in rows if r.planner == name}
        xs = np.arange(len(problems)) + k * width
        axes[0].bar(xs, [sel[p].time_median_s * 1e3 if p in sel else 0 for p in problems], width, label=name)
        axes[1].bar(xs, [sel[p].length_ratio if p in sel else 0 for p in problems], width, label=name)
    axes[0].set_yscale("log")
    axes[0].set_ylabel("time (ms; OMPL: first solution)")
    axes[1].set_ylabel("length / best found")
    axes[1].axhline(1.05, color="k", lw=0.8, ls="--")
    axes[1].set_ylim(0.9, 1.6)
    axes[1].set_xticks(np.arange(len(problems)) + 0.4 - width / 2)
    axes[1].set_xticklabels(problems, rotation=60, ha="right", fontsize=7)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def cold_start_s(map_path: Path, start: tuple[float, float, float], goal: tuple[float, float, float]) -> float:
    """Wall time of a fresh ``sphereplan plan`` process (imports, map load, plan)."""
    argv = [sys.executable, "-m", "service.cli", "plan", "--map", str(map_path), "--start", *map(str, start),
            "--goal", *map(str, goal), "--out", "/dev/null"]
    t0 = time.perf_counter()
    subprocess.run(argv, check=False, capture_output=True)
    return time.perf_counter() - t0
