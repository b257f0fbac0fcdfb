"""plan_reconfiguration: request validation, the swept-disc map check with alternatives, and the benchmark."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.errors import GoalOutsideMap, InvalidInput, NoValidPathFound, StartOccupied
from planner.occupancy import OccupancyGrid
from planner.spherobot.reconfigure import candidates, plan_reconfiguration
from planner.spherobot.request import ReconfigureRequest
from tests.reconfigcheck import check_result, disc_hits

EXAMPLE = {
    "method": "arc",
    "radius_m": 1.0,
    "start": [4.33, 2.50],
    "start_tilt": [30.0, 75.0],
    "goal": [0.0, 0.0],
    "alpha_final": 180.0,
    "degrees": True,
}


def _grid(
    boxes: list[tuple[float, float, float, float]],
    res: float = 0.1,
    origin=(-8.0, -8.0),
    size=(24.0, 20.0),
    free_boxes: list[tuple[float, float, float, float]] | None = None,
) -> OccupancyGrid:
    """Grid with the given (x0, y0, x1, y1) boxes occupied (or everything occupied but ``free_boxes``)."""
    w, h = round(size[0] / res), round(size[1] / res)
    xs = origin[0] + (np.arange(w) + 0.5) * res
    ys = origin[1] + (np.arange(h) + 0.5) * res
    X, Y = np.meshgrid(xs, ys)
    if free_boxes is not None:
        occ = np.ones((h, w), bool)
        for x0, y0, x1, y1 in free_boxes:
            occ &= ~((X >= x0) & (X <= x1) & (Y >= y0) & (Y <= y1))
    else:
        occ = np.zeros((h, w), bool)
        for x0, y0, x1, y1 in boxes:
            occ |= (X >= x0) & (X <= x1) & (Y >= y0) & (Y <= y1)
    return OccupancyGrid.from_occupied(occ, res, (origin[0], origin[1], 0.0))


def _assert_free(res: dict, grid: OccupancyGrid) -> None:
    R = res["radius_m"]
    assert not any(disc_hits(grid, s["x"], s["y"], R) for s in res["samples"][::5] + res["samples"][-1:])


@pytest.mark.parametrize(
    ("data", "field"),
    [
        ({"method": "walk"}, "method"),
        ({"start_tilt": [4.0, 0.0]}, "start_tilt"),
        ({"start_tilt": [200.0, 0.0], "degrees": True}, "start_tilt"),
        ({"start": [1.0]}, "start"),
        ({"goal": ["a", 1.0]}, "goal"),
        ({"radius_m": -1.0}, "radius_m"),
        ({"radius_m": float("nan")}, "radius_m"),
        ({"goal_heading": float("inf")}, "goal_heading"),
        ({"method": "triangle", "alpha_final": 1.0}, "alpha_final"),
        ({"goal_heading": 1.0, "alpha_final": 1.0}, "alpha_final"),
        ({"colour": "red"}, "colour"),
        ({"degrees": "yes"}, "degrees"),
        ({"roll_rate_rad_s": 0.0}, "roll_rate_rad_s"),
    ],
)
def test_bad_requests_name_the_field(data, field):
    req = {"start": [0.0, 0.0], "goal": [1.0, 1.0], **data}
    with pytest.raises(InvalidInput) as err:
        plan_reconfiguration(req)
    assert err.value.field == field


def test_defaults_come_from_the_spherobot_profile():
    res = plan_reconfiguration({"start": [0.0, 0.0], "goal": [1.0, 0.0]})
    assert res["radius_m"] == 0.25 and res["roll_rate_rad_s"] == 1.0 and res["method"] == "arc"
    assert math.isclose(res["duration_s"], res["length_m"] / 0.25)
    check_result(res, (1.0, 0.0), None)


def test_dataclass_and_dict_requests_give_the_same_plan():
    a = plan_reconfiguration(EXAMPLE)
    req = ReconfigureRequest(
        "arc", (4.33, 2.5), (0.0, 0.0), (math.radians(30), math.radians(75)), 0.0, None, math.pi, 1.0, 1.0
    )
    b = plan_reconfiguration(req)
    assert a["samples"] == b["samples"] and a["segments"] == b["segments"]


def test_map_check_picks_a_free_alternative():
    free = plan_reconfiguration(EXAMPLE)
    assert free["circle"] == "direct"
    grid = _grid([(1.0, 4.2, 4.0, 6.0)])  # blocks the top of the direct circle
    res = plan_reconfiguration(EXAMPLE, grid=grid)
    assert res["variant"] != free["variant"]
    assert res["map"]["alternatives_tried"] >= 2
    _assert_free(res, grid)
    # the reported clearance is a true lower bound: the disc grown by it is still free everywhere
    grown = res["radius_m"] + res["map"]["min_clearance_m"] - 1e-9
    assert not any(disc_hits(grid, s["x"], s["y"], grown) for s in res["samples"])
    assert any(disc_hits(grid, s["x"], s["y"], 1.0) for s in free["samples"])  # the shortest did collide
    check_result(res, (0.0, 0.0), None)


@pytest.mark.parametrize("method", ["arc", "triangle"])
def test_every_alternative_colliding_is_no_valid_path_with_a_reason(method):
    grid = _grid([], free_boxes=[(-0.75, -0.75, 0.75, 0.75), (3.0, -2.0, 8.0, 2.0)])
    req = {
        "method": method,
        "radius_m": 0.5,
        "start": [0.0, 0.0],
        "start_tilt": [1.0, 0.5],
        "goal": [5.0, 0.0],
        "goal_heading": 0.3,
    }
    with pytest.raises(NoValidPathFound) as err:
        plan_reconfiguration(req, grid=grid)
    assert "collide" in str(err.value) and "obstacle at" in str(err.value)
    assert err.value.code == 208


@pytest.mark.parametrize("method", ["arc", "triangle"])
def test_a_pillar_on_the_shortest_manoeuvre_is_avoided(method):
    req = {
        "method": method,
        "radius_m": 0.4,
        "start": [-2.0, 0.5],
        "start_tilt": [0.8, 2.0],
        "goal": [2.0, -0.5],
        "goal_heading": -1.0,
    }
    free = plan_reconfiguration(req)
    # put a pillar where the triangles / the circle of the shortest plan stray farthest from the rest of it
    t0 = min(s["t0_s"] for s in free["segments"] if s["step"].startswith(("triangle", "step 3")))
    pts = np.array([[p["t"], p["x"], p["y"]] for p in free["samples"]])
    late, early = pts[pts[:, 0] > t0, 1:], np.vstack([pts[pts[:, 0] <= t0, 1:], [[2.0, -0.5]]])
    away = np.min(
        np.hypot(late[:, None, 0] - early[None, :, 0], late[:, None, 1] - early[None, :, 1]), axis=1
    )
    px, py = late[int(np.argmax(away))]
    grid = _grid([(px - 0.1, py - 0.1, px + 0.1, py + 0.1)], origin=(-12.0, -12.0), size=(24.0, 24.0))
    res = plan_reconfiguration(req, grid=grid)
    assert res["variant"] != free["variant"] or res["length_m"] != free["length_m"]
    _assert_free(res, grid)
    check_result(res, (2.0, -0.5), -1.0)


def test_start_on_an_obstacle_and_goal_outside_the_map():
    grid = _grid([(3.5, 1.5, 5.0, 3.5)])
    with pytest.raises(StartOccupied):
        plan_reconfiguration(EXAMPLE, grid=grid)
    with pytest.raises(GoalOutsideMap):
        plan_reconfiguration({**EXAMPLE, "goal": [50.0, 0.0]}, grid=_grid([]))


def test_candidates_are_sorted_shortest_first():
    req = ReconfigureRequest.from_dict({**EXAMPLE, "alpha_final": None, "goal_heading": 40.0})
    lengths = [m.length_m for m in candidates(req)]
    assert lengths == sorted(lengths) and len(lengths) > 2
