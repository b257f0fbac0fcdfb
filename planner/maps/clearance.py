"""The one clearance model: how far every point of a map is from the nearest obstacle, and whether a
robot's footprint fits there. Every wing asks it: the Hybrid A* (covering circles, paper 001 §4.1,
Fig. 6), the MPC tracker (obstacle circles on boundary cells, paper 001 eq. 15f), the closed-loop
simulation (exact footprint clearance), the Spherobot swept-disc check and the map generator.

Footprint collision in two tiers (paper 001 §4.1, Fig. 6, then exact):

1. *Covering circles* (the paper's filter). The robot's padded footprint polygon
   (:attr:`planner.robot.RobotProfile.footprint_polygon`) is covered by 1..N equal circles along its
   longer axis; the count whose union overshoots the polygon least is used (one circle for a round
   sphere, three for a long body). Obstacles are "inflated" by r_c through a Euclidean distance
   transform, so a pose is certainly free when every circle centre has clearance ≥ r_c: O(N) lookups. Where
   that says "maybe", a pose is still proven free when every centre, from where it lies in its cell, is r_c
   from every blocked square (:func:`circles_clear_at`).
2. *The polygon decides* where the circles say "maybe": the blocked cells under the polygon's bounding
   box are tested exactly against the polygon (a cell square meets the polygon when its centre is inside
   or an edge of the polygon crosses it). Exact to the grid: a gap the footprint fits through is found.

One name per meaning (every wing uses these words, and only these):

* **clearance** (m, per cell): :attr:`ClearanceMap.clearance`, a conservative distance from anywhere in the
  cell to the nearest blocked cell (see below); what the covering circles are inflated against.
* **circle margin** (m, per pose): min over the covering circles of clearance − r_c; ≥ 0 proves the pose
  free, < 0 only says "maybe". Kernel :func:`circle_margin_at`, many poses :meth:`ClearanceMap.circle_margins`.
* **footprint hit** (bool, per pose): the exact polygon meets a blocked cell or leaves the map. Kernel
  :func:`footprint_hits`.
* **footprint margin** (m, per pose): the two-tier answer — the circle margin where it is ≥ 0, else 0.0
  where the polygon fits and the (negative) circle margin where it hits; ≥ 0 means free. Kernel
  :func:`footprint_margin`, many poses :meth:`ClearanceMap.footprint_margins`, a path's consecutive poses
  :meth:`ClearanceMap.path_margins` (measured where the path comes near, bounded from the last pose measured
  elsewhere).
* **footprint distance** (m, per pose): the exact distance from the polygon to the nearest blocked cell
  square or the map's edge, capped at a reach; 0 where they meet. Kernel :func:`footprint_distance`, many
  poses :meth:`ClearanceMap.footprint_distances`; the least over a path :meth:`ClearanceMap.least_footprint_distance`
  (pruned by circle margins) and :func:`least_footprint_distance` (from a grid and a robot).

Clearance is conservative: the distance transform measures cell centre to cell centre (d), and a point
anywhere in a cell is at least d − √2·res from any point of the nearest blocked cell, so that is what
is stored. Cells outside the map count as blocked (the robot must stay on the map).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numba import njit
from scipy import ndimage

from planner.jit import njit_leaf
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile

LEAST_SEED_M = 0.2  # the first pose of a least distance is measured this far past its lower bound first
SAMPLE_SPACING_M = 0.005  # spacing of the polygon samples the covering circles are sized on


@dataclass(frozen=True)
class CircleFootprint:
    """N covering circles in the body frame (x forward, y left), metres."""

    offsets_x: np.ndarray
    offsets_y: np.ndarray
    radius_m: float

    @classmethod
    def covering(cls, polygon: np.ndarray, n_circles: int) -> CircleFootprint:
        """``n_circles`` equal circles, evenly spaced along the longer axis of the polygon's bounding box,
        with the smallest radius whose union covers the polygon (checked on its edges and a dense interior
        grid: for a convex polygon the farthest point of each circle's share lies on the boundary)."""
        if n_circles < 1:
            raise ValueError("n_circles must be >= 1")
        poly = np.asarray(polygon, float)
        lo, hi = poly.min(axis=0), poly.max(axis=0)
        mid = (lo + hi) / 2.0
        axis = 0 if hi[0] - lo[0] >= hi[1] - lo[1] else 1
        seg = (hi[axis] - lo[axis]) / n_circles
        along = lo[axis] + (np.arange(n_circles) + 0.5) * seg
        centres = np.tile(mid, (n_circles, 1))
        centres[:, axis] = along
        samples = _polygon_samples(poly, SAMPLE_SPACING_M)
        dist = np.hypot(samples[:, None, 0] - centres[None, :, 0], samples[:, None, 1] - centres[None, :, 1])
        # every boundary point is within half a spacing of a sample
        radius = float(dist.min(axis=1).max()) + 0.5 * SAMPLE_SPACING_M
        return cls(centres[:, 0].copy(), centres[:, 1].copy(), radius)

    @classmethod
    def for_polygon(cls, polygon: np.ndarray, max_circles: int = 3) -> CircleFootprint:
        """The covering (1..``max_circles`` circles) that overshoots the polygon least in any direction."""
        poly = np.asarray(polygon, float)
        best: CircleFootprint | None = None
        best_excess = math.inf
        for n in range(1, max_circles + 1):
            cover = cls.covering(poly, n)
            excess = cover.excess(poly)
            if excess < best_excess - 1e-6:
                best, best_excess = cover, excess
        if best is None:
            raise ValueError("max_circles must be >= 1")
        return best

    @classmethod
    def for_robot(cls, robot: RobotProfile, max_circles: int = 3) -> CircleFootprint:
        """The covering of the robot's padded footprint polygon (see :meth:`for_polygon`), computed once per
        polygon in a process."""
        poly = np.asarray(robot.footprint_polygon, float)
        return _covering_of(tuple(map(tuple, poly.tolist())), max_circles)

    def excess(self, polygon: np.ndarray) -> float:
        """How far (m) the circles' union reaches beyond the polygon, in the worst of 360 directions."""
        u = np.stack([np.cos(np.radians(np.arange(360))), np.sin(np.radians(np.arange(360)))], axis=1)
        reach = (u @ np.stack([self.offsets_x, self.offsets_y])).max(axis=1) + self.radius_m
        return float((reach - (u @ np.asarray(polygon, float).T).max(axis=1)).max())

    def centres(self, x: float, y: float, yaw: float) -> np.ndarray:
        """World positions (N, 2) of the circle centres at pose (x, y, yaw)."""
        c, s = math.cos(yaw), math.sin(yaw)
        return np.stack(
            [x + c * self.offsets_x - s * self.offsets_y, y + s * self.offsets_x + c * self.offsets_y], axis=1
        )


@lru_cache(maxsize=32)
def _covering_of(polygon: tuple[tuple[float, ...], ...], max_circles: int) -> CircleFootprint:
    return CircleFootprint.for_polygon(np.array(polygon, float), max_circles)


def inscribed_radius(polygon: np.ndarray) -> float:
    """Radius (m) of the largest disc centred on the robot's origin that fits inside the polygon (kept per polygon:
    every plan asks it for its footprint)."""
    poly = np.ascontiguousarray(polygon, dtype=float)
    return _inscribed_radius(poly.tobytes(), poly.shape[0])


@lru_cache(maxsize=32)
def _inscribed_radius(data: bytes, n: int) -> float:
    poly = np.frombuffer(data, dtype=float).reshape(n, 2)
    a, b = poly, np.roll(poly, -1, axis=0)
    ab = b - a
    t = np.clip(-(a * ab).sum(axis=1) / np.maximum((ab * ab).sum(axis=1), 1e-300), 0.0, 1.0)
    return float(np.hypot(*(a + t[:, None] * ab).T).min())


def centre_distance(grid: OccupancyGrid, allow_unknown: bool = False) -> np.ndarray:
    """Distance (m, shape (height, width)) from each cell centre to the nearest blocked cell centre, the
    ring of cells just outside the map counting as blocked (exact Euclidean distance transform,
    :func:`edt_cells`)."""
    return _edt_scaled(grid.blocked(allow_unknown), float(grid.resolution_m), 0.0)


def edt_cells(blocked: np.ndarray) -> np.ndarray:
    """Exact Euclidean distance (in cells, float64, shape of ``blocked``) from each cell centre to the nearest
    blocked cell centre, the ring of cells just outside the grid counting as blocked.

    Felzenszwalb & Huttenlocher's separable transform (2012): per column the distance to the nearest blocked
    cell, then per row the lower envelope of the parabolas (x − q)² + g(q)², with the outside ring as two more
    sites at q = −1 and q = width. Equals :func:`scipy.ndimage.distance_transform_edt` of the padded grid
    (tested) in a fraction of its time.
    """
    return _edt_scaled(np.ascontiguousarray(blocked, dtype=np.bool_), 1.0, 0.0)


def clearance_cells(blocked: np.ndarray, resolution_m: float) -> np.ndarray:
    """The stored clearance (m) of :class:`ClearanceMap`: :func:`edt_cells` × resolution − √2·resolution, made
    in the transform's own last pass (no temporary arrays; ≈ 40 ms for 4 M cells on one core)."""
    return _edt_scaled(np.ascontiguousarray(blocked, dtype=np.bool_), float(resolution_m),
                       math.sqrt(2.0) * float(resolution_m))


@njit(cache=True)
def _edt_scaled(blocked: np.ndarray, scale: float, offset: float) -> np.ndarray:
    """:func:`edt_cells` × ``scale`` − ``offset``. Column distances are kept as int32 and the envelope's values
    as exact integers; the square roots are taken in one flat (vectorised) pass at the end."""
    h, w = blocked.shape
    g = np.empty((h, w), dtype=np.int32)
    # columns: distance to the nearest blocked cell above or below (or the outside ring), swept row by row
    for x in range(w):
        g[0, x] = 0 if blocked[0, x] else 1
    for y in range(1, h):
        for x in range(w):
            g[y, x] = 0 if blocked[y, x] else g[y - 1, x] + 1
    for x in range(w):
        if g[h - 1, x] > 1:
            g[h - 1, x] = 1
    for y in range(h - 2, -1, -1):
        for x in range(w):
            below = g[y + 1, x] + 1
            if below < g[y, x]:
                g[y, x] = below
    out = np.empty((h, w))
    n = w + 2
    f = np.empty(n, dtype=np.int64)
    v = np.empty(n, dtype=np.int64)
    z = np.empty(n + 1)
    for y in range(h):
        f[0] = 0  # the ring's cell at q = −1 (site index 0)
        for x in range(w):
            gx = np.int64(g[y, x])
            f[x + 1] = gx * gx
        f[n - 1] = 0  # the ring's cell at q = width
        k = 0
        v[0] = 0
        z[0] = -math.inf
        z[1] = math.inf
        for q in range(1, n):
            fq = f[q] + q * q
            while True:
                r = v[k]
                s = (fq - (f[r] + r * r)) / (2.0 * (q - r))
                if s <= z[k]:
                    k -= 1
                    continue
                break
            k += 1
            v[k] = q
            z[k] = s
            z[k + 1] = math.inf
        k = 0
        for x in range(w):
            q = x + 1
            while z[k + 1] < q:
                k += 1
            r = v[k]
            out[y, x] = (q - r) * (q - r) + f[r]
    flat = out.ravel()
    for i in range(flat.size):
        flat[i] = math.sqrt(flat[i]) * scale - offset
    return out


def boundary_cell_centres(grid: OccupancyGrid, allow_unknown: bool = False, edge_blocked: bool = False) -> np.ndarray:
    """World centres (n, 2) of the blocked cells that touch a free cell (4-neighbourhood): the only cells
    a body coming from free space can reach first. With ``edge_blocked`` the ring of cells just outside the
    map counts as blocked too."""
    blocked = grid.blocked(allow_unknown)
    res = grid.resolution_m
    ox, oy = float(grid.origin[0]), float(grid.origin[1])
    if edge_blocked:
        blocked = np.pad(blocked, 1, constant_values=True)
        ox, oy = ox - res, oy - res
    pad = np.pad(blocked, 1, constant_values=False)
    interior = pad[:-2, 1:-1] & pad[2:, 1:-1] & pad[1:-1, :-2] & pad[1:-1, 2:]
    iy, ix = np.nonzero(blocked & ~interior)
    return np.stack([ox + (ix + 0.5) * res, oy + (iy + 0.5) * res], axis=1)


class ClearanceMap:
    """Conservative clearance (m) of every cell to the nearest blocked cell, for O(1) pose checks."""

    def __init__(self, grid: OccupancyGrid, allow_unknown: bool = False) -> None:
        self.grid = grid
        self.blocked = grid.blocked(allow_unknown)
        self.clearance = clearance_cells(self.blocked, grid.resolution_m)
        self.origin_x = float(grid.origin[0])
        self.origin_y = float(grid.origin[1])
        self.resolution_m = float(grid.resolution_m)
        self.revision = 0  # how many times ``blocked`` was rewritten in place (write_blocked)

    def write_blocked(self, where: tuple[slice, slice], values: np.ndarray) -> None:
        """Rewrite blocked cells in place (a live map's update, planner/live/refresh.py) and count the revision:
        what was derived from them and cached by revision (the reachability labels) is computed again. The
        clearance itself is its writer's to update."""
        self.blocked[where] = values
        self.revision += 1

    def disc_components(self, inradius_m: float) -> np.ndarray:
        """Labels (height, width; int32) of the 8-connected pieces of cells that may hold the centre of a free
        disc of radius ``inradius_m`` (the footprint's inscribed disc); 0 = no such centre in the cell.

        A cell is kept when its centre is at least ``inradius_m − res·√2/2`` from every blocked cell centre
        (and from the ring outside the map): a superset of the cells containing a position where the disc —
        and so the footprint — is free, and any continuous motion passes through 8-adjacent kept cells. So
        start and goal in different pieces proves that no motion joins them (a flood fill, as Nav2's
        planners refuse a goal in another connected region).
        """
        # the stored clearance is the centre-to-centre distance − √2·res: compare without a temporary array
        kept = self.clearance >= inradius_m - self.resolution_m * (math.sqrt(0.5) + math.sqrt(2.0)) - 1e-9
        labels, _ = ndimage.label(kept, structure=np.ones((3, 3), dtype=bool))
        return np.asarray(labels, dtype=np.int32)

    def at(self, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
        """Clearance at world points (vectorised); −inf outside the map."""
        return _clearance_at(self.clearance, self.origin_x, self.origin_y, self.resolution_m,
                             np.asarray(xs, float).ravel(), np.asarray(ys, float).ravel())

    def circle_margins(self, footprint: CircleFootprint, poses: np.ndarray) -> np.ndarray:
        """Per pose (rows x, y, yaw): min over circles of clearance − r_c. Free where ≥ 0."""
        poses = np.atleast_2d(np.asarray(poses, float))
        c, s = np.cos(poses[:, 2:3]), np.sin(poses[:, 2:3])
        cx = poses[:, 0:1] + c * footprint.offsets_x - s * footprint.offsets_y
        cy = poses[:, 1:2] + s * footprint.offsets_x + c * footprint.offsets_y
        clear = self.at(cx, cy).reshape(cx.shape)
        return clear.min(axis=1) - footprint.radius_m

    def footprint_margins(self, footprint: CircleFootprint, polygon: np.ndarray, poses: np.ndarray) -> np.ndarray:
        """Per pose (rows x, y, yaw): the two-tier free-space margin of :func:`footprint_margin` (≥ 0 free)."""
        poses = np.ascontiguousarray(np.atleast_2d(np.asarray(poses, float))[:, :3])
        poly = np.asarray(polygon, float)
        return _footprint_margins(self.clearance, self.blocked, self.origin_x, self.origin_y, self.resolution_m, poses,
                              footprint.offsets_x, footprint.offsets_y, footprint.radius_m,
                              np.ascontiguousarray(poly[:, 0]), np.ascontiguousarray(poly[:, 1]))

    def path_margins(self, footprint: CircleFootprint, polygon: np.ndarray, poses: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
        """The exact check of a path's consecutive poses (rows x, y, yaw), measuring only where it must: per pose
        a lower bound of its footprint distance (≥ 0 free; < 0 only where the pose collides) and whether the pose
        was measured.

        A measured pose holds its footprint margin (:func:`footprint_margin`). After one with margin m > 0, the
        next poses are not measured while every covering-circle centre has moved less than PATH_SKIP_SHARE × m
        since (the step's length plus its turn × the farthest centre's offset, summed): such a pose holds m less
        that movement, a lower bound of its true circle margin (the clearance is a lower bound of the distance and
        a distance changes no faster than its point moves), so it is free. Where the path keeps room this
        measures one pose in tens (issue 21's seventeenth round); the lower bounds serve
        :meth:`least_footprint_distance` as the margins did, and its result is the same."""
        poses = np.ascontiguousarray(np.atleast_2d(np.asarray(poses, float))[:, :3])
        poly = np.asarray(polygon, float)
        return _path_margins(self.clearance, self.blocked, self.origin_x, self.origin_y, self.resolution_m, poses,
                             footprint.offsets_x, footprint.offsets_y, footprint.radius_m,
                             np.ascontiguousarray(poly[:, 0]), np.ascontiguousarray(poly[:, 1]))

    def footprint_distances(self, polygon: np.ndarray, poses: np.ndarray, reach_m: float = 1.0) -> np.ndarray:
        """Per pose: the exact distance (m) from the footprint polygon to the nearest blocked cell square or
        the map's edge, capped at ``reach_m``; 0 where the polygon meets a blocked cell or leaves the map."""
        poses = np.ascontiguousarray(np.atleast_2d(np.asarray(poses, float))[:, :3])
        poly = np.asarray(polygon, float)
        return _distances(self.blocked, self.origin_x, self.origin_y, self.resolution_m, poses,
                          np.ascontiguousarray(poly[:, 0]), np.ascontiguousarray(poly[:, 1]), reach_m)

    def least_footprint_distance(self, polygon: np.ndarray, poses: np.ndarray, lower_m: np.ndarray,
                                 reach_m: float = 1.0, footprint: CircleFootprint | None = None,
                                 measured: np.ndarray | None = None) -> float:
        """The smallest exact footprint distance over ``poses`` (capped at ``reach_m``), given a lower bound
        ``lower_m`` of each pose's distance (e.g. the covering circles' margin): poses are measured in order
        of their bound, each only as far as the best found so far, until no bound can beat it.

        With ``footprint`` and ``measured`` (:meth:`path_margins`' flags), a pose whose bound was only derived
        gets its footprint margin first, and is measured exactly only when that could still beat the best."""
        poses = np.ascontiguousarray(np.atleast_2d(np.asarray(poses, float))[:, :3])
        poly = np.asarray(polygon, float)
        px, py = np.ascontiguousarray(poly[:, 0]), np.ascontiguousarray(poly[:, 1])
        lower = np.ascontiguousarray(lower_m, dtype=float)
        if footprint is None or measured is None:  # every bound a margin: all poses in order of their bound
            order, rest, offx, offy, r_c = np.argsort(lower), _NO_POSES, _NO_OFFSETS, _NO_OFFSETS, 0.0
        else:
            first = np.flatnonzero(measured)
            order, rest = first[np.argsort(lower[first])], np.flatnonzero(~np.asarray(measured, dtype=bool))
            offx, offy, r_c = footprint.offsets_x, footprint.offsets_y, footprint.radius_m
        return float(_least_distance(self.blocked, self.origin_x, self.origin_y, self.resolution_m, poses, lower,
                                     order, px, py, reach_m, self.clearance, offx, offy, r_c, rest))


_NO_OFFSETS = np.zeros(0)
_NO_POSES = np.zeros(0, dtype=np.int64)


@njit(cache=True)
def _least_distance(blocked: np.ndarray, ox: float, oy: float, res: float, poses: np.ndarray, lower_m: np.ndarray,
                    order: np.ndarray, px: np.ndarray, py: np.ndarray, reach_m: float, clear: np.ndarray,
                    offx: np.ndarray, offy: np.ndarray, r_c: float, rest: np.ndarray) -> float:
    """:meth:`ClearanceMap.least_footprint_distance`'s loop, compiled (it ran in Python, a few ms per plan).

    The poses ``order`` (in order of their bound) are measured first. The measure of a pose scans the cells within
    the best distance so far of its polygon; the first pose measured is measured within its bound + LEAST_SEED_M first
    (a 2 m reach scans 10–20 times the cells): when it is nearer than that, its distance is exact and bounds the least,
    else it is measured again with the full reach. The poses ``rest`` (those whose bound was only derived) come after:
    each below the best is given its footprint margin (circles ``offx``, ``offy``, ``r_c`` on ``clear``), and those
    whose margin is below the best too are measured in order of their margins, as the first were. Every pose is
    measured or bounded: the least is exact either way.

    (Until issue 21's twentieth round the ``rest`` were measured in path order: a path closing in on a far wall was
    measured pose after pose, each a little nearer than the best so far. depot#9 of the real bench's seed 2, a 4.7 m
    path 1.5 m from everything: 64 measures, 0.72 ms of a 1.3 ms plan; in order of their margins, 10 and 0.10 ms.)"""
    turn = convex_turn(px, py)
    best = _least_in_order(blocked, ox, oy, res, poses, lower_m[order], order, px, py, reach_m, turn, reach_m)
    if best <= 0.0 or rest.size == 0:
        return best
    below = np.empty(rest.size, dtype=np.int64)  # the rest below the best, and their margins
    margin = np.empty(rest.size)
    n = 0
    for k in rest:
        if lower_m[k] >= best:
            continue
        m = footprint_margin(clear, blocked, ox, oy, res, poses[k, 0], poses[k, 1], poses[k, 2], offx, offy, r_c,
                             px, py, turn)
        if m < best:  # (the margin bounds the distance, as the derived bound did)
            below[n] = k
            margin[n] = max(lower_m[k], m)
            n += 1
    by_margin = np.argsort(margin[:n], kind="mergesort")
    return _least_in_order(blocked, ox, oy, res, poses, margin[:n][by_margin], below[:n][by_margin], px, py, best,
                           turn, reach_m)


@njit(cache=True)
def _least_in_order(blocked: np.ndarray, ox: float, oy: float, res: float, poses: np.ndarray, bounds: np.ndarray,
                    order: np.ndarray, px: np.ndarray, py: np.ndarray, best: float, turn: int, reach_m: float) -> float:
    """The least of ``best`` and the distances of the poses ``order``, measured in that order until no bound is below
    the best (``bounds[i]``: a lower bound of pose ``order[i]``'s distance, ascending); the first within its bound +
    LEAST_SEED_M first when nothing nearer than the reach is known yet."""
    if order.size and best >= reach_m:
        k = order[0]
        near = max(bounds[0], 0.0) + LEAST_SEED_M
        if near < reach_m:
            d = footprint_distance(blocked, ox, oy, res, poses[k, 0], poses[k, 1], poses[k, 2], px, py, near, turn)
            if d < near:
                best = d
    for i in range(order.size):
        if bounds[i] >= best:
            break
        k = order[i]
        if bounds[i] > 0.0:  # (no overlap test where the bound proves the pose free)
            d = _free_distance(blocked, ox, oy, res, poses[k, 0], poses[k, 1], poses[k, 2], px, py, best, turn)
        else:
            d = footprint_distance(blocked, ox, oy, res, poses[k, 0], poses[k, 1], poses[k, 2], px, py, best, turn)
        best = min(best, d)
        if best <= 0.0:
            return best
    return best


def _polygon_samples(poly: np.ndarray, spacing_m: float) -> np.ndarray:
    """Points (m, 2) on every edge of the polygon (≤ ``spacing_m`` apart) and on a grid inside it."""
    pts = [poly]
    for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
        n = max(2, int(math.ceil(np.hypot(*(b - a)) / spacing_m)))
        t = np.linspace(0.0, 1.0, n)[:, None]
        pts.append(a + t * (b - a))
    lo, hi = poly.min(axis=0), poly.max(axis=0)
    gx, gy = np.meshgrid(np.arange(lo[0], hi[0], 4 * spacing_m), np.arange(lo[1], hi[1], 4 * spacing_m))
    grid = np.column_stack([gx.ravel(), gy.ravel()])
    inside = np.array([_point_in_polygon(float(x), float(y), poly[:, 0], poly[:, 1]) for x, y in grid], bool)
    pts.append(grid[inside])
    return np.concatenate(pts)


@njit_leaf
def _point_in_polygon(x: float, y: float, px: np.ndarray, py: np.ndarray) -> bool:
    """Even-odd rule."""
    inside = False
    n = px.size
    j = n - 1
    for i in range(n):
        if (py[i] > y) != (py[j] > y):
            xc = (px[j] - px[i]) * (y - py[i]) / (py[j] - py[i]) + px[i]
            if x < xc:
                inside = not inside
        j = i
    return inside


@njit_leaf
def _segment_meets_box(x0: float, y0: float, x1: float, y1: float,
                       bx0: float, by0: float, bx1: float, by1: float) -> bool:
    """Does the segment (x0, y0)–(x1, y1) meet the closed box [bx0, bx1] × [by0, by1]? (Liang–Barsky)"""
    t0, t1 = 0.0, 1.0
    dx, dy = x1 - x0, y1 - y0
    for k in range(4):
        if k == 0:
            pp, q = -dx, x0 - bx0
        elif k == 1:
            pp, q = dx, bx1 - x0
        elif k == 2:
            pp, q = -dy, y0 - by0
        else:
            pp, q = dy, by1 - y0
        if pp == 0.0:
            if q < 0.0:
                return False
        else:
            r = q / pp
            if pp < 0.0:
                if r > t1:
                    return False
                if r > t0:
                    t0 = r
            else:
                if r < t0:
                    return False
                if r < t1:
                    t1 = r
    return True


@njit(cache=True)
def _placed(x: float, y: float, yaw: float, px: np.ndarray, py: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World coordinates of the body-frame polygon (px, py) at pose (x, y, yaw)."""
    c = math.cos(yaw)
    s = math.sin(yaw)
    return x + c * px - s * py, y + s * px + c * py


@njit_leaf
def convex_turn(px: np.ndarray, py: np.ndarray) -> int:
    """1 when the polygon (px, py) is convex and counter-clockwise, −1 when convex and clockwise, 0 otherwise: every
    two edges in a row turn the same way (or go straight) and the edges' x and y directions each change sign at
    most twice going round (which rules out a star that winds round more than once)."""
    n = px.size
    if n < 3:
        return 0
    turn = 0
    flips_x = flips_y = 0
    first_x = first_y = last_x = last_y = 0.0  # the first and the latest edge direction that is not 0
    for i in range(n):
        j = i + 1 if i + 1 < n else 0
        k = j + 1 if j + 1 < n else 0
        ex, ey = px[j] - px[i], py[j] - py[i]
        cross = ex * (py[k] - py[j]) - ey * (px[k] - px[j])
        if cross != 0.0:
            side = 1 if cross > 0.0 else -1
            if turn == 0:
                turn = side
            elif side != turn:
                return 0
        if ex != 0.0:
            if last_x != 0.0 and (ex > 0.0) != (last_x > 0.0):
                flips_x += 1
            if first_x == 0.0:
                first_x = ex
            last_x = ex
        if ey != 0.0:
            if last_y != 0.0 and (ey > 0.0) != (last_y > 0.0):
                flips_y += 1
            if first_y == 0.0:
                first_y = ey
            last_y = ey
    # and from the last edge back round to the first
    if first_x != 0.0 and (first_x > 0.0) != (last_x > 0.0):
        flips_x += 1
    if first_y != 0.0 and (first_y > 0.0) != (last_y > 0.0):
        flips_y += 1
    return turn if flips_x <= 2 and flips_y <= 2 else 0


@njit_leaf
def _square_meets_convex(cx: float, cy: float, half: float, c: float, s: float, px: np.ndarray, py: np.ndarray,
                         turn: int) -> bool:
    """Does the closed square of half-side ``half`` centred at (cx, cy) in the body frame, its sides along the world's
    axes (the world x axis is (c, −s) there, y is (s, c)), meet the convex polygon (px, py) (``turn`` as
    :func:`convex_turn` gives it)? Two convex shapes are apart exactly when an edge normal of one of them separates
    them (separating axes); the square's own axes never do here, as the caller takes only cells within the
    polygon's bounding box, so only the polygon's edges are tried: the square lies wholly beyond an edge when even
    its corner nearest that edge's line is beyond it. Touching counts as meeting."""
    n = px.size
    j = n - 1
    for i in range(n):
        nx = (py[i] - py[j]) * turn  # the edge's outward normal (not of unit length; the test scales with it)
        ny = (px[j] - px[i]) * turn
        if nx * cx + ny * cy - half * (abs(nx * c - ny * s) + abs(nx * s + ny * c)) > nx * px[j] + ny * py[j]:
            return False
        j = i
    return True


@njit_leaf
def footprint_hits(
    blocked: np.ndarray, ox: float, oy: float, res: float, x: float, y: float, yaw: float,
    px: np.ndarray, py: np.ndarray, turn: int = 2,
) -> bool:
    """Does the footprint polygon (body frame px, py) at pose (x, y, yaw) meet a blocked cell or leave the map?

    Exact for square cells: a blocked cell meets the polygon when its centre is inside it or one of its
    edges crosses the cell; for a convex polygon (every footprint in robots/ so far) when no edge of the polygon
    separates it (:func:`_square_meets_convex`, the same answer without the even-odd rule and the sixteen clipped
    edges). ``turn`` is :func:`convex_turn` of the polygon when the caller has it (it costs about 70 ns, a fifth of a
    call near a wall); 2 works it out here. ``blocked`` is the (height, width) boolean grid.

    The search calls this wherever the covering circles touch an obstacle, millions of times per plan batch,
    and there the polygon almost never does: a blocked cell of the bounding box farther from the pose than the
    farthest vertex (plus a nanometre, far beyond rounding) cannot meet the polygon, so only the cells in that
    disc are tested, and the answer is the one of testing them all (``tests/planner/maps/test_clearance.py``).
    """
    # the placed polygon's bounding box and farthest vertex, without building it (it is built only for a
    # blocked cell within reach, which is rare here)
    c = math.cos(yaw)
    s = math.sin(yaw)
    n = px.size
    h, w = blocked.shape
    x_lo = y_lo = math.inf
    x_hi = y_hi = -math.inf
    reach2 = 0.0
    for i in range(n):
        vx = x + c * px[i] - s * py[i]
        vy = y + s * px[i] + c * py[i]
        x_lo, x_hi, y_lo, y_hi = min(x_lo, vx), max(x_hi, vx), min(y_lo, vy), max(y_hi, vy)
        reach2 = max(reach2, (vx - x) ** 2 + (vy - y) ** 2)
    ix0 = int(math.floor((x_lo - ox) / res))
    ix1 = int(math.floor((x_hi - ox) / res))
    iy0 = int(math.floor((y_lo - oy) / res))
    iy1 = int(math.floor((y_hi - oy) / res))
    if ix0 < 0 or iy0 < 0 or ix1 >= w or iy1 >= h:
        return True
    reach2 = (math.sqrt(reach2) + 1e-9) ** 2
    for iy in range(iy0, iy1 + 1):
        by0 = oy + iy * res
        gy = max(by0 - y, 0.0, y - by0 - res)
        if gy * gy > reach2:
            continue
        for ix in range(ix0, ix1 + 1):
            if not blocked[iy, ix]:
                continue
            bx0 = ox + ix * res
            gx = max(bx0 - x, 0.0, x - bx0 - res)
            if gx * gx + gy * gy > reach2:
                continue
            # (the cell's centre in the body frame against the body-frame polygon: nothing is allocated, so the
            # search's compiled sweeps call this without reference counting)
            dx = bx0 + 0.5 * res - x
            dy = by0 + 0.5 * res - y
            if turn == 2:  # (not given: worked out at the first blocked cell within reach)
                turn = convex_turn(px, py)
            if turn != 0:
                if _square_meets_convex(c * dx + s * dy, -s * dx + c * dy, 0.5 * res, c, s, px, py, turn):
                    return True
                continue
            if _point_in_polygon(c * dx + s * dy, -s * dx + c * dy, px, py):
                return True
            j = n - 1
            for i in range(n):
                if _segment_meets_box(x + c * px[j] - s * py[j], y + s * px[j] + c * py[j],
                                      x + c * px[i] - s * py[i], y + s * px[i] + c * py[i],
                                      bx0, by0, bx0 + res, by0 + res):
                    return True
                j = i
    return False


@njit(cache=True)
def footprint_margin(
    clear: np.ndarray, blocked: np.ndarray, ox: float, oy: float, res: float, x: float, y: float, yaw: float,
    offx: np.ndarray, offy: np.ndarray, r_c: float, px: np.ndarray, py: np.ndarray, turn: int = 2,
) -> float:
    """Free-space margin (m) of the footprint at one pose: ≥ 0 means free (``turn`` as :func:`footprint_hits`).

    The covering circles' margin when they are clear of every obstacle (a lower bound of the polygon's
    clearance); otherwise the polygon decides: 0.0 when it fits, the (negative) circle margin when it hits.
    """
    c, s = math.cos(yaw), math.sin(yaw)
    m = circle_margin_at(clear, ox, oy, res, x, y, c, s, offx, offy, r_c)
    if m >= 0.0:
        return m
    if circles_clear_at(clear, ox, oy, res, x, y, c, s, offx, offy, r_c):
        return 0.0  # (what the polygon test answers there)
    if footprint_hits(blocked, ox, oy, res, x, y, yaw, px, py, turn):
        return m if m > -1e9 else -1e9
    return 0.0


PATH_SKIP_SHARE = 0.5  # path_margins: poses after a measured one are bounded, not measured, while they move less


@njit(cache=True)
def _path_margins(
    clear: np.ndarray, blocked: np.ndarray, ox: float, oy: float, res: float, poses: np.ndarray,
    offx: np.ndarray, offy: np.ndarray, r_c: float, px: np.ndarray, py: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`ClearanceMap.path_margins`' loop: per pose its footprint margin, or a lower bound of its footprint
    distance derived from the last pose measured, and whether it was measured."""
    n = poses.shape[0]
    out = np.empty(n)
    measured = np.zeros(n, dtype=np.bool_)
    turn = convex_turn(px, py)
    reach = 0.0  # the farthest covering-circle centre from the robot's centre
    for k in range(offx.size):
        reach = max(reach, math.hypot(offx[k], offy[k]))
    k = 0
    while k < n:
        m = footprint_margin(clear, blocked, ox, oy, res, poses[k, 0], poses[k, 1], poses[k, 2], offx, offy, r_c,
                             px, py, turn)
        out[k] = m
        measured[k] = True
        k += 1
        if not m > 0.0:
            continue
        moved = 0.0  # a bound of how far any circle centre has moved since the pose measured
        while k < n:
            turned = abs(poses[k, 2] - poses[k - 1, 2]) % (2.0 * math.pi)
            moved += math.hypot(poses[k, 0] - poses[k - 1, 0], poses[k, 1] - poses[k - 1, 1]) + reach * min(
                turned, 2.0 * math.pi - turned)
            if moved >= PATH_SKIP_SHARE * m:
                break
            out[k] = m - moved - 1e-9
            k += 1
    return out, measured


@njit(cache=True)
def _footprint_margins(
    clear: np.ndarray, blocked: np.ndarray, ox: float, oy: float, res: float, poses: np.ndarray,
    offx: np.ndarray, offy: np.ndarray, r_c: float, px: np.ndarray, py: np.ndarray,
) -> np.ndarray:
    out = np.empty(poses.shape[0])
    turn = convex_turn(px, py)
    for k in range(poses.shape[0]):
        out[k] = footprint_margin(clear, blocked, ox, oy, res, poses[k, 0], poses[k, 1], poses[k, 2],
                                   offx, offy, r_c, px, py, turn)
    return out


@njit(cache=True)
def _point_segment(x: float, y: float, ax: float, ay: float, bx: float, by: float) -> float:
    dx, dy = bx - ax, by - ay
    den = dx * dx + dy * dy
    t = 0.0 if den == 0.0 else min(1.0, max(0.0, ((x - ax) * dx + (y - ay) * dy) / den))
    return math.hypot(ax + t * dx - x, ay + t * dy - y)


@njit(cache=True)
def footprint_distance(
    blocked: np.ndarray, ox: float, oy: float, res: float, x: float, y: float, yaw: float,
    px: np.ndarray, py: np.ndarray, reach_m: float, turn: int = 2,
) -> float:
    """Exact distance (m) from the footprint polygon at (x, y, yaw) to the nearest blocked cell square or the
    map's edge, capped at ``reach_m``; 0 when they meet (``turn`` as :func:`footprint_hits`). Between two disjoint
    polygons the closest pair is a vertex of one and an edge of the other, so polygon vertices are measured to each
    cell square and cell corners to each polygon edge."""
    if footprint_hits(blocked, ox, oy, res, x, y, yaw, px, py, turn):
        return 0.0
    return _free_distance(blocked, ox, oy, res, x, y, yaw, px, py, reach_m, turn)


@njit(cache=True)
def _free_distance(
    blocked: np.ndarray, ox: float, oy: float, res: float, x: float, y: float, yaw: float,
    px: np.ndarray, py: np.ndarray, reach_m: float, turn: int = 2,
) -> float:
    """:func:`footprint_distance` of a pose known not to meet a blocked cell (nor to leave the map); ``turn`` as
    :func:`footprint_hits` (2: worked out here).

    Candidates that cannot beat the best distance so far are not measured (issue 21's seventeenth round; the
    distance is the same): a polygon vertex whose gap to the cell along x or y is already no shorter; a cell
    corner no nearer to (x, y) than the best + the polygon's reach; and, for a convex polygon, an edge with the
    corner on its inner side (for a point outside a convex polygon some edge nearest to it has the point on its
    outer side: at a nearest vertex, one of its two edges does)."""
    wx, wy = _placed(x, y, yaw, px, py)
    n = px.size
    h, w = blocked.shape
    if turn == 2:
        turn = convex_turn(px, py)
    best = reach_m
    r_out = 0.0  # every point of the polygon lies within r_out of (x, y)
    for i in range(n):  # the map's edge
        best = min(best, wx[i] - ox, ox + w * res - wx[i], wy[i] - oy, oy + h * res - wy[i])
        r_out = max(r_out, math.hypot(px[i], py[i]))
    ix0 = max(0, int(math.floor((wx.min() - reach_m - ox) / res)))
    ix1 = min(w - 1, int(math.floor((wx.max() + reach_m - ox) / res)))
    iy0 = max(0, int(math.floor((wy.min() - reach_m - oy) / res)))
    iy1 = min(h - 1, int(math.floor((wy.max() + reach_m - oy) / res)))
    # a cell no nearer to the polygon's bounding box than the best distance so far cannot beat it (every
    # vertex and edge point lies in the box); a nanometre of slack keeps rounding out of that decision
    x_lo, x_hi, y_lo, y_hi = wx.min(), wx.max(), wy.min(), wy.max()
    # and none farther than best + r_out from (x, y) (a cell d from it is at least d − r_out from the polygon): for a
    # round footprint the second test leaves a few cells of a wall at the best distance, the first a polygon's width
    for iy in range(iy0, iy1 + 1):
        by0 = oy + iy * res
        gap_y = max(by0 - y_hi, 0.0, y_lo - by0 - res)
        off_y = max(by0 - y, 0.0, y - by0 - res)
        if gap_y > best + 1e-9 or off_y - r_out > best + 1e-9:
            continue
        for ix in range(ix0, ix1 + 1):
            if not blocked[iy, ix]:
                continue
            bx0 = ox + ix * res
            if math.hypot(max(bx0 - x_hi, 0.0, x_lo - bx0 - res), gap_y) > best + 1e-9:
                continue
            if math.hypot(max(bx0 - x, 0.0, x - bx0 - res), off_y) - r_out > best + 1e-9:
                continue
            for i in range(n):
                gx = max(bx0 - wx[i], 0.0, wx[i] - bx0 - res)
                gy = max(by0 - wy[i], 0.0, wy[i] - by0 - res)
                if gx >= best or gy >= best:  # (the distance is at least either gap)
                    continue
                d = math.hypot(gx, gy)
                if d < best:
                    best = d
            for corner in range(4):
                cx = bx0 + res * (corner & 1)
                cy = by0 + res * (corner >> 1)
                if math.hypot(cx - x, cy - y) - r_out > best + 1e-9:
                    continue
                j = n - 1
                for i in range(n):
                    # (the edge j -> i has the polygon on its left when turn is 1, on its right when −1)
                    if turn != 0 and turn * ((wx[i] - wx[j]) * (cy - wy[j]) - (wy[i] - wy[j]) * (cx - wx[j])) > 0.0:
                        j = i
                        continue
                    d = _point_segment(cx, cy, wx[j], wy[j], wx[i], wy[i])
                    if d < best:
                        best = d
                    j = i
    return max(best, 0.0)


@njit(cache=True)
def _distances(blocked: np.ndarray, ox: float, oy: float, res: float, poses: np.ndarray,
               px: np.ndarray, py: np.ndarray, reach_m: float) -> np.ndarray:
    out = np.empty(poses.shape[0])
    turn = convex_turn(px, py)
    for k in range(poses.shape[0]):
        out[k] = footprint_distance(blocked, ox, oy, res, poses[k, 0], poses[k, 1], poses[k, 2], px, py, reach_m,
                                    turn)
    return out


@njit(cache=True)
def _clearance_at(clear: np.ndarray, ox: float, oy: float, res: float, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    out = np.empty(xs.size)
    h, w = clear.shape
    for i in range(xs.size):
        ix = int(math.floor((xs[i] - ox) / res))
        iy = int(math.floor((ys[i] - oy) / res))
        out[i] = clear[iy, ix] if 0 <= ix < w and 0 <= iy < h else -math.inf
    return out


@njit_leaf
def circle_margin_at(
    clear: np.ndarray, ox: float, oy: float, res: float, x: float, y: float, c: float, s: float,
    offx: np.ndarray, offy: np.ndarray, r_c: float,
) -> float:
    """Min over circles of (clearance − r_c) at one pose (x, y, heading with cosine ``c`` and sine ``s``: the
    search's sweeps compute them once per motion or share them with the pose itself); −inf when a circle leaves the
    map."""
    h, w = clear.shape
    best = math.inf
    for k in range(offx.size):
        px = x + c * offx[k] - s * offy[k]
        py = y + s * offx[k] + c * offy[k]
        ix = int(math.floor((px - ox) / res))
        iy = int(math.floor((py - oy) / res))
        if ix < 0 or iy < 0 or ix >= w or iy >= h:
            return -math.inf
        m = clear[iy, ix] - r_c
        if m < best:
            best = m
    return best


@njit_leaf
def circles_clear_at(
    clear: np.ndarray, ox: float, oy: float, res: float, x: float, y: float, c: float, s: float,
    offx: np.ndarray, offy: np.ndarray, r_c: float,
) -> bool:
    """Every covering circle is proven clear from where its centre q lies in its cell: the stored clearance is the
    centre-to-centre distance d less √2·res, the nearest blocked square is at least d − res/√2 from the cell's
    centre, so q is at least clearance + res/√2 − |q − cell centre| from every blocked square. Where the circle
    margin (which takes the worst point of the cell) says "maybe", this proves a quarter to a third of the poses
    near a wall free without the polygon test (issue 21's seventeenth round)."""
    h, w = clear.shape
    half_diagonal = res * math.sqrt(0.5)
    for k in range(offx.size):
        fx = (x + c * offx[k] - s * offy[k] - ox) / res
        fy = (y + s * offx[k] + c * offy[k] - oy) / res
        ix = int(math.floor(fx))
        iy = int(math.floor(fy))
        if ix < 0 or iy < 0 or ix >= w or iy >= h:
            return False
        if clear[iy, ix] + half_diagonal - res * math.hypot(fx - ix - 0.5, fy - iy - 0.5) < r_c + 1e-9:
            return False
    return True


def least_footprint_distance(grid: OccupancyGrid, robot: RobotProfile, poses: np.ndarray,
                             reach_m: float = 1.0) -> float:
    """Smallest exact distance (m) between the robot's padded footprint polygon at any of ``poses`` (m, 3: x, y,
    yaw) and a blocked cell (occupied or unknown) of the raw map or the map's edge; 0 when they meet; capped
    at ``reach_m``."""
    poly = robot.footprint_polygon
    poses = np.ascontiguousarray(np.atleast_2d(np.asarray(poses, float))[:, :3])
    dist = _distances(grid.blocked(), float(grid.origin[0]), float(grid.origin[1]), grid.resolution_m, poses,
                      np.ascontiguousarray(poly[:, 0]), np.ascontiguousarray(poly[:, 1]), reach_m)
    return float(dist.min()) if len(dist) else reach_m
