"""An independent judge for reconfiguration results, written apart from the planners' closed forms.

It rebuilds each result's ground path from the JSON segments, re-rolls it as a fine polyline
(``roll_polyline``: one straight roll per piece, no closed-form arc rotation) and checks the samples, the
final state and the goal; and it rasterises the sphere's disc on the raw grid for map checks.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from hypothesis import settings
from hypothesis import strategies as st

from planner.kinematics import wrap
from planner.occupancy import OccupancyGrid
from planner.spherobot.rolling import GroundSegment, quat_angle, roll_polyline, tilt_from_quat

# Shared hypothesis profiles of the rolling / reconfiguration tests: derandomized and bounded so the
# suite stays fast and repeatable.
FAST = settings(max_examples=40, derandomize=True, deadline=None)
PLANS = settings(max_examples=25, derandomize=True, deadline=None)
angle = st.floats(-math.pi, math.pi)

POSITION_TOL = 1e-3  # × R
ANGLE_TOL = math.radians(0.1)


def segments_from_json(result: dict[str, Any]) -> list[GroundSegment]:
    return [
        GroundSegment(
            s["start"][0], s["start"][1], s["heading_rad"], s["length_m"], s["curvature_1_m"], s["action"]
        )
        for s in result["segments"]
    ]


def reroll(result: dict[str, Any], pieces: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Re-roll the result's own ground path; returns (sample xy (N, 2) on the path, quaternions (N, 4))."""
    segs = segments_from_json(result)
    speed = result["speed_m_s"]
    samples = result["samples"]
    s_glob = np.array([p["t"] for p in samples]) * speed
    cum = np.concatenate([[0.0], np.cumsum([sg.length_m for sg in segs])])
    q0 = tuple(samples[0][k] for k in ("qw", "qx", "qy", "qz"))
    pts = [np.array([[samples[0]["x"], samples[0]["y"]]])]
    idx = [0]
    count = 1
    for j in range(1, len(samples)):
        mid = 0.5 * (s_glob[j - 1] + s_glob[j])
        i = int(np.searchsorted(cum, mid) - 1)
        i = min(max(i, 0), len(segs) - 1)
        local = np.linspace(s_glob[j - 1], s_glob[j], pieces + 1)[1:] - cum[i]
        x, y = segs[i].point_at(local)
        pts.append(np.column_stack([x, y]))
        count += pieces
        idx.append(count - 1)
    poly = np.concatenate(pts)
    quats = roll_polyline(q0, poly, result["radius_m"])  # type: ignore[arg-type]
    return poly[idx], quats[idx]


def check_result(result: dict[str, Any], goal: tuple[float, float], goal_heading: float | None) -> None:
    """Assert the samples agree with re-rolling the path and the re-rolled end meets the goal."""
    R = result["radius_m"]
    samples = result["samples"]
    xy = np.array([[p["x"], p["y"]] for p in samples])
    q = np.array([[p["qw"], p["qx"], p["qy"], p["qz"]] for p in samples])
    t = np.array([p["t"] for p in samples])
    # spacing: at most 0.02 R of rolling between samples, time increasing
    ds = np.diff(t) * result["speed_m_s"]
    assert np.all(ds > 0) and np.all(ds <= 0.02 * R * (1 + 1e-9))
    assert np.all(np.hypot(*np.diff(xy, axis=0).T) <= 0.02 * R * (1 + 1e-9))
    # samples agree with re-rolling their own ground path
    rxy, rq = reroll(result)
    assert np.allclose(rxy, xy, atol=1e-9 * max(1.0, R))
    worst = max(quat_angle(tuple(a), tuple(b)) for a, b in zip(q, rq, strict=True))  # type: ignore[arg-type]
    assert worst < 1e-4, f"samples disagree with re-rolling by {math.degrees(worst):.4f}°"
    # the re-rolled end state meets the goal
    theta, _, heading = tilt_from_quat(tuple(rq[-1]))  # type: ignore[arg-type]
    assert math.hypot(rxy[-1, 0] - goal[0], rxy[-1, 1] - goal[1]) <= POSITION_TOL * R
    assert theta <= ANGLE_TOL
    if goal_heading is not None:
        assert abs(wrap(heading - goal_heading)) <= ANGLE_TOL
    # the reported final state is the last sample
    f = result["final"]
    assert (f["x"], f["y"]) == (samples[-1]["x"], samples[-1]["y"])


def disc_hits(grid: OccupancyGrid, x: float, y: float, radius_m: float) -> bool:
    """True when the disc of radius ``radius_m`` at (x, y) overlaps a blocked cell or leaves the map."""
    res = grid.resolution_m
    ox, oy = grid.origin[0], grid.origin[1]
    if x - radius_m < ox or y - radius_m < oy:
        return True
    if x + radius_m > ox + grid.width * res or y + radius_m > oy + grid.height * res:
        return True
    blocked = grid.blocked()
    ix0, ix1 = int((x - radius_m - ox) // res), int((x + radius_m - ox) // res)
    iy0, iy1 = int((y - radius_m - oy) // res), int((y + radius_m - oy) // res)
    for iy in range(max(iy0, 0), min(iy1, grid.height - 1) + 1):
        for ix in range(max(ix0, 0), min(ix1, grid.width - 1) + 1):
            if not blocked[iy, ix]:
                continue
            cx = min(max(x, ox + ix * res), ox + (ix + 1) * res)
            cy = min(max(y, oy + iy * res), oy + (iy + 1) * res)
            if math.hypot(cx - x, cy - y) < radius_m:
                return True
    return False
