"""Heuristics of the spherical Hybrid A* (paper 001 eq. 14g–i).

* Holonomic cost-to-go with obstacles (eq. 14g): Dijkstra from the goal over a grid (optionally
  downsampled, as Nav2's Smac planner does) where a cell is passable when the robot's centre could be
  there, and each step costs its length × (1 + w·proximity), the same travel cost the search charges.
  16-connected moves keep the grid metric within 2.7 % of Euclidean; the result is divided by that
  factor and reduced by one coarse-cell diagonal, so it never exceeds the true cost (tested).
* Dubins distance without obstacles (eq. 14h): :func:`planner.hybrid_astar.dubins.dubins_distance` at the robot's
  minimum turning radius.

``h = max(holonomic, dubins)`` and ``f = g + h·(1 + greed)`` (eq. 14i–j) are combined in the search.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from planner.errors import PlannerCancelled, PlannerTimedOut
from planner.hybrid_astar.dubins import dubins_shortest
from planner.hybrid_astar.heap import heap_pop, heap_push
from planner.hybrid_astar.reeds_shepp import MAX_SEGS, MAX_WORDS, rs_words, word_cost

if TYPE_CHECKING:
    from planner.termination import Clock

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


@njit(cache=True)
def _dijkstra16(mult: np.ndarray, gx: int, gy: int, cell_m: float, sx: int, sy: int, stop_factor: float) -> np.ndarray:
    """Cost-to-go from cell (gx, gy). Once the start cell (sx, sy) is settled at d_s, the wavefront stops
    at stop_factor·d_s + 4 cells: every cell not settled by then gets the last settled cost, a lower
    bound of its own, so the table stays admissible while the far side of a large map is skipped.

    Run once per new goal, inside the plan's time: the passability of every cell, each move's length factor
    and the cells a knight move passes are looked up, not recomputed per move, and the heap starts at one
    entry per cell and grows when needed (it was sized for the worst case, 16 per cell). The pushes and pops
    are the same, in the same order, so the table is the same to the bit."""
    h, w = mult.shape
    dist = np.full((h, w), np.inf)
    if not (0 <= gx < w and 0 <= gy < h) or not np.isfinite(mult[gy, gx]):
        return dist
    n_moves = _MOVES.shape[0]
    # per move: (length × cell × ½) as the step below multiplies it, and the two cells a diagonal or knight
    # move passes (offsets from the cell left; both the target for a straight move)
    coef = np.empty(n_moves)
    pass_a = np.empty((n_moves, 2), dtype=np.int64)
    pass_b = np.empty((n_moves, 2), dtype=np.int64)
    for k in range(n_moves):
        mx = _MOVES[k, 0]
        my = _MOVES[k, 1]
        coef[k] = math.sqrt(mx * mx + my * my) * cell_m * 0.5
        if abs(mx) + abs(my) == 3:
            pass_a[k, 0] = mx // 2 if abs(mx) == 2 else 0
            pass_a[k, 1] = my // 2 if abs(my) == 2 else 0
            pass_b[k, 0] = mx if abs(mx) == 1 else mx // 2
            pass_b[k, 1] = my if abs(my) == 1 else my // 2
        elif abs(mx) + abs(my) == 2:
            pass_a[k, 0], pass_a[k, 1] = mx, 0
            pass_b[k, 0], pass_b[k, 1] = 0, my
        else:
            pass_a[k, 0], pass_a[k, 1] = mx, my
            pass_b[k, 0], pass_b[k, 1] = mx, my
    passable = np.empty((h, w), dtype=np.bool_)
    for iy in range(h):
        for ix in range(w):
            passable[iy, ix] = np.isfinite(mult[iy, ix])
    cap = h * w + 16
    keys = np.empty(cap)
    vals = np.empty(cap, dtype=np.int64)
    size = np.zeros(1, dtype=np.int64)
    dist[gy, gx] = 0.0
    heap_push(keys, vals, size, 0.0, gy * w + gx)
    done = np.zeros((h, w), dtype=np.bool_)
    stop = math.inf
    d = 0.0
    while size[0] > 0:
        d, idx = heap_pop(keys, vals, size)
        cy = idx // w
        cx = idx - cy * w
        if done[cy, cx]:
            continue
        if d > stop:
            break
        done[cy, cx] = True
        if cx == sx and cy == sy:
            stop = stop_factor * d + 4.0 * cell_m
        here = mult[cy, cx]
        if size[0] + n_moves > keys.size:  # each settled cell pushes at most one entry per move
            keys = np.concatenate((keys, np.empty(keys.size)))
            vals = np.concatenate((vals, np.empty(vals.size, dtype=np.int64)))
        for k in range(n_moves):
            nx = cx + _MOVES[k, 0]
            ny = cy + _MOVES[k, 1]
            if nx < 0 or ny < 0 or nx >= w or ny >= h or done[ny, nx] or not passable[ny, nx]:
                continue
            if not (passable[cy + pass_a[k, 1], cx + pass_a[k, 0]] and passable[cy + pass_b[k, 1], cx + pass_b[k, 0]]):
                continue
            nd = d + coef[k] * (mult[ny, nx] + here)
            if nd < dist[ny, nx]:
                dist[ny, nx] = nd
                heap_push(keys, vals, size, nd, ny * w + nx)
    if size[0] > 0:
        for iy in range(h):
            for ix in range(w):
                if not done[iy, ix] and passable[iy, ix]:
                    dist[iy, ix] = d
    return dist


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
    start_xy : when given, the wavefront stops at ``stop_factor`` × the start's cost (+ 4 cells); cells
        beyond get that cost as a lower bound. Nodes that far away have f = g + h·(1 + greed) above the
        goal's, so the search never needs their exact value.
    """

    def __init__(self, mult: np.ndarray, origin_xy: tuple[float, float], cell_m: float,
                 goal_xy: tuple[float, float], start_xy: tuple[float, float] | None = None,
                 stop_factor: float = 2.0) -> None:
        self.cell_m = cell_m
        self.origin_xy = origin_xy
        gx = math.floor((goal_xy[0] - origin_xy[0]) / cell_m)
        gy = math.floor((goal_xy[1] - origin_xy[1]) / cell_m)
        sx, sy = (-1, -1) if start_xy is None else (math.floor((start_xy[0] - origin_xy[0]) / cell_m),
                                                     math.floor((start_xy[1] - origin_xy[1]) / cell_m))
        raw = _dijkstra16(mult, gx, gy, cell_m, sx, sy, stop_factor)
        # Within one coarse cell the grid knows nothing: allow a diagonal of slack at each end, and
        # undo the 16-connected metric's overestimate of Euclidean length.
        slack = 2.0 * math.sqrt(2.0) * cell_m
        self.table = np.maximum(raw / SIXTEEN_CONNECTED_RATIO - slack, 0.0)
        finite = self.table[np.isfinite(self.table)]
        #: values at or above this are the wavefront's cut-off plateau (a lower bound, not the cost-to-go)
        self.cutoff = float(finite.max()) if start_xy is not None and finite.size else math.inf

    def __call__(self, x: float, y: float) -> float:
        ix = math.floor((x - self.origin_xy[0]) / self.cell_m)
        iy = math.floor((y - self.origin_xy[1]) / self.cell_m)
        h, w = self.table.shape
        if 0 <= ix < w and 0 <= iy < h:
            return float(self.table[iy, ix])
        return math.inf
