"""``sphereplan plan``: plan a rollable path on a map and print the result JSON (docs/contracts.md)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from planner.errors import InvalidInput, PlanningError
from service.cli._io import Stages, add_degrees_flag, angle, emit_json, finite_float, positive_float, say
from service.outcome import EXIT_OK

if TYPE_CHECKING:  # the planner's modules load numba and scipy: only when the verb runs (fast --help)
    from service.pipeline import PlanQuery

VERB = "plan"
HELP = "plan a path the sphere can roll from START to GOAL on a map"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--map", required=True, help="map file: ROS map_server YAML, or a mesh (.stl/.obj/.ply)")
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
    parser.add_argument("--out", default=None, help="write the JSON here instead of stdout")
    parser.add_argument("--plot", default=None, help="write a PNG of the plan")
    parser.set_defaults(func=run)


def _query(args: argparse.Namespace) -> PlanQuery:
    """The CLI arguments as the plan query every door builds (bad options are bad input here)."""
    from planner.hybrid_astar.search import PlannerOptions
    from service.pipeline import PlanQuery

    options: dict[str, Any] = {}
    if args.options:
        try:
            options = json.loads(args.options)
        except json.JSONDecodeError as exc:
            raise InvalidInput("--options", f"is not valid JSON: {exc}") from None
        if not isinstance(options, dict):
            raise InvalidInput("--options", "must be a JSON object")
    if args.reverse:
        options["allow_reverse"] = True
    if args.forward_only:
        options["allow_reverse"] = False
    (x0, y0, yaw0), (x1, y1, yaw1) = args.start, args.goal
    start, goal = (x0, y0, angle(args, yaw0)), (x1, y1, angle(args, yaw1))
    return PlanQuery(start, goal, PlannerOptions.from_dict(options), args.time_limit)


def run(args: argparse.Namespace) -> int:
    from planner.hybrid_astar.plot import plot_plan
    from planner.maps.load import load_any
    from planner.result import failure_json
    from planner.robot import load_robot
    from service.pipeline import execute_plan

    with Stages("plan", ["load the robot and the map", "plan", *(["plot"] if args.plot else [])]) as stages:
        stages.start("load the robot and the map")
        robot = load_robot(args.robot)
        query = _query(args)  # before the map is read
        if not Path(args.map).exists():
            raise InvalidInput("--map", f"{args.map} does not exist")
        grid = load_any(args.map, robot)
        stages.start("plan")
        try:
            result = execute_plan(query, grid, robot)
        except PlanningError as exc:  # the failed result is printed too; the exit code is the error's (outcome)
            emit_json(failure_json(exc.code, exc.msg, robot, exc.planning_time_s, exc.expansions), args.out)
            if args.plot:
                stages.start("plot")
                plot_plan(grid, robot, None, query.start, query.goal, args.plot,
                          title=f"{grid.name}: no path ({exc.code})")
            raise
        emit_json(result.to_json(), args.out)
        if args.plot:
            stages.start("plot")
            plot_plan(grid, robot, result.states, query.start, query.goal, args.plot,
                      title=f"{grid.name}: {robot.name}, {result.length_m:.2f} m in "
                            f"{result.planning_time_s * 1000:.0f} ms")
    if args.out:  # stdout is free: say where the result went (the README promised output)
        say("plan", f"{result.length_m:.2f} m in {result.planning_time_s * 1000:.0f} ms, "
                    f"wrote {args.out}{' and ' + args.plot if args.plot else ''}")
    return EXIT_OK
