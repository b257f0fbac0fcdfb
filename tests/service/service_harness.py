"""Shared by the service tests: test maps, free ports, and one real ``sphereplan serve`` process.

The server is started once per test session (the first test module that asks for it) with HTTP on a
free port and a Zenoh peer listening on another free loopback port given through ``--zenoh-config``
(never 7447), and stopped with SIGINT at the end of the session.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx
import numpy as np

from planner.maps.nav2 import save_map
from planner.occupancy import OccupancyGrid

REPO = Path(__file__).resolve().parents[2]
HALL_START = (2.0, 2.0, 0.0)
HALL_GOAL = (8.0, 2.0, 0.0)
# inside a dead-end slot 1.3 m wide, facing out of it: reachable for a point, never for a sphere that
# cannot turn on the spot or reverse (with ``SLOW``), so the search runs until its time limit or
# until its bounded reverse search proves the dead end
SLOT_GOAL = (0.7, 7.25, 0.0)
#: options that keep a plan to SLOT_GOAL searching until its time limit (the tests' slow job). Without the dead-end
#: check the search would still prove the slot unreachable by exhausting every state: at the default 36 heading bins
#: that took 4.5 s on an idle 2-core Xeon (72 bins: 8.4 s), within reach of the tests' limits on a fast machine; at
#: 288 bins it reaches the default iteration cap of 2 000 000 expansions first, after 22 s there
SLOW = {"allow_reverse": False, "dead_end_check": False, "n_yaw_bins": 288}


def hall_grid() -> OccupancyGrid:
    """10 m × 8 m at 0.1 m: a wall from the bottom at x = 5 m, a dead-end slot at the top left."""
    occupied = np.zeros((80, 100), dtype=bool)
    occupied[[0, -1], :] = True
    occupied[:, [0, -1]] = True
    occupied[:45, 50:53] = True
    occupied[65, :22] = True
    return OccupancyGrid.from_occupied(occupied, 0.1, name="hall")


def make_maps(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    save_map(hall_grid(), folder / "hall.yaml")
    return folder


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def plan_body(start: tuple[float, float, float] = HALL_START, goal: tuple[float, float, float] = HALL_GOAL,
              **extra: object) -> dict[str, object]:
    return {"map": "hall", "start": dict(zip(("x", "y", "yaw"), start, strict=True)),
            "goal": dict(zip(("x", "y", "yaw"), goal, strict=True)), **extra}


def strip_timing(result: dict[str, object]) -> dict[str, object]:
    """A result without its ``*_time_s`` wall-clock timings (all that differs between identical runs)."""
    return {k: v for k, v in result.items() if not k.endswith("_time_s")}


def strip_sim_timing(sim: dict[str, Any]) -> dict[str, Any]:
    """A SIM.json without the solver's wall-clock step times."""
    metrics = {k: v for k, v in sim["metrics"].items() if "_ms" not in k}
    return {**sim, "metrics": metrics}


@dataclass
class Server:
    proc: subprocess.Popen[bytes]
    url: str
    zenoh_endpoint: str
    maps_dir: Path
    log_path: Path

    def stop(self) -> tuple[int, float]:
        """SIGINT (Ctrl-C) and wait; returns (exit code, seconds until it exited)."""
        t0 = time.monotonic()
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        return int(self.proc.returncode), time.monotonic() - t0


def start_server(workers: int = 2, max_in_flight: int = 24, max_time_limit_s: float = 3.0, *extra: str,
                 zenoh_config: dict[str, Any] | None = None) -> Server:
    """``sphereplan serve`` on free ports with ``extra`` options; ``zenoh_config`` replaces the loopback peer's
    config (its ``listen`` endpoints are kept if given, else the free port is listened on)."""
    tmp = Path(tempfile.mkdtemp(prefix="sphereplan-serve-"))
    maps_dir = make_maps(tmp / "maps")
    port, zport = free_port(), free_port()
    endpoint = f"tcp/127.0.0.1:{zport}"
    config = tmp / "zenoh.json5"
    config.write_text(json.dumps(zenoh_config or {"mode": "peer", "listen": {"endpoints": [endpoint]},
                                                  "scouting": {"multicast": {"enabled": False}}}))
    log_path = tmp / "serve.log"
    cmd = [sys.executable, "-m", "service.cli", "serve", "--port", str(port), "--maps", str(maps_dir),
           "--zenoh-config", str(config), "--workers", str(workers), "--max-in-flight", str(max_in_flight),
           "--max-time-limit", str(max_time_limit_s), *extra]
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    with log_path.open("wb") as log:
        proc = subprocess.Popen(cmd, cwd=REPO, env=env, stdout=log, stderr=subprocess.STDOUT)
    server = Server(proc, f"http://127.0.0.1:{port}", endpoint, maps_dir, log_path)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise RuntimeError(f"sphereplan serve exited with {proc.returncode}:\n{log_path.read_text()}")
        try:
            if httpx.get(server.url + "/readyz", timeout=1).status_code == 200:
                return server
        except httpx.HTTPError:
            pass
        time.sleep(0.2)
    server.stop()
    raise RuntimeError(f"sphereplan serve not ready in time:\n{log_path.read_text()}")


_shared: Server | None = None
_users = 0


def acquire() -> Server:
    """The session's shared server (started on first use)."""
    global _shared, _users
    if _shared is None:
        _shared = start_server()
    _users += 1
    return _shared


def release() -> tuple[int, float] | None:
    """Drop one user; the last one stops the server and gets (exit code, seconds to exit)."""
    global _shared, _users
    _users -= 1
    if _users == 0 and _shared is not None:
        server, _shared = _shared, None
        return server.stop()
    return None


ZENOH_CLIENT = Path(__file__).with_name("zenoh_client.py")


def zenoh_steps(server: Server, steps: list[dict[str, Any]], timeout_s: float = 300) -> list[dict[str, Any]]:
    """Run the steps in a separate Zenoh client process (``zenoh_client.py``); its answers, one per step."""
    done = subprocess.run([sys.executable, str(ZENOH_CLIENT), server.zenoh_endpoint], input=json.dumps(steps),
                          capture_output=True, text=True, timeout=timeout_s, check=False)
    assert done.returncode == 0, done.stderr
    answers: list[dict[str, Any]] = json.loads(done.stdout)
    return answers
