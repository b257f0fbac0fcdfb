"""The numbers the lab's docstrings and the README state about the benchmark's collision models."""

from __future__ import annotations

import re
from pathlib import Path

from lab.planning import referee, shipped
from planner.hybrid_astar import search
from planner.maps.clearance import CircleFootprint
from planner.robot import load_robot

REPO = Path(__file__).resolve().parents[3]


def test_referee_caps_clearance_where_the_plan_does() -> None:
    assert referee.DEFAULT_REACH_M == search.CLEARANCE_REACH_M


def test_ompl_gets_the_covering_circle_the_readme_and_the_bench_state() -> None:
    cover = CircleFootprint.for_robot(load_robot("zju-60"))
    assert len(cover.offsets_x) == 1
    doc = shipped.__doc__ or ""
    assert re.search(rf"one circle, {cover.radius_m:.3f} m for zju-60", doc), doc
    readme = " ".join((REPO / "README.md").read_text().split())
    assert f"for zju-60 one {cover.radius_m:.3f} m circle over the padded polygon" in readme
    assert cover.excess(load_robot("zju-60").footprint_polygon) >= 0.0  # it covers the polygon
