"""The viewer at ``GET /`` in a real headless Chromium (Debian's ``chromium``, driven by Playwright): load the
page from a running ``sphereplan serve``, click and drag the start and goal, plan, and check that a path
is drawn and the numbers shown are the API's; refreshes the screenshot docs/img/viewer.png when
SPHEREPLAN_UPDATE_DOCS=1."""

from __future__ import annotations

import math
import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from tests.service import service_harness as harness
from tests.service.service_harness import HALL_GOAL, HALL_START, Server

REPO = Path(__file__).resolve().parents[2]
SCREENSHOT = REPO / "docs" / "img" / "viewer.png"
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync"]


@pytest.fixture(scope="module")
def server() -> Iterator[Server]:
    yield harness.acquire()
    harness.release()


def test_viewer_files_are_served_without_external_resources(server: Server) -> None:
    with httpx.Client(base_url=server.url, timeout=30) as client:
        page = client.get("/")
        assert page.status_code == 200 and page.headers["content-type"].startswith("text/html")
        for name in ("viewer.js", "viewer.css"):
            assert client.get(f"/viewer/{name}").status_code == 200
            assert f"/viewer/{name}" in page.text
        assert client.get("/viewer/../http.py").status_code == 404
        assert client.get("/viewer/nope.js").status_code == 404
        for text in (page.text, client.get("/viewer/viewer.js").text, client.get("/viewer/viewer.css").text):
            assert "http://" not in text and "https://" not in text and "//cdn" not in text


def layout(page: Any) -> list[float]:
    """Where the canvas and the side panel are and how tall the header is (CSS px)."""
    return page.evaluate("""() => {
        const c = document.getElementById('canvas').getBoundingClientRect();
        const a = document.querySelector('aside').getBoundingClientRect();
        return [c.left, c.top, c.width, c.height, a.left, a.width, document.querySelector('header').offsetHeight];
    }""")


def plan_again(page: Any, start: tuple[float, float], goal: tuple[float, float]) -> None:
    """Click a new start and goal and plan; wait for the answer."""
    page.select_option("#mode", "start")
    for x, y in (start, goal):
        px, py = page.evaluate("([x, y]) => window.viewer.worldToPage(x, y)", [x, y])
        page.mouse.click(px, py)
    page.click("#plan")
    page.wait_for_function("!window.viewer.busy && (window.viewer.plan !== null || window.viewer.error !== null)",
                           timeout=120_000)


@pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not installed (apt-get install chromium; "
                                              ".ci/run installs it)")
