"""``sphereplan serve``: argument errors, and Ctrl-C ending a server whose worker is mid-plan."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import httpx
import pytest

from service.cli import main as cli_main
from tests.service import service_harness as harness


@pytest.mark.parametrize(("args", "field"), [
    (["--maps", "/nonexistent/maps"], "--maps"),
    (["--workers", "0"], "workers"),
    (["--zenoh-config", "/nonexistent.json5"], "--zenoh-config"),
    (["--max-time-limit", "0"], "max_time_limit_s"),
])
def test_bad_arguments_exit_2_naming_the_field(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                               args: list[str], field: str) -> None:
    maps = harness.make_maps(tmp_path / "maps")
    assert cli_main(["serve", "--maps", str(maps), *args]) == 2
    assert field in capsys.readouterr().err


def test_bad_port_is_an_argparse_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli_main(["serve", "--port", "70000"]) == 2
    assert "--port" in capsys.readouterr().err


def test_default_time_limit_cap_matches_the_wire_models() -> None:
    from service.cli.serve import MAX_TIME_LIMIT_S
    from service.wire import MAX_TIME_LIMIT_S as WIRE_MAX

    assert MAX_TIME_LIMIT_S == WIRE_MAX


def test_ctrl_c_stops_the_server_while_a_plan_runs(tmp_path: Path) -> None:
    """A plan with a 60 s time limit is running when SIGINT arrives: the server must not wait for it."""
    maps = harness.make_maps(tmp_path / "maps")
    port = harness.free_port()
    url = f"http://127.0.0.1:{port}"
    proc = subprocess.Popen(
        [sys.executable, "-m", "service.cli", "serve", "--port", str(port), "--maps", str(maps), "--workers", "1",
         "--no-zenoh"], cwd=harness.REPO, env={**os.environ, "PYTHONPATH": str(harness.REPO)},
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        for _ in range(600):
            try:
                if httpx.get(url + "/readyz", timeout=1).status_code == 200:
                    break
            except httpx.HTTPError:
                pass
            assert proc.poll() is None, proc.stderr.read() if proc.stderr else ""
            time.sleep(0.2)
        slow = harness.plan_body(goal=harness.SLOT_GOAL, options=harness.SLOW, time_limit_s=60.0)
        thread = threading.Thread(target=lambda: _post_ignoring_errors(url, slow), daemon=True)
        thread.start()
        while httpx.get(url + "/healthz", timeout=5).json()["in_flight"] == 0:
            time.sleep(0.05)
        proc.send_signal(signal.SIGINT)
        code = proc.wait(timeout=30)  # far less than the 60 s the plan would run
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert code == 0, proc.stderr.read() if proc.stderr else ""


def _post_ignoring_errors(url: str, body: dict[str, object]) -> None:
    try:
        httpx.post(url + "/v1/plan", json=body, timeout=60)
    except httpx.HTTPError:
        pass
