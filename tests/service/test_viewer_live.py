"""The viewer's live session in headless Chromium against a real ``sphereplan serve``: start a session from the
clicked start and goal, report an obstacle on the path by clicking, and see the path replanned and the live map
redrawn (through the Server-Sent Events stream)."""

from __future__ import annotations

import math
import shutil
from collections.abc import Iterator

import pytest

from tests.service import service_harness as harness
from tests.service.service_harness import HALL_GOAL, HALL_START, Server

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync"]


@pytest.fixture(scope="module")
def server() -> Iterator[Server]:
    yield harness.acquire()
    harness.release()


@pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not installed")
def test_live_session_replans_when_an_obstacle_is_clicked(server: Server) -> None:
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=FLAGS)
        try:
            page = browser.new_page(viewport={"width": 1300, "height": 800})
            errors: list[str] = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(server.url + "/?map=hall", timeout=60_000)
            page.wait_for_function("window.viewer && window.viewer.ready && window.viewer.map === 'hall'",
                                   timeout=60_000)
            for pose in (HALL_START, HALL_GOAL):
                px, py = page.evaluate("([x, y]) => window.viewer.worldToPage(x, y)", list(pose[:2]))
                page.mouse.click(px, py)
            page.click("#live")
            page.wait_for_function("window.viewer.live !== null && window.viewer.plan !== null || "
                                   "window.viewer.error !== null", timeout=120_000)
            assert page.evaluate("window.viewer.error") is None
            first = page.evaluate("window.viewer.plan")
            # the path's state nearest the gap above the wall at x = 5 m: put an obstacle there
            xs = [s for s in first["states"] if abs(s["x"] - 5.15) < 0.1]
            target = min(xs, key=lambda s: abs(s["y"] - 5.5))
            page.select_option("#mode", "obstacle")
            px, py = page.evaluate("([x, y]) => window.viewer.worldToPage(x, y)", [target["x"], target["y"]])
            page.mouse.click(px, py)
            page.wait_for_function("document.getElementById('l-replans').textContent === '2'", timeout=120_000)
            second = page.evaluate("window.viewer.plan")
            assert second is not None and second["states"] != first["states"]
            nearest = min(math.dist((s["x"], s["y"]), (target["x"], target["y"])) for s in second["states"])
            assert nearest > 0.3  # the new path keeps off the reported obstacle
            assert page.inner_text("#l-last").startswith("blocked, ok")
        finally:
            browser.close()
    assert not errors, errors