def test_viewer_plans_in_headless_chromium(server: Server, tmp_path: Path) -> None:
    from playwright.sync_api import sync_playwright

    external: list[str] = []
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=FLAGS)
        try:
            page = browser.new_page(viewport={"width": 1300, "height": 800})
            page.on("request", lambda r: None if r.url.startswith(server.url) else external.append(r.url))
            errors: list[str] = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(server.url + "/?map=hall", timeout=60_000)
            page.wait_for_function("window.viewer && window.viewer.ready && window.viewer.map === 'hall'",
                                   timeout=60_000)

            # the start: press, drag towards +y (up the screen) for a heading of 90°, release; the goal: click
            sx, sy = page.evaluate("([x, y]) => window.viewer.worldToPage(x, y)", list(HALL_START[:2]))
            page.mouse.move(sx, sy)
            page.mouse.down()
            page.mouse.move(sx, sy - 40, steps=5)
            page.mouse.up()
            gx, gy = page.evaluate("([x, y]) => window.viewer.worldToPage(x, y)", list(HALL_GOAL[:2]))
            page.mouse.click(gx, gy)
            start = page.evaluate("window.viewer.start")
            goal = page.evaluate("window.viewer.goal")
            assert math.dist((start["x"], start["y"]), HALL_START[:2]) < 0.15
            assert math.dist((goal["x"], goal["y"]), HALL_GOAL[:2]) < 0.15
            assert start["yaw"] == pytest.approx(math.pi / 2, abs=0.05) and goal["yaw"] == 0

            page.click("#plan")
            page.wait_for_function("window.viewer.plan !== null || window.viewer.error !== null", timeout=120_000)
            assert page.evaluate("window.viewer.error") is None
            shown = page.evaluate("window.viewer.plan")
            request = page.evaluate("window.viewer.lastRequest")

            # a path is drawn: the canvas pixel under the path's middle is no longer the map's grey/white
            mid = shown["states"][len(shown["states"]) // 2]
            rgba = page.evaluate("""([x, y]) => {
                const [cx, cy] = window.viewer.worldToCanvas(x, y);
                return Array.from(document.getElementById('canvas').getContext('2d')
                    .getImageData(Math.round(cx), Math.round(cy), 1, 1).data);
            }""", [mid["x"], mid["y"]])
            r, g, b, _ = rgba
            assert not (r == g == b), f"no path drawn at the middle of the plan: {rgba}"

            numbers = {k: page.inner_text(f"#n-{k}") for k in ("status", "length", "expansions", "clearance")}

            # a closed-loop run of the plan from the same page: its metrics are shown
            page.click("#simulate")
            page.wait_for_function("window.viewer.sim !== null || window.viewer.error !== null", timeout=240_000)
            assert page.evaluate("window.viewer.error") is None
            metrics = page.evaluate("window.viewer.sim.metrics")
            assert page.inner_text("#s-rms") == f"{metrics['cross_track_rms_m']:.3f} m"
            page.screenshot(path=str(tmp_path / "viewer.png"))

            # a Spherobot reconfiguration between two new clicks, from the same page
            page.select_option("#mode", "start")
            for x, y in ((2.0, 2.0), (3.5, 3.0)):
                px, py = page.evaluate("([x, y]) => window.viewer.worldToPage(x, y)", [x, y])
                page.mouse.click(px, py)
            page.click("#reconfigure")
            page.wait_for_function("window.viewer.rec !== null || window.viewer.error !== null", timeout=120_000)
            assert page.evaluate("window.viewer.error") is None
            rec = page.evaluate("window.viewer.rec")
            assert rec["status"] == "exact"
            assert page.inner_text("#r-length") == f"{rec['length_m']:.2f} m"
            assert math.dist((rec["final"]["x"], rec["final"]["y"]), (3.5, 3.0)) < 0.15

            # a failed plan (the goal inside the wall): every old number goes, the panel says "failed" and why,
            # and nothing on the page moves
            plan_again(page, (2.0, 2.0), (4.0, 3.5))
            assert page.evaluate("window.viewer.error") is None and page.inner_text("#n-length") != "–"
            page.click("#simulate")
            page.wait_for_function("window.viewer.sim !== null || window.viewer.error !== null", timeout=240_000)
            before = layout(page)
            plan_again(page, (2.0, 2.0), (5.1, 2.0))
            assert page.evaluate("window.viewer.error") is not None
            assert page.inner_text("#n-status") == "failed" and "goal" in page.inner_text("#n-why")
            for cell in ("n-length", "n-duration", "n-time", "n-expansions", "n-clearance", "n-roll", "s-status",
                         "s-rms", "s-max", "s-final", "s-est", "r-mode", "r-length", "r-pos", "r-p"):
                assert page.inner_text(f"#{cell}") == "–", cell
            assert page.evaluate("[window.viewer.plan, window.viewer.sim, window.viewer.rec]") == [None, None, None]
            assert "failed" in page.inner_text("#status")
            assert layout(page) == before
        finally:
            browser.close()
    assert not errors, errors
    assert not external, f"the page loaded from elsewhere: {external}"

    # the numbers shown are the API's for the same request
    with httpx.Client(base_url=server.url, timeout=60) as client:
        api = client.post("/v1/plan", json=request)
    assert api.status_code == 200, api.text
    body = api.json()
    assert numbers["status"] == body["status"] == shown["status"] == "exact"
    assert numbers["length"] == f"{body['length_m']:.2f} m"
    assert numbers["clearance"] == f"{body['min_clearance_m']:.2f} m"
    assert int(numbers["expansions"]) == body["expansions"]
    assert len(shown["states"]) == len(body["states"])
    if os.environ.get("SPHEREPLAN_UPDATE_DOCS") == "1":  # a test run leaves the checkout as it found it
        shutil.copyfile(tmp_path / "viewer.png", SCREENSHOT)
