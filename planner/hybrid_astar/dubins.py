"""Dubins shortest paths (forward-only, minimum turning radius ρ), numba-compiled.

Used for the non-holonomic heuristic (paper 001 eq. 14h) and for analytic expansions. The six words
LSL, LSR, RSL, RSR, RLR, LRL follow Shkel & Lumelsky's closed forms; the tests check lengths and end
poses against OMPL's ``DubinsStateSpace`` (the reference implementation) on random pairs.

A path is (word, t, p, q): three segments of normalised lengths t, p, q (multiply by ρ for metres)
with turn signs ``WORD_TURNS[word]`` (+1 left, 0 straight, −1 right).
"""

from __future__ import annotations

import math

import numpy as np

from planner.jit import njit_leaf

TWO_PI = 2.0 * math.pi
# a word is skipped when its straight or middle part alone exceeds the best so far by this (normalised lengths;
# far above _mod2pi's rounding, which can leave t or q a few ulps below 0)
SKIP_MARGIN = 1e-9
WORD_NAMES = ("LSL", "LSR", "RSL", "RSR", "RLR", "LRL")
WORD_TURNS = np.array([[1, 0, 1], [1, 0, -1], [-1, 0, 1], [-1, 0, -1], [-1, 1, -1], [1, -1, 1]], dtype=np.int64)


@njit_leaf
def _mod2pi(a: float) -> float:
    return a - TWO_PI * math.floor(a / TWO_PI)


@njit_leaf
def dubins_shortest(
    x0: float, y0: float, th0: float, x1: float, y1: float, th1: float, rho: float
) -> tuple[int, float, float, float]:
    """Shortest Dubins word and normalised segment lengths from (x0, y0, th0) to (x1, y1, th1).

    A word is not worked out when its straight or middle part alone is already longer than the best word so far
    (its t and q are ≥ 0, so it cannot be chosen; SKIP_MARGIN covers the last bits of _mod2pi's rounding), and
    RLR and LRL reuse RSR's and LSL's angle (the same atan2, or its negation: atan2 is odd in y). The word and
    lengths returned are those of working out all six (tested)."""
    dx = (x1 - x0) / rho
    dy = (y1 - y0) / rho
    d = math.hypot(dx, dy)
    theta = _mod2pi(math.atan2(dy, dx)) if d > 1e-12 else 0.0
    a = _mod2pi(th0 - theta)
    b = _mod2pi(th1 - theta)
    sa, sb, ca, cb = math.sin(a), math.sin(b), math.cos(a), math.cos(b)
    cab = math.cos(a - b)
    best = math.inf
    bw, bt, bp, bq = -1, 0.0, 0.0, 0.0
    # LSL
    lsl_y = cb - ca
    lsl_x = d + sa - sb
    lsl = math.nan  # atan2(lsl_y, lsl_x) once worked out
    p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sa - sb)
    if p2 >= 0.0:
        lsl = math.atan2(lsl_y, lsl_x)
        t = _mod2pi(-a + lsl)
        p = math.sqrt(p2)
        q = _mod2pi(b - lsl)
        if t + p + q < best:
            best, bw, bt, bp, bq = t + p + q, 0, t, p, q
    # LSR
    p2 = -2.0 + d * d + 2.0 * cab + 2.0 * d * (sa + sb)
    if p2 >= 0.0:
        p = math.sqrt(p2)
        if p < best + SKIP_MARGIN:
            tmp = math.atan2(-ca - cb, d + sa + sb) - math.atan2(-2.0, p)
            t = _mod2pi(-a + tmp)
            q = _mod2pi(-b + tmp)
            if t + p + q < best:
                best, bw, bt, bp, bq = t + p + q, 1, t, p, q
    # RSL
    p2 = d * d - 2.0 + 2.0 * cab - 2.0 * d * (sa + sb)
    if p2 >= 0.0:
        p = math.sqrt(p2)
        if p < best + SKIP_MARGIN:
            tmp = math.atan2(ca + cb, d - sa - sb) - math.atan2(2.0, p)
            t = _mod2pi(a - tmp)
            q = _mod2pi(b - tmp)
            if t + p + q < best:
                best, bw, bt, bp, bq = t + p + q, 2, t, p, q
    # RSR
    rsr = math.nan  # atan2(ca − cb, d − sa + sb) once worked out
    p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sb - sa)
    if p2 >= 0.0:
        p = math.sqrt(p2)
        if p < best + SKIP_MARGIN:
            rsr = math.atan2(ca - cb, d - sa + sb)
            t = _mod2pi(a - rsr)
            q = _mod2pi(-b + rsr)
            if t + p + q < best:
                best, bw, bt, bp, bq = t + p + q, 3, t, p, q
    # RLR and LRL: the middle arc p is 2π − acos(·) ≥ π (or 0 when acos gives 0)
    ccc = best + SKIP_MARGIN > math.pi
    # RLR
    tmp = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sa - sb)) / 8.0
    if abs(tmp) <= 1.0 and (ccc or tmp == 1.0):
        p = _mod2pi(TWO_PI - math.acos(tmp))
        if math.isnan(rsr):
            rsr = math.atan2(ca - cb, d - sa + sb)
        t = _mod2pi(a - rsr + p / 2.0)
        q = _mod2pi(a - b - t + p)
        if t + p + q < best:
            best, bw, bt, bp, bq = t + p + q, 4, t, p, q
    # LRL
    tmp = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sb - sa)) / 8.0
    if abs(tmp) <= 1.0 and (ccc or tmp == 1.0):
        p = _mod2pi(TWO_PI - math.acos(tmp))
        if math.isnan(lsl):
            lsl = math.atan2(lsl_y, lsl_x)
        lrl = lsl if lsl_y == 0.0 else -lsl  # atan2(ca − cb, lsl_x): ca − cb is −lsl_y exactly
        t = _mod2pi(-a - lrl + p / 2.0)
        q = _mod2pi(_mod2pi(b) - a - t + p)
        if t + p + q < best:
            best, bw, bt, bp, bq = t + p + q, 5, t, p, q
    return bw, bt, bp, bq


@njit_leaf
def dubins_distance(x0: float, y0: float, th0: float, x1: float, y1: float, th1: float, rho: float) -> float:
    """Length (m) of the shortest Dubins path at minimum turning radius ``rho`` (m)."""
    w, t, p, q = dubins_shortest(x0, y0, th0, x1, y1, th1, rho)
    return (t + p + q) * rho
