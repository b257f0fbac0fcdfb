"""Spherobot reconfiguration (paper 004, docs/references.md): the entry point and its result JSON.

:func:`plan_reconfiguration` is the one call the CLI, HTTP and Zenoh layers make. It asks the chosen
planner (§3 spherical triangles, :mod:`planner.spherobot.triangle`; §4 straight rolls and circles,
:mod:`planner.spherobot.arc`) for its candidate manoeuvres, shortest first, rolls each through SO(3)
(:mod:`planner.spherobot.rollout`) and returns the first that reaches the goal (and, with a map, whose
swept disc of radius R stays in free space) as a JSON-ready dict: segments with the paper's controls
ω'x, ω'y (eq. 1–4 inverted), samples, the rolled final state and its errors.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any

import numpy as np

from planner.errors import (
    GoalOccupied,
    GoalOutsideMap,
    NoValidPathFound,
    StartOccupied,
    StartOutsideMap,
)
from planner.maps.clearance import ClearanceMap
from planner.occupancy import OccupancyGrid
from planner.spherobot.arc import arc_candidates
from planner.spherobot.manoeuvre import Manoeuvre
from planner.spherobot.request import ReconfigureRequest
from planner.spherobot.rolling import (
    GroundSegment,
    Quat,
    model_controls,
    quat_conj,
    quat_rotate,
    tilt_from_quat,
)
from planner.spherobot.rollout import RolledManoeuvre, goal_errors, roll_manoeuvre
from planner.spherobot.triangle import triangle_candidates
from planner.termination import Termination

POSITION_TOL = 1e-3  # goal position tolerance, in radii
ANGLE_TOL_RAD = math.radians(0.1)
SAMPLE_FIELDS = ("t", "x", "y", "qw", "qx", "qy", "qz")


def _load_grid(path: str) -> OccupancyGrid:
    from planner.maps.nav2 import load_map  # imported only when a map is used

    return load_map(path)


def candidates(req: ReconfigureRequest) -> list[Manoeuvre]:
    """All candidate manoeuvres of the request's method, shortest first."""
    assert req.radius_m is not None
    q0 = req.start_quat
    if req.method == "arc":
        return arc_candidates(req.start, q0, req.goal, req.goal_heading, req.alpha_final, req.radius_m)
    return triangle_candidates(req.start, q0, req.goal, req.goal_heading, req.radius_m)


def plan_reconfiguration(
    request: ReconfigureRequest | Mapping[str, Any], grid: OccupancyGrid | None = None,
    termination: Termination | None = None,
) -> dict[str, Any]:
    """Plan, roll and (optionally) map-check a reconfiguration; return the result JSON as a dict.

    The doors pass the :class:`ReconfigureRequest` they built; a JSON request (Python callers) is read
    with :meth:`ReconfigureRequest.from_dict`. ``grid`` overrides ``request.map``. Raises InvalidInput for
    a bad request or map, Start/GoalOccupied, Start/GoalOutsideMap, and NoValidPathFound (with the
    reason) when every alternative collides. ``termination`` bounds the wall clock (and may cancel): checked
    before each candidate manoeuvre is rolled.
    """
    t_start = time.perf_counter()
    clock = termination.start() if termination is not None else None
    req = request if isinstance(request, ReconfigureRequest) else ReconfigureRequest.from_dict(request)
    assert req.radius_m is not None and req.roll_rate_rad_s is not None
    R = req.radius_m
    speed = req.roll_rate_rad_s * R
    if grid is None and req.map is not None:
        grid = _load_grid(req.map)
    checker = ClearanceMap(grid, req.allow_unknown) if grid is not None else None
    if checker is not None:
        assert grid is not None
        for name, pt, outside, occupied in (
            ("start", req.start, StartOutsideMap, StartOccupied),
            ("goal", req.goal, GoalOutsideMap, GoalOccupied),
        ):
            if not grid.contains(*pt):
                raise outside(f"{name} ({pt[0]:.3f}, {pt[1]:.3f}) is outside map {grid.name!r}")
            if checker.at(np.array([pt[0]]), np.array([pt[1]]))[0] < R:
                raise occupied(
                    f"the sphere (radius {R} m) at the {name} overlaps an obstacle of map {grid.name!r}"
                )

    cands = candidates(req)
    q0 = req.start_quat
    tried = 0
    first_hit: str | None = None
    for m in cands:
        if clock is not None:
            clock.check("the reconfiguration")
        rolled = roll_manoeuvre(m, req.start, q0, R, speed)
        pos_err, p_err, head_err = goal_errors(rolled.xy[-1], rolled.final_quat, req.goal, req.goal_heading)
        if (
            pos_err > POSITION_TOL * R
            or p_err > ANGLE_TOL_RAD
            or (head_err is not None and head_err > ANGLE_TOL_RAD)
        ):
            continue  # a candidate the simulator rejects is never returned
        tried += 1
        clearance = None
        if checker is not None:
            cl = checker.at(rolled.xy[:, 0], rolled.xy[:, 1])
            bad = np.flatnonzero(cl < R)
            if bad.size:
                if first_hit is None:
                    i = int(bad[0])
                    seg = int(np.searchsorted(np.asarray(rolled.segment_t0), rolled.t[i], side="right")) - 1
                    where = m.steps[max(0, min(seg, len(m.steps) - 1))] if m.steps else "start"
                    first_hit = (
                        f"the shortest ({m.variant}, {m.length_m:.3f} m) sweeps an obstacle at "
                        f"({rolled.xy[i, 0]:.3f}, {rolled.xy[i, 1]:.3f}) during '{where}'"
                    )
                continue
            clearance = float(cl.min()) - R
        return _result(req, rolled, time.perf_counter() - t_start, grid, tried, clearance)
    if first_hit is None:
        raise NoValidPathFound(f"the {req.method} planner found no manoeuvre for this problem")
    raise NoValidPathFound(
        f"all {tried} alternatives of the {req.method} method collide with the map; {first_hit}"
    )


