"""The compiled inner loop of the spherical Hybrid A* (see :mod:`planner.hybrid_astar.search` for the algorithm).

Everything here works on preallocated arrays so that numba can compile it; the Python driver in
:mod:`planner.hybrid_astar.search` owns the arrays, checks the deadline and cancellation between chunks, grows the
node storage and turns the result into a path. Status codes returned by :func:`search_chunk`:
RUNNING (chunk finished, call again), FOUND, EXHAUSTED (open list empty), FULL (grow node storage).

:func:`search_chunk` stays one long function on purpose: its body is one expansion (pop, goal test, analytic shot,
children, push) run hundreds of thousands of times, and keeping it in one compiled frame avoids passing the
twenty-odd arrays through a call per stage per expansion. Its stages are marked with numbered comments instead.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from planner.hybrid_astar import closed_set
from planner.hybrid_astar.dubins import WORD_TURNS, dubins_distance, dubins_shortest
from planner.hybrid_astar.heap import heap_pop, heap_push
from planner.hybrid_astar.reeds_shepp import MAX_SEGS as RS_MAX_SEGS
from planner.hybrid_astar.reeds_shepp import MAX_SHOT_M, rs_best, rs_ranked
from planner.jit import njit_leaf
from planner.kinematics import STRAIGHT_EPS, arc_step, roll_shift, roll_shift_cs, wrap
from planner.maps.clearance import circle_margin_at, circles_clear_at, footprint_hits

RUNNING, FOUND, EXHAUSTED, FULL = 0, 1, 2, 3
SHOT_DUBINS, SHOT_WEIGHTED, SHOT_SHORTEST, SHOT_SECOND, SHOT_THIRD = 0, 1, 2, 3, 4  # analytic shot kinds (try_shot)

# counters[] slots
C_NODES, C_EXPANSIONS, C_SINCE_SHOT, C_RESULT, C_SHOT_SEGS, C_BEST, C_TRIED = 0, 1, 2, 3, 4, 5, 6
C_HELD_NODE, C_HELD_SEGS, C_HELD_UNTIL = 7, 8, 9  # a mostly-backwards shot held back (see search_chunk, 3c)
C_FALL_NODE, C_FALL_SEGS, C_FALL_UNTIL = 10, 11, 12  # a shot that keeps less room than asked, kept to fall back on (3d)
C_FELL_BACK = 13  # 1 when the result is that shot
C_FALL_BACKWARDS = 14  # 1 when the shot kept to fall back on makes the path roll mostly backwards
N_COUNTERS = 15
# params[] slots (float64)
(P_OX, P_OY, P_RES, P_RC, P_HOX, P_HOY, P_HCELL, P_RHO, P_GX, P_GY, P_GYAW, P_TOL_XY, P_TOL_YAW, P_RADIUS,
 P_STEP, P_SPACING, P_NON_STRAIGHT, P_CHANGE, P_REVERSE, P_SWITCH, P_COST_PENALTY, P_PROX_RANGE, P_GREED,
 P_SHOT_RATIO, P_MAX_ROLL, P_USE_DUBINS, P_ALLOW_REVERSE, P_N_YAW, P_USE_RS, P_RS_CELL, P_RS_HALF,
 P_PREFERRED, P_REACH, P_BEST_H, P_REJECT, P_CLOSER_H, P_HELD_COST, P_BACK_SHARE, P_BOUND, P_LONG,
 P_GCOS, P_GSIN, P_FALL_WAIT, P_BACK_WAIT, P_HOLD_WAIT, P_CONVEX, P_GENTLE_N, P_ROOT_SHOT, P_CLOSED_CELL,
 P_GENTLE) = range(50)
# P_GCOS, P_GSIN: cos and sin of P_GYAW (for the Reeds–Shepp table's frame); P_FALL_WAIT: expansions a fallback
# shot (3d) waits for one that keeps the room asked, 0 = no fallback shots; P_BACK_WAIT: a fallback shot that rolls
# the path mostly backwards waits this × P_FALL_WAIT, 0 = none is kept; P_HOLD_WAIT: expansions a held-back shot (3c)
# waits for a path that rolls forwards more; P_CONVEX: clearance.convex_turn of the footprint polygon (0, the old
# test, when left unset); P_GENTLE_N: how many turns gentler than ±P_MAX_ROLL at radius P_RHO a shortcut may be
# rolled with instead (:func:`_gentler`), as pairs (radius, roll) from P_GENTLE on, gentlest first; P_ROOT_SHOT: 1 =
# the first node's cheapest Reeds–Shepp shot (SHOT_WEIGHTED) is taken even when it rolls mostly backwards (3c);
# P_CLOSED_CELL: the side (m) of the closed set's square cells, a whole number of map cells
MAX_GENTLE = 4
N_PARAMS = 50 + 2 * MAX_GENTLE
BEST_SHOT_EVERY = 256  # reversing: every this many expansions, a Reeds–Shepp shot from the closest node if new
NEAR_TIE = 1.05  # the second / third cheapest Reeds–Shepp word is shot only within this ratio of the cheapest
MAX_SHOT_SEGS = 6  # a Dubins shot has 3 segments, a Reeds–Shepp shot up to 5
OPEN_MIN_H = 3.0  # long steps in the open only this far (heuristic metres) from the goal
LEAST_KEPT_MARGIN_M = 0.2  # a shortcut (or the search's shot) keeps at least this margin where the stretch it
# replaces (the shot's ends) came closer than the preferred clearance; the preferred clearance when that is less
SHORTCUT_SLACK_M = 0.2  # shortcut: a target is not shot at when the car's Dubins distance is this far over budget


@njit_leaf
def _pose_margin(
    clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray, px: np.ndarray,
    py: np.ndarray, x: float, y: float, yaw: float,
) -> float:
    """:func:`planner.maps.clearance.footprint_margin` (the same value at every pose), with one shortcut: where
    the robot's centre is so close to a blocked cell that the cell meets the disc inscribed in the footprint,
    the pose collides and the exact polygon test is skipped.

    The stored clearance of the centre's cell is d − √2·res (d: its centre to the nearest blocked cell's
    centre), so that blocked cell is at most d + res/√2 from the robot's centre; p[P_REJECT] is
    r_in − (√2 + 1/√2)·res less a micrometre (r_in: the inscribed radius), and a stored clearance below it
    proves the hit.
    """
    return _pose_margin_at(clear, blocked, p, offx, offy, px, py, x, y, yaw, math.cos(yaw), math.sin(yaw))


@njit_leaf
def _pose_margin_at(
    clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray, px: np.ndarray,
    py: np.ndarray, x: float, y: float, yaw: float, c: float, s: float,
) -> float:
    """:func:`_pose_margin` given cos(yaw) = ``c`` and sin(yaw) = ``s`` as well (the same value to the bit): the
    sweeps below compute them once per motion, not once per sample."""
    ox, oy, res = p[P_OX], p[P_OY], p[P_RES]
    m = circle_margin_at(clear, ox, oy, res, x, y, c, s, offx, offy, p[P_RC])
    if m >= 0.0:
        return m
    hit = m if m > -1e9 else -1e9
    ix = int(math.floor((x - ox) / res))
    iy = int(math.floor((y - oy) / res))
    h, w = clear.shape
    if 0 <= ix < w and 0 <= iy < h and clear[iy, ix] < p[P_REJECT]:
        return hit
    if circles_clear_at(clear, ox, oy, res, x, y, c, s, offx, offy, p[P_RC]):
        return 0.0  # (what the polygon test answers there)
    if footprint_hits(blocked, ox, oy, res, x, y, yaw, px, py, int(p[P_CONVEX])):
        return hit
    return 0.0


@njit_leaf
def _shift_margin(
    clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray, px: np.ndarray,
    py: np.ndarray, x: float, y: float, yaw: float, d_roll: float, worst_so_far: float,
) -> float:
    """The roll-change part of :func:`_motion_margin`: the smallest margin while the shell rolls sideways by
    r·``d_roll`` (returns as soon as it is negative)."""
    return _shift_margin_at(clear, blocked, p, offx, offy, px, py, x, y, yaw, math.cos(yaw), math.sin(yaw), d_roll,
                            worst_so_far)


@njit_leaf
def _shift_margin_at(
    clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray, px: np.ndarray,
    py: np.ndarray, x: float, y: float, yaw: float, cy: float, sy: float, d_roll: float, worst_so_far: float,
) -> float:
    """:func:`_shift_margin` given cos(yaw) = ``cy`` and sin(yaw) = ``sy``: the heading does not change during a
    roll change, so no sample computes a sine (the poses are :func:`roll_shift`'s to the bit)."""
    radius, spacing = p[P_RADIUS], p[P_SPACING]
    worst = worst_so_far
    shift = abs(radius * d_roll)
    t = 0.0
    advance = spacing
    while t < shift:
        t = min(shift, t + advance)
        dr = math.copysign(t / radius, d_roll)
        xs, ys = roll_shift_cs(x, y, cy, sy, radius, dr)
        m = _pose_margin_at(clear, blocked, p, offx, offy, px, py, xs, ys, yaw, cy, sy)
        if m < worst:
            worst = m
            if worst < 0.0:
                return worst
        advance = max(spacing, m) if m > 0.0 else 0.5 * spacing
    return worst


@njit_leaf
def _arc_margin(
    clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray, px: np.ndarray,
    py: np.ndarray, x1: float, y1: float, yaw: float, curv: float, s: float, worst_so_far: float,
) -> float:
    """The arc part of :func:`_motion_margin`, from (x1, y1, yaw) after the roll change."""
    return _arc_margin_at(clear, blocked, p, offx, offy, px, py, x1, y1, yaw, math.cos(yaw), math.sin(yaw), curv, s,
                          worst_so_far)


@njit_leaf
def _arc_margin_at(
    clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray, px: np.ndarray,
    py: np.ndarray, x1: float, y1: float, yaw: float, cy: float, sy: float, curv: float, s: float,
    worst_so_far: float,
) -> float:
    """:func:`_arc_margin` given cos(yaw) = ``cy`` and sin(yaw) = ``sy``: a sample on an arc computes the sine and
    cosine of its own heading once (for its position and its circles), one on a straight none; the poses are
    :func:`arc_step`'s to the bit."""
    spacing = p[P_SPACING]
    worst = worst_so_far
    length = abs(s)
    factor = 1.0 + abs(curv) * p[P_REACH]
    straight = abs(curv) < STRAIGHT_EPS
    t = 0.0
    advance = spacing
    while t < length:
        t = min(length, t + advance)
        st = math.copysign(t, s)
        if straight:
            m = _pose_margin_at(clear, blocked, p, offx, offy, px, py, x1 + st * cy, y1 + st * sy, yaw, cy, sy)
        else:
            ya2 = yaw + curv * st
            c2 = math.cos(ya2)
            s2 = math.sin(ya2)
            m = _pose_margin_at(clear, blocked, p, offx, offy, px, py, x1 + (s2 - sy) / curv, y1 - (c2 - cy) / curv,
                                ya2, c2, s2)
        if m < worst:
            worst = m
            if worst < 0.0:
                return worst
        advance = max(spacing, m / factor) if m > 0.0 else 0.5 * spacing
    return worst


@njit_leaf
def _motion_margin(
    clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray, px: np.ndarray,
    py: np.ndarray, x: float, y: float, yaw: float, d_roll: float, curv: float, s: float, worst_so_far: float,
) -> float:
    """Smallest footprint margin (m) along a roll change then an arc (the covering circles' margin, or 0 where
    only the exact polygon fits; negative = collision).

    Poses are sampled at most p[P_SPACING] apart, farther where there is room: with margin m > 0 the circles
    stay clear while their centres move less than m, and a centre moves at most (1 + |κ|·reach) per metre
    travelled (reach = the farthest circle centre from the robot's centre). The start pose itself is not sampled (it
    is the end of the motion before): a motion of length 0 samples nothing and returns ``worst_so_far``; a pose's
    own margin is :func:`_pose_margin`. After a pose where only the exact
    polygon fits (m = 0) the next is half p[P_SPACING] on (a quarter cell, the spacing of the final exact check of a
    path): at half a cell a polygon corner could clip a cell between two samples, and the search then kept motions
    the final check rejects (bays#5 of the seed-1 real-map draw: every path through one such motion, found by the
    goal side after 85 k expansions and by 141 joins after it, was dropped; 372 k expansions, 3.8 s, now 18 k).
    """
    worst = _shift_margin(clear, blocked, p, offx, offy, px, py, x, y, yaw, d_roll, worst_so_far)
    if worst < 0.0:
        return worst
    x1, y1 = roll_shift(x, y, yaw, p[P_RADIUS], d_roll)
    return _arc_margin(clear, blocked, p, offx, offy, px, py, x1, y1, yaw, curv, s, worst)


@njit_leaf
def _travel(p: np.ndarray, length: float, shift: float, curv: float, direction: int, parent_dir: int,
            margin: float) -> float:
    """The search's cost of one motion (eq. 14f with Nav2's terms): its length and sideways shift × proximity (from
    the footprint ``margin``), × the non-straight and reverse multipliers, plus the roll-change and direction-switch
    costs."""
    prox = 0.0
    if p[P_PROX_RANGE] > 0.0:
        prox = max(0.0, 1.0 - margin / p[P_PROX_RANGE])
    travel = (length + shift) * (1.0 + p[P_COST_PENALTY] * prox)
    if abs(curv) > 1e-12:
        travel *= p[P_NON_STRAIGHT]
    if direction < 0:
        travel *= p[P_REVERSE]
    travel += p[P_CHANGE] * shift
    if parent_dir != 0 and parent_dir != direction:
        travel += p[P_SWITCH]
    return travel


@njit_leaf
def _heuristic(htab: np.ndarray, rs: np.ndarray, p: np.ndarray, x: float, y: float, yaw: float) -> float:
    """max(holonomic table, Dubins distance) forward; max(holonomic, Reeds–Shepp table) with reversing."""
    ix = int(math.floor((x - p[P_HOX]) / p[P_HCELL]))
    iy = int(math.floor((y - p[P_HOY]) / p[P_HCELL]))
    hh, hw = htab.shape
    if ix < 0 or iy < 0 or ix >= hw or iy >= hh:
        return math.inf
    h = htab[iy, ix]
    if p[P_USE_DUBINS] > 0.5:
        d = dubins_distance(x, y, yaw, p[P_GX], p[P_GY], p[P_GYAW], p[P_RHO])
        if d > h:
            h = d
    elif p[P_USE_RS] > 0.5:
        # the Reeds–Shepp table is in the goal's frame, ±P_RS_HALF cells of P_RS_CELL around it
        dx = x - p[P_GX]
        dy = y - p[P_GY]
        c = p[P_GCOS]
        s = p[P_GSIN]
        half = p[P_RS_HALF]
        i = int(math.floor((c * dx + s * dy) / p[P_RS_CELL] + half))
        j = int(math.floor((-s * dx + c * dy) / p[P_RS_CELL] + half))
        n_yaw, n_y, n_x = rs.shape
        if 0 <= i < n_x and 0 <= j < n_y:
            k = int(math.floor((wrap(yaw - p[P_GYAW]) + math.pi) / (2.0 * math.pi) * n_yaw))
            d = rs[min(k, n_yaw - 1), j, i]
            if d > h:
                h = d
    return h


@njit_leaf
def _closed_key(p: np.ndarray, w: int, x: float, y: float, yaw: float, rb: int, n_rb: int) -> int:
    ix = int(math.floor((x - p[P_OX]) / p[P_CLOSED_CELL]))
    iy = int(math.floor((y - p[P_OY]) / p[P_CLOSED_CELL]))
    n_yaw = int(p[P_N_YAW])
    a = yaw - 2.0 * math.pi * math.floor(yaw / (2.0 * math.pi))
    yb = int(a / (2.0 * math.pi) * n_yaw) % n_yaw
    return ((iy * w + ix) * n_yaw + yb) * n_rb + rb


@njit(cache=True)
def _shot_word(p: np.ndarray, kind: int, x: float, y: float, yaw: float, tx: float, ty: float,
               gyaw: float, turns: np.ndarray, lens: np.ndarray) -> int:
    """The car's word from (x, y, yaw) to (tx, ty, gyaw): segment turns (+1, 0, −1) and signed lengths (m).
    ``kind`` :data:`SHOT_DUBINS`, :data:`SHOT_WEIGHTED` (the cheapest Reeds–Shepp word under the search's reverse
    and cusp weights), :data:`SHOT_SHORTEST` (the shortest Reeds–Shepp word), :data:`SHOT_SECOND` /
    :data:`SHOT_THIRD` (the second / third cheapest under the weights, if within NEAR_TIE of the cheapest); 0 = none."""
    rho = p[P_RHO]
    if kind == SHOT_WEIGHTED:
        n, _ = rs_best(x, y, yaw, tx, ty, gyaw, rho, p[P_REVERSE], p[P_SWITCH], turns, lens)
        return n
    if kind == SHOT_SHORTEST:
        n, _ = rs_best(x, y, yaw, tx, ty, gyaw, rho, 1.0, 0.0, turns, lens)
        return n
    if kind == SHOT_SECOND or kind == SHOT_THIRD:
        n, _ = rs_ranked(x, y, yaw, tx, ty, gyaw, rho, p[P_REVERSE], p[P_SWITCH], kind - SHOT_WEIGHTED, turns, lens,
                         NEAR_TIE)
        return n
    word, t, pp, q = dubins_shortest(x, y, yaw, tx, ty, gyaw, rho)
    if word < 0:
        return 0
    n = 0
    for k in range(3):
        length = (t, pp, q)[k] * rho
        if length < 1e-9:
            continue
        turns[n] = WORD_TURNS[word, k]
        lens[n] = length
        n += 1
    return n


@njit_leaf
def _rolled_end(x: float, y: float, yaw: float, roll: float, groll: float, turns: np.ndarray, lens: np.ndarray,
                n: int, radius: float, rho: float, max_roll: float) -> tuple[float, float, float]:
    """Where the sphere ends after rolling the word (each arc held at ±φmax, straights upright), then ``groll``."""
    cx, cy, cyaw, croll = x, y, yaw, roll
    for k in range(n):
        r_k = turns[k] * max_roll
        cx, cy = roll_shift(cx, cy, cyaw, radius, r_k - croll)
        cx, cy, cyaw = arc_step(cx, cy, cyaw, turns[k] / rho, lens[k])
        croll = r_k
    cx, cy = roll_shift(cx, cy, cyaw, radius, groll - croll)
    return cx, cy, cyaw


@njit(cache=True)
def _land(x: float, y: float, yaw: float, roll: float, gx: float, gy: float, gyaw: float, groll: float,
          turns: np.ndarray, lens: np.ndarray, n: int, radius: float, rho: float, max_roll: float) -> bool:
    """Solve the word's segment lengths (signs kept, magnitudes ≥ 0) so that the rolled sphere lands on the goal
    (< 0.1 mm, < 1e-4 rad): Gauss–Newton with the least-norm step, the car's lengths as the first guess."""
    jac = np.zeros((3, n))
    res = np.zeros(3)
    sign = np.empty(n)
    for k in range(n):
        sign[k] = 1.0 if lens[k] >= 0.0 else -1.0
    for _ in range(12):
        ex, ey, eyaw = _rolled_end(x, y, yaw, roll, groll, turns, lens, n, radius, rho, max_roll)
        res[0], res[1], res[2] = ex - gx, ey - gy, rho * wrap(eyaw - gyaw)
        if math.hypot(res[0], res[1]) < 1e-4 and abs(res[2]) < 1e-4 * rho:
            return True
        for k in range(n):
            lens[k] += sign[k] * 1e-6
            fx, fy, fyaw = _rolled_end(x, y, yaw, roll, groll, turns, lens, n, radius, rho, max_roll)
            lens[k] -= sign[k] * 1e-6
            jac[0, k], jac[1, k], jac[2, k] = (fx - ex) / 1e-6, (fy - ey) / 1e-6, rho * wrap(fyaw - eyaw) / 1e-6
        # least-norm step jac^T (jac jac^T)^-1 res, the 3×3 solve written out (np.linalg costs seconds of compiling)
        a = np.empty((3, 3))
        for i in range(3):
            for j in range(3):
                acc = 1e-12 if i == j else 0.0
                for k in range(n):
                    acc += jac[i, k] * jac[j, k]
                a[i, j] = acc
        det = (a[0, 0] * (a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]) - a[0, 1] * (a[1, 0] * a[2, 2] - a[1, 2] * a[2, 0])
               + a[0, 2] * (a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]))
        if det == 0.0 or not math.isfinite(det):
            return False
        z0 = (res[0] * (a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]) - a[0, 1] * (res[1] * a[2, 2] - a[1, 2] * res[2])
              + a[0, 2] * (res[1] * a[2, 1] - a[1, 1] * res[2])) / det
        z1 = (a[0, 0] * (res[1] * a[2, 2] - a[1, 2] * res[2]) - res[0] * (a[1, 0] * a[2, 2] - a[1, 2] * a[2, 0])
              + a[0, 2] * (a[1, 0] * res[2] - res[1] * a[2, 0])) / det
        z2 = (a[0, 0] * (a[1, 1] * res[2] - res[1] * a[2, 1]) - a[0, 1] * (a[1, 0] * res[2] - res[1] * a[2, 0])
              + res[0] * (a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0])) / det
        for k in range(n):
            step = jac[0, k] * z0 + jac[1, k] * z1 + jac[2, k] * z2
            lens[k] = sign[k] * max(0.0, abs(lens[k]) - step)
    return False


