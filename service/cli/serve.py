"""``sphereplan serve``: run the HTTP API and the Zenoh node as one embedded service.

Defaults need nothing else running: HTTP on 127.0.0.1:8000, a Zenoh peer listening on
tcp/127.0.0.1:7447 only (multicast scouting off), the shipped maps and robot profiles, two warmed
worker processes. Ctrl-C stops it within a few seconds (running plans are cut off).
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from planner.errors import InvalidInput
from service.settings import MAX_TIME_LIMIT_S, ServiceSettings

VERB = "serve"
HELP = "serve planning over HTTP (FastAPI) and Zenoh from one process"
GRACEFUL_SHUTDOWN_S = 2


def _port(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port number") from None
    if not 1 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"{value} is not in 1..65535")
    return value


def _count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"{value} must be ≥ 0")
    return value


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--host", default="127.0.0.1", help="HTTP bind address (default 127.0.0.1)")
    parser.add_argument("--port", type=_port, default=8000, help="HTTP port (default 8000)")
    parser.add_argument("--maps", default=None, help="maps folder (default: the shipped maps)")
    parser.add_argument("--zenoh-config", default=None, metavar="FILE",
                        help="standard Zenoh JSON5 config (router / multi-host); default: loopback peer")
    parser.add_argument("--zenoh-listen", default="tcp/127.0.0.1:7447", metavar="ENDPOINT",
                        help="listen endpoint of the default peer (default tcp/127.0.0.1:7447)")
    parser.add_argument("--no-zenoh", action="store_true", help="HTTP only")
    parser.add_argument("--ros2", action="store_true", help="also speak ROS 2 over Zenoh (rmw_zenoh format): "
                        "<ns>/goal_pose, <ns>/pose, <ns>/map in, <ns>/plan out (docs/ros2.md)")
    parser.add_argument("--ros2-domain", type=int, default=0, metavar="ID", help="ROS_DOMAIN_ID (default 0)")
    parser.add_argument("--ros2-namespace", default="/", metavar="NS", help="namespace of the ROS 2 topics (/)")
    parser.add_argument("--ros2-map", default=None, metavar="NAME",
                        help="map (in the maps folder) goals are planned on until a map arrives on <ns>/map")
    parser.add_argument("--ros2-robot", default=None, metavar="NAME", help="robot profile for ROS 2 goals")
    parser.add_argument("--workers", type=_count, default=2, help="planning processes (default 2)")
    parser.add_argument("--max-in-flight", type=_count, default=0,
                        help="jobs queued or running before 503 (default 4 per worker)")
    parser.add_argument("--max-time-limit", type=float, default=MAX_TIME_LIMIT_S,
                        help=f"largest time_limit_s a request may ask (default {MAX_TIME_LIMIT_S:g})")
    parser.set_defaults(func=run)


def settings_from_args(args: argparse.Namespace) -> ServiceSettings:
    from planner.maps.catalogue import default_maps_dir

    maps_dir = Path(args.maps) if args.maps else default_maps_dir()
    if not maps_dir.is_dir():
        raise InvalidInput("--maps", f"{maps_dir} is not a directory")
    zenoh_config = Path(args.zenoh_config) if args.zenoh_config else None
    if zenoh_config is not None and not zenoh_config.is_file():
        raise InvalidInput("--zenoh-config", f"{zenoh_config} is not a file")
    return ServiceSettings(maps_dir=maps_dir, workers=args.workers, max_in_flight=args.max_in_flight,
                           max_time_limit_s=args.max_time_limit, zenoh=not args.no_zenoh,
                           zenoh_config=zenoh_config, zenoh_listen=args.zenoh_listen, ros2=args.ros2,
                           ros2_domain_id=args.ros2_domain, ros2_namespace=args.ros2_namespace,
                           ros2_map=args.ros2_map, ros2_robot=args.ros2_robot)


def run(args: argparse.Namespace) -> int:
    import uvicorn

    from service.http import create_app

    settings = settings_from_args(args)
    logging.getLogger("service").setLevel(logging.INFO)
    config = uvicorn.Config(create_app(settings), host=args.host, port=args.port, lifespan="on",
                            timeout_graceful_shutdown=GRACEFUL_SHUTDOWN_S, log_level="info")
    server = uvicorn.Server(config)
    try:
        server.run()
    except KeyboardInterrupt:  # uvicorn re-raises the Ctrl-C it handled, after a clean shutdown
        pass
    return 0 if server.started else 1
