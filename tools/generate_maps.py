"""Generate sphereplan's shipped maps, the cave mesh, the problem sets and the previews.

Run from the repository root::

    python tools/generate_maps.py            # writes maps/*.yaml|pgm, cave.stl, problems/*.json, preview/*.png
    python tools/generate_maps.py --no-preview --out /tmp/m   # what the tests do (byte-identical check)

Everything is deterministic (one seeded ``numpy.random.Generator`` per map). Every problem's start and
goal is checked here with a Euclidean distance transform of the blocked cells (the map edge counts as
blocked): both at least 0.8 m from any obstacle; a *solvable* problem's start and goal are connected
through cells at least 0.45 m from obstacles (the zju-60 footprint half-width 0.35 m plus margin); an
*unsolvable* goal is cut off from the start even for a body of radius 0.25 m (passages under 0.5 m).
The corridors are sized for zju-60's minimum turning radius (1.12 m, forward only): see docs/maps.md.
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypedDict

import numpy as np
import trimesh
from scipy import ndimage

from planner.maps.clearance import centre_distance
from planner.maps.mesh_world import MeshWorld
from planner.maps.nav2 import save_map
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot

REPO = Path(__file__).resolve().parent.parent


class ProblemCheckFailed(ValueError):
    """A generated problem breaks one of the rules of the module docstring (a bug in this generator)."""


def _require(ok: bool, msg: str) -> None:
    if not ok:
        raise ProblemCheckFailed(msg)


def _typed(value: Any, kind: type, what: str) -> Any:
    if not isinstance(value, kind):
        raise TypeError(f"{what} is a {type(value).__name__}, expected {kind.__name__}")
    return value


class ProblemSpec(TypedDict):
    """One entry of ``maps/problems/<map>.json`` (poses [x m, y m, yaw rad])."""

    name: str
    map: str
    start: list[float]
    goal: list[float]
    solvable: bool
    time_limit_s: float


MIN_CLEARANCE_M = 0.8  # start/goal distance from any obstacle
PASS_RADIUS_M = 0.45  # solvable: connected through cells this far from obstacles
BLOCK_RADIUS_M = 0.25  # unsolvable: not connected even through cells this far from obstacles
TIME_LIMIT_S = 5.0
TRINARY = {"mode": "trinary", "occupied_thresh": 0.65, "free_thresh": 0.196}


# ---------------------------------------------------------------------------------------------- drawing


class Canvas:
    """A boolean occupancy raster in world coordinates (row 0 at the bottom, origin (0, 0))."""

    def __init__(self, width_m: float, height_m: float, resolution_m: float) -> None:
        self.res = resolution_m
        self.nx = round(width_m / resolution_m)
        self.ny = round(height_m / resolution_m)
        self.occ = np.zeros((self.ny, self.nx), dtype=bool)
        centres_x = (np.arange(self.nx) + 0.5) * resolution_m
        centres_y = (np.arange(self.ny) + 0.5) * resolution_m
        self.X, self.Y = np.meshgrid(centres_x, centres_y)

    def _span(self, lo: float, hi: float, n: int) -> slice:
        i0 = max(0, math.ceil(lo / self.res - 0.5 - 1e-9))
        i1 = min(n - 1, math.floor(hi / self.res - 0.5 + 1e-9))
        return slice(i0, i1 + 1)

    def rect(self, x0: float, y0: float, x1: float, y1: float, value: bool = True) -> None:
        """Fill the axis-aligned rectangle [x0, x1] × [y0, y1] (cells whose centres lie inside)."""
        self.occ[self._span(y0, y1, self.ny), self._span(x0, x1, self.nx)] = value

    def box(self, cx: float, cy: float, length: float, width: float, yaw: float) -> None:
        """Fill a rectangle of ``length`` along ``yaw`` and ``width`` across, centred on (cx, cy)."""
        c, s = math.cos(yaw), math.sin(yaw)
        dx, dy = self.X - cx, self.Y - cy
        u, v = c * dx + s * dy, -s * dx + c * dy
        self.occ |= (np.abs(u) <= length / 2) & (np.abs(v) <= width / 2)

    def disc(self, cx: float, cy: float, r: float) -> None:
        self.occ |= (self.X - cx) ** 2 + (self.Y - cy) ** 2 <= r * r

    def walls(self, x0: float, y0: float, x1: float, y1: float, t: float) -> None:
        """A closed rectangular wall ring of thickness ``t`` whose outer edge is [x0, x1] × [y0, y1]."""
        self.rect(x0, y0, x1, y0 + t)
        self.rect(x0, y1 - t, x1, y1)
        self.rect(x0, y0, x0 + t, y1)
        self.rect(x1 - t, y0, x1, y1)

    def grid(self, name: str, extra: dict[str, Any] | None = None) -> OccupancyGrid:
        g = OccupancyGrid.from_occupied(self.occ, self.res, (0.0, 0.0, 0.0), name=name)
        return OccupancyGrid(data=g.data, resolution_m=g.resolution_m, origin=g.origin, name=name,
                             source={**TRINARY, **(extra or {})})


# ---------------------------------------------------------------------------------------------- checks


def check_problem(grid: OccupancyGrid, dist: np.ndarray, problem: ProblemSpec) -> None:
    """Check the problem's start/goal are sensible on ``grid`` (see the module docstring); raise
    :class:`ProblemCheckFailed` when not."""
    name = problem["name"]
    cells = []
    for key in ("start", "goal"):
        x, y, _ = problem[key]
        ix, iy = grid.world_to_cell(x, y)
        _require(0 <= ix < grid.width and 0 <= iy < grid.height, f"{name}: {key} outside the map")
        _require(dist[iy, ix] >= MIN_CLEARANCE_M, f"{name}: {key} only {dist[iy, ix]:.2f} m from an obstacle")
        cells.append((iy, ix))
    (sy, sx), (gy, gx) = cells
    if problem["solvable"]:
        labels, _ = ndimage.label(dist >= PASS_RADIUS_M)
        _require(labels[sy, sx] == labels[gy, gx], f"{name}: start and goal not connected at {PASS_RADIUS_M} m")
    else:
        labels, _ = ndimage.label(dist > BLOCK_RADIUS_M)
        gap = 2 * BLOCK_RADIUS_M
        _require(labels[sy, sx] != labels[gy, gx], f"{name}: goal reachable through a {gap} m gap")


def _pose_json(pose: tuple[float, float, float]) -> list[float]:
    """[x, y, yaw]: positions rounded to 0.1 mm; yaw wrapped into [-π, π) (OMPL's SO2 interval: it
    rejects +π) and not rounded (a rounded π would fall outside it)."""
    yaw = (pose[2] + PI) % (2 * PI) - PI
    return [round(pose[0], 4), round(pose[1], 4), yaw]


def problem(name: str, map_file: str, start: tuple[float, float, float], goal: tuple[float, float, float],
            solvable: bool = True) -> ProblemSpec:
    return {
        "name": name,
        "map": map_file,
        "start": _pose_json(start),
        "goal": _pose_json(goal),
        "solvable": solvable,
        "time_limit_s": TIME_LIMIT_S,
    }


PI = math.pi


# ---------------------------------------------------------------------------------------------- garage


def make_garage() -> tuple[OccupancyGrid, list[ProblemSpec]]:
    """Underground garage, 40 × 30 m at 0.05 m (paper 001 §6.5 patrol).

    Bands from south to north: a row of parked cars against the wall (y 0.3–5.3), lane 1 (5.5 m),
    a back-to-back double row with a line of pillars in the middle (10 m), lane 2 (5.5 m), and a strip
    along the north wall with parallel-parked cars and two store rooms (one sealed, one behind a 0.4 m
    gap). Cross aisles at both ends and in the middle join the lanes into loops.
    """
    rng = np.random.default_rng(2001)
    c = Canvas(40.0, 30.0, 0.05)
    c.walls(0.0, 0.0, 40.0, 30.0, 0.3)
    pitch, car_w, car_l = 2.5, 1.8, 4.6

    def car_row(x_from: float, x_to: float, y0: float, y1: float) -> None:
        """Perpendicular parking between x_from and x_to, cars filling [y0, y1]; a pillar every 3 cars."""
        x = x_from
        slot = 0
        while x + pitch <= x_to + 1e-9:
            if slot % 4 == 3:
                c.rect(x + pitch / 2 - 0.3, (y0 + y1) / 2 - 0.3, x + pitch / 2 + 0.3, (y0 + y1) / 2 + 0.3)
            elif rng.random() > 0.15:
                jitter = rng.uniform(-0.15, 0.15)
                cx = x + pitch / 2 + jitter
                cy = (y0 + y1) / 2 + rng.uniform(-0.1, 0.1)
                c.box(cx, cy, car_w, car_l - 0.1, rng.uniform(-0.03, 0.03))
            x += pitch
            slot += 1

    # south row against the wall
    car_row(6.0, 34.0, 0.5, 5.3)
    # double row in the middle, split by a middle cross aisle at x 18.5..23.5
    for x0, x1 in ((6.0, 18.5), (23.5, 36.0)):
        car_row(x0, x1, 10.8, 15.6)
        car_row(x0, x1, 15.8, 20.6)
        c.rect(x0, 15.6, x1, 15.8)  # low wall between the back-to-back rows
    # pillars along the lanes' outer edges every 8 m
    for px in (8.0, 16.0, 24.0, 32.0):
        c.rect(px - 0.3, 26.4, px + 0.3, 27.0)
    # north strip: store rooms and parallel parking (strip y 26.6 .. 29.7)
    c.walls(10.0, 26.6, 15.0, 30.0, 0.2)  # sealed room
    c.walls(24.0, 26.6, 29.0, 30.0, 0.2)  # room behind a 0.4 m gap
    c.rect(26.3, 26.6, 26.7, 26.8, value=False)
    for x_car in (3.0, 7.6, 17.5, 21.5, 32.0, 36.6):
        c.box(x_car, 28.75, car_l, car_w, rng.uniform(-0.03, 0.03))
    grid = c.grid("garage")

    lane1, lane2 = 8.05, 23.55
    f = "garage.yaml"
    problems = [
        problem("lane1_straight", f, (3.5, lane1, 0.0), (37.0, lane1, 0.0)),
        problem("u_turn_east_loop", f, (12.0, lane1, 0.0), (12.0, lane2, PI)),
        problem("lane2_to_lane1_west", f, (35.0, lane2, PI), (14.0, lane1, PI)),
        problem("into_middle_aisle", f, (30.0, lane1, PI), (21.0, 15.5, PI / 2)),
        problem("west_aisle_north", f, (33.0, lane2, PI), (3.2, 15.0, -PI / 2)),
        problem("sealed_store_room", f, (20.0, lane2, 0.0), (12.5, 28.3, 0.0), solvable=False),
        problem("store_room_behind_gap", f, (20.0, lane2, 0.0), (26.5, 28.3, PI / 2), solvable=False),
    ]
    return grid, problems


# ---------------------------------------------------------------------------------------------- maze


def make_maze() -> tuple[OccupancyGrid, list[ProblemSpec]]:
    """A 20 × 20 m maze at 0.05 m: 8 × 8 cells of 2.5 m, walls 0.25 m, passages 2.25 m wide.

    A randomized depth-first maze (seeded) plus a few knocked-out walls for loops. Cell (7, 0) is sealed
    off; cell (7, 7) is reached only through a 0.4 m slot.
    """
    rng = np.random.default_rng(2002)
    n, pitch, t = 8, 2.5, 0.25
    sealed, slotted = (7, 0), (7, 7)
    # walls between cells: open[(a, b)] for neighbours a, b
    opened: set[tuple[tuple[int, int], tuple[int, int]]] = set()

    def key(a: tuple[int, int], b: tuple[int, int]) -> tuple[tuple[int, int], tuple[int, int]]:
        return (a, b) if a < b else (b, a)

    def neighbours(cell: tuple[int, int]) -> list[tuple[int, int]]:
        i, j = cell
        out = [(i + di, j + dj) for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1))]
        return [p for p in out if 0 <= p[0] < n and 0 <= p[1] < n and p not in (sealed, slotted)]

    start = (0, 0)
    visited = {start}
    stack = [start]
    while stack:
        cur = stack[-1]
        options = [p for p in neighbours(cur) if p not in visited]
        if not options:
            stack.pop()
            continue
        nxt = options[int(rng.integers(len(options)))]
        opened.add(key(cur, nxt))
        visited.add(nxt)
        stack.append(nxt)
    # a few loops
    candidates = sorted(
        {key(a, b) for a in visited for b in neighbours(a) if b in visited} - opened
    )
    for idx in rng.choice(len(candidates), size=6, replace=False):
        opened.add(candidates[int(idx)])

    c = Canvas(20.0, 20.0, 0.05)
    c.walls(0.0, 0.0, 20.0, 20.0, t / 2)
    for i in range(n):
        for j in range(n):
            if i + 1 < n and key((i, j), (i + 1, j)) not in opened:  # wall at x = (i + 1) * pitch
                x = (i + 1) * pitch
                c.rect(x - t / 2, j * pitch - t / 2, x + t / 2, (j + 1) * pitch + t / 2)
            if j + 1 < n and key((i, j), (i, j + 1)) not in opened:  # wall at y = (j + 1) * pitch
                y = (j + 1) * pitch
                c.rect(i * pitch - t / 2, y - t / 2, (i + 1) * pitch + t / 2, y + t / 2)
    # the slotted cell's only way in: a 0.4 m slot in its west wall
    sx = slotted[0] * pitch
    sy = (slotted[1] + 0.5) * pitch
    c.rect(sx - t / 2 - 0.01, sy - 0.2, sx + t / 2 + 0.01, sy + 0.2, value=False)
    grid = c.grid("maze")

    # BFS through the maze graph gives each goal the heading of the last move into it
    def route(a: tuple[int, int], b: tuple[int, int]) -> list[tuple[int, int]]:
        prev = {a: a}
        queue = [a]
        for cur in queue:
            for p in [(cur[0] + 1, cur[1]), (cur[0] - 1, cur[1]), (cur[0], cur[1] + 1), (cur[0], cur[1] - 1)]:
                if p not in prev and key(cur, p) in opened:
                    prev[p] = cur
                    queue.append(p)
        path = [b]
        while path[-1] != a:
            path.append(prev[path[-1]])
        return path[::-1]

    def centre(cell: tuple[int, int]) -> tuple[float, float]:
        return (cell[0] + 0.5) * pitch, (cell[1] + 0.5) * pitch

    def heading(a: tuple[int, int], b: tuple[int, int]) -> float:
        return math.atan2(b[1] - a[1], b[0] - a[0])

    f = "maze.yaml"
    problems = []
    for name, goal_cell in (("maze_to_top_left", (0, 7)), ("maze_to_centre", (4, 4)),
                            ("maze_to_right", (6, 3)), ("maze_across", (6, 6))):
        path = route(start, goal_cell)
        problems.append(problem(name, f, (*centre(start), heading(path[0], path[1])),
                                (*centre(goal_cell), heading(path[-2], path[-1]))))
    for name, cell in (("maze_sealed_cell", sealed), ("maze_behind_slot", slotted)):
        problems.append(problem(name, f, (*centre(start), 0.0), (*centre(cell), 0.0), solvable=False))
    return grid, problems


# ---------------------------------------------------------------------------------------------- field


TRACK = (16.2, 8.4)


def make_field() -> tuple[OccupancyGrid, list[ProblemSpec], dict[str, Any]]:
    """An open field, 30 × 20 m at 0.05 m, with the 16.2 × 8.4 m track of paper 001 §6.2.

    The track is painted (free cells); its corners go to ``field_track.json``. A few small obstacles
    stand outside the track, and two fenced pens (one closed, one with a 0.4 m gate) in the corners.
    """
    rng = np.random.default_rng(2003)
    c = Canvas(30.0, 20.0, 0.05)
    cx, cy = 15.0, 10.0
    x0, x1 = cx - TRACK[0] / 2, cx + TRACK[0] / 2
    y0, y1 = cy - TRACK[1] / 2, cy + TRACK[1] / 2
    for ox, oy in ((3.0, 10.0), (15.0, 2.5), (15.0, 17.5), (27.0, 10.0), (9.0, 17.8), (21.0, 2.2)):
        size = rng.uniform(0.5, 1.0)
        if rng.random() < 0.5:
            c.disc(ox + rng.uniform(-0.3, 0.3), oy + rng.uniform(-0.2, 0.2), size / 2)
        else:
            c.box(ox + rng.uniform(-0.3, 0.3), oy + rng.uniform(-0.2, 0.2), size, size, rng.uniform(0, PI))
    c.walls(0.3, 0.3, 4.3, 4.3, 0.1)  # closed pen
    c.walls(25.7, 15.7, 29.7, 19.7, 0.1)  # pen with a 0.4 m gate
    c.rect(25.69, 17.5, 25.81, 17.9, value=False)
    grid = c.grid("field")
    track = {
        "map": "field.yaml",
        "size_m": list(TRACK),
        "corners": [[x0, y0], [x0, y1], [x1, y1], [x1, y0]],
        "direction": "clockwise",
        "note": "paper 001 §6.2: 16.2 m x 8.4 m rectangle drawn on the ground, patrolled clockwise "
                "from the origin (first corner)",
    }
    f = "field.yaml"
    problems = [
        problem("track_west_leg", f, (x0, y0, PI / 2), (x0, y1, PI / 2)),
        problem("track_half_lap", f, (x0, y0, PI / 2), (x1, y0, -PI / 2)),
        problem("track_u_turn", f, (x1 - 2.0, y1, 0.0), (x1 - 2.0, y0, PI)),
        problem("around_obstacle", f, (1.5, 7.0, PI / 2), (5.5, 13.5, 0.0)),
        problem("field_closed_pen", f, (8.0, 3.0, PI), (2.3, 2.3, 0.0), solvable=False),
        problem("field_pen_behind_gate", f, (22.0, 17.7, 0.0), (27.7, 17.7, 0.0), solvable=False),
    ]
    return grid, problems, track


# ---------------------------------------------------------------------------------------------- bench20


def make_bench20() -> tuple[OccupancyGrid, list[ProblemSpec]]:
    """Benchmark map, 20 × 20 m at 0.05 m (400 × 400): two walls and a block.

    Wall 1 rises from the south edge at x ≈ 6 (to y = 13), wall 2 hangs from the north edge at x ≈ 13
    (down to y = 7), so the way from the south-west to the north-east is an S. The block (2.6 × 5 m)
    stands east of wall 2; it is hollow with two 2.2 × 2.2 m compartments, one sealed and one behind
    a 0.4 m slot.
    """
    c = Canvas(20.0, 20.0, 0.05)
    c.rect(5.85, 0.0, 6.15, 13.0)
    c.rect(12.85, 7.0, 13.15, 20.0)
    bx0, by0 = 15.7, 9.0
    c.walls(bx0, by0, bx0 + 2.6, by0 + 5.0, 0.2)
    c.rect(bx0, by0 + 2.4, bx0 + 2.6, by0 + 2.6)  # split into two compartments
    c.rect(bx0 - 0.01, by0 + 3.6, bx0 + 0.21, by0 + 4.0, value=False)  # 0.4 m slot into the upper one
    grid = c.grid("bench20")
    f = "bench20.yaml"
    problems = [
        problem("bench_s_route", f, (2.5, 2.5, PI / 2), (17.0, 17.5, PI / 2)),
        problem("bench_over_wall1", f, (3.0, 10.0, PI / 2), (9.5, 3.0, -PI / 2)),
        problem("bench_under_wall2", f, (9.5, 16.0, -PI / 2), (17.0, 4.0, 0.0)),
        problem("bench_around_block", f, (17.0, 4.0, PI / 2), (17.0, 17.5, PI / 2)),
        problem("bench_sealed_compartment", f, (2.5, 2.5, PI / 2), (bx0 + 1.3, by0 + 1.3, 0.0), False),
        problem("bench_behind_slot", f, (2.5, 2.5, PI / 2), (bx0 + 1.3, by0 + 3.7, 0.0), False),
    ]
    return grid, problems


# ---------------------------------------------------------------------------------------------- cave


CAVE_POINTS = np.array(
    [(4, 6), (14, 5), (24, 9), (29, 18), (24, 28), (31, 35), (42, 34), (50, 27), (48, 17), (54, 8), (58, 5)],
    dtype=float,
)


def _centreline(points: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Catmull-Rom spline through ``points`` resampled every ``step`` m: (xy (n, 2), arc length (n,))."""
    pts = np.vstack([2 * points[0] - points[1], points, 2 * points[-1] - points[-2]])
    dense = []
    for k in range(1, len(pts) - 2):
        p0, p1, p2, p3 = pts[k - 1], pts[k], pts[k + 1], pts[k + 2]
        for u in np.linspace(0, 1, 60, endpoint=False):
            dense.append(0.5 * ((2 * p1) + (-p0 + p2) * u + (2 * p0 - 5 * p1 + 4 * p2 - p3) * u**2
                                + (-p0 + 3 * p1 - 3 * p2 + p3) * u**3))
    dense.append(points[-1])
    d = np.asarray(dense)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(d, axis=0).T))])
    s_new = np.arange(0.0, s[-1], step)
    xy = np.column_stack([np.interp(s_new, s, d[:, 0]), np.interp(s_new, s, d[:, 1])])
    return xy, s_new