@njit(cache=True)
def try_shot(
    clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray, px: np.ndarray,
    py: np.ndarray,
    x: float, y: float, yaw: float, roll: float, gx: float, gy: float, gyaw: float, groll: float,
    seg_roll: np.ndarray, seg_curv: np.ndarray, seg_len: np.ndarray, max_len: float, min_margin: float,
    kind: int = 0,
) -> int:
    """Analytic expansion from (x, y, yaw, roll) to (gx, gy, gyaw) arriving with roll ``groll``.

    A Dubins path (forward only, ``kind`` :data:`SHOT_DUBINS`) or a Reeds–Shepp path (the cheapest under the
    search's reverse and cusp weights, :data:`SHOT_WEIGHTED`, or the shortest, :data:`SHOT_SHORTEST`) at the
    minimum radius is turned into roll-held segments (±φmax on arcs, 0 on straights; signed lengths, < 0 rolling
    backwards). Each roll change shifts the centre sideways (eq. 1): a Reeds–Shepp word of three or more segments
    keeps the car's word and has its lengths solved (Gauss–Newton) so that the rolled end lands on the goal;
    otherwise (Dubins, shorter words, or no landing) the car's target is corrected by fixed-point iteration until
    the rolled end lands (< 0.1 mm). Returns the number of segments written, or 0 when no valid shot keeps a
    footprint margin of at least ``min_margin`` (0 = collision-free) and is shorter than ``max_len``.
    """
    return _shot_or_fallback(clear, blocked, p, offx, offy, px, py, x, y, yaw, roll, gx, gy, gyaw, groll, seg_roll,
                             seg_curv, seg_len, max_len, min_margin, kind, False)[0]


