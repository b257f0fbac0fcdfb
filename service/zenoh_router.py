"""A Zenoh router as a Python process: ``python -m service.zenoh_router [--listen EP] [--config FILE]``.

Several ``sphereplan serve`` instances and the robots meet at one router (the eclipse-zenoh package opens a
session in ``router`` mode; no separate ``zenohd`` binary is needed). The instances connect to it in peer or
client mode; a plan query routed through it reaches one complete queryable (docs/service.md, "Several
instances"). With ``--config`` it runs a standard Zenoh JSON5 config (TLS, user/password and the access-control
list of ``deploy/zenoh/router.json5``); otherwise it listens on ``--listen`` (loopback by default) with
scouting off. It runs until SIGTERM or Ctrl-C.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import threading
from collections.abc import Sequence
from types import FrameType

import zenoh


def router_config(listen: str, config_file: str | None) -> zenoh.Config:
    if config_file is not None:
        conf = zenoh.Config.from_file(config_file)
    else:
        conf = zenoh.Config()
        conf.insert_json5("listen/endpoints", json.dumps([listen]))
        conf.insert_json5("scouting/multicast/enabled", "false")
    conf.insert_json5("mode", '"router"')
    return conf


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m service.zenoh_router", description=__doc__.splitlines()[0])
    parser.add_argument("--listen", default="tcp/127.0.0.1:7447", help="listen endpoint (default tcp/127.0.0.1:7447)")
    parser.add_argument("--config", default=None, metavar="FILE",
                        help="a Zenoh JSON5 config (its mode is set to router)")
    args = parser.parse_args(argv)
    try:
        conf = router_config(args.listen, args.config)
        session = zenoh.open(conf)
    except Exception as exc:  # a bad config file or a port in use: one line, exit 2
        print(f"zenoh_router: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return 2
    stop = threading.Event()

    def on_signal(sig: int, frame: FrameType | None) -> None:
        stop.set()

    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    print(f"zenoh router {session.zid()} listening", flush=True)
    while not stop.wait(0.5):
        pass
    session.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
