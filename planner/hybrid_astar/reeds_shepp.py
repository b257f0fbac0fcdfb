"""Reeds–Shepp paths and analytic expansions for reversing spheres (paper 001 §4.1's analytic expansion, with
reverse).

**Compiled words** (used by the search's analytic shots, :func:`planner.hybrid_astar.kernels.try_shot`). A
Reeds–Shepp path joins two poses with at most five segments — arcs of the minimum turning radius ρ and
straights, each rolled forwards or backwards. Reeds & Shepp (1990, formulas 8.1–8.11) give eight base families in
closed form for a goal (x, y, φ) seen from the start (lengths in units of ρ); every other word follows from three
symmetries: *time-flip* (x, y, φ) → (−x, y, −φ) negates every length, *reflection* (x, y, φ) → (x, −y, −φ) swaps
left and right, and *backwards* (reading the path from the goal) turns the goal into
(x cos φ + y sin φ, x sin φ − y cos φ, φ) and reverses the segment order. That gives the :data:`MAX_WORDS`
candidates covering Reeds & Shepp's 48 words (:func:`rs_words`). :func:`rs_best` returns the cheapest under the
planner's direction weights (backward metres × ``reverse_penalty``, ``switch_cost_m`` per cusp; the forward-only
Dubins word is a candidate too, since under weights rolling forwards all the way round can be cheapest); with
weights (1, 0) it is the classic shortest path and :func:`rs_distance` equals OMPL's ``ReedsSheppStateSpace``
distance (tested to 1e-6).

**OMPL reference** (:func:`car_word`, :func:`sphere_shot`, kept as the independent check of the compiled shots):

OMPL's ``ReedsSheppStateSpace`` gives the shortest car path with cusps between two poses at a turning radius
ρ; its Python bindings expose only ``distance`` and ``interpolate``. The path's *word* — its turning
segments (left, straight, right) and their directions — is read off densely interpolated states; then
the segments' lengths are solved so that the *sphere* lands on the goal: every segment holds a roll
(±φmax on arcs, 0 on straights) and each roll change rolls the shell sideways by r·Δφ (eq. 1), which a
car does not do. The result is a list of (held roll, curvature, signed arc length) motions, the form the
search and its smoother use.
"""

from __future__ import annotations

import math
import sys
from functools import lru_cache
from typing import Any

import numpy as np
from numba import njit
from scipy.optimize import least_squares

from planner.hybrid_astar.dubins import WORD_TURNS, dubins_shortest
from planner.jit import njit_leaf
from planner.kinematics import arc_step, roll_shift, wrap

SAMPLE_M = 0.01  # spacing of the interpolated states the word is read from
MAX_SHOT_M = 10.0  # longer Reeds–Shepp shots are not tried (Nav2 Smac caps its analytic expansions too)
LAND_TOL_M = 1e-4  # the rolled end must land this close to the goal (and within 1e-4 rad of its heading)
MAX_WORDS = 44  # 8 base families × (time-flip, reflection), three of them also read backwards
MAX_SEGS = 5
_ZERO = 10.0 * sys.float_info.epsilon
_HALF_PI = 0.5 * math.pi

# Base families (Reeds & Shepp 1990): the turn of each segment; unused slots are 2.
FAMILY_TURNS = np.array([
    [1, 0, 1, 2, 2],      # 8.1  L+ S+ L+
    [1, 0, -1, 2, 2],     # 8.2  L+ S+ R+
    [1, -1, 1, 2, 2],     # 8.3  L+ R- L
    [1, -1, 1, -1, 2],    # 8.7  L+ R+u L-u R-
    [1, -1, 1, -1, 2],    # 8.8  L+ R-u L-u R+
    [1, -1, 0, 1, 2],     # 8.9  L+ R-π/2 S- L-
    [1, -1, 0, -1, 2],    # 8.10 L+ R-π/2 S- R-
    [1, -1, 0, 1, -1],    # 8.11 L+ R-π/2 S L-π/2 R+
], dtype=np.int64)
N_FAMILIES = FAMILY_TURNS.shape[0]
FAMILY_SEGS = np.array([3, 3, 3, 4, 4, 4, 4, 5], dtype=np.int64)
# read backwards, CSC, CCCC and CCSCC give words their time-flips and reflections already give
FAMILY_BACKWARDS = np.array([0, 0, 1, 0, 0, 1, 1, 0], dtype=np.int64)


