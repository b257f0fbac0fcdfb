"""``sphereplan plan``: plan a rollable path on a map and print the result JSON (docs/contracts.md)."""

from __future__ import annotations

import argparse
import json
from typing import TYPE_CHECKING, Any

from planner.errors import InvalidInput, PlanningError
from service.cli._io import (
    Stages,
    add_degrees_flag,
    angle,
    check_output,
    emit_result,
    finite_float,
    plot_formats,
    positive_float,
    read_map_arg,
    say,
    write_file,
)
from service.outcome import EXIT_OK

if TYPE_CHECKING:  # the planner's modules load numba and scipy: only when the verb runs (fast --help)
    from service.pipeline import PlanQuery

VERB = "plan"
HELP = "plan a path the sphere can roll from START to GOAL on a map"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--map", required=True, help="map file: ROS map_server YAML, a mesh (.stl/.obj/.ply), "
                        "or an MCAP file / rosbag2 folder holding a nav_msgs/OccupancyGrid (see --map-topic)")
    parser.add_argument("--map-topic", default=None, help="topic of the OccupancyGrid in an MCAP/rosbag2 --map "
                        "(default /map)")
    parser.add_argument("--start", required=True, nargs=3, type=finite_float, metavar=("X", "Y", "YAW"))
    parser.add_argument("--goal", required=True, nargs=3, type=finite_float, metavar=("X", "Y", "YAW"))
    parser.add_argument("--robot", default=None, help="built-in profile name (default zju-60) or a TOML file")
    parser.add_argument("--time-limit", type=positive_float, default=None, help="seconds (default 5)")
    parser.add_argument("--options", default=None, help="JSON object of planner options, e.g. '{\"greed\": 1.0}'")
    direction = parser.add_mutually_exclusive_group()
    direction.add_argument("--reverse", action="store_true",
                           help="allow reversing (the default for robots whose profile says reversible, as spheres)")
    direction.add_argument("--forward-only", action="store_true", help="never reverse")
    add_degrees_flag(parser)
    parser.add_argument("--out", default=None, help="write the JSON here instead of stdout; a name ending in .mcap "
                        "writes ROS 2 messages (/map, /plan, /plan/footprints) and prints the JSON")
    parser.add_argument("--plot", default=None, help="write a PNG of the plan")
    parser.set_defaults(func=run)


def _query(args: argparse.Namespace) -> PlanQuery:
    """The CLI arguments as the plan query every door builds (bad options are bad input here)."""
    from planner.hybrid_astar.search import PlannerOptions
    from planner.termination import Termination
    from service.pipeline import PlanQuery

    options: dict[str, Any] = {}
    if args.options:
        try:
            options = json.loads(args.options)
        except json.JSONDecodeError as exc:
            raise InvalidInput("--options", f"is not valid JSON: {exc}") from None
        except RecursionError:
            raise InvalidInput("--options", "is nested too deeply") from None
        if not isinstance(options, dict):
            raise InvalidInput("--options", "must be a JSON object")
    if args.reverse:
        options["allow_reverse"] = True
    if args.forward_only:
        options["allow_reverse"] = False
    (x0, y0, yaw0), (x1, y1, yaw1) = args.start, args.goal
    start, goal = (x0, y0, angle(args, yaw0, "--start")), (x1, y1, angle(args, yaw1, "--goal"))
    termination = Termination() if args.time_limit is None else Termination(args.time_limit)
    return PlanQuery(start, goal, PlannerOptions.from_dict(options), termination)


def _pose(p: tuple[float, float, float]) -> dict[str, float]:
    return {"x": p[0], "y": p[1], "yaw": p[2]}


def _failure_words(exc: PlanningError) -> str:
    """What went wrong, in the words a plot title can carry."""
    from planner.errors import GoalOccupied, GoalOutsideMap, PlannerTimedOut, StartOccupied, StartOutsideMap

    words = {StartOutsideMap: "start outside the map", GoalOutsideMap: "goal outside the map",
             StartOccupied: "start in collision", GoalOccupied: "goal in collision",
             PlannerTimedOut: "timed out"}
    return next((w for cls, w in words.items() if isinstance(exc, cls)), "no path exists")


def run(args: argparse.Namespace) -> int:
    from planner.hybrid_astar.plot import plot_plan
    from planner.result import failure_json
    from planner.robot import load_robot
    from service.pipeline import execute_plan
    from service.ros import write_plan_mcap

    with Stages("plan", ["load the robot and the map", "plan", *(["plot"] if args.plot else [])]) as stages:
        stages.start("load the robot and the map")
        robot = load_robot(args.robot)
        query = _query(args)  # before the map is read
        check_output(args.out, "--out")
        if args.plot:
            check_output(args.plot, "--plot", plot_formats())
        grid = read_map_arg(args.map, args.map_topic, robot)
        stages.start("plan")
        try:
            result = execute_plan(query, grid, robot)
        except PlanningError as exc:  # the failed result is printed too; the exit code is the error's (outcome)
            emit_result(failure_json(exc.code, exc.msg, robot, exc.planning_time_s, exc.expansions), args.out,
                        lambda out: write_plan_mcap(
                            out, {"start": _pose(query.start), "goal": _pose(query.goal), "robot": robot.to_json()},
                            grid))
            if args.plot:
                stages.start("plot")
                title = f"{grid.name}: {robot.name}, no path: {_failure_words(exc)} (code {exc.code})"
                write_file(args.plot, "--plot",
                           lambda: plot_plan(grid, robot, None, query.start, query.goal, args.plot, title=title))
            raise
        body = result.to_json()
        emit_result(body, args.out, lambda out: write_plan_mcap(out, body, grid))
        if args.plot:
            stages.start("plot")
            title = f"{grid.name}: {robot.name}, {result.length_m:.2f} m in {result.planning_time_s * 1000:.0f} ms"
            write_file(args.plot, "--plot",
                       lambda: plot_plan(grid, robot, result.states, query.start, query.goal, args.plot, title=title))
    went = f"wrote {args.out}" if args.out else "printed the JSON"
    extra = result.extra
    backwards = f", {extra['reverse_length_m']:.2f} m of it backwards" if extra.get("reverse_states") else ""
    rounds = extra.get("improvements")
    improved = "" if not rounds else (
        f", improved from {rounds[0]['length_m']:.2f} m by {', '.join(r['by'] for r in rounds[1:])}" if len(rounds) > 1
        else ", no path cheaper than the first found") + f" (rounds stopped: {extra['improvement_stop']})"
    say("plan", f"{result.length_m:.2f} m{backwards}{improved} in {result.planning_time_s * 1000:.0f} ms "
                f"({extra['search']} search), {went}{' and ' + args.plot if args.plot else ''}")
    return EXIT_OK