def _tube(xy: np.ndarray, widths: np.ndarray, heights: np.ndarray, floor: np.ndarray) -> trimesh.Trimesh:
    """A closed tube along ``xy`` with a boxy arched cross-section and a floor, as a CAVITY (inward normals).

    ``widths``/``heights`` (m) per ring; ``floor`` (n, k_floor) floor heights of the floor points.
    """
    n = len(xy)
    tang = np.gradient(xy, axis=0)
    tang /= np.linalg.norm(tang, axis=1, keepdims=True)
    left = np.column_stack([-tang[:, 1], tang[:, 0]])
    k_arch, k_floor = 18, floor.shape[1]
    theta = np.linspace(0.0, PI, k_arch)
    rings = []
    for i in range(n):
        cos_t = np.cos(theta)
        u_arch = widths[i] / 2 * np.sign(cos_t) * np.abs(cos_t) ** 0.5
        z_arch = heights[i] * np.sin(theta) ** 0.8
        u_floor = np.linspace(-widths[i] / 2, widths[i] / 2, k_floor + 2)[1:-1]
        u = np.concatenate([u_arch, u_floor])
        z = np.concatenate([z_arch, floor[i]])
        ring = np.column_stack([xy[i, 0] + u * left[i, 0], xy[i, 1] + u * left[i, 1], z])
        rings.append(ring)
    k = k_arch + k_floor
    verts = np.vstack([*rings, np.append(xy[0], 1.0)[None, :], np.append(xy[-1], 1.0)[None, :]])
    faces = []
    for i in range(n - 1):
        for j in range(k):
            a, b = i * k + j, i * k + (j + 1) % k
            c_, d = a + k, b + k
            faces += [(a, b, d), (a, d, c_)]
    cap0, cap1 = n * k, n * k + 1
    for j in range(k):
        faces.append((cap0, (j + 1) % k, j))
        faces.append((cap1, (n - 1) * k + j, (n - 1) * k + (j + 1) % k))
    mesh = trimesh.Trimesh(vertices=verts, faces=np.asarray(faces), process=False)
    if mesh.volume > 0:
        mesh.invert()
    return mesh


