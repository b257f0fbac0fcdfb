"""Our compiled Dubins paths against OMPL's DubinsStateSpace (the reference)."""

import math

import numpy as np
from numba import njit
from ompl import base as ob

from planner.hybrid_astar.dubins import WORD_TURNS, _mod2pi, dubins_distance, dubins_shortest
from planner.kinematics import arc_step


def test_lengths_and_end_poses_match_ompl():
    rng = np.random.default_rng(3)
    for rho in (0.5, 1.12, 3.0):
        space = ob.DubinsStateSpace(rho)
        a, b = space.allocState(), space.allocState()
        for _ in range(300):
            v = rng.uniform(-6, 6, 6)
            v[2], v[5] = rng.uniform(-math.pi, math.pi, 2)
            a.setX(v[0]); a.setY(v[1]); a.setYaw(v[2])  # noqa: E702
            b.setX(v[3]); b.setY(v[4]); b.setYaw(v[5])  # noqa: E702
            assert abs(space.distance(a, b) - dubins_distance(*v, rho)) < 1e-7
            word, t, p, q = dubins_shortest(*v, rho)
            x, y, th = v[0], v[1], v[2]
            for turn, length in zip(WORD_TURNS[word], (t, p, q), strict=True):
                x, y, th = arc_step(x, y, th, turn / rho, length * rho)
            assert math.hypot(x - v[3], y - v[4]) < 1e-7
            assert abs(math.remainder(th - v[5], 2 * math.pi)) < 1e-7


@njit(cache=False)
def _all_six(x0, y0, th0, x1, y1, th1, rho):
    """Every word worked out (dubins_shortest before it skipped words and shared angles)."""
    dx, dy = (x1 - x0) / rho, (y1 - y0) / rho
    d = math.hypot(dx, dy)
    theta = _mod2pi(math.atan2(dy, dx)) if d > 1e-12 else 0.0
    a, b = _mod2pi(th0 - theta), _mod2pi(th1 - theta)
    sa, sb, ca, cb = math.sin(a), math.sin(b), math.cos(a), math.cos(b)
    cab = math.cos(a - b)
    best, bw, bt, bp, bq = math.inf, -1, 0.0, 0.0, 0.0
    p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sa - sb)
    if p2 >= 0.0:
        tmp = math.atan2(cb - ca, d + sa - sb)
        t, p, q = _mod2pi(-a + tmp), math.sqrt(p2), _mod2pi(b - tmp)
        if t + p + q < best:
            best, bw, bt, bp, bq = t + p + q, 0, t, p, q
    p2 = -2.0 + d * d + 2.0 * cab + 2.0 * d * (sa + sb)
    if p2 >= 0.0:
        p = math.sqrt(p2)
        tmp = math.atan2(-ca - cb, d + sa + sb) - math.atan2(-2.0, p)
        t, q = _mod2pi(-a + tmp), _mod2pi(-b + tmp)
        if t + p + q < best:
            best, bw, bt, bp, bq = t + p + q, 1, t, p, q
    p2 = d * d - 2.0 + 2.0 * cab - 2.0 * d * (sa + sb)
    if p2 >= 0.0:
        p = math.sqrt(p2)
        tmp = math.atan2(ca + cb, d - sa - sb) - math.atan2(2.0, p)
        t, q = _mod2pi(a - tmp), _mod2pi(b - tmp)
        if t + p + q < best:
            best, bw, bt, bp, bq = t + p + q, 2, t, p, q
    p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sb - sa)
    if p2 >= 0.0:
        tmp = math.atan2(ca - cb, d - sa + sb)
        t, p, q = _mod2pi(a - tmp), math.sqrt(p2), _mod2pi(-b + tmp)
        if t + p + q < best:
            best, bw, bt, bp, bq = t + p + q, 3, t, p, q
    tmp = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sa - sb)) / 8.0
    if abs(tmp) <= 1.0:
        p = _mod2pi(2.0 * math.pi - math.acos(tmp))
        t = _mod2pi(a - math.atan2(ca - cb, d - sa + sb) + p / 2.0)
        q = _mod2pi(a - b - t + p)
        if t + p + q < best:
            best, bw, bt, bp, bq = t + p + q, 4, t, p, q
    tmp = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sb - sa)) / 8.0
    if abs(tmp) <= 1.0:
        p = _mod2pi(2.0 * math.pi - math.acos(tmp))
        t = _mod2pi(-a - math.atan2(ca - cb, d + sa - sb) + p / 2.0)
        q = _mod2pi(_mod2pi(b) - a - t + p)
        if t + p + q < best:
            best, bw, bt, bp, bq = t + p + q, 5, t, p, q
    return bw, bt, bp, bq


def _poses(rng, n, spread):
    v = rng.uniform(-spread, spread, (n, 6))
    v[:, 2] = rng.uniform(-math.pi, math.pi, n)
    v[:, 5] = rng.uniform(-math.pi, math.pi, n)
    return v


def test_the_word_chosen_is_that_of_working_out_all_six():
    """Skipping the words that cannot win and sharing RSR's and LSL's angle with RLR and LRL changes nothing: the
    same word and the same lengths to the bit, near (where RLR and LRL exist and often win), far, and at the edge
    cases (the same pose, the same place turned round, a straight line, a half turn)."""
    rng = np.random.default_rng(11)
    cases = [_poses(rng, 20_000, 0.6), _poses(rng, 20_000, 2.0), _poses(rng, 5_000, 20.0)]
    edges = []
    for th0 in (0.0, math.pi / 2, math.pi, -math.pi / 2, 1e-12, math.pi - 1e-12):
        for dth in (0.0, math.pi, -math.pi, 1e-15, math.pi / 2):
            for dx, dy in ((0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (4.0, 0.0), (1e-13, 0.0), (2.0, 2.0)):
                edges.append((0.0, 0.0, th0, dx, dy, th0 + dth))
    cases.append(np.array(edges))
    words = np.zeros(6, dtype=int)
    for v in np.concatenate(cases):
        for rho in (1.0, 0.7):
            got = dubins_shortest(*v, rho)
            want = _all_six(*v, rho)
            assert got == want, (v, rho, got, want)
            words[want[0]] += 1
    assert (words > 100).all(), words  # every word won somewhere (RLR and LRL near)