@njit_leaf
def _angle(a: float) -> float:
    """``a`` wrapped to [−π, π)."""
    return a - 2.0 * math.pi * math.floor(a / (2.0 * math.pi) + 0.5)


@njit_leaf
def _tau_omega(u: float, v: float, xi: float, eta: float, phi: float) -> tuple[float, float]:
    """The first and last arc of the CCCC families (Reeds & Shepp's τ and ω)."""
    delta = _angle(u - v)
    a = math.sin(u) - math.sin(delta)
    b = math.cos(u) - math.cos(delta) - 1.0
    t1 = math.atan2(eta * a - xi * b, xi * a + eta * b)
    t2 = 2.0 * (math.cos(delta) - math.cos(v) - math.cos(u)) + 3.0
    tau = _angle(t1 + math.pi) if t2 < 0.0 else _angle(t1)
    return tau, _angle(tau - u + v - phi)


@njit_leaf
def _family(f: int, x: float, y: float, phi: float, out: np.ndarray) -> bool:
    """Base family ``f`` from the origin (heading 0) to (x, y, φ) in units of ρ: writes its segment lengths
    into ``out`` and returns whether that family has a solution there."""
    sp, cp = math.sin(phi), math.cos(phi)
    if f == 0 or f == 2 or f == 5:
        xi, eta = x - sp, y - 1.0 + cp
    else:
        xi, eta = x + sp, y - 1.0 - cp
    rho = math.hypot(xi, eta)
    theta = math.atan2(eta, xi)
    if f == 0:  # L+ S+ L+
        t, u = theta, rho
        v = _angle(phi - t)
        out[0], out[1], out[2] = t, u, v
        return t >= -_ZERO and v >= -_ZERO
    if f == 1:  # L+ S+ R+
        if rho * rho < 4.0:
            return False
        u = math.sqrt(rho * rho - 4.0)
        t = _angle(theta + math.atan2(2.0, u))
        v = _angle(t - phi)
        out[0], out[1], out[2] = t, u, v
        return t >= -_ZERO and v >= -_ZERO
    if f == 2:  # L+ R- L
        if rho > 4.0:
            return False
        u = -2.0 * math.asin(0.25 * rho)
        t = _angle(theta + 0.5 * u + math.pi)
        v = _angle(phi - t + u)
        out[0], out[1], out[2] = t, u, v
        return t >= -_ZERO and u <= _ZERO
    if f == 3:  # L+ R+u L-u R-
        r = 0.25 * (2.0 + rho)
        if r > 1.0:
            return False
        u = math.acos(r)
        t, v = _tau_omega(u, -u, xi, eta, phi)
        out[0], out[1], out[2], out[3] = t, u, -u, v
        return t >= -_ZERO and v <= _ZERO
    if f == 4:  # L+ R-u L-u R+
        r = (20.0 - rho * rho) / 16.0
        if r < 0.0 or r > 1.0:
            return False
        u = -math.acos(r)
        if u < -_HALF_PI:
            return False
        t, v = _tau_omega(u, u, xi, eta, phi)
        out[0], out[1], out[2], out[3] = t, u, u, v
        return t >= -_ZERO and v >= -_ZERO
    if f == 5:  # L+ R-π/2 S- L-
        if rho < 2.0:
            return False
        r = math.sqrt(rho * rho - 4.0)
        u = 2.0 - r
        t = _angle(theta + math.atan2(r, -2.0))
        v = _angle(phi - _HALF_PI - t)
        out[0], out[1], out[2], out[3] = t, -_HALF_PI, u, v
        return t >= -_ZERO and u <= _ZERO and v <= _ZERO
    if f == 6:  # L+ R-π/2 S- R-
        rho2 = math.hypot(-eta, xi)
        if rho2 < 2.0:
            return False
        t = math.atan2(xi, -eta)
        u = 2.0 - rho2
        v = _angle(t + _HALF_PI - phi)
        out[0], out[1], out[2], out[3] = t, -_HALF_PI, u, v
        return t >= -_ZERO and u <= _ZERO and v <= _ZERO
    # f == 7: L+ R-π/2 S- L-π/2 R+
    if rho < 2.0:
        return False
    u = 4.0 - math.sqrt(rho * rho - 4.0)
    if u > _ZERO:
        return False
    t = _angle(math.atan2((4.0 - u) * xi - 2.0 * eta, -2.0 * xi + (u - 4.0) * eta))
    v = _angle(t - phi)
    out[0], out[1], out[2], out[3], out[4] = t, -_HALF_PI, u, -_HALF_PI, v
    return t >= -_ZERO and v >= -_ZERO


