"""Seeded exploration worlds: a known map, and the true world made from it by adding what the map misses.

Each :class:`World` takes a start–goal problem on a map (shipped problem sets and Nav2's real maps), plans it
on the known map, and hides obstacles on that route in the true world:

* ``boxes`` — one to three boxes (0.8–1.6 m a side) on the route, away from the start and goal;
* ``aisle`` — a wall across the route in its middle part, reaching the obstacles on both sides (a blocked
  aisle);
* ``door`` — the same wall at the route's narrowest place (a closed door; whether a detour exists is the map's).

Whether the true world still has a path is decided by planning on it with full knowledge (``true_length_m``
None = no path), never assumed.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from planner.errors import PlanningError
from planner.hybrid_astar.search import HybridAStar, PlannerOptions, Pose
from planner.maps.clearance import ClearanceMap
from planner.maps.load import load_any
from planner.occupancy import OCCUPIED, OccupancyGrid
from planner.robot import RobotProfile
from planner.termination import Termination

KINDS = ("boxes", "aisle", "door")
ROUTE_OPTIONS = PlannerOptions(open_step_factor=1)  # the planner settings the worlds' routes are planned with
KEEP_CLEAR_M = 2.5
"""Nothing is hidden this close to the start or the goal."""
WALL_REACH_M = 8.0
"""A hidden wall reaches at most this far to each side of the route."""


@dataclass(frozen=True)
class WorldSpec:
    """One world of the sweep: ``map`` (a path), the problem, the kind of hidden obstacle and its seed."""

    name: str
    map: str
    start: Pose
    goal: Pose
    kind: str
    seed: int


@dataclass
class World:
    spec: WorldSpec
    known: OccupancyGrid
    true: OccupancyGrid
    hidden_cells: int


def _segment_cells(grid: OccupancyGrid, a: np.ndarray, b: np.ndarray,
                   half_width_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(iy, ix) of the cells whose centres lie within ``half_width_m`` of segment a–b."""
    res = grid.resolution_m
    lo = np.minimum(a, b) - half_width_m
    hi = np.maximum(a, b) + half_width_m
    ix0, iy0 = grid.world_to_cell(lo[0], lo[1])
    ix1, iy1 = grid.world_to_cell(hi[0], hi[1])
    ix0, iy0 = max(ix0, 0), max(iy0, 0)
    ix1, iy1 = min(ix1, grid.width - 1), min(iy1, grid.height - 1)
    if ix1 < ix0 or iy1 < iy0:
        return np.zeros(0, int), np.zeros(0, int)
    gy, gx = np.mgrid[iy0:iy1 + 1, ix0:ix1 + 1]
    cx = grid.origin[0] + (gx + 0.5) * res
    cy = grid.origin[1] + (gy + 0.5) * res
    d = b - a
    t = np.clip(((cx - a[0]) * d[0] + (cy - a[1]) * d[1]) / max(float(d @ d), 1e-12), 0.0, 1.0)
    near = np.hypot(cx - (a[0] + t * d[0]), cy - (a[1] + t * d[1])) <= half_width_m
    return gy[near], gx[near]


