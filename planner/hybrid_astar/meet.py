"""Meet in the middle: join the forward search's tree and the goal side's with an analytic shot.

A problem with a manoeuvre at both ends (a sphere parked across a narrow bay at the start and across another
at the goal) traps both searches of the two-ended search (:mod:`two_ended`): the forward search turns round in
the start's bay, leaves it, and then has to turn round in the goal's bay as well, state by state, while the goal
side does the same the other way round. Each alone fills both bays (``bays#4`` of the seed-21 real-map draw:
220 k expansions, 3.4 s). Long before either gets through the far bay, both trees cover the ground between the
bays, many of their nodes in nearly the same pose. A shot from a forward node to a goal-side node joins them: the
forward chain to its node, the shot, and the goal side's chain run backwards (:func:`two_ended.goal_side_motions`)
to the goal.

Each tree's nodes are bucketed by (cell of :data:`CELL_M`, heading bin of 2π / :data:`YAW_BINS`), headings in the
forward problem's frame (a goal-side node's turned by π); a bucket keeps its cheapest node (least g). A tree's
buckets are a hash map (:class:`Buckets`: the closed set's open addressing, :mod:`closed_set`, with the node and its
g in parallel arrays), sized by the tree, not the map: until issue 21's nineteenth round they were four arrays over the
whole map (1.4 M buckets each on a 100 m map, 46 MB a meeting), whose filling took 1.3 ms a meeting in a warm
process and up to 7 ms an array where its pages were new (the real-map bench: 100by100_20#7 of seed 1, 107 ms,
of which 10 in the search loop). After each
round of chunks, every new node of one tree looks up the other tree's buckets in the same heading bin and the
3 × 3 cells around its own; a pair is ranked by g_forward + an estimate of the shot + g_goal-side, and the best
:data:`TRIES_PER_ROUND` pairs not tried before are shot at (:func:`kernels.try_shot`, collision-checked like every
shot). A goal-side node is used only upright (held roll 0), so the shot ends upright where that node's chain
starts. The joined path is checked like every goal-side path (rolled from the true start, exact footprint).

The first join found is returned, as the first path of either search is: the smoother shortens it after.

A join by a shot needs the two trees to roll the shared way in the same direction. When each side rolled it the
other way round (a goal that faces back the way the start came: the forward tree arrives facing away from the
goal's heading, the goal side's the same at the start), both sides have to turn round in the narrow far end, state
by state. :func:`find_turn` finds where the two trees hold nodes in one cell with opposite headings, the roomiest
such cell first; :meth:`two_ended.GoalSide.meet` then searches the turn between the two poses there with a small
budget (a turn in a wider place than either end).
"""

from __future__ import annotations

import heapq
import math
from typing import Any

import numpy as np

from planner.hybrid_astar import closed_set, kernels
from planner.hybrid_astar.reeds_shepp import MAX_SHOT_M
from planner.jit import njit_leaf
from planner.kinematics import wrap

CELL_M = 0.5  # bucket size (m)
YAW_BINS = 36  # heading bins of the buckets (10°)
BEST_PER_ROUND = 64  # candidate pairs kept from one round's look-ups
TRIES_PER_ROUND = 8  # shots tried per round
PENDING_KEPT = 512  # untried candidate pairs carried over between rounds


@njit_leaf
def _bucket(x: float, y: float, yaw: float, ox: float, oy: float, cell: float, nx: int, ny: int, nyaw: int,
            dx: int, dy: int) -> int:
    """Bucket index of a pose, shifted by (dx, dy) cells; -1 outside the map."""
    ix = int(math.floor((x - ox) / cell)) + dx
    iy = int(math.floor((y - oy) / cell)) + dy
    if ix < 0 or iy < 0 or ix >= nx or iy >= ny:
        return -1
    a = yaw - 2.0 * math.pi * math.floor(yaw / (2.0 * math.pi))
    yb = int(a / (2.0 * math.pi) * nyaw) % nyaw
    return (iy * nx + ix) * nyaw + yb


@njit_leaf
def _node_of(keys: np.ndarray, nodes: np.ndarray, b: int) -> int:
    """The node kept in bucket ``b``, -1 when it holds none."""
    i = closed_set._slot(keys, b)
    return nodes[i] if keys[i] == b else -1