@njit(cache=True)
def _shot_or_fallback(
    clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray, px: np.ndarray,
    py: np.ndarray, x: float, y: float, yaw: float, roll: float, gx: float, gy: float, gyaw: float, groll: float,
    seg_roll: np.ndarray, seg_curv: np.ndarray, seg_len: np.ndarray, max_len: float, keep: float, kind: int,
    fall: bool,
) -> tuple[int, bool]:
    """:func:`try_shot` with margin ``keep``: (segments, False) when the shot keeps it; with ``fall``, (segments,
    True) when it is free but keeps less (a fallback, search_chunk 3d, in one sweep that stops only at a collision);
    else (0, False)."""
    n = _shot_segments(p, x, y, yaw, roll, gx, gy, gyaw, groll, seg_roll, seg_curv, seg_len, max_len, math.inf,
                       kind, np.zeros(RS_MAX_SEGS, dtype=np.int64), np.zeros(RS_MAX_SEGS))
    if n <= 0:
        return 0, False
    worst = shot_margin(clear, blocked, p, offx, offy, px, py, x, y, yaw, roll, seg_roll, seg_curv, seg_len, n, groll,
                        0.0 if fall else keep)
    if worst >= keep:
        return n, False
    if fall and worst >= 0.0:
        return n, True
    return 0, False


