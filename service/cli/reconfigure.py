"""``sphereplan reconfigure``: bring a sphere to rest at a goal with P on top (paper 004 Spherobot)."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

from service.cli._io import (
    add_degrees_flag,
    emit_result,
    finite_float,
    is_bag,
    map_path,
    positive_float,
    read_bag_map,
    say,
)

#: planner.spherobot.request.METHODS, repeated so that --help does not import the planner (1.5 s; a test
#: keeps the two equal)
METHODS = ("arc", "triangle")

VERB = "reconfigure"
HELP = "Plan a Spherobot reconfiguration (position, P on top, optional heading) and prove it by rolling."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--method", choices=METHODS, default="arc", help="arc (§4, default) or triangle (§3)")
    parser.add_argument(
        "--radius", type=positive_float, metavar="R", help="sphere radius in m (default: profile)"
    )
    parser.add_argument("--start", type=finite_float, nargs=2, metavar=("X", "Y"), required=True)
    parser.add_argument(
        "--start-tilt",
        type=finite_float,
        nargs=2,
        metavar=("THETA", "ALPHA"),
        default=[0.0, 0.0],
        help="P's polar angle from the top and its azimuth (default 0 0)",
    )
    parser.add_argument(
        "--start-spin", type=finite_float, default=0.0, metavar="PSI", help="spin about P (default 0)"
    )
    parser.add_argument("--goal", type=finite_float, nargs=2, metavar=("X", "Y"), required=True)
    parser.add_argument(
        "--goal-heading",
        type=finite_float,
        metavar="PSI",
        help="azimuth of body +x with P on top; omitted = partial reconfiguration",
    )
    parser.add_argument(
        "--alpha-final", type=finite_float, metavar="A", help="arc method: direction of the last roll"
    )
    parser.add_argument(
        "--roll-rate", type=positive_float, metavar="W", help="shell rate in rad/s (default: profile)"
    )
    add_degrees_flag(parser)
    parser.add_argument("--map", metavar="M.yaml", help="check the swept sphere against this map (map_server YAML, "
                        "or an MCAP file / rosbag2 folder with a nav_msgs/OccupancyGrid)")
    parser.add_argument("--map-topic", metavar="TOPIC", help="topic of the map in an MCAP/rosbag2 --map (/map)")
    parser.add_argument("--allow-unknown", action="store_true", help="treat unknown map cells as free")
    parser.add_argument("--plot", metavar="F.png", help="draw the ground path and P's track on the sphere")
    parser.add_argument("--out", metavar="F.json", help="write the JSON here instead of stdout; a name ending in "
                        ".mcap writes ROS 2 messages (the sphere's pose over time, its path) and prints the JSON")
    parser.set_defaults(func=run)


if TYPE_CHECKING:
    from planner.occupancy import OccupancyGrid


def _load_map(path: str) -> OccupancyGrid:
    from planner.maps.nav2 import load_map

    return load_map(map_path(path))


def request_from_args(args: argparse.Namespace) -> dict[str, Any]:
    """The JSON request the parsed options describe (angles as typed, with ``degrees``)."""
    return {
        "method": args.method,
        "radius_m": args.radius,
        "start": list(args.start),
        "start_tilt": list(args.start_tilt),
        "start_spin": args.start_spin,
        "goal": list(args.goal),
        "goal_heading": args.goal_heading,
        "alpha_final": args.alpha_final,
        "roll_rate_rad_s": args.roll_rate,
        "degrees": args.degrees,
        "map": args.map,
        "allow_unknown": args.allow_unknown,
    }


def run(args: argparse.Namespace) -> int:
    from planner.spherobot.reconfigure import plan_reconfiguration
    from planner.spherobot.request import ReconfigureRequest
    from service.ros import write_reconfiguration_mcap

    grid = None
    if args.map:
        grid = read_bag_map(args.map, args.map_topic) if is_bag(args.map) else _load_map(args.map)
    result = plan_reconfiguration(ReconfigureRequest.from_dict(request_from_args(args)), grid=grid)
    emit_result(result, args.out, lambda out: write_reconfiguration_mcap(out, result, grid))
    if args.plot:
        from planner.spherobot.plot import plot_reconfiguration

        plot_reconfiguration(result, args.plot, grid)
    say("reconfigure", f"{result['method']} ({result['mode']}): {result['length_m']:.2f} m rolled in "
                       f"{result['duration_s']:.1f} s, planned in {result['planning_time_s'] * 1000:.0f} ms"
                       f"{', wrote ' + args.out if args.out else ''}")
    return 0
