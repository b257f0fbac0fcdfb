"""``sphereplan serve``: run the HTTP API and the Zenoh node as one embedded service.

Defaults need nothing else running: HTTP on 127.0.0.1:8000, a Zenoh peer listening on
tcp/127.0.0.1:7447 only (multicast scouting off), the shipped maps and robot profiles, two warmed
worker processes. Ctrl-C stops it within a few seconds (running plans are cut off).
"""

from __future__ import annotations

import argparse
import logging
import re
import threading
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, Any

from planner.errors import InvalidInput
from service.auth import loopback_host
from service.settings import MAX_TIME_LIMIT_S, ServiceSettings

if TYPE_CHECKING:
    from service.core import PlanningService

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
    parser.add_argument("--robots", default="*", metavar="PATTERNS",
                        help="robot ids whose Zenoh pose/goal topics this instance plans, comma-separated Zenoh key "
                             "chunks (default '*': all; e.g. 'r1,r2' or 'east-$*'); give each instance of a fleet "
                             "a disjoint set so that every goal is planned once")
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
    parser.add_argument("--worker-memory", type=_count, default=2048, metavar="MB",
                        help="address-space ceiling of each worker process, MB (0 = none; default 2048)")
    parser.add_argument("--token-file", default=None, metavar="FILE",
                        help="require the token on every door: 'Authorization: Bearer <token>' on every HTTP route "
                             "but /healthz and /readyz, the attachment 'Bearer <token>' on Zenoh queries and "
                             "pose/goal puts; the token is the file's first line")
    parser.add_argument("--insecure", action="store_true",
                        help="allow a non-loopback --host or Zenoh listen endpoint without credentials")
    parser.set_defaults(func=run)


def read_token(path: str) -> str:
    """The bearer token: the first line of ``path`` (at least 16 characters)."""
    p = Path(path)
    try:
        token = p.read_text().splitlines()[0].strip() if p.is_file() else None
    except (OSError, UnicodeDecodeError, IndexError):
        token = None
    if token is None:
        raise InvalidInput("--token-file", f"{path} is not a readable text file with the token on its first line")
    if len(token) < 16:
        raise InvalidInput("--token-file", "the token must be at least 16 characters")
    return token


def load_zenoh_config(path: Path) -> Any:
    """The ``zenoh.Config`` of ``path``, or :class:`InvalidInput` naming ``--zenoh-config`` with Zenoh's reason
    on one line (checked before any worker starts)."""
    import zenoh

    try:
        return zenoh.Config.from_file(str(path))
    except Exception as exc:  # zenoh.ZError: not JSON5/YAML, unknown keys, bad values
        reason = " ".join(str(exc).split())
        reason = re.sub(r" at /\S+:\d+\.?$", "", reason)  # the Rust source location of the error
        raise InvalidInput("--zenoh-config", f"{path} is not a usable Zenoh configuration: {reason}") from None


def check_zenoh_door(config_path: Path | None, listen: str, has_token: bool, insecure: bool, ros2: bool) -> None:
    """The Zenoh door's half of :mod:`service.auth`: the config file loads, and a listen beyond loopback has
    credentials (the token, or the config's user/password) or ``--insecure``."""
    from service.auth import exposure_problem, zenoh_has_credentials, zenoh_listen_endpoints

    endpoints: list[str] | None
    if config_path is None:
        endpoints, usrpwd, field = [listen], False, "--zenoh-listen"
    else:
        config = load_zenoh_config(config_path)
        endpoints, usrpwd, field = zenoh_listen_endpoints(config), zenoh_has_credentials(config), "--zenoh-config"
    problem = exposure_problem(endpoints, has_token or usrpwd, insecure)
    if problem is not None:
        raise InvalidInput(field, f"the Zenoh node {problem}: give --token-file, a --zenoh-config with "
                                  "user/password (deploy/zenoh/service.json5), or --insecure")
    if ros2 and has_token and not usrpwd:
        raise InvalidInput("--ros2", "ROS 2 messages cannot carry the token: with --token-file, lock the Zenoh door "
                                     "with a --zenoh-config that has user/password and access control instead")


