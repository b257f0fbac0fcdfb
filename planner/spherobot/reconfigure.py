"""Reconfiguration requests and results: plan with either Spherobot method, prove it by rolling, check a map.

:func:`plan_reconfiguration` is the one entry point the CLI, HTTP and Zenoh layers call. It takes a request
(a :class:`ReconfigureRequest` or the equivalent JSON dict), asks the chosen planner (paper 004 §3
spherical triangles, ``planner.spherobot.triangle``; §4 straight rolls and circles,
``planner.spherobot.arc``) for its candidate manoeuvres, shortest first, rolls each through the exact
SO(3) rolling simulator (``planner.spherobot.rolling``), and returns the first one that reaches the goal (and, with a
map, whose swept disc of radius R stays in free space) as a JSON-ready dict: segments, samples at most
0.02·R of rolling apart, the rolled final state and its errors. ``python -m planner.spherobot.reconfigure`` prints a
plan-time benchmark table.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.errors import (
    GoalOccupied,
    GoalOutsideMap,
    InvalidInput,
    NoValidPathFound,
    StartOccupied,
    StartOutsideMap,
)
from planner.kinematics import wrap
from planner.maps.clearance import ClearanceMap
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from planner.spherobot.arc import arc_candidates
from planner.spherobot.manoeuvre import Manoeuvre
from planner.spherobot.rolling import (
    GroundSegment,
    Quat,
    model_controls,
    quat_conj,
    quat_from_tilt,
    quat_rotate,
    sample_segment,
    tilt_from_quat,
)
from planner.spherobot.triangle import triangle_candidates

METHODS = ("arc", "triangle")
SAMPLE_SPACING = 0.02  # samples at most this many radii of rolling apart
POSITION_TOL = 1e-3  # goal position tolerance, in radii
ANGLE_TOL_RAD = math.radians(0.1)
ROBOT = "spherobot"
SAMPLE_FIELDS = ("t", "x", "y", "qw", "qx", "qy", "qz")


@dataclass(frozen=True)
class ReconfigureRequest:
    """A reconfiguration problem (SI units, radians).

    ``start_tilt`` is (θ, α) of paper 004 Fig. 2: P = (sin θ cos α, sin θ sin α, cos θ), θ ∈ [0, π]; the
    start orientation is Rot((−sin α, cos α, 0), θ)·Rz(start_spin). Without ``goal_heading`` (azimuth of
    body +x with P on top) it is a partial reconfiguration; ``alpha_final`` (arc method only) fixes the
    direction of the last roll. ``radius_m`` and ``roll_rate_rad_s`` default to the ``spherobot`` profile.
    """

    method: str
    start: tuple[float, float]
    goal: tuple[float, float]
    start_tilt: tuple[float, float] = (0.0, 0.0)
    start_spin: float = 0.0
    goal_heading: float | None = None
    alpha_final: float | None = None
    radius_m: float | None = None
    roll_rate_rad_s: float | None = None
    map: str | None = None
    allow_unknown: bool = False

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ReconfigureRequest:
        """Validate a JSON request; angles are in degrees when ``degrees`` is true. Raises InvalidInput."""
        known = {f for f in cls.__dataclass_fields__} | {"degrees"}
        for key in data:
            if key not in known:
                raise InvalidInput(key, f"unknown field; expected some of {sorted(known)}")
        deg = data.get("degrees", False)
        if not isinstance(deg, bool):
            raise InvalidInput("degrees", "must be true or false")
        scale = math.pi / 180.0 if deg else 1.0
        method = data.get("method", "arc")
        if method not in METHODS:
            raise InvalidInput("method", f"must be one of {', '.join(METHODS)}, got {method!r}")
        if "start" not in data:
            raise InvalidInput("start", "is required")
        if "goal" not in data:
            raise InvalidInput("goal", "is required")
        tilt = _pair(data.get("start_tilt", (0.0, 0.0)), "start_tilt")
        map_path = data.get("map")
        if map_path is not None and not isinstance(map_path, str):
            raise InvalidInput("map", "must be a path to a map YAML")
        allow_unknown = data.get("allow_unknown", False)
        if not isinstance(allow_unknown, bool):
            raise InvalidInput("allow_unknown", "must be true or false")
        return cls(
            method=method,
            start=_pair(data["start"], "start"),
            goal=_pair(data["goal"], "goal"),
            start_tilt=(tilt[0] * scale, tilt[1] * scale),
            start_spin=_number(data.get("start_spin", 0.0), "start_spin") * scale,
            goal_heading=_optional(data.get("goal_heading"), "goal_heading", scale),
            alpha_final=_optional(data.get("alpha_final"), "alpha_final", scale),
            radius_m=_optional(data.get("radius_m"), "radius_m", 1.0),
            roll_rate_rad_s=_optional(data.get("roll_rate_rad_s"), "roll_rate_rad_s", 1.0),
            map=map_path,
            allow_unknown=allow_unknown,
        )

    def validated(self) -> ReconfigureRequest:
        """Check ranges and fill the profile defaults; raises InvalidInput naming the field."""
        if self.method not in METHODS:
            raise InvalidInput("method", f"must be one of {', '.join(METHODS)}, got {self.method!r}")
        for name in ("start", "goal", "start_tilt"):
            for v in getattr(self, name):
                _number(v, name)
        _number(self.start_spin, "start_spin")
        theta = self.start_tilt[0]
        if not 0.0 <= theta <= math.pi:
            raise InvalidInput("start_tilt", f"θ must be in [0, π] rad (0..180°), got {theta!r}")
        for name in ("goal_heading", "alpha_final"):
            v = getattr(self, name)
            if v is not None:
                _number(v, name)
        if self.alpha_final is not None and self.method != "arc":
            raise InvalidInput("alpha_final", "only the arc method has a final roll direction")
        if self.alpha_final is not None and self.goal_heading is not None:
            raise InvalidInput("alpha_final", "cannot be combined with goal_heading (the heading fixes α_f)")
        profile = None
        radius, rate = self.radius_m, self.roll_rate_rad_s
        if radius is None or rate is None:
            profile = load_robot(ROBOT)
        if radius is None:
            assert profile is not None
            radius = profile.radius_m
        if rate is None:
            assert profile is not None
            rate = float(profile.extra.get("spherobot", {}).get("roll_rate_rad_s", 1.0))
        for name, v in (("radius_m", radius), ("roll_rate_rad_s", rate)):
            if not (math.isfinite(v) and v > 0):
                raise InvalidInput(name, f"must be a finite number > 0, got {v!r}")
        return ReconfigureRequest(
            self.method,
            self.start,
            self.goal,
            self.start_tilt,
            self.start_spin,
            self.goal_heading,
            self.alpha_final,
            radius,
            rate,
            self.map,
            self.allow_unknown,
        )

    @property
    def start_quat(self) -> Quat:
        return quat_from_tilt(self.start_tilt[0], self.start_tilt[1], self.start_spin)


def _number(value: Any, field: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InvalidInput(field, f"must be a number, got {value!r}")
    if not math.isfinite(value):
        raise InvalidInput(field, f"must be finite, got {value!r}")
    return float(value)


def _optional(value: Any, field: str, scale: float) -> float | None:
    return None if value is None else _number(value, field) * scale


def _pair(value: Any, field: str) -> tuple[float, float]:
    if not isinstance(value, Sequence) or isinstance(value, str) or len(value) != 2:
        raise InvalidInput(field, f"must be two numbers, got {value!r}")
    return _number(value[0], field), _number(value[1], field)


# ---------------------------------------------------------------------------------------------------------
# Rolling a manoeuvre: samples and the final state.
# ---------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class RolledManoeuvre:
    """A manoeuvre rolled through SO(3): samples (N,) t, x, y and (N, 4) quaternions; per-segment starts."""

    manoeuvre: Manoeuvre
    t: np.ndarray
    xy: np.ndarray
    quat: np.ndarray
    segment_quat: tuple[Quat, ...]
    segment_t0: tuple[float, ...]

    @property
    def final_quat(self) -> Quat:
        return tuple(float(v) for v in self.quat[-1])  # type: ignore[return-value]


def roll_manoeuvre(
    m: Manoeuvre, start: tuple[float, float], q0: Quat, radius_m: float, speed_m_s: float
) -> RolledManoeuvre:
    """Roll ``m`` exactly and sample it at most ``SAMPLE_SPACING·R`` of rolling apart."""
    ts: list[np.ndarray] = [np.zeros(1)]
    xys: list[np.ndarray] = [np.array([start], dtype=float)]
    qs: list[np.ndarray] = [np.array([q0], dtype=float)]
    seg_q: list[Quat] = []
    seg_t0: list[float] = []
    q, t = q0, 0.0
    step = SAMPLE_SPACING * radius_m
    for seg in m.segments:
        seg_q.append(q)
        seg_t0.append(t)
        if seg.length_m <= 0.0:
            continue
        n = max(1, math.ceil(seg.length_m / step - 1e-9))
        s = np.linspace(0.0, seg.length_m, n + 1)[1:]
        quats = sample_segment(q, seg, radius_m, s)
        x, y = seg.point_at(s)
        ts.append(t + s / speed_m_s)
        xys.append(np.column_stack([x, y]))
        qs.append(quats)
        q = tuple(float(v) for v in quats[-1])  # type: ignore[assignment]
        t += seg.length_m / speed_m_s
    return RolledManoeuvre(
        m, np.concatenate(ts), np.concatenate(xys), np.concatenate(qs), tuple(seg_q), tuple(seg_t0)
    )


def goal_errors(
    xy: Sequence[float], q: Quat, goal: tuple[float, float], goal_heading: float | None
) -> tuple[float, float, float | None]:
    """(position error m, P's angle from the top rad, heading error rad or None) of a final state."""
    theta, _, spin = tilt_from_quat(q)
    head_err = None if goal_heading is None else abs(wrap(spin - goal_heading))
    return math.hypot(xy[0] - goal[0], xy[1] - goal[1]), theta, head_err


# ---------------------------------------------------------------------------------------------------------
# Map check: the swept disc of radius R.
# ---------------------------------------------------------------------------------------------------------
def _load_grid(path: str) -> OccupancyGrid:
    from planner.maps.nav2 import load_map  # imported only when a map is used

    return load_map(path)


# ---------------------------------------------------------------------------------------------------------
# The entry point.
# ---------------------------------------------------------------------------------------------------------
def candidates(req: ReconfigureRequest) -> list[Manoeuvre]:
    """All candidate manoeuvres of the request's method, shortest first (request must be validated)."""
    assert req.radius_m is not None
    q0 = req.start_quat
    if req.method == "arc":
        return arc_candidates(req.start, q0, req.goal, req.goal_heading, req.alpha_final, req.radius_m)
    return triangle_candidates(req.start, q0, req.goal, req.goal_heading, req.radius_m)


def plan_reconfiguration(
    request: ReconfigureRequest | Mapping[str, Any], grid: OccupancyGrid | None = None
) -> dict[str, Any]:
    """Plan, roll and (optionally) map-check a reconfiguration; return the result JSON as a dict.

    ``grid`` overrides ``request.map``. Raises InvalidInput for bad requests, Start/GoalOccupied,
    Start/GoalOutsideMap, and NoValidPathFound (with the reason) when every alternative collides.
    """
    t_start = time.perf_counter()
    req = request if isinstance(request, ReconfigureRequest) else ReconfigureRequest.from_dict(request)
    req = req.validated()
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


# ---------------------------------------------------------------------------------------------------------
# Benchmark (python -m planner.spherobot.reconfigure).
# ---------------------------------------------------------------------------------------------------------
def random_request(rng: np.random.Generator, method: str, complete: bool) -> ReconfigureRequest:
    """A random problem: R in [0.1, 2] m, start/goal within 10·R, any tilt, spin and heading."""
    R = float(rng.uniform(0.1, 2.0))
    return ReconfigureRequest(
        method=method,
        start=(float(rng.uniform(-10, 10)) * R, float(rng.uniform(-10, 10)) * R),
        goal=(float(rng.uniform(-10, 10)) * R, float(rng.uniform(-10, 10)) * R),
        start_tilt=(float(rng.uniform(0, math.pi)), float(rng.uniform(-math.pi, math.pi))),
        start_spin=float(rng.uniform(-math.pi, math.pi)),
        goal_heading=float(rng.uniform(-math.pi, math.pi)) if complete else None,
        radius_m=R,
        roll_rate_rad_s=1.0,
    )


def benchmark(n: int = 200, seed: int = 0) -> list[dict[str, Any]]:
    """Plan ``n`` random problems per method and mode; rows of median / p95 / max times (ms).

    ``plan`` is :func:`plan_reconfiguration` end to end (candidates, rolling, samples, result dict);
    ``geometry`` is the planner's candidate generation alone.
    """
    rows = []
    for method in METHODS:
        for complete in (False, True):
            rng = np.random.default_rng(seed)
            reqs = [random_request(rng, method, complete) for _ in range(n)]
            plan_ms, geo_ms, lengths = [], [], []
            for req in reqs:
                t0 = time.perf_counter()
                candidates(req)
                t1 = time.perf_counter()
                res = plan_reconfiguration(req)
                t2 = time.perf_counter()
                geo_ms.append((t1 - t0) * 1e3)
                plan_ms.append((t2 - t1) * 1e3)
                lengths.append(res["length_m"] / res["radius_m"])
            rows.append(
                {
                    "method": method,
                    "mode": "complete" if complete else "partial",
                    "n": n,
                    "plan_median_ms": float(np.median(plan_ms)),
                    "plan_p95_ms": float(np.percentile(plan_ms, 95)),
                    "plan_max_ms": float(np.max(plan_ms)),
                    "geometry_median_ms": float(np.median(geo_ms)),
                    "median_length_radii": float(np.median(lengths)),
                }
            )
    return rows


def format_benchmark(rows: Sequence[Mapping[str, Any]]) -> str:
    """The benchmark rows as a fixed-width table."""
    head = (
        f"{'method':<9}{'mode':<10}{'n':>5}{'plan med ms':>13}{'p95 ms':>9}{'max ms':>9}"
        f"{'geom med ms':>13}{'len/R med':>11}"
    )
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(
            f"{r['method']:<9}{r['mode']:<10}{r['n']:>5}{r['plan_median_ms']:>13.2f}{r['plan_p95_ms']:>9.2f}"
            f"{r['plan_max_ms']:>9.2f}{r['geometry_median_ms']:>13.2f}{r['median_length_radii']:>11.1f}"
        )
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m planner.spherobot.reconfigure", description="Reconfiguration plan-time benchmark."
    )
    parser.add_argument("-n", type=int, default=200, help="problems per method and mode (default 200)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    print(format_benchmark(benchmark(args.n, args.seed)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