def _boulder(rng: np.random.Generator, centre: tuple[float, float], radii: tuple[float, float, float],
             yaw: float) -> trimesh.Trimesh:
    """A lumpy ellipsoid resting on z = 0 (a SOLID: outward normals)."""
    m = trimesh.creation.icosphere(subdivisions=1)
    v = m.vertices * (1.0 + rng.uniform(-0.12, 0.12, size=(len(m.vertices), 1)))
    v = v * np.asarray(radii)
    c, s = math.cos(yaw), math.sin(yaw)
    v = v @ np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    v[:, 2] -= v[:, 2].min()
    v[:, 0] += centre[0]
    v[:, 1] += centre[1]
    return trimesh.Trimesh(vertices=v, faces=m.faces, process=False)


def make_cave_mesh() -> tuple[trimesh.Trimesh, dict[str, Any]]:
    """A lunar lava tube, ~60 × 40 m footprint: one winding tube 3–8 m wide, 3–4.5 m high, with an uneven
    floor (±3 cm), boulders, a rockfall near its east end leaving a 0.4 m crack, and a sealed chamber
    (a collapsed-off tube section) beside it. Returns the mesh and the features' positions.
    """
    rng = np.random.default_rng(2004)
    xy, s = _centreline(CAVE_POINTS, 0.5)
    total = s[-1]
    widths = 5.5 + 2.5 * np.sin(2 * PI * s / 37.0 + 0.7) * np.cos(2 * PI * s / 83.0)
    widths = np.clip(widths, 3.0, 8.0)
    heights = 3.8 + 0.7 * np.sin(2 * PI * s / 23.0)
    floor = rng.uniform(-0.03, 0.03, size=(len(xy), 8))
    parts = [_tube(xy, widths, heights, floor)]
    tang = np.gradient(xy, axis=0)
    tang /= np.linalg.norm(tang, axis=1, keepdims=True)
    left = np.column_stack([-tang[:, 1], tang[:, 0]])

    def at(s_m: float) -> int:
        return int(np.argmin(np.abs(s - s_m)))

    # boulders: lateral offset keeps >= 2.2 m of passage on the other side
    for s_b in (16.0, 31.0, 47.0, 62.0, 78.0, 91.0):
        i = at(s_b)
        side = 1.0 if rng.random() < 0.5 else -1.0
        radii = (rng.uniform(0.4, 0.8), rng.uniform(0.4, 0.8), rng.uniform(0.4, 1.0))
        reach = 1.12 * max(radii[:2])  # lateral extent whatever its yaw (lumps up to +12 %)
        offset = side * max(0.0, widths[i] / 2 - reach - 0.1)
        if widths[i] - 2 * reach - 0.1 < 2.2:
            offset = side * (widths[i] / 2 + 0.3)  # too narrow here: half buried in the wall
        cx, cy = xy[i] + offset * left[i]
        parts.append(_boulder(rng, (cx, cy), radii, rng.uniform(0, PI)))
    # rockfall 8 m before the east end: two slabs from the walls with a 0.4 m crack between them
    i_r = at(total - 8.0)
    yaw_r = math.atan2(tang[i_r, 1], tang[i_r, 0])
    w_r = widths[i_r]
    crack = 0.4
    for side in (1.0, -1.0):
        inner = crack / 2
        outer = w_r / 2 + 1.0
        mid = side * (inner + outer) / 2
        slab = trimesh.creation.box((1.2, outer - inner, 2.5))
        rot = trimesh.transformations.rotation_matrix(yaw_r, (0, 0, 1))
        slab.apply_transform(rot)
        cx, cy = xy[i_r] + mid * left[i_r]
        slab.apply_translation((cx, cy, 1.25 - 0.02))
        parts.append(slab)
    # sealed chamber: a short tube section inside the big northern loop, cut off from the main tube
    xy_p, _ = _centreline(np.array([(34.0, 21.0), (37.5, 23.5), (41.0, 23.0)]), 0.5)
    n_p = len(xy_p)
    parts.append(_tube(xy_p, np.full(n_p, 4.5), np.full(n_p, 3.0), rng.uniform(-0.03, 0.03, size=(n_p, 8))))
    mesh = _typed(trimesh.util.concatenate(parts), trimesh.Trimesh, "the cave mesh")
    features = {
        "centreline": xy,
        "s": s,
        "widths": widths,
        "rockfall_index": i_r,
        "chamber": xy_p,
    }
    return mesh, features