@njit_leaf
def _variant(back: int, flip: int, mirror: int, x: float, y: float, phi: float, xb: float, yb: float
             ) -> tuple[float, float, float]:
    """The goal a symmetric variant solves its base family for."""
    gx, gy = (xb, yb) if back else (x, y)
    return (-gx if flip else gx), (-gy if mirror else gy), (-phi if flip != mirror else phi)


@njit(cache=True)
def rs_words(x: float, y: float, phi: float, turns: np.ndarray, lens: np.ndarray) -> int:
    """Every Reeds–Shepp candidate from the origin (heading 0) to (x, y, φ), all in units of ρ.

    Writes up to :data:`MAX_WORDS` rows: ``turns[k, :]`` (+1 left, −1 right, 0 straight, 2 unused) and
    ``lens[k, :]`` (signed, < 0 backwards; 0 in unused slots). Returns the number of rows written.
    """
    n = 0
    base = np.zeros(MAX_SEGS)
    xb = x * math.cos(phi) + y * math.sin(phi)
    yb = x * math.sin(phi) - y * math.cos(phi)
    for f in range(N_FAMILIES):
        m = FAMILY_SEGS[f]
        for back in range(1 + FAMILY_BACKWARDS[f]):
            for flip in range(2):
                for mirror in range(2):
                    px, py, pphi = _variant(back, flip, mirror, x, y, phi, xb, yb)
                    base[:] = 0.0
                    if not _family(f, px, py, pphi, base):
                        continue
                    for s in range(MAX_SEGS):
                        turns[n, s] = 2
                        lens[n, s] = 0.0
                    for s in range(m):
                        d = m - 1 - s if back else s
                        turn = FAMILY_TURNS[f, s]
                        turns[n, d] = -turn if mirror else turn
                        lens[n, d] = -base[s] if flip else base[s]
                    n += 1
    return n


@njit_leaf
def word_cost(lens: np.ndarray, rho: float, reverse_penalty: float, switch_cost: float) -> float:
    """Weighted cost (m) of one word (lengths in units of ρ): forward metres + ``reverse_penalty`` × backward
    metres + ``switch_cost`` per change of direction between consecutive non-empty segments."""
    cost = 0.0
    last = 0
    for s in range(lens.size):
        length = lens[s]
        if abs(length) < 1e-12:
            continue
        d = 1 if length > 0 else -1
        cost += rho * abs(length) * (reverse_penalty if d < 0 else 1.0)
        if last != 0 and d != last:
            cost += switch_cost
        last = d
    return cost


@njit_leaf
def _local(x0: float, y0: float, yaw0: float, x1: float, y1: float, yaw1: float, rho: float
           ) -> tuple[float, float, float]:
    """The goal in the start's frame, in units of ρ."""
    dx, dy = x1 - x0, y1 - y0
    c, s = math.cos(yaw0), math.sin(yaw0)
    return (c * dx + s * dy) / rho, (-s * dx + c * dy) / rho, yaw1 - yaw0


@njit_leaf
def _write_word(turns: np.ndarray, lens: np.ndarray, rho: float, seg_turn: np.ndarray, seg_len: np.ndarray) -> int:
    """Write one word's non-empty segments (turn +1/0/−1, signed length in units of ``rho``) into ``seg_turn``
    and ``seg_len`` (metres); returns how many."""
    m = 0
    for s in range(MAX_SEGS):
        if turns[s] != 2 and abs(lens[s]) > 1e-12:
            seg_turn[m] = turns[s]
            seg_len[m] = lens[s] * rho
            m += 1
    return m


