"""``sphereplan simulate``: roll a plan in closed loop (simulator + localisation + MPC) and report metrics.

sphereplan simulate --map M.yaml --path PLAN.json [--robot P] [--seed N] [--noise none|default]
                    [--tracker mpc|pursuit] [--model kinematic|dynamic] --out SIM.json [--plot SIM.png]
sphereplan simulate --track [--map M.yaml] ...     paper 001's 16.2 m × 8.4 m clockwise lap

Exit 0 when the robot reached the path's end without a collision, 3 when it collided or did not reach it (the
result is written either way, with ``status: failed`` and ``error_msg`` saying why), 2 on bad input — including
a plan made on another map or for another robot than the ones given (``--allow-other-map``,
``--allow-other-robot`` roll it anyway).
"""

from __future__ import annotations

import argparse
from typing import Any

from planner.errors import InvalidInput
from service.cli._io import Stages, emit_result, is_bag, positive_float, read_json_file, read_map_arg, say, seed_int
from service.outcome import EXIT_NO_SOLUTION, EXIT_OK

VERB = "simulate"
HELP = "roll a plan in closed loop (paper 001 MPC + odometry/GNSS fusion) and report tracking metrics"


def _positive_int(text: str) -> int:
    value = seed_int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must be >= 1")
    return value


def add_arguments(parser: argparse.ArgumentParser) -> None:
    src = parser.add_mutually_exclusive_group()
    src.add_argument("--path", metavar="PLAN.json", help="plan result JSON (from `sphereplan plan`)")
    src.add_argument(
        "--track",
        action="store_true",
        help="roll paper 001's 16.2 m x 8.4 m track clockwise (centred on the map)",
    )
    parser.add_argument(
        "--map", metavar="M.yaml", help="ROS map_server YAML, or an MCAP file / rosbag2 folder with a "
        "nav_msgs/OccupancyGrid (optional with --track: open field)"
    )
    parser.add_argument("--map-topic", metavar="TOPIC", help="topic of the map in an MCAP/rosbag2 --map (/map)")
    parser.add_argument("--allow-other-map", action="store_true",
                        help="roll the plan even if it was made on another map than --map (refused otherwise)")
    parser.add_argument("--allow-other-robot", action="store_true",
                        help="roll the plan with --robot even if it was made for another robot (refused otherwise)")
    parser.add_argument("--robot", metavar="P", help="robot profile name or TOML (default: the plan's robot)")
    parser.add_argument("--seed", type=seed_int, default=0, help="seed of every disturbance (default 0)")
    parser.add_argument("--noise", choices=("none", "default"), default="default", help="disturbances")
    parser.add_argument(
        "--tracker",
        choices=("mpc", "pursuit"),
        default="mpc",
        help="mpc = paper 001 eq. 15 with pure-pursuit fallback; pursuit = geometric only",
    )
    parser.add_argument(
        "--model",
        choices=("kinematic", "dynamic"),
        default="kinematic",
        help="kinematic = eq. 1 with a roll lag (fast); dynamic = paper 001's pendulum plant under LMPC + RSLQR",
    )
    parser.add_argument("--rate", type=positive_float, default=50.0, metavar="HZ", help="control rate (50)")
    parser.add_argument("--horizon", type=_positive_int, default=15, metavar="N", help="MPC horizon (15)")
    parser.add_argument(
        "--corner-radius",
        type=positive_float,
        default=1.5,
        metavar="M",
        help="--track corner radius (m, >= the robot's minimum turning radius)",
    )
    parser.add_argument(
        "--time-limit", type=positive_float, metavar="S", help="stop after S simulated seconds"
    )
    parser.add_argument("--out", metavar="SIM.json", help="write the result here (default: stdout); a name ending "
                        "in .mcap writes ROS 2 messages (map, plan, executed and estimated poses) and prints the JSON")
    parser.add_argument("--plot", metavar="SIM.png", help="also draw the run")
    parser.set_defaults(func=run)


