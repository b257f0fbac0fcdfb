"""Heuristics of the spherical Hybrid A* (paper 001 eq. 14g–i).

* Holonomic cost-to-go with obstacles (eq. 14g): a wavefront from the goal over a grid (optionally
  downsampled, as Nav2's Smac planner does) where a cell is passable when the robot's centre could be
  there, and each step costs its length × (1 + w·proximity), the same travel cost the search charges.
  16-connected moves keep the grid metric within 2.7 % of Euclidean; the result is divided by that
  factor and reduced by two coarse-cell diagonals, so it never exceeds the true cost (tested). Given the
  start, the wavefront is an A* towards it and computes exactly only the part around the way between them
  (:func:`_wavefront16`); elsewhere the table holds a lower bound.
* Dubins distance without obstacles (eq. 14h): :func:`planner.hybrid_astar.dubins.dubins_distance` at the robot's
  minimum turning radius.

``h = max(holonomic, dubins)`` and ``f = g + h·(1 + greed)`` (eq. 14i–j) are combined in the search.
"""

from __future__ import annotations

import math
import weakref
from collections import OrderedDict
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from planner.errors import PlannerCancelled, PlannerTimedOut
from planner.hybrid_astar.dubins import dubins_shortest
from planner.hybrid_astar.reeds_shepp import MAX_SEGS, MAX_WORDS, rs_words, word_cost

if TYPE_CHECKING:
    from planner.termination import Clock

# The wavefront towards a start stops where cost + distance to the start exceeds this × the start's cost + margin
# (issue 21's eleventh round, 480 real-map problems of seeds 0–7: every expansion and path as with 1.3 × + 2 m, which
# was measured as with the full table, at 30 % fewer cells; 1.0 × + 1 m changed 20 of 240 paths, 1.1 × + 0.5 m one).
STOP_FACTOR = 1.1
STOP_MARGIN_M = 1.0
# The same for the goal side's tables (towards the start; guided by the forward table, so the part computed
# exactly is the ellipse cost from the start + cost to the goal < bound): 1.2 changes no expansion or path there.
GOAL_SIDE_STOP_FACTOR = 1.2

# Worst-case ratio of the 16-connected grid metric to Euclidean distance.
SIXTEEN_CONNECTED_RATIO = 1.0 / math.cos(math.atan2(1.0, 2.0) / 2.0)

_MOVES = np.array(
    [[1, 0], [-1, 0], [0, 1], [0, -1], [1, 1], [1, -1], [-1, 1], [-1, -1],
     [2, 1], [1, 2], [-1, 2], [-2, 1], [-2, -1], [-1, -2], [1, -2], [2, -1]],
    dtype=np.int64,
)


def proximity_cost(margin_m: np.ndarray | float, range_m: float) -> np.ndarray | float:
    """Normalised proximity cost in [0, 1]: 1 touching the inflated obstacles, 0 beyond ``range_m``."""
    if range_m <= 0:
        return np.zeros_like(np.asarray(margin_m, float))
    return np.clip(1.0 - np.asarray(margin_m, float) / range_m, 0.0, 1.0)


def coarse_cost_grid(
    clearance: np.ndarray, centre_threshold_m: float, circle_radius_m: float, prox_range_m: float,
    cost_penalty: float, factor: int,
) -> np.ndarray:
    """Per coarse cell: multiplier 1 + w·proximity (the smallest over its fine cells), inf if impassable.

    A fine cell is passable when its clearance ≥ ``centre_threshold_m``; the proximity uses the
    clearance margin over ``circle_radius_m`` (an upper bound of the search's per-pose margin).
    """
    blocks = _block_max(clearance, factor)
    prox = proximity_cost(blocks - circle_radius_m, prox_range_m)
    mult = 1.0 + cost_penalty * np.asarray(prox, float)
    mult[blocks < centre_threshold_m] = np.inf
    return mult