def _segment_json(
    seg: GroundSegment, step: str, q: Quat, t0: float, R: float, speed: float
) -> dict[str, Any]:
    h = seg.heading_rad
    w = speed / R
    omega_world = (-w * math.sin(h), w * math.cos(h), 0.0)
    omega_body = quat_rotate(quat_conj(q), omega_world)
    theta, alpha, _ = tilt_from_quat(q)
    if theta < 1e-9:
        alpha = h  # α is undefined with P on top; rolling away tilts P towards the direction of travel
    wxp, wyp = model_controls(h, speed, alpha, R)
    out: dict[str, Any] = {
        "kind": seg.kind,
        "action": seg.action,
        "step": step,
        "start": [seg.x0, seg.y0],
        "end": list(seg.end),
        "heading_rad": h,
        "length_m": seg.length_m,
        "curvature_1_m": seg.curvature_1_m,
    }
    if seg.kind == "arc":
        out["center"] = list(seg.center or ())
        out["radius_m"] = 1.0 / abs(seg.curvature_1_m)
        out["turn_rad"] = seg.curvature_1_m * seg.length_m
    out.update(
        {
            "omega_body_rad_s": list(omega_body),
            "omega_xp_rad_s": wxp,
            "omega_yp_rad_s": wyp,
            "t0_s": t0,
            "duration_s": seg.length_m / speed,
        }
    )
    return out


def _result(
    req: ReconfigureRequest,
    rolled: RolledManoeuvre,
    planning_time_s: float,
    grid: OccupancyGrid | None,
    tried: int,
    clearance: float | None,
) -> dict[str, Any]:
    assert req.radius_m is not None and req.roll_rate_rad_s is not None
    R, speed = req.radius_m, req.roll_rate_rad_s * req.radius_m
    m = rolled.manoeuvre
    qf = rolled.final_quat
    theta_f, alpha_f, heading_f = tilt_from_quat(qf)
    pos_err, p_err, head_err = goal_errors(rolled.xy[-1], qf, req.goal, req.goal_heading)
    q0 = req.start_quat
    table = np.column_stack([rolled.t, rolled.xy, rolled.quat]).tolist()
    samples = [dict(zip(SAMPLE_FIELDS, row, strict=True)) for row in table]
    result: dict[str, Any] = {
        "status": "exact",
        "error_code": 0,
        "error_msg": "",
        "method": req.method,
        "mode": "partial" if req.goal_heading is None else "complete",
        "variant": m.variant,
        "radius_m": R,
        "roll_rate_rad_s": req.roll_rate_rad_s,
        "speed_m_s": speed,
        "start": {
            "x": req.start[0],
            "y": req.start[1],
            "theta_rad": req.start_tilt[0],
            "alpha_rad": req.start_tilt[1],
            "spin_rad": req.start_spin,
            "qw": q0[0],
            "qx": q0[1],
            "qy": q0[2],
            "qz": q0[3],
        },
        "goal": {
            "x": req.goal[0],
            "y": req.goal[1],
            "heading_rad": req.goal_heading,
            "alpha_final_rad": req.alpha_final,
        },
        "length_m": m.length_m,
        "path_length_m": m.length_m,
        "duration_s": m.length_m / speed,
        "planning_time_s": planning_time_s,
        "segments": [
            _segment_json(seg, step, q, t0, R, speed)
            for seg, step, q, t0 in zip(
                m.segments, m.steps, rolled.segment_quat, rolled.segment_t0, strict=True
            )
        ],
        "samples": samples,
        "final": {
            "x": float(rolled.xy[-1, 0]),
            "y": float(rolled.xy[-1, 1]),
            "qw": qf[0],
            "qx": qf[1],
            "qy": qf[2],
            "qz": qf[3],
            "theta_rad": theta_f,
            "alpha_rad": alpha_f,
            "heading_rad": heading_f,
            "position_error_m": pos_err,
            "p_from_top_rad": p_err,
            "heading_error_rad": head_err,
        },
    }
    result.update(m.info)
    if grid is not None:
        result["map"] = {**grid.metadata(), "alternatives_tried": tried, "min_clearance_m": clearance}
    return result
