"""Benchmark of the spherical Hybrid A* against OMPL's BIT* and RRT* on the shipped problem sets.

The OMPL planners get a Dubins state space with the robot's minimum turning radius and the covering-circle
validity check of :class:`planner.maps.clearance.ClearanceMap` (``CircleFootprint.for_robot``: for the
near-disc sphere footprints that is one circle, 0.381 m for zju-60, which covers the padded polygon), while
sphereplan checks the exact polygon; the circle is the more conservative of the two, so OMPL is never given an
easier collision model. BIT* given ``ompl_time_s`` (10 s by default) is the length reference.
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
from planner.termination import Termination


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
            result = plan_path(grid, robot, problem.start, problem.goal, termination=Termination(problem.time_limit_s))
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


def ompl_states(space: Any, *poses: tuple[float, float, float]) -> list[Any]:
    """OMPL SE(2) states (Dubins or Reeds–Shepp space) at ``poses`` (x, y, yaw), the yaw put in OMPL's [−π, π)."""
    states = []
    for pose in poses:
        st = space.allocState()
        st.setX(pose[0])
        st.setY(pose[1])
        st.setYaw(math.remainder(pose[2], 2 * math.pi) if pose[2] < math.pi else -math.pi)
        states.append(st)
    return states


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
        return bool(clearance.circle_margins(footprint, pose)[0] >= 0.0)

    setup.setStateValidityChecker(valid)
    info = setup.getSpaceInformation()
    extent = max(grid.size_m)
    info.setStateValidityCheckingResolution(0.5 * grid.resolution_m / extent)
    start, goal = ompl_states(space, problem.start, problem.goal)
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
        clearance_m = float(clearance.circle_margins(footprint, poses).min())
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


_PLANNER_COLOURS = {"sphere-hybrid-a*": "tab:blue", "ompl-BIT*": "tab:orange", "ompl-RRT*": "tab:green"}


def _planner_label(name: str, runs: int | None, budgets: dict[str, float]) -> str:
    if name == "sphere-hybrid-a*":
        return "sphere Hybrid A*: plan time" + (f" (median of {runs} runs)" if runs else " (median)")
    if name == "ompl-BIT*":
        return "OMPL BIT*: time to its first solution, length after " + (
            f"{budgets[name]:g} s" if name in budgets else "its budget")
    if name == "ompl-RRT*":
        b = f"{budgets[name]:g} s" if name in budgets else "its budget"
        return f"OMPL RRT*: best path within {b} (not a first solution; time = the budget)"
    return name


def failure_word(row: BenchRow) -> str:
    """How a solvable problem's run failed, in one word for the picture: "timeout" or "failed"."""
    return "timeout" if row.note.startswith("207") or "no solution in time" in row.note else "failed"


def reported_unsolvable(row: BenchRow) -> bool:
    """An unsolvable problem the planner answered with "no path" (not by running out of time)."""
    return (not row.solvable and row.success and not row.note.startswith("207")
            and "no solution in time" not in row.note)