def _read_plan(path: str) -> dict[str, Any]:
    plan = read_json_file(path, "path")
    if not isinstance(plan, dict):
        raise InvalidInput("path", "must be a plan result object")
    states = plan.get("states")
    if not isinstance(states, list) or len(states) < 2:
        status = plan.get("status", "?")
        raise InvalidInput("path", f"has no path to roll (status {status!r}, needs at least two states)")
    return plan


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from planner.closed_loop.simulate import SimulationOptions, check_plan_fits, simulate_plan
    from planner.closed_loop.tracker import MPCParams
    from planner.occupancy import OccupancyGrid
    from planner.robot import RobotProfile, load_robot
    from planner.synthetic_paths import track_plan

    if not args.path and not args.track:
        raise InvalidInput("path", "give --path PLAN.json or --track")
    given = _read_plan(args.path) if args.path else None
    if args.map:
        grid = read_map_arg(args.map, args.map_topic)
    elif args.track:
        grid = OccupancyGrid.from_occupied(
            np.zeros((248, 404), dtype=bool), 0.05, (-2.0, -2.0, 0.0), name="field"
        )
    else:
        raise InvalidInput("map", "is required with --path")

    robot: RobotProfile | None
    if args.track:
        robot = load_robot(args.robot)
        (ox, oy, _), (w, h) = grid.origin, grid.size_m
        x0, y0 = ox + (w - 16.2) / 2, oy + (h - 8.4) / 2
        if w < 16.2 + 2 * robot.footprint_width_m or h < 8.4 + 2 * robot.footprint_width_m:
            raise InvalidInput(
                "track", f"the 16.2 m x 8.4 m track does not fit the {w:.1f} m x {h:.1f} m map"
            )
        plan = track_plan(robot, corner_radius_m=args.corner_radius, origin=(x0, y0))
    else:
        assert given is not None
        plan = given
        robot = load_robot(args.robot) if args.robot else None
        # a map read from a bag is named after the bag, not the map: compared only for map files
        check_plan_fits(plan, None if is_bag(args.map) else grid.name, robot.name if robot is not None else None,
                        allow_other_map=args.allow_other_map, allow_other_robot=args.allow_other_robot,
                        map_field="--map", robot_field="--robot", map_flag="--allow-other-map",
                        robot_flag="--allow-other-robot")

    options = SimulationOptions(
        control_rate_hz=args.rate,
        tracker=args.tracker,
        model=args.model,
        mpc=MPCParams(horizon=args.horizon),
        time_limit_s=args.time_limit,
    )
    with Stages("simulate", ["simulate", *(["plot"] if args.plot else [])]) as stages:
        stages.start("simulate")
        result = simulate_plan(grid, plan, robot, seed=args.seed, noise=args.noise, options=options)
        if args.plot:
            stages.start("plot")
            from planner.closed_loop.plot import plot_simulation

            plot_simulation(grid, plan, result, args.plot)
    from service.ros import write_simulation_mcap

    emit_result(result, args.out, lambda out: write_simulation_mcap(out, plan, result, grid))
    m = result["metrics"]
    verdict = "reached the goal" if m["reached_goal"] else "did NOT reach the goal"
    if m["stopped_at_estimated_goal"] and not m["reached_goal"]:
        verdict += " (it stopped where its estimate put the goal)"
    if m["collided"]:
        verdict += ", COLLIDED"
    say(
        "simulate",
        f"{verdict}: true end {m['final_position_error_m']:.3f} m from the path's end, estimate "
        f"{m['estimate_error_final_m']:.3f} m off the truth; cross-track rms {m['cross_track_rms_m']:.3f} m, "
        f"max {m['cross_track_max_m']:.3f} m; clearance {m['min_clearance_m']:.3f} m; "
        f"fallback steps {m['fallback_steps']}; fused error max {m['estimate_error_max_m']:.3f} m vs "
        f"odometry {m['odometry_error_max_m']:.3f} m",
    )
    if result["status"] != "reached":  # the result is written for a look; the exit code says it failed
        return EXIT_NO_SOLUTION
    return EXIT_OK
