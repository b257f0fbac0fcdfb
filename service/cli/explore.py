"""``sphereplan explore``: roll the sphere through a true world while the planner only knows a map plus what a
simulated range sensor has seen; replan when the path is blocked (docs/live.md).

sphereplan explore --map KNOWN.yaml --world TRUE.yaml --start X Y YAW --goal X Y YAW [--robot P]
                   [--sensor-range 10] [--seed N] [--tracker mpc|pursuit] [--plan-time-limit S]
                   [--plot F.png] [--out F.json|F.mcap]

Exit codes: 0 the sphere reached the goal; 2 bad input; 3 no path (the planner found none on what it knew,
and nothing new could be seen); 4 simulated time ran out; 5 the sphere collided with the true world.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from planner.errors import InvalidInput
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
    seed_int,
)
from service.outcome import EXIT_NO_SOLUTION, EXIT_OK, EXIT_TIMEOUT

VERB = "explore"
HELP = "explore a world the planner does not know: simulated range sensor, live map, replanning (closed loop)"

EXIT_COLLIDED = 5
"""The simulated sphere touched an obstacle of the true world."""

EXIT_FOR_OUTCOME = {"reached": EXIT_OK, "no_path": EXIT_NO_SOLUTION, "timeout": EXIT_TIMEOUT, "collided": EXIT_COLLIDED}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--map", required=True, metavar="KNOWN.yaml", help="what the planner knows at the start")
    parser.add_argument("--world", required=True, metavar="TRUE.yaml",
                        help="the true world the sphere rolls through and the sensor sees (same cells as --map)")
    parser.add_argument("--start", required=True, nargs=3, type=finite_float, metavar=("X", "Y", "YAW"))
    parser.add_argument("--goal", required=True, nargs=3, type=finite_float, metavar=("X", "Y", "YAW"))
    add_degrees_flag(parser)
    parser.add_argument("--robot", metavar="P", help="robot profile name or TOML (default zju-60)")
    parser.add_argument("--sensor-range", type=positive_float, default=10.0, metavar="M",
                        help="range of the simulated sensor and of marking/clearing (paper 001: 10 m)")
    parser.add_argument("--sensor-rate", type=positive_float, default=5.0, metavar="HZ", help="sweeps per second (5)")
    parser.add_argument("--seed", type=seed_int, default=0, help="seed of the sensor noise (default 0)")
    parser.add_argument("--tracker", choices=("mpc", "pursuit"), default="mpc",
                        help="mpc = paper 001 eq. 15 with pure-pursuit fallback (default); pursuit = geometric only")
    parser.add_argument("--replan-period", type=positive_float, default=None, metavar="S",
                        help="also replan every S s of simulated time (default: only when the path is blocked)")
    parser.add_argument("--plan-time-limit", type=positive_float, default=5.0, metavar="S",
                        help="time limit of each (re)plan, s (default 5; one that runs out is retried with 2x, 4x)")
    parser.add_argument("--time-limit", type=positive_float, default=None, metavar="S",
                        help="simulated seconds before giving up (default 3 × straight distance / speed + 60)")
    parser.add_argument("--out", metavar="F.json", help="write the result here (default: stdout); a name ending in "
                        ".mcap writes ROS 2 messages (the live map at each replan, every path, the driven track) "
                        "and prints the JSON")
    parser.add_argument("--plot", metavar="F.png", help="draw the map filling in and every path over time")
    parser.set_defaults(func=run)


def _write_mcap(out: str, known: Any, result: dict[str, Any]) -> None:
    from planner.occupancy import OccupancyGrid
    from service.ros import MAP_TOPIC, OCCUPANCY_GRID, PATH, McapOut, occupancy_grid_msg, path_msg

    t0 = time.time()
    with McapOut(out) as mcap:
        for t, data in result["_snapshots"]:
            grid = OccupancyGrid(data, known.resolution_m, known.origin, known.occupied_threshold, known.name)
            mcap.write(MAP_TOPIC, OCCUPANCY_GRID, occupancy_grid_msg(grid, t0 + t), t0 + t)
        for p in result["paths"]:
            rows = [(0.0, x, y, 0.0) for x, y in p["xy"]]
            mcap.write("/plan", PATH, path_msg(rows, t0 + p["t"]), t0 + p["t"])
        track = [(r["t"], r["x"], r["y"], r["yaw"]) for r in result["trajectory"]]
        end = result["trajectory"][-1]["t"] if result["trajectory"] else 0.0
        mcap.write("/explore/driven", PATH, path_msg(track, t0), t0 + end)


def run(args: argparse.Namespace) -> int:
    from planner.closed_loop.explore import ExploreOptions, explore, explore_json
    from planner.live.range_sensor import RangeSensor
    from planner.robot import load_robot

    check_output(args.out, "--out")
    if args.plot:
        check_output(args.plot, "--plot", plot_formats())
    if args.sensor_range > 100:
        raise InvalidInput("--sensor-range", f"must be at most 100 m, got {args.sensor_range}")
    robot = load_robot(args.robot)
    start = (args.start[0], args.start[1], angle(args, args.start[2], "--start"))
    goal = (args.goal[0], args.goal[1], angle(args, args.goal[2], "--goal"))
    known = read_map_arg(args.map, None, robot)
    if not Path(args.world).exists():
        raise InvalidInput("--world", f"{args.world} does not exist")
    from planner.closed_loop.explore import same_geometry
    from service.grids import read_map

    world = read_map(args.world, robot, "--world")
    if not same_geometry(known, world):
        raise InvalidInput("--world", f"must cover the same cells as --map ({known.width}×{known.height} cells of "
                                      f"{known.resolution_m} m from {list(known.origin)}), got {world.width}×"
                                      f"{world.height} of {world.resolution_m} m from {list(world.origin)}")
    options = ExploreOptions(sensor=RangeSensor(range_m=args.sensor_range), sensor_rate_hz=args.sensor_rate,
                             tracker=args.tracker, replan_period_s=args.replan_period, time_limit_s=args.time_limit,
                             plan_time_limit_s=args.plan_time_limit)
    with Stages("explore", ["explore", *(["plot"] if args.plot else [])]) as stages:
        stages.start("explore")
        result = explore(known, world, robot, start, goal, options, seed=args.seed)
        if args.plot:
            stages.start("plot")
            from planner.closed_loop.explore_plot import plot_explore

            plot_explore(known, world, result, args.plot)
    emit_result(explore_json(result), args.out, lambda out: _write_mcap(out, known, result))
    m = result["metrics"]
    lat = m["replan_latency_p95_s"]
    say("explore", f"{result['outcome']}: drove {m['length_m']:.1f} m"
        + (f" (full knowledge: {m['length_known_world_m']:.1f} m)" if m["length_known_world_m"] else
           " (the true world has no path)")
        + f", {m['replans']} replans" + (f" (p95 {1e3 * lat:.0f} ms)" if lat is not None else "")
        + f", clearance {m['min_clearance_m']:.2f} m" + (f"; {result['error_msg']}" if result["error_msg"] else ""))
    return EXIT_FOR_OUTCOME[result["outcome"]]