def bench_figure(rows: list[BenchRow], title: str = "", runs: int | None = None,
                 budgets: dict[str, float] | None = None) -> Any:
    """The bench picture: per problem (all of them, unsolvable ones shaded and marked) and planner, the time
    (log scale) and the length ÷ best length found; failed runs drawn as hatched bars with a red × and why."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from planner.plotstyle import pyplot

    plt = pyplot()
    budgets = budgets or {}
    problems = list(dict.fromkeys(r.problem for r in rows))
    solvable = {r.problem: r.solvable for r in rows}
    planners = list(dict.fromkeys(r.planner for r in rows))
    fig, axes = plt.subplots(2, 1, figsize=(max(12.0, 0.42 * len(problems) + 3), 9), sharex=True)
    ax_t, ax_l = axes
    width = 0.8 / len(planners)
    centres = np.arange(len(problems))
    ratio_top = 1.6
    for i, p in enumerate(problems):
        if not solvable[p]:
            for ax in axes:
                ax.axvspan(i - 0.5, i + 0.5, color="0.9", zorder=0)
            said = [r.planner.replace("sphere-hybrid-a*", "Hybrid A*") for r in rows
                    if r.problem == p and reported_unsolvable(r)]
            ax_l.text(i, 1.25, f"unsolvable (reported by {', '.join(said)})" if said
                      else "unsolvable (no planner reported it)", rotation=90, ha="center", va="center", fontsize=7,
                      color="0.3")
    failed_any = False
    for k, name in enumerate(planners):
        sel = {r.problem: r for r in rows if r.planner == name}
        colour = _PLANNER_COLOURS.get(name, f"C{k}")
        for i, p in enumerate(problems):
            if p not in sel:
                continue
            r = sel[p]
            x = centres[i] - 0.4 + (k + 0.5) * width
            t_ms = max(r.time_median_s * 1e3, 1e-3)
            if r.solvable and not r.success:  # failed on a solvable problem: explicit
                failed_any = True
                ax_t.bar(x, t_ms, width, fc="white", ec="red", hatch="//", lw=0.8, zorder=2)
                ax_t.plot(x, t_ms, "x", color="red", ms=7, mew=2, zorder=3)
                ax_l.plot(x, 0.93, "x", color="red", ms=8, mew=2, zorder=3)  # no length: below the scale's 1.0
                ax_l.text(x, 0.96, failure_word(r), rotation=90, ha="center", va="bottom", fontsize=7, color="red")
            elif not r.solvable:  # an unsolvable problem: the time it took to say so (or to give up)
                ax_t.bar(x, t_ms, width, fc=colour, alpha=0.45, hatch=".." if reported_unsolvable(r) else "//",
                         zorder=2)
            else:
                ax_t.bar(x, t_ms, width, fc=colour, zorder=2)
                ratio = r.length_ratio
                ax_l.bar(x, min(ratio, ratio_top) - 0.9, width, bottom=0.9, fc=colour, zorder=2)
                if ratio > ratio_top:
                    ax_l.text(x, ratio_top - 0.01, f"{ratio:.2f}", rotation=90, ha="center", va="top", fontsize=7,
                              color="white", fontweight="bold")
    ax_t.set_yscale("log")
    ax_t.set_ylabel("time (ms, log scale)")
    ax_t.grid(axis="y", alpha=0.3, which="both")
    ax_l.set_ylabel("length ÷ best length found")
    ax_l.axhline(1.05, color="k", lw=0.8, ls="--", zorder=1)
    ax_l.set_ylim(0.9, ratio_top)
    ax_l.set_xticks(centres)
    ax_l.set_xticklabels([p if solvable[p] else f"{p} (unsolvable)" for p in problems], rotation=60, ha="right",
                         fontsize=7)
    ax_l.set_xlim(-0.6, len(problems) - 0.4)
    handles: list[Any] = [Patch(fc=_PLANNER_COLOURS.get(n, f"C{k}"), label=_planner_label(n, runs, budgets))
                          for k, n in enumerate(planners)]
    handles.append(Line2D([], [], color="k", lw=0.8, ls="--", label="5 % longer than the best length found"))
    handles.append(Patch(fc="0.9", label="unsolvable problem: the right answer is \"no path\" (bar: time to say so)"))
    handles.append(Patch(fc="0.7", hatch="..", label="unsolvable, answered \"no path\" (dotted bar)"))
    handles.append(Patch(fc="0.7", hatch="//", label="unsolvable, ran its whole budget (hatched bar)"))
    if failed_any:
        handles.append(Line2D([], [], marker="x", color="red", ls="", mew=2,
                              label="failed on a solvable problem (timeout / failed)"))
    fig.legend(handles=handles, loc="lower center", ncol=2, fontsize=8, frameon=False)
    fig.suptitle(title or "sphereplan bench: time and path length per problem and planner")
    fig.tight_layout(rect=(0.0, 0.1, 1.0, 1.0))
    return fig


def plot_bench(rows: list[BenchRow], path: str | Path, title: str = "", runs: int | None = None,
               budgets: dict[str, float] | None = None) -> None:
    """Write :func:`bench_figure` to ``path``."""
    from planner.plotstyle import save

    save(bench_figure(rows, title, runs, budgets), path)


def read_csv(path: str | Path) -> list[BenchRow]:
    """Rows written by :func:`write_csv` (to redraw a picture without re-running the bench)."""
    import csv

    out = []
    with open(path, newline="") as fh:
        for d in csv.DictReader(fh):
            out.append(BenchRow(
                problem=d["problem"], planner=d["planner"], solvable=d["solvable"] == "True",
                success=d["success"] == "True", time_median_s=float(d["time_median_s"]),
                time_p95_s=float(d["time_p95_s"]), length_m=float(d["length_m"]),
                length_ratio=float(d["length_ratio"]), min_clearance_m=float(d["min_clearance_m"]),
                max_curvature=float(d["max_curvature"]), expansions=int(d["expansions"]), note=d["note"]))
    return out


def cold_start_s(map_path: Path, start: tuple[float, float, float], goal: tuple[float, float, float]) -> float:
    """Wall time of a fresh ``sphereplan plan`` process (imports, map load, plan)."""
    argv = [sys.executable, "-m", "service.cli", "plan", "--map", str(map_path), "--start", *map(str, start),
            "--goal", *map(str, goal), "--out", "/dev/null"]
    t0 = time.perf_counter()
    subprocess.run(argv, check=False, capture_output=True)
    return time.perf_counter() - t0