@njit_leaf
def index_nodes(node_f: np.ndarray, node_i: np.ndarray, lo: int, hi: int, turn: float, upright_roll: int,
                ox: float, oy: float, cell: float, nx: int, ny: int, nyaw: int,
                keys: np.ndarray, nodes: np.ndarray, gs: np.ndarray) -> int:
    """Put nodes [lo, hi) into the buckets (heading turned by ``turn``), each bucket keeping its least-g node (g as
    it was when the node was put in: ``gs``); ``upright_roll`` ≥ 0 keeps only nodes holding that roll index.
    ``keys`` / ``nodes`` / ``gs`` is the hash map (room for hi − lo more buckets at a load of at most one half:
    :meth:`Buckets.add` makes it). Returns the buckets added."""
    added = 0
    for k in range(lo, hi):
        if upright_roll >= 0 and node_i[k, 1] != upright_roll:
            continue
        b = _bucket(node_f[k, 0], node_f[k, 1], node_f[k, 2] + turn, ox, oy, cell, nx, ny, nyaw, 0, 0)
        if b < 0:
            continue
        i = closed_set._slot(keys, b)
        if keys[i] != b:
            keys[i] = b
            added += 1
        elif node_f[k, 4] >= gs[i]:
            continue
        nodes[i] = k
        gs[i] = node_f[k, 4]
    return added


@njit_leaf
def rehash(keys: np.ndarray, nodes: np.ndarray, gs: np.ndarray, out_keys: np.ndarray, out_nodes: np.ndarray,
           out_gs: np.ndarray) -> None:
    """Put every bucket of ``keys`` / ``nodes`` / ``gs`` into the empty (larger) ``out_*``."""
    for i in range(keys.size):
        if keys[i] != closed_set.EMPTY:
            j = closed_set._slot(out_keys, keys[i])
            out_keys[j] = keys[i]
            out_nodes[j] = nodes[i]
            out_gs[j] = gs[i]


@njit_leaf
def find_pairs(node_f: np.ndarray, node_i: np.ndarray, lo: int, hi: int, turn: float, upright_roll: int,
               other_f: np.ndarray, other_turn: float, other_keys: np.ndarray, other_nodes: np.ndarray,
               ox: float, oy: float, cell: float, nx: int, ny: int, nyaw: int, rho: float, max_len: float,
               out_a: np.ndarray, out_b: np.ndarray, out_cost: np.ndarray) -> int:
    """For each node of [lo, hi) (heading turned by ``turn``; only roll index ``upright_roll`` if ≥ 0), the other
    tree's bucket nodes in its heading bin and the 3 × 3 cells around: keep the ``out_cost.size`` cheapest pairs by
    g + |Δxy| + ρ·|Δyaw| + g_other (a rough shot estimate: its ranking, not a bound). Returns how many were kept
    (unordered)."""
    cap = out_cost.size
    n = 0
    worst = 0
    for k in range(lo, hi):
        if upright_roll >= 0 and node_i[k, 1] != upright_roll:
            continue
        x, y, yaw = node_f[k, 0], node_f[k, 1], node_f[k, 2] + turn
        for dy in range(-1, 2):
            for dx in range(-1, 2):
                b = _bucket(x, y, yaw, ox, oy, cell, nx, ny, nyaw, dx, dy)
                if b < 0:
                    continue
                j = _node_of(other_keys, other_nodes, b)
                if j < 0:
                    continue
                d = math.hypot(other_f[j, 0] - x, other_f[j, 1] - y)
                if d > max_len:
                    continue
                dyaw = abs(wrap(other_f[j, 2] + other_turn - yaw))
                cost = node_f[k, 4] + other_f[j, 4] + d + rho * dyaw
                if n < cap:
                    out_a[n], out_b[n], out_cost[n] = k, j, cost
                    if n == 0 or cost > out_cost[worst]:
                        worst = n
                    n += 1
                elif cost < out_cost[worst]:
                    out_a[worst], out_b[worst], out_cost[worst] = k, j, cost
                    worst = 0
                    for m in range(1, cap):
                        if out_cost[m] > out_cost[worst]:
                            worst = m
    return n


