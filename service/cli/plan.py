"""``sphereplan plan``: plan a rollable path on a map and print the result JSON (docs/contracts.md)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from planner.errors import InvalidInput, PlanningError
from planner.hybrid_astar.plot import plot_plan
from planner.hybrid_astar.search import PlannerOptions
from planner.result import failure_json
from planner.robot import load_robot
from service.cli._io import check_output, emit_json, finite_float, plot_formats, positive_float, write_file
from service.grids import read_map
from service.outcome import EXIT_OK
from service.pipeline import PlanQuery, execute_plan

VERB = "plan"
HELP = "plan a path the sphere can roll from START to GOAL on a map"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--map", required=True, help="map file: ROS map_server YAML, or a mesh (.stl/.obj/.ply)")
    parser.add_argument("--start", required=True, nargs=3, type=finite_float, metavar=("X", "Y", "YAW"))
    parser.add_argument("--goal", required=True, nargs=3, type=finite_float, metavar=("X", "Y", "YAW"))
    parser.add_argument("--robot", default=None, help="built-in profile name (default zju-60) or a TOML file")
    parser.add_argument("--time-limit", type=positive_float, default=None, help="seconds (default 5)")
    parser.add_argument("--options", default=None, help="JSON object of planner options, e.g. '{\"greed\": 1.0}'")
    parser.add_argument("--reverse", action="store_true", help="allow reversing")
    parser.add_argument("--out", default=None, help="write the JSON here instead of stdout")
    parser.add_argument("--plot", default=None, help="write a PNG of the plan")
    parser.set_defaults(func=run)


def _query(args: argparse.Namespace) -> PlanQuery:
    """The CLI arguments as the plan query every door builds (bad options are bad input here)."""
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
    (x0, y0, yaw0), (x1, y1, yaw1) = args.start, args.goal
    return PlanQuery((x0, y0, yaw0), (x1, y1, yaw1), PlannerOptions.from_dict(options), args.time_limit)


def run(args: argparse.Namespace) -> int:
    robot = load_robot(args.robot)
    query = _query(args)  # before the map is read
    check_output(args.out, "--out")
    if args.plot:
        check_output(args.plot, "--plot", plot_formats())
    if not Path(args.map).exists():
        raise InvalidInput("--map", f"{args.map} does not exist")
    grid = read_map(args.map, robot, "--map")
    try:
        result = execute_plan(query, grid, robot)
    except PlanningError as exc:  # the failed result is printed too; the exit code is the error's (service.outcome)
        emit_json(failure_json(exc.code, exc.msg, robot), args.out)
        if args.plot:
            title = f"{grid.name}: no path ({exc.code})"
            write_file(args.plot, "--plot",
                       lambda: plot_plan(grid, robot, None, query.start, query.goal, args.plot, title=title))
        raise
    emit_json(result.to_json(), args.out)
    if args.plot:
        title = f"{grid.name}: {robot.name}, {result.length_m:.2f} m in {result.planning_time_s * 1000:.0f} ms"
        write_file(args.plot, "--plot",
                   lambda: plot_plan(grid, robot, result.states, query.start, query.goal, args.plot, title=title))
    return EXIT_OK