@njit(cache=True)
def _block_max(clearance: np.ndarray, factor: int) -> np.ndarray:
    """Max of each ``factor`` × ``factor`` block (partial blocks at the far edges), in one pass over the grid."""
    h, w = clearance.shape
    hc, wc = -(-h // factor), -(-w // factor)
    out = np.full((hc, wc), -np.inf)
    for y in range(h):
        row = out[y // factor]
        for x in range(w):
            v = clearance[y, x]
            if v > row[x // factor]:
                row[x // factor] = v
    return out


_BUCKETS_A_CELL = 4  # the wavefront's queue: buckets a quarter of a cell wide (fewer cells come out of order)
_RING = 256  # buckets in flight (a step reaching further is filed again when due)


@njit(cache=True)
def _wavefront16(mult: np.ndarray, gx: int, gy: int, cell_m: float, sx: int, sy: int, stop_factor: float,
                 stop_margin_m: float, scale: float, slack: float, guide: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, float]:
    """Cost-to-go from cell (gx, gy) over the 16-connected grid, returned as the heuristic table
    max(cost × ``scale`` − ``slack``, 0) (inf where impassable or unreachable), with the counts (cells expanded,
    queue entries pushed) and the bound B of the part computed exactly (inf when all of it was).

    With a start cell (sx, sy) the wavefront is an A* towards it: cells come out in order of cost + e(cell), e the
    straight distance between cell centres to the start (a lower bound of the cost, consistent: a step costs at
    least its length). Once the start is reached at cost d_s it stops at B ≈ stop_factor·d_s + ``stop_margin_m``:
    every cell with cost + e < B has its exact cost, and every other cell costs at least B − e (its cheapest
    path leaves the exact part through a cell of cost + e ≥ B), which the table holds there. The exact part is an
    ellipse-like region around the start and the goal, not the disc of radius B around the goal, so far less
    of a large map is computed; a node of a search from the start lying beyond it has g + h ≥ about B.

    ``guide`` (shape (0, 0) for none), a table towards the start's cell (the forward table, for the goal side's
    table towards the start), is a lower bound of the cost to the start and consistent like e: e is then the larger
    of the two, and the exact part shrinks to about cost from the goal + cost to the start < B. Cells the guide
    cannot reach the start from are left out (inf).

    The queue is bucketed (Dial's) by cost + e, a quarter of a cell wide: O(1) a push. Cells of one bucket come out
    in any order, so a cell may be reached more cheaply after it was expanded: it is then queued and expanded again
    (label-correcting), and a cell's value is taken as the smaller of its cost found and B − e, so the table
    never exceeds the true cost. Work (pops, pushes, neighbour looks) is in proportion to the cells expanded;
    the grid as a whole is only allocated and filled (with a start: and given each cell's e, once, which the pushes
    and the last pass read instead of working out a square root each; issue 21's seventeenth round, 8 % of the
    wavefront's time)."""
    h, w = mult.shape
    n = h * w
    flat = mult.ravel()
    table = np.full(n, np.inf)  # the cost found so far (raw) until the last pass makes it the table
    counts = np.zeros(2, dtype=np.int64)
    if not (0 <= gx < w and 0 <= gy < h) or not flat[gy * w + gx] < np.inf:
        return table.reshape(h, w), counts, math.inf
    n_moves = _MOVES.shape[0]
    # per move: (length × cell × ½) as the step below multiplies it, its flat offset, and those of the two cells a
    # diagonal or knight move passes (both its target for a straight move), looked at only when the step improves
    coef = np.empty(n_moves)
    off = np.empty(n_moves, dtype=np.int64)
    off_a = np.empty(n_moves, dtype=np.int64)
    off_b = np.empty(n_moves, dtype=np.int64)
    for k in range(n_moves):
        mx = _MOVES[k, 0]
        my = _MOVES[k, 1]
        coef[k] = math.sqrt(mx * mx + my * my) * cell_m * 0.5
        off[k] = my * w + mx
        if abs(mx) + abs(my) == 3:
            ax = mx // 2 if abs(mx) == 2 else 0
            ay = my // 2 if abs(my) == 2 else 0
            bx = mx if abs(mx) == 1 else mx // 2
            by = my if abs(my) == 1 else my // 2
        elif abs(mx) + abs(my) == 2:
            ax, ay, bx, by = mx, 0, 0, my
        else:
            ax, ay, bx, by = mx, my, mx, my
        off_a[k] = ay * w + ax
        off_b[k] = by * w + bx
    directed = 0 <= sx < w and 0 <= sy < h
    guided = directed and guide.shape == mult.shape
    to_start = guide.ravel()
    # e(cell) once per cell (the key's lower bound; inf where the guide cannot reach the start), not once per push
    low = np.zeros(n if directed else 0)
    if directed:
        for iy in range(h):
            dy2 = float((iy - sy) * (iy - sy))
            row = iy * w
            for ix in range(w):
                low[row + ix] = cell_m * math.sqrt(float((ix - sx) * (ix - sx)) + dy2)
        if guided:
            for i in range(n):
                low[i] = max(low[i], to_start[i])
    width = cell_m / _BUCKETS_A_CELL
    inv = 1.0 / width
    mask = _RING - 1
    head = np.full(_RING, -1, dtype=np.int64)
    # queue entries (cell, its cost and key when queued, the next entry of its bucket) in a pool with a free list
    cap = 1024
    ent_cell = np.empty(cap, dtype=np.int64)
    ent_cost = np.empty(cap)
    ent_key = np.empty(cap)
    ent_next = np.empty(cap, dtype=np.int64)
    g = gy * w + gx
    table[g] = 0.0
    ent_cell[0] = g
    ent_cost[0] = 0.0
    ent_key[0] = low[g] if directed else 0.0
    cur = int(ent_key[0] * inv)
    ent_next[0] = -1
    head[cur & mask] = 0
    used = 1
    free = -1
    queued = 1
    stop = math.inf
    while queued > 0:
        slot = cur & mask
        e = head[slot]
        if e < 0:
            cur += 1
            if cur * width > stop:
                break
            continue
        head[slot] = ent_next[e]
        c = ent_cell[e]
        d = ent_cost[e]
        if d == table[c]:
            due = int(ent_key[e] * inv)
            if due > cur:  # filed early (its step reached beyond the ring): file it again
                due = min(due, cur + _RING - 1)
                ent_next[e] = head[due & mask]
                head[due & mask] = e
                continue
        ent_next[e] = free
        free = e
        queued -= 1
        if d != table[c]:  # reached more cheaply since it was queued
            continue
        counts[0] += 1
        cy = c // w
        cx = c - cy * w
        if cx == sx and cy == sy and stop == math.inf:
            stop = stop_factor * d + stop_margin_m
        if queued + n_moves > cap:  # room for one entry a move
            ent_cell = np.concatenate((ent_cell, np.empty(cap, dtype=np.int64)))
            ent_cost = np.concatenate((ent_cost, np.empty(cap)))
            ent_key = np.concatenate((ent_key, np.empty(cap)))
            ent_next = np.concatenate((ent_next, np.empty(cap, dtype=np.int64)))
            cap *= 2
        here = flat[c]
        interior = 2 <= cx < w - 2 and 2 <= cy < h - 2
        for k in range(n_moves):
            if not interior:
                nx = cx + _MOVES[k, 0]
                ny = cy + _MOVES[k, 1]
                if nx < 0 or ny < 0 or nx >= w or ny >= h:
                    continue
            nb = c + off[k]
            nd = d + coef[k] * (flat[nb] + here)
            if nd < table[nb] and flat[c + off_a[k]] < np.inf and flat[c + off_b[k]] < np.inf:
                key = nd
                if directed:
                    lower = low[nb]
                    if not lower < np.inf:  # (guided) no way from there to the start
                        continue
                    key += lower
                table[nb] = nd
                b = min(max(int(key * inv), cur), cur + _RING - 1)
                if free >= 0:
                    e = free
                    free = ent_next[e]
                else:
                    e = used
                    used += 1
                ent_cell[e] = nb
                ent_cost[e] = nd
                ent_key[e] = key
                ent_next[e] = head[b & mask]
                head[b & mask] = e
                queued += 1
                counts[1] += 1
    bound = cur * width if queued > 0 else math.inf  # every key left in the queue is at least this
    for i in range(n):
        if flat[i] < np.inf:
            v = table[i]
            if bound < math.inf:
                v = min(v, bound - low[i])
            if v < np.inf:
                table[i] = max(v * scale - slack, 0.0)
    return table.reshape(h, w), counts, bound


_NO_GUIDE = np.zeros((0, 0))


_RS_TABLES: OrderedDict[tuple[float, int, float, float, float, float], np.ndarray] = OrderedDict()
_RS_TABLES_KEPT = 4
RS_TABLE_MARGIN_CELLS = 1.0  # the table's margin below its bin's sampled minimum, in cells (see reeds_shepp_table)
NEAR_GOAL_M = 0.6  # within this of the goal the table holds the Reeds–Shepp distance (see _build_reeds_shepp_table)


def reeds_shepp_table(rho: float, n_yaw: int = 72, cell_m: float = 0.1, half_width_m: float = 0.0,
                      clock: Clock | None = None, reverse_penalty: float = 1.0, switch_cost_m: float = 0.0
                      ) -> np.ndarray:
    """Cost of the cheapest Reeds–Shepp word to a goal at the origin (heading 0) under the search's direction
    weights: forward metres + ``reverse_penalty`` × backward metres + ``switch_cost_m`` per cusp, the forward-only
    Dubins word a candidate too (:func:`planner.hybrid_astar.reeds_shepp.rs_best`'s cost). With the weights
    (1, 0) it is the Reeds–Shepp distance (OMPL's ``ReedsSheppStateSpace``, tested).

    Used as the non-holonomic heuristic when reversing is allowed (Dubins is not a lower bound then). With the
    search's own weights it prices what the search pays for rolling backwards and for each cusp, so where turning
    round costs less than reversing the heuristic says so (the plain distance sees both as equally long).
    Sampled every ``cell_m`` over ±``half_width_m`` (default max(3 m, 3ρ)) and every 2π/``n_yaw``, then
    each bin holds the minimum over its 8 corner samples less one cell, so a lookup at any pose inside the
    bin does not exceed the cheapest word's cost there (checked on random poses in the tests). Shape
    (n_yaw, 2n, 2n) with n = half_width / cell; compiled from the closed-form words (≈ 0.2 s at 72 bins), built
    once per (ρ, bins, weights) in a process. Its size is the request's (``n_yaw``), so with ``clock`` the build
    stops at the clock's deadline or cancel (:class:`~planner.errors.PlannerTimedOut` /
    :class:`~planner.errors.PlannerCancelled`) and keeps nothing.
    """
    key = (float(rho), int(n_yaw), float(cell_m), float(half_width_m), float(reverse_penalty), float(switch_cost_m))
    cached = _RS_TABLES.get(key)
    if cached is not None:
        _RS_TABLES.move_to_end(key)
        return cached
    table = _build_reeds_shepp_table(rho, n_yaw, cell_m, half_width_m, clock, reverse_penalty, switch_cost_m)
    _RS_TABLES[key] = table
    while len(_RS_TABLES) > _RS_TABLES_KEPT:
        _RS_TABLES.popitem(last=False)
    return table


@njit(cache=True)
def _word_costs(yaw: float, coords: np.ndarray, rho: float, reverse_penalty: float, switch_cost: float,
                weighted: np.ndarray, shortest: np.ndarray) -> None:
    """From (coords[i], coords[j], yaw) to the origin (heading 0): ``weighted[j, i]``, the cheapest word under the
    weights (forward Dubins and backward Dubins words among the candidates), and ``shortest[j, i]``, the
    Reeds–Shepp distance."""
    turns = np.empty((MAX_WORDS, MAX_SEGS), dtype=np.int64)
    lens = np.empty((MAX_WORDS, MAX_SEGS))
    c, s = math.cos(yaw), math.sin(yaw)
    for j in range(coords.size):
        for i in range(coords.size):
            # the goal (origin, heading 0) in the pose's frame, in units of ρ
            dx, dy = -coords[i], -coords[j]
            x, y, phi = (c * dx + s * dy) / rho, (-s * dx + c * dy) / rho, -yaw
            best, dist = math.inf, math.inf
            for k in range(rs_words(x, y, phi, turns, lens)):
                best = min(best, word_cost(lens[k], rho, reverse_penalty, switch_cost))
                dist = min(dist, word_cost(lens[k], rho, 1.0, 0.0))
            word, t, p, q = dubins_shortest(0.0, 0.0, 0.0, x, y, phi, 1.0)
            if word >= 0:
                best = min(best, rho * (t + p + q))
            # rolling backwards all the way: the time-flipped goal's forward Dubins word
            word, t, p, q = dubins_shortest(0.0, 0.0, 0.0, -x, y, -phi, 1.0)
            if word >= 0:
                best = min(best, reverse_penalty * rho * (t + p + q))
            weighted[j, i] = best
            shortest[j, i] = dist


def _build_reeds_shepp_table(rho: float, n_yaw: int, cell_m: float, half_width_m: float,
                             clock: Clock | None, reverse_penalty: float, switch_cost_m: float) -> np.ndarray:
    half = half_width_m or max(3.0, 3.0 * rho)
    n = round(half / cell_m)
    coords = (np.arange(2 * n + 1) - n) * cell_m
    weighted = np.empty((n_yaw + 1, 2 * n + 1, 2 * n + 1))
    shortest = np.empty_like(weighted)
    for k in range(n_yaw // 2 + 1):
        if clock is not None:
            if clock.cancelled():
                raise PlannerCancelled("cancelled while building the Reeds–Shepp heuristic table")
            if clock.expired():
                raise PlannerTimedOut(f"the time limit of {clock.time_limit_s:g} s ran out while building the "
                                      f"Reeds–Shepp heuristic table for {n_yaw} yaw bins (options.n_yaw_bins)",
                                      planning_time_s=clock.elapsed_s())
        _word_costs(-math.pi + 2.0 * math.pi * k / n_yaw, coords, rho, reverse_penalty, switch_cost_m, weighted[k],
                    shortest[k])
    # the rest by reflection: (x, y, yaw) and (x, −y, −yaw) cost the same (left and right turns swap); the
    # yaw sample k mirrors n_yaw − k
    for k in range(n_yaw // 2 + 1, n_yaw + 1):
        weighted[k] = weighted[n_yaw - k, ::-1]
        shortest[k] = shortest[n_yaw - k, ::-1]
    lows = [np.minimum.reduce([samples[dk:dk + n_yaw, dj:dj + 2 * n, di:di + 2 * n]
                               for dk in (0, 1) for dj in (0, 1) for di in (0, 1)]) for samples in (weighted, shortest)]
    # Near the goal the weighted cost jumps by a cusp's cost across thin slivers (a short word without a cusp exists
    # only in a narrow cone), thinner than a bin, so its corners miss them: there the bin holds the distance, which
    # the weighted cost never goes below.
    centre = (np.arange(2 * n) - n + 0.5) * cell_m
    near = np.hypot(centre[None, :], centre[:, None]) < NEAR_GOAL_M + cell_m
    table = np.where(near, lows[1], lows[0])
    # the cost is not monotone inside a bin (it dips by a few mm between corners): keep a cell of margin
    return np.maximum(table - RS_TABLE_MARGIN_CELLS * cell_m, 0.0)


def auto_downsample(shape: tuple[int, ...], max_cells: int = 50_000) -> int:
    """Smallest factor ≥ 2 that brings a grid of ``shape`` to at most ``max_cells`` coarse cells."""
    cells = int(shape[0]) * int(shape[1])
    return max(2, math.ceil(math.sqrt(cells / max_cells)))


class HolonomicHeuristic:
    """Admissible holonomic cost-to-go (m, weighted like the search's travel cost) from one goal.

    Parameters
    ----------
    mult : (h, w) coarse cost multipliers from :func:`coarse_cost_grid` (inf = impassable); it does not
        depend on the goal, so a planner builds it once per map.
    origin_xy : the grid's origin (m).
    cell_m : coarse cell size (m) = fine resolution × downsampling factor.
    goal_xy : goal position (m).
    start_xy : when given, the wavefront is an A* towards it and stops once cost + straight distance to the
        start exceeds ``stop_factor`` × the start's cost + ``stop_margin_m`` (:func:`_wavefront16`); every cell
        beyond holds a lower bound (that bound less its distance to the start). A node there has g + h at least
        about that bound, above the goal's f, so the search never needs its exact value (on the 60 real-map
        problems 1.1 × + 1 m leaves every expansion as it was with the full table).
    guide : a table towards the start's cell (same grid), a tighter lower bound of the cost to the start than
        the straight distance (:func:`_wavefront16`); held weakly for :meth:`covers`.

    :attr:`expanded` and :attr:`pushes` count the wavefront's work; :meth:`covers` says whether the table is
    exact along the cheapest way from another start (a cached table's reuse).
    """

    def __init__(self, mult: np.ndarray, origin_xy: tuple[float, float], cell_m: float,
                 goal_xy: tuple[float, float], start_xy: tuple[float, float] | None = None,
                 stop_factor: float = STOP_FACTOR, stop_margin_m: float = STOP_MARGIN_M,
                 guide: np.ndarray | None = None) -> None:
        self.cell_m = cell_m
        self.origin_xy = origin_xy
        gx = math.floor((goal_xy[0] - origin_xy[0]) / cell_m)
        gy = math.floor((goal_xy[1] - origin_xy[1]) / cell_m)
        sx, sy = (-1, -1) if start_xy is None else (math.floor((start_xy[0] - origin_xy[0]) / cell_m),
                                                     math.floor((start_xy[1] - origin_xy[1]) / cell_m))
        # Within one coarse cell the grid knows nothing: allow a diagonal of slack at each end, and
        # undo the 16-connected metric's overestimate of Euclidean length.
        slack = 2.0 * math.sqrt(2.0) * cell_m
        guided = guide is not None and guide.shape == mult.shape
        self.table, counts, self.bound = _wavefront16(
            np.ascontiguousarray(mult), gx, gy, cell_m, sx, sy, stop_factor, stop_margin_m,
            1.0 / SIXTEEN_CONNECTED_RATIO, slack, guide if guide is not None and guided else _NO_GUIDE)
        # held weakly: a cached table does not keep another alive (covers() answers no once it is gone)
        self._guide = weakref.ref(guide) if guide is not None and guided else None
        self._scale, self._slack, self._start_cell = 1.0 / SIXTEEN_CONNECTED_RATIO, slack, (sx, sy)
        #: cells the wavefront expanded and queue entries it pushed (its work; the rest of the grid is only filled)
        self.expanded, self.pushes = int(counts[0]), int(counts[1])

    def covers(self, start_xy: tuple[float, float]) -> bool:
        """The cheapest way from ``start_xy`` to the goal lies in the part computed exactly: every cell z on it
        has cost(z) + e(z) ≤ cost(start) + e(start) (e the straight distance to the table's own start), below
        the bound."""
        if not math.isfinite(self.bound):
            return True
        ix = math.floor((start_xy[0] - self.origin_xy[0]) / self.cell_m)
        iy = math.floor((start_xy[1] - self.origin_xy[1]) / self.cell_m)
        h, w = self.table.shape
        if not (0 <= ix < w and 0 <= iy < h) or not math.isfinite(self.table[iy, ix]):
            return False
        # the cost there (at most: below a value of 0 it is anywhere under the slack); beyond the exact part the
        # table holds bound − e, so the test fails there
        cost = (float(self.table[iy, ix]) + self._slack) / self._scale
        e = self.cell_m * math.hypot(ix - self._start_cell[0], iy - self._start_cell[1])
        if self._guide is not None:
            guide = self._guide()
            if guide is None:
                return False
            e = max(e, float(guide[iy, ix]))
        return cost + e < self.bound - self.cell_m

    def __call__(self, x: float, y: float) -> float:
        ix = math.floor((x - self.origin_xy[0]) / self.cell_m)
        iy = math.floor((y - self.origin_xy[1]) / self.cell_m)
        h, w = self.table.shape
        if 0 <= ix < w and 0 <= iy < h:
            return float(self.table[iy, ix])
        return math.inf
