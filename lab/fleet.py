"""Start a small fleet on loopback: ``sphereplan serve`` instances, a Zenoh router and HAProxy.

Used by the scale-out tests (``tests/service/test_scale_out.py``) and by ``sphereplan bench --suite load``.
Everything listens on free loopback ports; HAProxy runs the shipped ``deploy/haproxy/sphereplan.cfg`` with
the addresses in its environment, the router is :mod:`service.zenoh_router`. Every process is started in its
own process group and stopped by :meth:`Fleet.close` (SIGINT, then SIGKILL after a grace period).
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx

REPO = Path(__file__).resolve().parents[1]
HAPROXY_CFG = REPO / "deploy" / "haproxy" / "sphereplan.cfg"


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@dataclass
class Process:
    """A started process, its log and (for a server) its HTTP address."""

    name: str
    proc: subprocess.Popen[bytes]
    log_path: Path
    url: str = ""
    port: int = 0

    def alive(self) -> bool:
        return self.proc.poll() is None

    def kill(self) -> None:
        """SIGKILL the process group at once (an instance lost: its workers go with it)."""
        if self.alive():
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait(timeout=60)

    def stop(self, grace_s: float = 30.0) -> None:
        if not self.alive():
            return
        os.killpg(self.proc.pid, signal.SIGINT)
        try:
            self.proc.wait(timeout=grace_s)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait(timeout=60)


@dataclass
class Fleet:
    """Processes started in ``folder`` (logs there too)."""

    folder: Path
    token: str | None = None
    processes: list[Process] = field(default_factory=list)

    # ------------------------------------------------------------------ starting

    def _start(self, name: str, cmd: list[str], env: dict[str, str] | None = None) -> Process:
        log_path = self.folder / f"{name}.log"
        with log_path.open("wb") as log:
            proc = subprocess.Popen(cmd, cwd=REPO, env={**os.environ, "PYTHONPATH": str(REPO), **(env or {})},
                                    stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        process = Process(name, proc, log_path)
        self.processes.append(process)
        return process

    def token_file(self) -> Path:
        assert self.token is not None
        path = self.folder / "token"
        path.write_text(self.token + "\n")
        path.chmod(0o600)
        return path

    def instance(self, name: str, maps_dir: Path, workers: int = 1, zenoh_config: dict[str, Any] | None = None,
                 extra: tuple[str, ...] = ()) -> Process:
        """``sphereplan serve`` on a free port (HTTP only unless ``zenoh_config`` is given)."""
        port = free_port()
        cmd = [sys.executable, "-m", "service.cli", "serve", "--port", str(port), "--maps", str(maps_dir),
               "--workers", str(workers), *extra]
        if self.token is not None:
            cmd += ["--token-file", str(self.token_file())]
        if zenoh_config is None:
            cmd.append("--no-zenoh")
        else:
            config = self.folder / f"{name}.json5"
            config.write_text(json.dumps(zenoh_config))
            cmd += ["--zenoh-config", str(config)]
        process = self._start(name, cmd)
        process.url, process.port = f"http://127.0.0.1:{port}", port
        return process

    def router(self) -> tuple[Process, str]:
        """A Zenoh router (Python, router mode) on a free loopback port; (process, its endpoint)."""
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        process = self._start("router", [sys.executable, "-m", "service.zenoh_router", "--listen", endpoint])
        return process, endpoint

    def haproxy(self, backends: list[Process]) -> Process:
        """HAProxy with the shipped config in front of two instances."""
        binary = shutil.which("haproxy") or "/usr/sbin/haproxy"
        if not Path(binary).exists():
            raise FileNotFoundError("haproxy is not installed (Debian: apt-get install haproxy)")
        assert len(backends) == 2, "the shipped config has two server lines"
        port = free_port()
        env = {"SPHEREPLAN_LB_BIND": f"127.0.0.1:{port}", "SPHEREPLAN_P1": f"127.0.0.1:{backends[0].port}",
               "SPHEREPLAN_P2": f"127.0.0.1:{backends[1].port}"}
        process = self._start("haproxy", [binary, "-db", "-f", str(HAPROXY_CFG)], env)
        process.url, process.port = f"http://127.0.0.1:{port}", port
        return process

    # ------------------------------------------------------------------ waiting and stopping

    def wait_ready(self, process: Process, timeout_s: float = 300.0, path: str = "/readyz") -> None:
        """Poll ``path`` until it answers 200 (the process must stay alive meanwhile)."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            if not process.alive():
                raise RuntimeError(f"{process.name} exited with {process.proc.returncode}:\n"
                                   f"{process.log_path.read_text()[-3000:]}")
            try:
                if httpx.get(process.url + path, timeout=2).status_code == 200:
                    return
            except httpx.HTTPError:
                pass
            time.sleep(0.2)
        raise RuntimeError(f"{process.name} not ready within {timeout_s} s:\n{process.log_path.read_text()[-3000:]}")

    def wait_log(self, process: Process, text: str, timeout_s: float = 60.0) -> None:
        end = time.monotonic() + timeout_s
        while text not in process.log_path.read_text():
            if not process.alive() or time.monotonic() > end:
                raise RuntimeError(f"{process.name}: no {text!r} in its log:\n{process.log_path.read_text()[-3000:]}")
            time.sleep(0.1)

    def close(self) -> None:
        for process in reversed(self.processes):
            process.stop()