@njit_leaf
def find_turn(f_keys: np.ndarray, f_nodes: np.ndarray, b_keys: np.ndarray, b_nodes: np.ndarray,
              f_node_f: np.ndarray, f_node_i: np.ndarray, upright: int, nyaw: int, clear: np.ndarray, ox: float,
              oy: float, res: float, tried: np.ndarray) -> tuple[int, int, int]:
    """Where the forward tree and the goal side roll the same way in opposite directions: the (forward node,
    goal-side node, cell) of the bucket pair in one cell whose forward node is upright and whose heading bin is
    opposite to the goal-side node's (both in the forward frame), in the untried cell (``tried``) with the most
    stored clearance under the forward node, the least bucket index among equals; (-1, -1, -1) when there is
    none."""
    best = -1.0
    best_b = -1
    out_i, out_j, out_cell = -1, -1, -1
    half = nyaw // 2
    for s in range(f_keys.size):
        b = f_keys[s]
        if b == closed_set.EMPTY:
            continue
        i = f_nodes[s]
        if f_node_i[i, 1] != upright:
            continue
        cell = b // nyaw
        if tried[cell]:
            continue
        j = _node_of(b_keys, b_nodes, cell * nyaw + (b % nyaw + half) % nyaw)
        if j < 0:
            continue
        ix = int(math.floor((f_node_f[i, 0] - ox) / res))
        iy = int(math.floor((f_node_f[i, 1] - oy) / res))
        if 0 <= ix < clear.shape[1] and 0 <= iy < clear.shape[0] and (
                clear[iy, ix] > best or (clear[iy, ix] == best and b < best_b)):
            best = clear[iy, ix]
            best_b = b
            out_i, out_j, out_cell = i, j, cell
    return out_i, out_j, out_cell


class Buckets:
    """One tree's buckets: a hash map from bucket index to the cheapest node in it and its g (``keys``, ``nodes``,
    ``gs``), grown (rehashed) so that it is never more than half full."""

    def __init__(self, capacity: int = 1024) -> None:
        self.keys = closed_set.new_table(capacity)
        self.nodes = np.full(self.keys.size, -1, dtype=np.int64)
        self.gs = np.full(self.keys.size, np.inf)
        self.count = 0

    def add(self, node_f: np.ndarray, node_i: np.ndarray, lo: int, hi: int, turn: float, upright_roll: int,
            geo: tuple[float, float, float, int, int, int]) -> None:
        """Put nodes [lo, hi) in (:func:`index_nodes`, ``geo`` its (ox, oy, cell, nx, ny, nyaw)), room made first."""
        self._room_for(hi - lo)
        self.count += index_nodes(node_f, node_i, lo, hi, turn, upright_roll, *geo, self.keys, self.nodes, self.gs)

    def _room_for(self, more: int) -> None:
        """Make room for ``more`` buckets at a load of at most one half."""
        if 2 * (self.count + more) <= self.keys.size:
            return
        keys = closed_set.new_table(self.count + more)
        nodes = np.full(keys.size, -1, dtype=np.int64)
        gs = np.full(keys.size, np.inf)
        rehash(self.keys, self.nodes, self.gs, keys, nodes, gs)
        self.keys, self.nodes, self.gs = keys, nodes, gs

    def node(self, b: int) -> int:
        """The node kept in bucket ``b``, -1 when it holds none."""
        return int(_node_of(self.keys, self.nodes, b))


def warm_up() -> None:
    """Compile (or load from numba's cache) the look-up kernels on a one-node tree, with the argument types of
    :meth:`Meeting.round`, so that no plan's time limit is spent on it (a plan meets only after thousands of
    expansions, never in the search's own warm-up)."""
    node_f, node_i = np.zeros((1, 5)), np.zeros((1, 3), dtype=np.int64)
    tree = Buckets(1)
    geo = (0.0, 0.0, CELL_M, 1, 1, YAW_BINS)
    tree.add(node_f, node_i, 0, 1, math.pi, 0, geo)
    tree.add(node_f, node_i, 0, 1, math.pi, 0, geo)  # (its table of 2 slots is then full: rehash compiled too)
    out_a, out_b, out_cost = np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.int64), np.zeros(1)
    find_pairs(node_f, node_i, 0, 1, 0.0, -1, node_f, math.pi, tree.keys, tree.nodes, *geo, 1.0, MAX_SHOT_M, out_a,
               out_b, out_cost)
    find_turn(tree.keys, tree.nodes, tree.keys, tree.nodes, node_f, node_i, 0, YAW_BINS, np.zeros((1, 1)), 0.0, 0.0,
              1.0, np.zeros(1, dtype=np.bool_))