@njit(cache=True)
def _shot_segments(
    p: np.ndarray, x: float, y: float, yaw: float, roll: float, gx: float, gy: float, gyaw: float, groll: float,
    seg_roll: np.ndarray, seg_curv: np.ndarray, seg_len: np.ndarray, max_len: float, slack: float, kind: int,
    turns: np.ndarray, lens: np.ndarray,
) -> int:
    """The segments of :func:`try_shot`'s shot (its collision check left out), in scratch arrays ``turns`` and
    ``lens`` (RS_MAX_SEGS long): the number written, 0 when no shot lands, −1 when the landed shot is not shorter
    than ``max_len``, or (Dubins) when the car's first word is ``slack`` or more longer than that (its target not
    yet corrected for the roll changes' sideways shifts, which move the rolled shot's length by about a shift)."""
    radius, rho, max_roll = p[P_RADIUS], p[P_RHO], p[P_MAX_ROLL]
    ok = False
    n = 0
    if kind != SHOT_DUBINS:
        n = _shot_word(p, kind, x, y, yaw, gx, gy, gyaw, turns, lens)
        if n == 0:
            return 0
        length = 0.0
        for k in range(n):
            length += abs(lens[k])
        if length >= max_len:  # the car's length is within a few sideways shifts of the sphere's
            return -1
        if 3 <= n <= seg_roll.size and _land(x, y, yaw, roll, gx, gy, gyaw, groll, turns, lens, n, radius, rho,
                                             max_roll):
            for k in range(n):
                seg_roll[k] = turns[k] * max_roll
                seg_curv[k] = turns[k] / rho
                seg_len[k] = lens[k]
            ok = True
    tx, ty = gx, gy
    for it in range(0 if ok else 8):
        # move the car's target until the rolled sphere lands (the word may change on the way)
        n = _shot_word(p, kind, x, y, yaw, tx, ty, gyaw, turns, lens)
        if n == 0 or n > seg_roll.size:
            return 0
        if it == 0 and kind == SHOT_DUBINS:
            car = 0.0
            for k in range(n):
                car += lens[k]
            if car >= max_len + slack:
                return -1
        cx, cy, cyaw, croll = x, y, yaw, roll
        for k in range(n):
            turn = turns[k]
            r_k = turn * max_roll
            seg_roll[k] = r_k
            seg_curv[k] = turn / rho
            seg_len[k] = lens[k]
            cx, cy = roll_shift(cx, cy, cyaw, radius, r_k - croll)
            cx, cy, cyaw = arc_step(cx, cy, cyaw, turn / rho, lens[k])
            croll = r_k
        cx, cy = roll_shift(cx, cy, cyaw, radius, groll - croll)
        ex = cx - gx
        ey = cy - gy
        if ex * ex + ey * ey < 1e-8:  # (within 0.1 mm; squared, as every distance test below: libm's hypot is dear)
            ok = True
            break
        tx -= ex
        ty -= ey
    if not ok or n == 0:
        return 0
    if shot_length(radius, roll, groll, seg_roll, seg_len, n) >= max_len:
        return -1
    return n


@njit_leaf
def shot_margin(
    clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray, px: np.ndarray,
    py: np.ndarray, x: float, y: float, yaw: float, roll: float, seg_roll: np.ndarray, seg_curv: np.ndarray,
    seg_len: np.ndarray, n: int, groll: float, min_margin: float,
) -> float:
    """Smallest footprint margin along ``n`` motions (held roll, curvature, signed length) from (x, y, yaw,
    roll), ending with the roll brought to ``groll``; stops early once it falls below ``min_margin``."""
    radius = p[P_RADIUS]
    cx, cy, cyaw, croll = x, y, yaw, roll
    worst = math.inf
    for k in range(n):
        worst = _motion_margin(clear, blocked, p, offx, offy, px, py, cx, cy, cyaw, seg_roll[k] - croll,
                               seg_curv[k], seg_len[k], worst)
        if worst < min_margin:
            return worst
        cx, cy = roll_shift(cx, cy, cyaw, radius, seg_roll[k] - croll)
        cx, cy, cyaw = arc_step(cx, cy, cyaw, seg_curv[k], seg_len[k])
        croll = seg_roll[k]
    return _motion_margin(clear, blocked, p, offx, offy, px, py, cx, cy, cyaw, groll - croll, 0.0, 0.0, worst)


@njit_leaf
def shot_length(radius: float, roll: float, groll: float, seg_roll: np.ndarray, seg_len: np.ndarray, n: int) -> float:
    """Distance the centre travels along a shot: arcs (forwards or backwards) plus the sideways shifts of its roll
    changes. (Until issue 21's fourteenth round the backward arcs were subtracted: a landed Reeds–Shepp shot of
    −6 310 m and +6 310 m on one circle passed as 0.04 m, under the 10 m cap.)"""
    total = 0.0
    croll = roll
    for k in range(n):
        total += abs(seg_len[k]) + radius * abs(seg_roll[k] - croll)
        croll = seg_roll[k]
    return total + radius * abs(groll - croll)


@njit_leaf
def _probe_margin(
    clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray, px: np.ndarray,
    py: np.ndarray, x: float, y: float, yaw: float, roll: float, seg_roll: np.ndarray, seg_curv: np.ndarray,
    seg_len: np.ndarray, n: int, min_margin: float, scratch: np.ndarray,
) -> float:
    """The smallest footprint margin at five poses of each of the ``n`` motions (at 1/2, 1/4, 3/4, 1/8 and 7/8 of
    its arc, rolled as :func:`shot_margin` rolls them), stopping below ``min_margin``: a few poses that find most
    colliding shots before their sweep does (which samples every P_SPACING near obstacles). A pose found below
    ``min_margin`` rejects the shot even where the sweep's samples, spaced by their margins, would pass over it.

    The poses are visited by fraction first (every motion's middle, then every motion's quarter, ...): a shot that
    cuts a corner usually does so in one of its motions, and that motion's middle is then the second or third pose
    tried rather than up to the eleventh. The poses are the same in any order, and so is the decision.

    ``scratch`` (3, ≥ n) holds the motions' start poses (allocated once by the caller: thousands of probes a plan)."""
    radius = p[P_RADIUS]
    sx = scratch[0]
    sy = scratch[1]
    syaw = scratch[2]
    cx, cy, cyaw, croll = x, y, yaw, roll
    for k in range(n):
        cx, cy = roll_shift(cx, cy, cyaw, radius, seg_roll[k] - croll)
        sx[k], sy[k], syaw[k] = cx, cy, cyaw
        cx, cy, cyaw = arc_step(cx, cy, cyaw, seg_curv[k], seg_len[k])
        croll = seg_roll[k]
    worst = math.inf
    for f in (0.5, 0.25, 0.75, 0.125, 0.875):
        for k in range(n):
            mx, my, myaw = arc_step(sx[k], sy[k], syaw[k], seg_curv[k], f * seg_len[k])
            m = _pose_margin(clear, blocked, p, offx, offy, px, py, mx, my, myaw)
            if m < worst:
                worst = m
                if worst < min_margin:
                    return worst
    return worst


@njit(cache=True)
def _range_min_table(values: np.ndarray) -> np.ndarray:
    """Sparse table of ``values`` for :func:`_range_min`: row r holds the minimum of each run of 2^r values (the
    smoother's smallest knot margin between two knots, looked up for the few shots built, not rebuilt a knot at a
    time: that was O(n) a knot, O(n²) a pass)."""
    n = values.size
    levels = 1
    while (1 << levels) <= n:
        levels += 1
    table = np.empty((levels, max(n, 1)))
    table[0, :n] = values
    for r in range(1, levels):
        half = 1 << (r - 1)
        for k in range(n - (1 << r) + 1):
            table[r, k] = min(table[r - 1, k], table[r - 1, k + half])
    return table


@njit_leaf
def _range_min(table: np.ndarray, i: int, j: int) -> float:
    """The minimum of the values i..j (both included) of :func:`_range_min_table`'s ``table``."""
    r = 0
    while (2 << r) <= j - i + 1:
        r += 1
    return min(table[r, i], table[r, j - (1 << r) + 1])