def make_cave(out: Path) -> tuple[OccupancyGrid, list[ProblemSpec]]:
    """Write cave.stl; slice it at 0.1 m for zju-60 into the cave grid."""
    mesh, feat = make_cave_mesh()
    stl_path = out / "cave.stl"
    data = _typed(mesh.export(file_type="stl"), bytes, "the STL export")
    stl_path.write_bytes(data)
    world = MeshWorld.from_file(stl_path)
    grid = world.to_grid(0.1, load_robot("zju-60"), mesh_ref="cave.stl")
    grid = OccupancyGrid(data=grid.data, resolution_m=grid.resolution_m, origin=grid.origin, name="cave",
                         source=grid.source)
    xy = _typed(feat["centreline"], np.ndarray, "the centreline")
    s = _typed(feat["s"], np.ndarray, "the arc length")

    def pose(s_m: float, lateral: float = 0.0, reverse: bool = False) -> tuple[float, float, float]:
        i = int(np.argmin(np.abs(s - s_m)))
        j = min(i + 1, len(xy) - 1)
        d = xy[j] - xy[max(i - 1, 0)]
        yaw = math.atan2(d[1], d[0])
        px = xy[i, 0] - lateral * math.sin(yaw)
        py = xy[i, 1] + lateral * math.cos(yaw)
        return px, py, (yaw + PI if reverse else yaw)

    total = float(s[-1])
    chamber = _typed(feat["chamber"], np.ndarray, "the chamber")
    mid = chamber[len(chamber) // 2]
    f = "cave.yaml"
    problems = [
        problem("cave_first_bend", f, pose(3.0), pose(26.0)),
        problem("cave_to_middle", f, pose(3.0), pose(55.0)),
        problem("cave_full_length", f, pose(3.0), pose(total - 12.0)),
        problem("cave_back_west", f, pose(70.0, reverse=True), pose(20.0, reverse=True)),
        problem("cave_sealed_chamber", f, pose(3.0), (float(mid[0]), float(mid[1]), 0.0), solvable=False),
        problem("cave_behind_rockfall", f, pose(3.0), pose(total - 4.0), solvable=False),
    ]
    return grid, problems


# ---------------------------------------------------------------------------------------------- preview


def preview(grid: OccupancyGrid, problems: list[ProblemSpec], path: Path,
            track: dict[str, Any] | None = None) -> None:
    """A small PNG of the map with each problem's start (green) and goal (blue solvable / red not)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    w, h = grid.size_m
    fig, ax = plt.subplots(figsize=(6.0, 6.0 * h / w + 0.4), dpi=80)
    shown = np.where(grid.data < 0, 0.5, np.where(grid.blocked(), 0.0, 1.0))
    ox, oy, _ = grid.origin
    ax.imshow(shown, origin="lower", cmap="gray", vmin=0, vmax=1, extent=(ox, ox + w, oy, oy + h),
              interpolation="nearest")
    if track:
        corners = np.asarray([*track["corners"], track["corners"][0]])
        ax.plot(corners[:, 0], corners[:, 1], color="orange", lw=1.5, ls="--")
    for p in problems:
        sx, sy, syaw = p["start"]
        gx, gy, gyaw = p["goal"]
        colour = "tab:blue" if p["solvable"] else "tab:red"
        ax.annotate("", (sx + 1.2 * math.cos(syaw), sy + 1.2 * math.sin(syaw)), (sx, sy),
                    arrowprops={"arrowstyle": "->", "color": "tab:green", "lw": 1.5})
        ax.annotate("", (gx + 1.2 * math.cos(gyaw), gy + 1.2 * math.sin(gyaw)), (gx, gy),
                    arrowprops={"arrowstyle": "->", "color": colour, "lw": 1.5})
        ax.plot([gx], [gy], "o", color=colour, ms=3)
    ax.set_title(f"{grid.name}: {w:.0f} x {h:.0f} m, {grid.resolution_m} m cells", fontsize=9)
    ax.tick_params(labelsize=7)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


# ---------------------------------------------------------------------------------------------- main


MAKERS: dict[str, Callable[[], tuple[OccupancyGrid, list[ProblemSpec]]]] = {
    "garage": make_garage,
    "maze": make_maze,
    "bench20": make_bench20,
}


def generate(out: Path, with_preview: bool = True) -> list[str]:
    """Write every map, problem set (and preview) into ``out``; returns the written file names."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "problems").mkdir(exist_ok=True)
    built: list[tuple[OccupancyGrid, list[ProblemSpec], dict[str, Any] | None]] = []
    for maker in MAKERS.values():
        grid, problems = maker()
        built.append((grid, problems, None))
    field, field_problems, track = make_field()
    built.append((field, field_problems, track))
    cave, cave_problems = make_cave(out)
    built.append((cave, cave_problems, None))
    written = ["cave.stl"]
    for grid, problems, extra in built:
        dist = centre_distance(grid)
        for p in problems:
            check_problem(grid, dist, p)
        save_map(grid, out / f"{grid.name}.yaml")
        written += [f"{grid.name}.yaml", f"{grid.name}.pgm", f"problems/{grid.name}.json"]
        lines = ",\n".join("  " + json.dumps(p) for p in problems)
        (out / "problems" / f"{grid.name}.json").write_text("[\n" + lines + "\n]\n")
        if extra is not None:
            (out / "field_track.json").write_text(json.dumps(extra, indent=2, ensure_ascii=False) + "\n")
            written.append("field_track.json")
        if with_preview:
            (out / "preview").mkdir(exist_ok=True)
            preview(grid, problems, out / "preview" / f"{grid.name}.png", extra)
    return sorted(written)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO / "maps", help="output folder")
    parser.add_argument("--no-preview", action="store_true", help="skip the PNG previews")
    args = parser.parse_args(argv)
    for name in generate(args.out, with_preview=not args.no_preview):
        print(args.out / name)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