class Meeting:
    """The bucket tables of both trees and the pairs still to shoot at, for one two-ended search.

    ``forward`` and ``back`` are the two searches (search.py's ``_Search``: ``node_f``, ``node_i``, ``counters``,
    ``p``); :meth:`round` indexes their new nodes, ranks new pairs and shoots at the best untried ones, returning
    the forward node, the goal-side node and the shot's segments when one is free.
    """

    def __init__(self, planner: Any) -> None:
        self.planner = planner
        grid = planner.grid
        self.ox, self.oy = planner.clearance.origin_x, planner.clearance.origin_y
        self.nx = max(1, math.ceil(grid.width * grid.resolution_m / CELL_M))
        self.ny = max(1, math.ceil(grid.height * grid.resolution_m / CELL_M))
        self.forward = Buckets()  # the forward tree's buckets
        self.back = Buckets()  # the goal side's
        self.f_done = 0  # nodes of each tree indexed so far
        self.b_done = 0
        self.pending: list[tuple[float, int, int]] = []
        self.tried: set[tuple[int, int]] = set()
        self.upright = int(planner.options.n_rolls // 2)
        self.out_a = np.zeros(BEST_PER_ROUND, dtype=np.int64)
        self.out_b = np.zeros(BEST_PER_ROUND, dtype=np.int64)
        self.out_cost = np.zeros(BEST_PER_ROUND)
        self.seg_roll, self.seg_curv, self.seg_len = (np.zeros(kernels.MAX_SHOT_SEGS) for _ in range(3))
        self.shots = 0

    def _collect(self, n: int) -> None:
        for m in range(n):
            pair = (int(self.out_a[m]), int(self.out_b[m]))
            if pair not in self.tried:
                heapq.heappush(self.pending, (float(self.out_cost[m]), *pair))

    def round(self, forward: Any, back: Any) -> tuple[int, int, int] | None:
        """Index both trees' new nodes, then shoot at the best untried pairs; (forward node, goal-side node,
        segments written to ``seg_*``) for the first free shot, else None."""
        pl = self.planner
        geo = (self.ox, self.oy, CELL_M, self.nx, self.ny, YAW_BINS)
        f_hi = int(forward.counters[kernels.C_NODES])
        b_hi = int(back.counters[kernels.C_NODES])
        for tree, run, done, hi, turn, upright in ((self.forward, forward, self.f_done, f_hi, 0.0, -1),
                                                   (self.back, back, self.b_done, b_hi, math.pi, self.upright)):
            tree.add(run.node_f, run.node_i, done, hi, turn, upright, geo)
        rho = pl.robot.min_turning_radius_m
        # new forward nodes against the goal side's buckets, new goal-side nodes against the forward ones
        n = find_pairs(forward.node_f, forward.node_i, self.f_done, f_hi, 0.0, -1, back.node_f, math.pi,
                       self.back.keys, self.back.nodes, *geo, rho, MAX_SHOT_M, self.out_a, self.out_b, self.out_cost)
        self._collect(n)
        n = find_pairs(back.node_f, back.node_i, self.b_done, b_hi, math.pi, self.upright, forward.node_f, 0.0,
                       self.forward.keys, self.forward.nodes, *geo, rho, MAX_SHOT_M, self.out_b, self.out_a,
                       self.out_cost)
        self._collect(n)
        self.f_done, self.b_done = f_hi, b_hi
        if len(self.pending) > PENDING_KEPT:
            self.pending = heapq.nsmallest(PENDING_KEPT, self.pending)
            heapq.heapify(self.pending)
        reverse = forward.p[kernels.P_ALLOW_REVERSE] > 0.5
        kinds = (kernels.SHOT_WEIGHTED, kernels.SHOT_SHORTEST) if reverse else (kernels.SHOT_DUBINS,)
        tries = 0
        best: tuple[float, int, int, int] | None = None
        seg = (np.zeros(kernels.MAX_SHOT_SEGS), np.zeros(kernels.MAX_SHOT_SEGS), np.zeros(kernels.MAX_SHOT_SEGS))
        while self.pending and tries < TRIES_PER_ROUND:
            _, i, j = heapq.heappop(self.pending)
            if (i, j) in self.tried:
                continue
            self.tried.add((i, j))
            tries += 1
            x, y, yaw, roll = (float(v) for v in forward.node_f[i, :4])
            bx, by, byaw = (float(v) for v in back.node_f[j, :3])
            for kind in kinds:
                self.shots += 1
                n = kernels.try_shot(pl.clearance.clearance, pl.clearance.blocked, forward.p, pl.footprint.offsets_x,
                                     pl.footprint.offsets_y, pl._px, pl._py, x, y, yaw, roll, bx, by,
                                     wrap(byaw + math.pi), 0.0, *seg, MAX_SHOT_M, 0.0, kind)
                if n > 0:
                    cost = (float(forward.node_f[i, 4]) + float(back.node_f[j, 4])
                            + float(kernels._shot_cost(forward.p, int(forward.node_i[i, 2]), seg[2], n)))
                    if best is None or cost < best[0]:
                        best = (cost, i, j, n)
                        for a, b in zip((self.seg_roll, self.seg_curv, self.seg_len), seg, strict=True):
                            a[:n] = b[:n]
                    break
        return None if best is None else best[1:]


__all__ = ["CELL_M", "YAW_BINS", "Buckets", "Meeting", "find_pairs", "find_turn", "index_nodes", "warm_up"]