@njit(cache=True)
def rs_ranked(x0: float, y0: float, yaw0: float, x1: float, y1: float, yaw1: float, rho: float,
              reverse_penalty: float, switch_cost: float, rank: int, seg_turn: np.ndarray, seg_len: np.ndarray,
              max_ratio: float = math.inf) -> tuple[int, float]:
    """The ``rank``-th cheapest candidate word (0 = the cheapest) under the weights, the forward-only Dubins word
    among them, written like :func:`rs_best`; (0, inf) when there are not that many or it costs more than
    ``max_ratio`` × the cheapest. Near-ties (mirror-image words of almost the same cost) make the second and third
    cheapest worth a shot when the first collides."""
    x, y, phi = _local(x0, y0, yaw0, x1, y1, yaw1, rho)
    turns = np.full((MAX_WORDS + 1, MAX_SEGS), 2, dtype=np.int64)
    lens = np.zeros((MAX_WORDS + 1, MAX_SEGS))
    n = rs_words(x, y, phi, turns, lens)
    word, t, p, q = dubins_shortest(0.0, 0.0, 0.0, x, y, phi, 1.0)
    if word >= 0:
        for s in range(MAX_SEGS):
            turns[n, s] = WORD_TURNS[word, s] if s < 3 else 2
            lens[n, s] = (t, p, q)[s] if s < 3 else 0.0
        n += 1
    if rank >= n:
        return 0, math.inf
    costs = np.empty(n)
    for k in range(n):
        costs[k] = word_cost(lens[k], rho, reverse_penalty, switch_cost)
    order = np.argsort(costs, kind="mergesort")
    best_k = order[rank]
    if costs[best_k] > max_ratio * costs[order[0]]:
        return 0, math.inf
    return _write_word(turns[best_k], lens[best_k], rho, seg_turn, seg_len), costs[best_k]


@njit(cache=True)
def rs_best(x0: float, y0: float, yaw0: float, x1: float, y1: float, yaw1: float, rho: float,
            reverse_penalty: float, switch_cost: float, seg_turn: np.ndarray, seg_len: np.ndarray
            ) -> tuple[int, float]:
    """The cheapest Reeds–Shepp word from (x0, y0, yaw0) to (x1, y1, yaw1) under the weights.

    Writes its non-empty segments into ``seg_turn`` (+1, 0, −1) and ``seg_len`` (signed metres) and returns
    (number of segments, weighted cost in m); (0, inf) when there is none (never for distinct poses). The
    forward-only Dubins word counts as a candidate (see the module docstring)."""
    x, y, phi = _local(x0, y0, yaw0, x1, y1, yaw1, rho)
    turns = np.empty((MAX_WORDS, MAX_SEGS), dtype=np.int64)
    lens = np.empty((MAX_WORDS, MAX_SEGS))
    n = rs_words(x, y, phi, turns, lens)
    best, best_k = math.inf, -1
    for k in range(n):
        c = word_cost(lens[k], rho, reverse_penalty, switch_cost)
        if c < best:
            best, best_k = c, k
    word, t, p, q = dubins_shortest(0.0, 0.0, 0.0, x, y, phi, 1.0)
    if word >= 0 and rho * (t + p + q) < best:  # rolling forwards all the way, arcs beyond a half turn
        m = 0
        for s in range(3):
            length = (t, p, q)[s]
            if length > 1e-12:
                seg_turn[m] = WORD_TURNS[word, s]
                seg_len[m] = length * rho
                m += 1
        return m, rho * (t + p + q)
    if best_k < 0:
        return 0, math.inf
    return _write_word(turns[best_k], lens[best_k], rho, seg_turn, seg_len), best



@njit(cache=True)
def rs_distance(x0: float, y0: float, yaw0: float, x1: float, y1: float, yaw1: float, rho: float) -> float:
    """Length (m) of the shortest Reeds–Shepp path (OMPL's ``ReedsSheppStateSpace::distance``)."""
    x, y, phi = _local(x0, y0, yaw0, x1, y1, yaw1, rho)
    turns = np.empty((MAX_WORDS, MAX_SEGS), dtype=np.int64)
    lens = np.empty((MAX_WORDS, MAX_SEGS))
    n = rs_words(x, y, phi, turns, lens)
    best = math.inf
    for k in range(n):
        best = min(best, word_cost(lens[k], rho, 1.0, 0.0))
    return best



@lru_cache(maxsize=8)
def _space(rho: float) -> Any:
    from ompl import base as ob

    return ob.ReedsSheppStateSpace(rho)