def _reach(blocked: np.ndarray, grid: OccupancyGrid, p: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The point where a ray from ``p`` along ``u`` first enters a blocked cell (or WALL_REACH_M along it)."""
    step = grid.resolution_m / 2
    for k in range(1, int(WALL_REACH_M / step) + 1):
        q = p + u * k * step
        ix, iy = grid.world_to_cell(q[0], q[1])
        if not (0 <= ix < grid.width and 0 <= iy < grid.height) or blocked[iy, ix]:
            return q + u * grid.resolution_m
    return p + u * WALL_REACH_M


Segment = tuple[float, float, float, float, float]
"""A hidden obstacle: the cells whose centres lie within ``half`` (m) of the segment (x0, y0)–(x1, y1)."""

PINNED_PATH = Path(__file__).with_name("explore_worlds.json")
"""The sweep's hidden obstacles as they were made (``python -m lab.explore_worlds --pin`` writes them): the
worlds are data, so a change to the planner, which plans the routes they are put on, does not move them."""


def route_segments(spec: WorldSpec, robot: RobotProfile, known: OccupancyGrid) -> list[Segment]:
    """The hidden obstacles of ``spec`` made afresh: planned on the known map (with :data:`ROUTE_OPTIONS`) and put
    on that route with the spec's seed (see the module docstring)."""
    rng = np.random.default_rng(spec.seed)
    route = HybridAStar(known, robot, ROUTE_OPTIONS).plan(spec.start, spec.goal, Termination(10.0)).states
    xy, s = route[:, :2], route[:, 6]
    total = float(s[-1])
    ends = np.array([spec.start[:2], spec.goal[:2]])

    def away(p: np.ndarray) -> bool:
        return bool(np.hypot(*(ends - p).T).min() > KEEP_CLEAR_M + 1.0)

    out: list[Segment] = []
    if spec.kind == "boxes":
        for _ in range(int(rng.integers(1, 4))):
            for _try in range(50):
                i = int(np.searchsorted(s, rng.uniform(0.25, 0.75) * total))
                centre = xy[min(i, len(xy) - 1)] + rng.uniform(-0.3, 0.3, 2)
                if away(centre):
                    break
            half = rng.uniform(0.4, 0.8, 2)
            out.append((float(centre[0] - half[0]), float(centre[1]), float(centre[0] + half[0]), float(centre[1]),
                        float(half[1])))
    elif spec.kind in ("aisle", "door"):
        lo, hi = np.searchsorted(s, 0.3 * total), np.searchsorted(s, 0.7 * total)
        candidates = [i for i in range(lo, max(lo + 1, hi)) if away(xy[i])] or [int((lo + hi) // 2)]
        if spec.kind == "door":
            clear = ClearanceMap(known).at(xy[candidates, 0], xy[candidates, 1])
            i = candidates[int(np.argmin(clear))]
        else:
            i = candidates[int(rng.integers(len(candidates)))]
        yaw = float(route[i, 2])
        n = np.array([-math.sin(yaw), math.cos(yaw)])
        p = xy[i]
        blocked = known.blocked()
        a, b = _reach(blocked, known, p, n), _reach(blocked, known, p, -n)
        out.append((float(a[0]), float(a[1]), float(b[0]), float(b[1]), 0.15))
    else:
        raise ValueError(f"kind must be one of {KINDS}, got {spec.kind!r}")
    return out


def spec_key(spec: WorldSpec) -> dict[str, object]:
    """What a pinned entry must match to be used: the map's file name, the problem, the kind and the seed."""
    return {"map": Path(spec.map).name, "start": list(spec.start), "goal": list(spec.goal), "kind": spec.kind,
            "seed": spec.seed}


def pinned_segments(spec: WorldSpec, path: Path = PINNED_PATH) -> list[Segment] | None:
    """The pinned hidden obstacles of ``spec`` (None when it has none, or the entry was made for another problem)."""
    if not path.is_file():
        return None
    entry = json.loads(path.read_text()).get(spec.name)
    if entry is None or entry["spec"] != json.loads(json.dumps(spec_key(spec))):
        return None
    return [(float(a), float(b), float(c), float(d), float(e)) for a, b, c, d, e in entry["segments"]]


def build_world(spec: WorldSpec, robot: RobotProfile, pinned: bool = True) -> World:
    """The known map and the true world of ``spec``: its pinned hidden obstacles (:data:`PINNED_PATH`), or with
    ``pinned`` false or none pinned, ones made afresh on a route planned now (:func:`route_segments`)."""
    known = load_any(spec.map)
    segments = pinned_segments(spec) if pinned else None
    if segments is None:
        segments = route_segments(spec, robot, known)
    data = known.data.copy()
    for x0, y0, x1, y1, half in segments:
        iy, ix = _segment_cells(known, np.array([x0, y0]), np.array([x1, y1]), half)
        data[iy, ix] = OCCUPIED
    # never bury the start or the goal
    for e in np.array([spec.start[:2], spec.goal[:2]]):
        iy, ix = _segment_cells(known, e, e, KEEP_CLEAR_M)
        data[iy, ix] = known.data[iy, ix]
    true = OccupancyGrid(data, known.resolution_m, known.origin, known.occupied_threshold,
                         f"{known.name}-{spec.kind}-{spec.seed}")
    return World(spec, known, true, int(np.count_nonzero(data != known.data)))


def pin(robot: RobotProfile, path: Path = PINNED_PATH) -> dict[str, object]:
    """Make every sweep world's hidden obstacles afresh and write them to ``path``; returns what was written."""
    out: dict[str, object] = {}
    for spec in sweep_specs():
        segments = route_segments(spec, robot, load_any(spec.map))
        out[spec.name] = {"spec": spec_key(spec), "segments": [[round(v, 6) for v in seg] for seg in segments]}
    lines = [f"{json.dumps(name)}: {json.dumps(entry)}" for name, entry in out.items()]  # one world per line
    path.write_text("{\n" + ",\n".join(lines) + "\n}\n")
    return out


def true_length(world: World, robot: RobotProfile) -> float | None:
    """Length of the plan on the true world with full knowledge, or None when it has no path."""
    try:
        return HybridAStar(world.true, robot, PlannerOptions()).plan(world.spec.start, world.spec.goal,
                                                                      Termination(10.0)).length_m
    except PlanningError:
        return None


def maps_dir() -> Path:
    from planner.maps.catalogue import default_maps_dir

    return Path(default_maps_dir())


def sweep_specs() -> list[WorldSpec]:
    """The sweep's worlds: shipped problems and problems on Nav2's real maps, each with hidden obstacles."""
    m = maps_dir()
    pi = math.pi
    problems: list[tuple[str, str, Pose, Pose, tuple[str, ...]]] = [
        ("garage-lane1", "garage.yaml", (3.5, 8.05, 0.0), (37.0, 8.05, 0.0), ("boxes", "aisle")),
        ("garage-aisle", "garage.yaml", (30.0, 8.05, -pi), (21.0, 15.5, pi / 2), ("boxes", "door")),
        ("garage-west", "garage.yaml", (33.0, 23.55, -pi), (3.2, 15.0, -pi / 2), ("aisle",)),
        ("field-half-lap", "field.yaml", (6.9, 5.8, pi / 2), (23.1, 5.8, -pi / 2), ("boxes", "aisle")),
        ("field-around", "field.yaml", (1.5, 7.0, pi / 2), (5.5, 13.5, 0.0), ("boxes", "aisle")),
        ("maze-top-left", "maze.yaml", (1.25, 1.25, pi / 2), (1.25, 18.75, pi / 2), ("boxes", "door")),
        ("maze-centre", "maze.yaml", (1.25, 1.25, pi / 2), (11.25, 11.25, 0.0), ("aisle", "door")),
        ("bench-s-route", "bench20.yaml", (2.5, 2.5, pi / 2), (17.0, 17.5, pi / 2), ("boxes", "door")),
        ("bench-around", "bench20.yaml", (17.0, 4.0, pi / 2), (17.0, 17.5, pi / 2), ("aisle", "door")),
        ("depot", "real/depot.yaml", (3.0, 3.0, 0.0), (25.0, 12.0, 0.0), ("boxes", "aisle")),
        ("smoothers", "real/smoothers_world.yaml", (5.0, 1.0, 0.0), (12.5, 9.0, pi / 2), ("boxes", "door")),
        ("warehouse", "real/warehouse.yaml", (-10.0, 1.0, 0.0), (2.0, -20.0, -pi / 2), ("boxes", "aisle")),
        ("field100", "real/100by100_20.yaml", (10.0, 10.0, 0.0), (35.0, 30.0, 0.0), ("boxes",)),
    ]
    out = []
    for i, (name, path, start, goal, kinds) in enumerate(problems):
        for kind in kinds:
            out.append(WorldSpec(f"{name}-{kind}", str(m / path), start, goal, kind, 100 + i))
    return out


if __name__ == "__main__":  # python -m lab.explore_worlds --pin: make the sweep's hidden obstacles afresh and pin them
    import sys

    from planner.robot import load_robot

    if sys.argv[1:] != ["--pin"]:
        sys.exit("usage: python -m lab.explore_worlds --pin")
    print(f"pinned {len(pin(load_robot()))} worlds in {PINNED_PATH}")
