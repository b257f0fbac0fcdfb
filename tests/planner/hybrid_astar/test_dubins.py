"""Our compiled Dubins paths against OMPL's DubinsStateSpace (the reference)."""

import math

import numpy as np
from ompl import base as ob

from planner.hybrid_astar.dubins import WORD_TURNS, dubins_distance, dubins_shortest
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