def car_word(start: tuple[float, float, float], goal: tuple[float, float, float], rho: float,
             max_length_m: float = math.inf) -> list[tuple[int, int, float]]:
    """The Reeds–Shepp path from ``start`` to ``goal`` as segments (turn −1/0/+1, direction ±1, length m);
    empty when it is longer than ``max_length_m``."""
    space = _space(rho)
    a, b, out = space.allocState(), space.allocState(), space.allocState()
    for state, pose in ((a, start), (b, goal)):
        state.setX(float(pose[0]))
        state.setY(float(pose[1]))
        yaw = wrap(float(pose[2]))
        state.setYaw(yaw if yaw < math.pi else -math.pi)  # OMPL's SO(2) is [−π, π)
    total = space.distance(a, b)
    if total < 1e-9 or total > max_length_m:
        return []
    n = max(8, math.ceil(total / SAMPLE_M))
    pts = np.empty((n + 1, 3))
    for i in range(n + 1):
        space.interpolate(a, b, i / n, out)
        pts[i] = out.getX(), out.getY(), out.getYaw()
    d = np.diff(pts[:, :2], axis=0)
    ds = np.hypot(d[:, 0], d[:, 1])
    heading = pts[:-1, 2]
    direction = np.where(d[:, 0] * np.cos(heading) + d[:, 1] * np.sin(heading) >= 0.0, 1, -1)
    dyaw = np.remainder(np.diff(pts[:, 2]) + math.pi, 2 * math.pi) - math.pi
    turning = np.abs(dyaw) > 0.5 * ds / rho
    turn = np.where(turning, np.sign(dyaw) * direction, 0).astype(int)
    segments: list[tuple[int, int, float]] = []
    for t, dr, step in zip(turn, direction, ds, strict=True):
        if segments and segments[-1][0] == t and segments[-1][1] == dr:
            segments[-1] = (t, dr, segments[-1][2] + float(step))
        else:
            segments.append((int(t), int(dr), float(step)))
    # a sample straddling a segment boundary can form a sliver of its own: fold it into its neighbour
    merged: list[tuple[int, int, float]] = []
    for seg in segments:
        if merged and seg[2] < 2.5 * SAMPLE_M:
            t, dr, length = merged[-1]
            merged[-1] = (t, dr, length + seg[2])
        else:
            merged.append(seg)
    return merged


def _roll(start: tuple[float, float, float, float], segs: list[tuple[float, float, float]], radius: float,
          end_roll: float) -> tuple[float, float, float]:
    """End pose of the sphere after the (held roll, curvature, signed length) motions, then ``end_roll``."""
    x, y, yaw, roll = start
    for held, curv, s in segs:
        x, y = roll_shift(x, y, yaw, radius, held - roll)
        x, y, yaw = arc_step(x, y, yaw, curv, s)
        roll = held
    x, y = roll_shift(x, y, yaw, radius, end_roll - roll)
    return x, y, yaw


def sphere_shot(
    start: tuple[float, float, float, float], goal: tuple[float, float, float], rho: float, max_roll: float,
    radius: float,
) -> list[tuple[float, float, float]] | None:
    """Motions (held roll, curvature, signed arc length) that roll the sphere from ``start`` (x, y, yaw, roll)
    along the Reeds–Shepp word towards ``goal`` and land on it upright, or None when the car's path is
    longer than :data:`MAX_SHOT_M` or the lengths cannot be solved (the sideways shifts of the roll changes
    do not fit the word's geometry)."""
    word = car_word(start[:3], goal, rho, MAX_SHOT_M)
    if not word:
        return None
    turns = [t for t, _, _ in word]
    dirs = [d for _, d, _ in word]

    def motions(lengths: np.ndarray) -> list[tuple[float, float, float]]:
        return [(t * max_roll, t / rho, d * float(abs(s))) for t, d, s in zip(turns, dirs, lengths, strict=True)]

    def residual(lengths: np.ndarray) -> np.ndarray:
        x, y, yaw = _roll(start, motions(lengths), radius, 0.0)
        return np.array([x - goal[0], y - goal[1], rho * wrap(yaw - goal[2])])

    guess = np.array([s for _, _, s in word])
    fit = least_squares(residual, guess, bounds=(0.0, np.inf), xtol=1e-12, ftol=1e-12, gtol=1e-12)
    err = residual(fit.x)
    if math.hypot(err[0], err[1]) > LAND_TOL_M or abs(err[2]) > LAND_TOL_M * rho:
        return None
    return [m for m in motions(fit.x) if abs(m[2]) > 1e-9]