def check_listen_port(endpoint: str, field: str) -> None:
    """Refuse, before any worker is started, a ``tcp/HOST:PORT`` endpoint whose port is already taken (7447 is
    also where a ROS 2 Zenoh router listens): bad input naming ``field``, one line, not a traceback."""
    import socket

    kind, _, address = endpoint.partition("/")
    host, _, port_text = address.rpartition(":")
    if kind != "tcp" or not port_text.isdigit() or not host:
        return
    host = host.strip("[]")
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as probe:
        try:
            probe.bind((host, int(port_text)))
        except OSError as exc:
            raise InvalidInput(field, f"cannot listen on {endpoint}: {exc.strerror or exc} (another program, e.g. "
                                      "a Zenoh router, holds it); choose another endpoint or give --no-zenoh") from None


def settings_from_args(args: argparse.Namespace) -> ServiceSettings:
    from planner.maps.catalogue import default_maps_dir

    maps_dir = Path(args.maps) if args.maps else default_maps_dir()
    if not maps_dir.is_dir():
        raise InvalidInput("--maps", f"{maps_dir} is not a directory")
    zenoh_config = Path(args.zenoh_config) if args.zenoh_config else None
    if zenoh_config is not None and not zenoh_config.is_file():
        raise InvalidInput("--zenoh-config", f"{zenoh_config} is not a file")
    if not args.no_zenoh and zenoh_config is None:
        check_listen_port(args.zenoh_listen, "--zenoh-listen")
    token = read_token(args.token_file) if args.token_file else None
    if token is None and not loopback_host(args.host) and not args.insecure:
        raise InvalidInput("--host", f"{args.host} is not a loopback address: give --token-file (or --insecure to "
                                     "serve without authentication)")
    if zenoh_config is not None:
        load_zenoh_config(zenoh_config)
    if not args.no_zenoh:
        check_zenoh_door(zenoh_config, args.zenoh_listen, token is not None, args.insecure, args.ros2)
    return ServiceSettings(maps_dir=maps_dir, workers=args.workers, max_in_flight=args.max_in_flight,
                           max_time_limit_s=args.max_time_limit, zenoh=not args.no_zenoh,
                           zenoh_config=zenoh_config, zenoh_listen=args.zenoh_listen, ros2=args.ros2,
                           zenoh_robots=tuple(p.strip() for p in args.robots.split(",")),
                           ros2_domain_id=args.ros2_domain, ros2_namespace=args.ros2_namespace,
                           ros2_map=args.ros2_map, ros2_robot=args.ros2_robot,
                           worker_memory_mb=args.worker_memory, http_token=token)


def _server_class() -> type:
    import uvicorn

    class Server(uvicorn.Server):
        """uvicorn that, on SIGTERM/Ctrl-C, first has the service answer every job in flight with the JSON
        503 "shutting down", so open requests end before uvicorn stops waiting for them."""

        def __init__(self, config: uvicorn.Config, service: PlanningService) -> None:
            super().__init__(config)
            self.service = service

        def handle_exit(self, sig: int, frame: FrameType | None) -> None:
            # in a thread: a signal handler must not take the service's locks the interrupted code may hold
            threading.Thread(target=self.service.begin_shutdown, name="sphereplan-shutdown").start()
            super().handle_exit(sig, frame)

    return Server


def _http_protocol() -> type:
    """uvicorn's h11 protocol with its own 400s (a request line or header it cannot parse, answered before the
    app sees anything) as the service's error JSON instead of text/plain."""
    import h11
    from uvicorn.protocols.http.h11_impl import H11Protocol

    from service.outcome import dumps, error_body

    class JsonErrorProtocol(H11Protocol):
        def send_400_response(self, msg: str) -> None:
            body = dumps(error_body(f"malformed HTTP request: {msg}", "request"))
            headers = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode()),
                       (b"connection", b"close")]
            for event in (h11.Response(status_code=400, headers=headers, reason=b"Bad Request"), h11.Data(data=body),
                          h11.EndOfMessage()):
                self.transport.write(self.conn.send(event))
            self.transport.close()

    return JsonErrorProtocol


def run(args: argparse.Namespace) -> int:
    import uvicorn

    from service.http import create_app

    settings = settings_from_args(args)
    logging.getLogger("service").setLevel(logging.INFO)
    app = create_app(settings)
    config = uvicorn.Config(app, host=args.host, port=args.port, lifespan="on", http=_http_protocol(),
                            timeout_graceful_shutdown=GRACEFUL_SHUTDOWN_S, log_level="info")
    server = _server_class()(config, app.state.service)
    try:
        server.run()
    except KeyboardInterrupt:  # uvicorn re-raises the Ctrl-C it handled, after a clean shutdown
        pass
    return 0 if server.started else 1