@njit(cache=True)
def _shortcut_from(
    clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray, px: np.ndarray,
    py: np.ndarray, knots: np.ndarray, cum: np.ndarray, max_tries: int, recheck: int,
    least: np.ndarray, failed_from: np.ndarray, i: int, sr: np.ndarray, sc: np.ndarray, sl: np.ndarray,
    turns: np.ndarray, lens: np.ndarray, counts: np.ndarray, probe: np.ndarray, pg: np.ndarray,
    gr: np.ndarray, gc: np.ndarray, gl: np.ndarray,
) -> tuple[int, int]:
    """:func:`shortcut`'s tries from knot ``i``: the farthest candidate target j reached by a valid, shorter shot
    and the shot's number of segments (in ``sr``, ``sc``, ``sl``), or (−1, 0). ``least`` is
    :func:`_range_min_table` of the knots' margins."""
    n = knots.shape[0]
    stride = max(1, (n - 2 - i) // max_tries)
    x, y, yaw, roll = knots[i, 0], knots[i, 1], knots[i, 2], knots[i, 3]
    j = n - 1
    while j > i + 1:
        budget = cum[j] - cum[i] - 1e-6
        gx, gy, gyaw = knots[j, 0], knots[j, 1], knots[j, 2]
        if budget <= 0.0 or (gx - x) ** 2 + (gy - y) ** 2 >= budget * budget:
            j -= stride
            continue
        if i - failed_from[j] < recheck and (i + j) % recheck != 0:
            counts[2] += 1
            j -= stride
            continue
        counts[0] += 1
        m = _shot_segments(p, x, y, yaw, roll, gx, gy, gyaw, knots[j, 3], sr, sc, sl, budget, SHORTCUT_SLACK_M,
                           SHOT_DUBINS, turns, lens)
        if m < 0:
            counts[1] += 1
        if m > 0:
            stretch = min(p[P_PREFERRED], max(_range_min(least, i, j), LEAST_KEPT_MARGIN_M))
            if _probe_margin(clear, blocked, p, offx, offy, px, py, x, y, yaw, roll, sr, sc, sl, m, stretch,
                             probe) < stretch:
                m = 0
            elif shot_margin(clear, blocked, p, offx, offy, px, py, x, y, yaw, roll, sr, sc, sl, m, knots[j, 3],
                             stretch) >= stretch:
                best = shot_length(p[P_RADIUS], roll, knots[j, 3], sr, sl, m)
                return j, _gentler(clear, blocked, p, pg, offx, offy, px, py, x, y, yaw, roll, knots[j], stretch,
                                   best, sr, sc, sl, m, gr, gc, gl, turns, lens, probe)
        failed_from[j] = i
        j -= stride
    return -1, 0


@njit(cache=True)
def _gentler(
    clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, pg: np.ndarray, offx: np.ndarray, offy: np.ndarray,
    px: np.ndarray, py: np.ndarray, x: float, y: float, yaw: float, roll: float, target: np.ndarray, keep: float,
    best: float, sr: np.ndarray, sc: np.ndarray, sl: np.ndarray, m: int, gr: np.ndarray, gc: np.ndarray,
    gl: np.ndarray, turns: np.ndarray, lens: np.ndarray, probe: np.ndarray,
) -> int:
    """The shortcut's shot to ``target`` (``m`` segments in ``sr``, ``sc``, ``sl``, rolling ``best`` metres) or, when
    shorter, the Dubins shot rolled with a gentler turn (``pg``: :data:`P_RHO` and :data:`P_MAX_ROLL` of each gentler
    pair) that keeps the margin ``keep``, written over them; returns the number of segments. A roll change shifts the
    sphere sideways by radius × the change (eq. 1), so a small turn made at a smaller roll can be the shorter path."""
    radius = p[P_RADIUS]
    for g in range(pg.shape[0]):
        mg = _shot_segments(pg[g], x, y, yaw, roll, target[0], target[1], target[2], target[3], gr, gc, gl, best,
                            SHORTCUT_SLACK_M, SHOT_DUBINS, turns, lens)
        if mg <= 0 or _probe_margin(clear, blocked, p, offx, offy, px, py, x, y, yaw, roll, gr, gc, gl, mg, keep,
                                    probe) < keep:
            continue
        if shot_margin(clear, blocked, p, offx, offy, px, py, x, y, yaw, roll, gr, gc, gl, mg, target[3],
                       keep) < keep:
            continue
        best = shot_length(radius, roll, target[3], gr, gl, mg)
        for k in range(mg):
            sr[k], sc[k], sl[k] = gr[k], gc[k], gl[k]
        m = mg
    return m


@njit(cache=True)
def shortcut(
    clear: np.ndarray, blocked: np.ndarray, p: np.ndarray, offx: np.ndarray, offy: np.ndarray, px: np.ndarray,
    py: np.ndarray, knots: np.ndarray, cum: np.ndarray,
    max_tries: int, recheck: int, out_ij: np.ndarray, out_roll: np.ndarray, out_curv: np.ndarray,
    out_len: np.ndarray, out_n: np.ndarray, counts: np.ndarray,
) -> int:
    """Greedy shortcutting: from knot i, connect to the farthest knot j reachable by a valid, shorter shot.

    knots (n, 4) are poses (x, y, yaw, roll) at motion ends; cum[i] is the distance travelled up to knot i.
    At most ``max_tries`` candidate j are tried per i, from the far end down. A shortcut may not come closer to
    the obstacles than the preferred clearance p[P_PREFERRED], unless the stretch it replaces already did (its
    knots' smallest footprint margin), and never closer than LEAST_KEPT_MARGIN_M. (Until issue 21's fifth round
    the knots' margins were measured with a motion of length 0, which samples no pose: every shortcut had to keep the
    preferred clearance, so none could straighten a stretch through a narrow place.) Returns the number of shortcuts
    written.

    A candidate is dropped before its collision check when the car's Dubins word to it is already
    SHORTCUT_SLACK_M or more over the stretch's length (:func:`_shot_segments`), and a shot is swept only when
    :func:`_probe_margin`'s few poses keep the margin. With ``recheck`` > 1 a target
    whose shot failed from one of the last ``recheck`` knots is tried again only from every ``recheck``-th knot
    ((i + j) % recheck == 0): from the next knot along the path the same shot almost always fails the same way
    (measured: 99 % of 459 000 pairs on the real-map problems), and the stagger still tries each target every
    ``recheck`` knots. When a shortcut is found, the ``recheck`` − 1 knots before it are tried again with every
    candidate, back to the first that finds none, so that a shot that became possible at a skipped knot starts
    there, as with ``recheck`` = 1, which tries every candidate from every knot. ``counts`` (int64, 4) is added
    to: shots built, shots dropped by their length (the Dubins bound or the rolled length), candidates skipped by
    ``recheck``, shortcuts taken.

    The shot to the target taken is then rolled with each gentler turn of the search's held rolls
    (p[P_GENTLE_N], see :func:`_gentler`), and the shortest that keeps the margin is written: the sphere shifts
    sideways at every roll change, so a small turn at a smaller roll is often shorter. (Issue 21, fourteenth round:
    on the 240 real-map problems of seeds 0–3 the total length fell by 0.27 %, at the same plan time.)
    """
    n = knots.shape[0]
    knot_margin = np.empty(n)
    for k in range(n):
        knot_margin[k] = _pose_margin(clear, blocked, p, offx, offy, px, py, knots[k, 0], knots[k, 1], knots[k, 2])
    sr = np.zeros(MAX_SHOT_SEGS)
    sc = np.zeros(MAX_SHOT_SEGS)
    sl = np.zeros(MAX_SHOT_SEGS)
    br = np.zeros(MAX_SHOT_SEGS)
    bc = np.zeros(MAX_SHOT_SEGS)
    bl = np.zeros(MAX_SHOT_SEGS)
    turns = np.zeros(RS_MAX_SEGS, dtype=np.int64)
    lens = np.zeros(RS_MAX_SEGS)
    probe = np.empty((3, MAX_SHOT_SEGS))  # _probe_margin's scratch
    ng = int(p[P_GENTLE_N])  # the gentler turns' parameters, for _gentler
    pg = np.empty((ng, p.size))
    for g in range(ng):
        pg[g] = p
        pg[g, P_RHO] = p[P_GENTLE + 2 * g]
        pg[g, P_MAX_ROLL] = p[P_GENTLE + 2 * g + 1]
    gr = np.zeros(MAX_SHOT_SEGS)
    gc = np.zeros(MAX_SHOT_SEGS)
    gl = np.zeros(MAX_SHOT_SEGS)
    failed_from = np.full(n, -n - recheck, dtype=np.int64)  # failed_from[j]: the last knot whose shot to j failed
    least = _range_min_table(knot_margin)  # the smallest knot margin from knot i to knot j, for any i ≤ j
    count = 0
    i = 0
    first = 0  # the first knot since the last shortcut (knots before it are not tried again)
    while i < n - 2:
        j, m = _shortcut_from(clear, blocked, p, offx, offy, px, py, knots, cum, max_tries, recheck, least,
                              failed_from, i, sr, sc, sl, turns, lens, counts, probe, pg, gr, gc, gl)
        if j < 0:
            i += 1
            continue
        for k in range(m):
            br[k], bc[k], bl[k] = sr[k], sc[k], sl[k]
        if recheck > 1:
            for i2 in range(i - 1, max(first, i - recheck + 1) - 1, -1):
                j2, m2 = _shortcut_from(clear, blocked, p, offx, offy, px, py, knots, cum, max_tries, 1, least,
                                        failed_from, i2, sr, sc, sl, turns, lens, counts, probe, pg, gr, gc, gl)
                if j2 < 0:
                    break
                i, j, m = i2, j2, m2
                for k in range(m):
                    br[k], bc[k], bl[k] = sr[k], sc[k], sl[k]
        out_ij[count, 0] = i
        out_ij[count, 1] = j
        out_n[count] = m
        for k in range(m):
            out_roll[count, k] = br[k]
            out_curv[count, k] = bc[k]
            out_len[count, k] = bl[k]
        count += 1
        counts[3] += 1
        i = j
        first = j
    return count


@njit_leaf
def _backwards(node_f: np.ndarray, node_i: np.ndarray, k: int, step: float, seg_len: np.ndarray, n: int
               ) -> tuple[float, float]:
    """Metres rolled backwards and in all (sideways shifts left out) along the path to node ``k`` and then
    the ``n`` shot segments."""
    back = 0.0
    total = 0.0
    while node_i[k, 0] >= 0:
        total += step * abs(node_i[k, 2])
        if node_i[k, 2] < 0:
            back -= step * node_i[k, 2]
        k = node_i[k, 0]
    for m in range(n):
        total += abs(seg_len[m])
        if seg_len[m] < 0.0:
            back -= seg_len[m]
    return back, total


@njit_leaf
def _shot_cost(p: np.ndarray, parent_dir: int, seg_len: np.ndarray, n: int) -> float:
    """The search's direction-weighted cost of ``n`` shot segments after a motion in direction ``parent_dir``:
    backward metres × reverse multiplier, a switch cost per change of direction."""
    cost = 0.0
    last = 1 if parent_dir > 0 else -1 if parent_dir < 0 else 0
    for m in range(n):
        s = seg_len[m]
        if abs(s) < 1e-12:
            continue
        d = 1 if s > 0.0 else -1
        cost += abs(s) * (p[P_REVERSE] if d < 0 else 1.0)
        if last != 0 and d != last:
            cost += p[P_SWITCH]
        last = d
    return cost


@njit_leaf
def _copy_shot(seg_roll: np.ndarray, seg_curv: np.ndarray, seg_len: np.ndarray, src: int, dst: int, n: int) -> None:
    """Copy ``n`` shot segments from offset ``src`` to offset ``dst`` of the segment arrays (the shot found at 0,
    the held-back one at MAX_SHOT_SEGS, the fallback at 2·MAX_SHOT_SEGS)."""
    for m in range(n):
        seg_roll[dst + m] = seg_roll[src + m]
        seg_curv[dst + m] = seg_curv[src + m]
        seg_len[dst + m] = seg_len[src + m]


@njit_leaf
def take_fallback(counters: np.ndarray, seg_roll: np.ndarray, seg_curv: np.ndarray, seg_len: np.ndarray) -> None:
    """Make the fallback shot (3d) the result."""
    _copy_shot(seg_roll, seg_curv, seg_len, 2 * MAX_SHOT_SEGS, 0, counters[C_FALL_SEGS])
    counters[C_RESULT] = counters[C_FALL_NODE]
    counters[C_SHOT_SEGS] = counters[C_FALL_SEGS]
    counters[C_FALL_SEGS] = 0
    counters[C_FELL_BACK] = 1


@njit_leaf
def _may_fall(counters: np.ndarray, p: np.ndarray, keep: float) -> bool:
    """A shot asked to keep ``keep`` may become the fallback (3d) when it keeps less: fallbacks are on, and none is
    kept yet or the one kept rolls the path mostly backwards (any other replaces it)."""
    return keep > 0.0 and p[P_FALL_WAIT] > 0.0 and (counters[C_FALL_SEGS] == 0 or counters[C_FALL_BACKWARDS] == 1)


@njit_leaf
def _keep_fallback(counters: np.ndarray, p: np.ndarray, k: int, seg_roll: np.ndarray, seg_curv: np.ndarray,
                   seg_len: np.ndarray, n: int, backwards: bool = False) -> None:
    """Keep the ``n`` shot segments from node ``k`` as the fallback (3d), waiting P_FALL_WAIT expansions, or
    P_BACK_WAIT × that many when the shot makes the path roll mostly ``backwards``."""
    counters[C_FALL_NODE] = k
    counters[C_FALL_SEGS] = n
    counters[C_FALL_BACKWARDS] = 1 if backwards else 0
    counters[C_FALL_UNTIL] = counters[C_EXPANSIONS] + int((p[P_BACK_WAIT] if backwards else 1.0) * p[P_FALL_WAIT])
    _copy_shot(seg_roll, seg_curv, seg_len, 0, 2 * MAX_SHOT_SEGS, n)


@njit_leaf
def take_held(counters: np.ndarray, seg_roll: np.ndarray, seg_curv: np.ndarray, seg_len: np.ndarray) -> None:
    """Make the held-back shot (3c) the result."""
    _copy_shot(seg_roll, seg_curv, seg_len, MAX_SHOT_SEGS, 0, counters[C_HELD_SEGS])
    counters[C_RESULT] = counters[C_HELD_NODE]
    counters[C_SHOT_SEGS] = counters[C_HELD_SEGS]
    counters[C_HELD_SEGS] = 0
    counters[C_FELL_BACK] = 0


@njit_leaf
def clear_closed(bits: np.ndarray, p: np.ndarray, w: int, node_f: np.ndarray, node_i: np.ndarray, n_nodes: int,
                 roll_bins: np.ndarray, n_roll_bins: int) -> None:
    """Zero every byte of the bitset ``bits`` that a key of the search's nodes 0 … ``n_nodes`` − 1 falls in:
    :func:`search_chunk` closes only the keys of nodes it popped (1.), and a node's key is its stored pose's, so
    afterwards the whole bitset is zero (:class:`planner.hybrid_astar.closed_set.BitsetPool`)."""
    for k in range(n_nodes):
        key = _closed_key(p, w, node_f[k, 0], node_f[k, 1], node_f[k, 2], roll_bins[node_i[k, 1]], n_roll_bins)
        if 0 <= key >> 3 < bits.size:
            bits[key >> 3] = 0


def child_turns(curvs: np.ndarray, p: np.ndarray) -> np.ndarray:
    """cos (``[0]``) and sin (``[1]``) of every child's heading change in :func:`search_chunk`, rows forward and
    backward one step, then forward and backward P_LONG steps, one column per held roll: a child's heading's cos and
    sin are its parent's turned by these (no trigonometry per child)."""
    long_steps = int(p[P_LONG]) if p[P_LONG] > 1.0 else 1
    s = p[P_STEP] * np.array([1.0, -1.0, long_steps, -long_steps])
    turn = s[:, None] * np.asarray(curvs, dtype=float)[None, :]
    return np.stack([np.cos(turn), np.sin(turn)])


@njit(cache=True)
def search_chunk(
    clear: np.ndarray, blocked: np.ndarray, htab: np.ndarray, rs: np.ndarray, p: np.ndarray, offx: np.ndarray,
    offy: np.ndarray, px: np.ndarray, py: np.ndarray,
    rolls: np.ndarray, curvs: np.ndarray, roll_bins: np.ndarray, n_roll_bins: int,
    node_f: np.ndarray, node_i: np.ndarray,
    heap_keys: np.ndarray, heap_vals: np.ndarray, heap_size: np.ndarray,
    closed: np.ndarray, closed_table: np.ndarray, counters: np.ndarray, max_expansions: int,
    seg_roll: np.ndarray, seg_curv: np.ndarray, seg_len: np.ndarray, turns: np.ndarray,
) -> int:
    """Run up to ``max_expansions`` Hybrid-A* expansions.

    node_f[k] = (x, y, yaw, roll, g); node_i[k] = (parent, roll index, direction ±1 × steps rolled). The closed
    set is the bitset ``closed`` or, when that is empty, the hash set ``closed_table`` (:mod:`closed_set`).
    """
    w = clear.shape[1]
    n_roll = rolls.size
    radius = p[P_RADIUS]
    step = p[P_STEP]
    allow_reverse = p[P_ALLOW_REVERSE] > 0.5
    greed = p[P_GREED]
    goal_pose_margin = _pose_margin(clear, blocked, p, offx, offy, px, py, p[P_GX], p[P_GY], p[P_GYAW])
    c2 = s2 = 0.0
    done = 0
    while done < max_expansions:
        # 1. Pop the cheapest open node; skip it if its (cell, yaw bin, roll) was already expanded. (A shot held
        #    back, 3c, is taken once its wait is over or nothing is left to expand.)
        if counters[C_HELD_SEGS] > 0 and (heap_size[0] == 0 or counters[C_EXPANSIONS] >= counters[C_HELD_UNTIL]):
            take_held(counters, seg_roll, seg_curv, seg_len)
            return FOUND
        if counters[C_FALL_SEGS] > 0 and (heap_size[0] == 0 or counters[C_EXPANSIONS] >= counters[C_FALL_UNTIL]):
            take_fallback(counters, seg_roll, seg_curv, seg_len)  # (3d)
            return FOUND
        if heap_size[0] == 0:
            return EXHAUSTED
        if counters[C_NODES] + 2 * n_roll >= node_f.shape[0] or heap_size[0] + 2 * n_roll >= heap_keys.size:
            return FULL
        _, k = heap_pop(heap_keys, heap_vals, heap_size)
        x, y, yaw, roll, g = node_f[k, 0], node_f[k, 1], node_f[k, 2], node_f[k, 3], node_f[k, 4]
        key = _closed_key(p, w, x, y, yaw, roll_bins[node_i[k, 1]], n_roll_bins)
        if closed_set.is_closed(closed, closed_table, key):
            continue
        if node_i[k, 0] >= 0:
            # 1b. Lazy sweep: a child was checked only at its end pose when it was pushed (and costed with that
            #     pose's margin); its motion from the parent is swept now that it is the cheapest open node (about
            #     six children are pushed per expansion and most are never popped, so most sweeps are never needed).
            #     A motion that collides is dropped without closing its key: another motion may still reach that
            #     state; one dearer than its estimate is pushed again with its true cost.
            par = node_i[k, 0]
            pyaw = node_f[par, 2]
            cp = math.cos(pyaw)
            sp = math.sin(pyaw)
            d_roll = roll - node_f[par, 3]
            mk = _shift_margin_at(clear, blocked, p, offx, offy, px, py, node_f[par, 0], node_f[par, 1], pyaw, cp, sp,
                                  d_roll, math.inf)
            if mk >= 0.0:
                mk = _arc_margin_at(clear, blocked, p, offx, offy, px, py, node_f[par, 0] - radius * d_roll * sp,
                                    node_f[par, 1] + radius * d_roll * cp, pyaw, cp, sp, curvs[node_i[k, 1]],
                                    step * node_i[k, 2], mk)
            if mk < 0.0:
                continue
            # The motion's true cost: its proximity term from the sweep's least margin, as an eager sweep charges it
            # (the child was pushed with its end pose's margin, which is never below it, so the estimate is a lower
            # bound). When it is dearer, the node goes back into the open list with its true cost.
            steps = node_i[k, 2]
            pdir = 1 if node_i[par, 2] > 0 else -1 if node_i[par, 2] < 0 else 0
            true_g = node_f[par, 4] + _travel(p, step * abs(steps), abs(radius * d_roll), curvs[node_i[k, 1]],
                                              1 if steps > 0 else -1, pdir, mk)
            if true_g > g + 1e-9:
                node_f[k, 4] = true_g
                h_true = _heuristic(htab, rs, p, x, y, yaw)
                if true_g + h_true <= p[P_BOUND]:
                    heap_push(heap_keys, heap_vals, heap_size, true_g + h_true * (1.0 + greed), k)
                continue
        closed_set.close(closed, closed_table, key)
        done += 1
        counters[C_EXPANSIONS] += 1
        c_yaw = math.cos(yaw)
        s_yaw = math.sin(yaw)
        # 2. Goal test: bring the roll back to 0 (a sideways shift) and compare with the goal pose.
        gx, gy = roll_shift_cs(x, y, c_yaw, s_yaw, radius, -roll)
        if ((gx - p[P_GX]) ** 2 + (gy - p[P_GY]) ** 2 <= p[P_TOL_XY] * p[P_TOL_XY]
                and abs(wrap(yaw - p[P_GYAW])) <= p[P_TOL_YAW]
                and _motion_margin(clear, blocked, p, offx, offy, px, py, x, y, yaw, -roll, 0.0, 0.0, math.inf) >= 0.0):
            counters[C_RESULT] = k
            counters[C_SHOT_SEGS] = 0
            return FOUND
        # 3. Analytic expansion every N expansions, N shrinking as the goal gets closer (Nav2's rule).
        h_here = _heuristic(htab, rs, p, x, y, yaw)
        if h_here < p[P_BEST_H]:  # the closest node so far (3b shoots from it)
            p[P_BEST_H] = h_here
            counters[C_BEST] = k
        counters[C_SINCE_SHOT] += 1
        if counters[C_SINCE_SHOT] >= max(1, int(h_here / p[P_SHOT_RATIO])):
            counters[C_SINCE_SHOT] = 0
            # forward-only: the Dubins shot is optimal, take it; with reversing a forward shot may be far
            # longer than a manoeuvre with a reverse leg, so take it only when it is within 2× of h
            # the shot keeps the preferred clearance where its two ends have it, else as much as they have but at
            # least LEAST_KEPT_MARGIN_M (their pose margins: a motion of length 0 samples no pose, and measured so the
            # ends never limited the shot until issue 21's fifth round; without the floor a goal 3 cm from a wall let a
            # shot graze every wall on its way, maze_across 33.8 -> 36.3 m)
            here = _pose_margin(clear, blocked, p, offx, offy, px, py, x, y, yaw)
            keep = max(0.0, min(p[P_PREFERRED], max(LEAST_KEPT_MARGIN_M, min(here, goal_pose_margin))))
            # 3d. A shot that is free but keeps less than ``keep`` is kept to fall back on (the first one): the search
            #     goes on for P_FALL_WAIT expansions for a shot that keeps it and takes the fallback when it finds none
            #     (1.), not the thousands of expansions that finding one can take in a tight map, often for a path that
            #     then passes as close elsewhere (issue 21's ninth round: smoothers_world#7 of seed 0, 6 136 -> 468).
            #     A Reeds–Shepp fallback that makes the path roll mostly backwards (3b) waits P_BACK_WAIT × as long,
            #     gives way to any other fallback and to a held shot (3c, which keeps the room), and is not kept while
            #     a shot is held (tenth round: pockets#5 of seed 1, 3 901 -> 1 702 expansions, 9.71 -> 8.63 m)
            n, short = _shot_or_fallback(clear, blocked, p, offx, offy, px, py, x, y, yaw, roll, p[P_GX], p[P_GY],
                                         p[P_GYAW], 0.0, seg_roll, seg_curv, seg_len,
                                         2.0 * h_here + 1e-6 if allow_reverse else math.inf, keep, SHOT_DUBINS,
                                         _may_fall(counters, p, keep))
            if short:
                _keep_fallback(counters, p, k, seg_roll, seg_curv, seg_len, n)
            elif n > 0:
                counters[C_RESULT] = k
                counters[C_SHOT_SEGS] = n
                return FOUND
        src = -1
        if (allow_reverse and h_here < 0.9 * p[P_CLOSER_H]
                and (x - p[P_GX]) ** 2 + (y - p[P_GY]) ** 2 < MAX_SHOT_M * MAX_SHOT_M):
            # 3b. Reeds–Shepp (reversing), from each node a tenth closer to the goal (by h) than the last one shot
            #     from (the start first) ...
            p[P_CLOSER_H] = h_here
            src = k
        elif allow_reverse and counters[C_EXPANSIONS] % BEST_SHOT_EVERY == 0 and counters[C_BEST] != counters[C_TRIED]:
            # ... and every BEST_SHOT_EVERY expansions from the closest node so far when it is a new one
            src = counters[C_BEST]
        if src >= 0:
            # the cheapest word under the search's reverse and cusp weights, else the shortest, else the second and
            # third cheapest (mirror-image words of nearly the same cost sweep other ground), up to MAX_SHOT_M
            counters[C_TRIED] = src
            sx, sy, syaw, sroll = node_f[src, 0], node_f[src, 1], node_f[src, 2], node_f[src, 3]
            # (the footprint margins of both ends themselves: a motion of length 0 samples no pose)
            here = _pose_margin(clear, blocked, p, offx, offy, px, py, sx, sy, syaw)
            keep = max(0.0, min(p[P_PREFERRED], here, goal_pose_margin))
            n = 0
            took = -1
            for kind in (SHOT_WEIGHTED, SHOT_SHORTEST, SHOT_SECOND, SHOT_THIRD):
                took = kind
                n, short = _shot_or_fallback(clear, blocked, p, offx, offy, px, py, sx, sy, syaw, sroll, p[P_GX],
                                             p[P_GY], p[P_GYAW], 0.0, seg_roll, seg_curv, seg_len, MAX_SHOT_M, keep,
                                             kind, _may_fall(counters, p, keep))
                if short:
                    back, total = _backwards(node_f, node_i, src, step, seg_len, n)
                    if back <= p[P_BACK_SHARE] * total:
                        _keep_fallback(counters, p, src, seg_roll, seg_curv, seg_len, n)  # 3d
                    elif p[P_BACK_WAIT] > 0.0 and counters[C_FALL_SEGS] == 0 and counters[C_HELD_SEGS] == 0:
                        _keep_fallback(counters, p, src, seg_roll, seg_curv, seg_len, n, True)
                    n = 0
                if n > 0:
                    break
            if n > 0:
                back, total = _backwards(node_f, node_i, src, step, seg_len, n)
                # (a shot from the start itself, P_ROOT_SHOT, by the word cheapest under the search's weights is the
                # cheapest path in free space by the measure a path that turns round would have to beat: none can,
                # so it is not held, however far it rolls backwards; issue 21's eighteenth round, depot#1 of seed 1:
                # 634 expansions -> 1, the same path)
                if back <= p[P_BACK_SHARE] * total or (p[P_ROOT_SHOT] > 0.5 and node_i[src, 0] < 0
                                                       and took == SHOT_WEIGHTED):
                    counters[C_RESULT] = src
                    counters[C_SHOT_SEGS] = n
                    return FOUND
                # 3c. A shot that would make the path roll mostly backwards is held back: the search goes on for
                #     P_HOLD_WAIT more expansions looking for a path that turns round,
                #     and takes the cheapest held shot when it finds none (or runs dry). (When it finds one, the plan
                #     keeps the held shot instead if that costs less: search.py, HybridAStar._plan.)
                cost = node_f[src, 4] + _shot_cost(p, node_i[src, 2], seg_len, n)
                if cost < p[P_HELD_COST]:
                    if counters[C_FALL_BACKWARDS]:  # a held shot keeps the room a mostly-backwards fallback does not
                        counters[C_FALL_SEGS] = 0
                        counters[C_FALL_BACKWARDS] = 0
                    p[P_HELD_COST] = cost
                    counters[C_HELD_NODE] = src
                    counters[C_HELD_SEGS] = n
                    _copy_shot(seg_roll, seg_curv, seg_len, 0, MAX_SHOT_SEGS, n)
                    if counters[C_HELD_UNTIL] == 0:
                        counters[C_HELD_UNTIL] = counters[C_EXPANSIONS] + int(p[P_HOLD_WAIT])
        # 4. Expand: every held roll, forward (and reverse), one exact step of eq. 1.
        #    In the open (the stored clearance of the node's cell exceeds the covering circles' reach and radius,
        #    the longest sideways shift and P_LONG steps: the circles stay clear wherever the child goes) and over
        #    OPEN_MIN_H from the goal, a child rolls P_LONG steps at once (item 3 of issue 21: fewer expansions where
        #    there is room); its sweep is checked as any.
        #    node_i[., 2] then holds direction × steps.
        #    The parent's heading's sine and cosine are computed once (at the goal test, 2.): a child's are them turned
        #    by its primitive's heading change (``turns``, child_turns), so no child computes a sine, cosine or atan2;
        #    its pose is arc_step's to rounding and its heading is wrap()ped by whole turns.
        parent_dir = 1 if node_i[k, 2] > 0 else -1 if node_i[k, 2] < 0 else 0
        mult = 1
        if p[P_LONG] > 1.0 and h_here > OPEN_MIN_H:
            nix = int(math.floor((x - p[P_OX]) / p[P_RES]))
            niy = int(math.floor((y - p[P_OY]) / p[P_RES]))
            if (0 <= nix < w and 0 <= niy < clear.shape[0]
                    and clear[niy, nix] >= p[P_REACH] + p[P_RC] + p[P_LONG] * step + 2.0 * radius * p[P_MAX_ROLL]):
                mult = int(p[P_LONG])
        straight_yaw = wrap(yaw)
        row0 = 2 if mult > 1 else 0
        for d in range(2):
            direction = 1 if d == 0 else -1
            if direction < 0 and not allow_reverse:
                break
            s_child = direction * step * mult
            for ri in range(n_roll):
                d_roll = rolls[ri] - roll
                x1 = x - radius * d_roll * s_yaw
                y1 = y + radius * d_roll * c_yaw
                curv = curvs[ri]
                if abs(curv) < STRAIGHT_EPS:
                    cx = x1 + s_child * c_yaw
                    cy = y1 + s_child * s_yaw
                    cyaw = straight_yaw
                    c2, s2 = c_yaw, s_yaw
                else:
                    tc = turns[0, row0 + d, ri]
                    ts = turns[1, row0 + d, ri]
                    c2 = c_yaw * tc - s_yaw * ts
                    s2 = s_yaw * tc + c_yaw * ts
                    cx = x1 + (s2 - s_yaw) / curv
                    cy = y1 - (c2 - c_yaw) / curv
                    cyaw = wrap(yaw + curv * s_child)
                # a child already expanded is dropped before its (far dearer) collision sweep
                ckey = _closed_key(p, w, cx, cy, cyaw, roll_bins[ri], n_roll_bins)
                if closed_set.is_closed(closed, closed_table, ckey):
                    continue
                # only the end pose now, and its margin for the proximity cost: the motion is swept (and its cost
                # corrected) when the child is popped (1b)
                margin = _pose_margin_at(clear, blocked, p, offx, offy, px, py, cx, cy, cyaw, c2, s2)
                if margin < 0.0:
                    continue
                h = _heuristic(htab, rs, p, cx, cy, cyaw)
                if not math.isfinite(h):
                    continue
                # 5. Travel cost (eq. 14f with Nav2's cost terms), 1b charges the same with the sweep's margin
                cg = g + _travel(p, step * mult, abs(radius * d_roll), curvs[ri], direction, parent_dir, margin)
                if cg + h > p[P_BOUND]:  # no cheaper than a path already known (h never exceeds the cost-to-go)
                    continue
                c = counters[C_NODES]
                node_f[c, 0] = cx
                node_f[c, 1] = cy
                node_f[c, 2] = cyaw
                node_f[c, 3] = rolls[ri]
                node_f[c, 4] = cg
                node_i[c, 0] = k
                node_i[c, 1] = ri
                node_i[c, 2] = direction * mult
                counters[C_NODES] = c + 1
                heap_push(heap_keys, heap_vals, heap_size, cg + h * (1.0 + greed), c)
    return RUNNING
