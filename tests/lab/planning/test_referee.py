"""The benchmark's exact polygon checker against a brute-force rasterisation on random poses.

The brute force (tests/polycheck.py) shares no code with :mod:`lab.planning.referee`: it clips
the placed polygon against every nearby blocked cell square (Sutherland–Hodgman) and calls a pose colliding
when some clipped area is positive or a vertex leaves the map; clearances are vertex-to-edge distances over
every blocked cell, in numpy.
"""

from __future__ import annotations

import numpy as np
import pytest

from lab.planning.referee import FootprintReferee
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from tests.polycheck import brute_clearance, brute_collides

ZJU = load_robot("zju-60").footprint_polygon
# a non-convex footprint (an arrow head), to show the checks do not assume convexity
ARROW = np.array([[0.45, 0.0], [-0.3, 0.35], [-0.1, 0.0], [-0.3, -0.35]])


def _grid(seed: int) -> OccupancyGrid:
    rng = np.random.default_rng(seed)
    data = np.zeros((90, 110), dtype=np.int8)
    data[rng.random(data.shape) < 0.002] = 100  # scattered single cells
    data[rng.random(data.shape) < 0.001] = -1
    data[30:33, 5:60] = 100  # a wall and a block, so that many poses graze something
    data[55:68, 65:72] = -1
    return OccupancyGrid(data=data, resolution_m=0.05, origin=(-1.3, 0.7, 0.0), name="random")


def _random_poses(grid: OccupancyGrid, rng: np.random.Generator, n: int) -> np.ndarray:
    ox, oy = grid.origin[:2]
    w, h = grid.size_m
    return np.column_stack([rng.uniform(ox, ox + w, n), rng.uniform(oy, oy + h, n), rng.uniform(-np.pi, np.pi, n)])


@pytest.mark.parametrize(("poly", "allow_unknown"), [(ZJU, False), (ARROW, False), (ZJU, True)])
def test_collision_matches_brute_force(poly: np.ndarray, allow_unknown: bool) -> None:
    grid = _grid(1)
    rng = np.random.default_rng(7)
    checker = FootprintReferee(poly.copy(), grid.blocked(allow_unknown), grid.origin[:2], grid.resolution_m)
    poses = _random_poses(grid, rng, 250)
    expected = np.array([brute_collides(grid, poly, p, allow_unknown) for p in poses])
    got = checker.collides_many(poses)
    assert 30 < expected.sum() < 220, "the sample must hold both free and colliding poses"
    np.testing.assert_array_equal(got, expected)
    assert [checker.collides(*p) for p in poses[:40]] == expected[:40].tolist()


def test_unknown_blocks_unless_allowed_and_leaving_the_map_collides() -> None:
    data = np.zeros((40, 40), dtype=np.int8)
    data[20, 20] = -1
    grid = OccupancyGrid(data=data, resolution_m=0.05)
    robot = load_robot("zju-60")
    strict, lax = FootprintReferee.for_robot(grid, robot), FootprintReferee.for_robot(grid, robot, allow_unknown=True)
    assert strict.collides(1.025, 1.025, 0.3) and not lax.collides(1.025, 1.025, 0.3)
    # 0.32 m from the centre to the padded polygon's front; the map edge at x = 2.0
    assert not lax.collides(2.0 - 0.321, 0.5, 0.0) and lax.collides(2.0 - 0.319, 0.5, 0.0)
    assert lax.clearances(np.array([[2.0 - 0.42, 0.5, 0.0]]))[0] == pytest.approx(0.1, abs=1e-9)


@pytest.mark.parametrize("poly", [ZJU, ARROW])
def test_clearance_matches_brute_force(poly: np.ndarray) -> None:
    grid = _grid(2)
    rng = np.random.default_rng(3)
    checker = FootprintReferee(poly.copy(), grid.blocked(), grid.origin[:2], grid.resolution_m)
    poses = _random_poses(grid, rng, 120)
    expected = np.array([brute_clearance(grid, poly, p, 0.5) for p in poses])
    got = checker.clearances(poses, reach_m=0.5)
    assert (expected > 0).sum() > 20 and (expected == 0).sum() > 10
    np.testing.assert_allclose(got, expected, atol=1e-9)
    assert checker.min_clearance(poses, 0.5) == pytest.approx(expected.min())


def test_inradius_and_circumradius_of_the_zju_polygon() -> None:
    grid = _grid(0)
    checker = FootprintReferee.for_robot(grid, load_robot("zju-60"))
    assert checker.inradius_m == pytest.approx(0.32)  # the padded 16-gon's front edge: 0.30 / cos(π/16)·… + 0.02
    assert checker.circumradius_m == pytest.approx(float(np.hypot(ZJU[:, 0], ZJU[:, 1]).max()))


@pytest.mark.parametrize("pad", [0.05, 0.3])
def test_a_grown_polygon_collides_where_the_footprint_comes_within_the_pad(pad: float) -> None:
    """The room-matched reference's check: the zju polygon grown by ``pad`` collides exactly where the brute-force
    clearance of the polygon itself is below the pad (or it collides), up to the chords' GROWTH_ERROR × pad."""
    from lab.planning.referee import GROWTH_ERROR

    grid = _grid(4)
    rng = np.random.default_rng(11)
    plain = FootprintReferee(ZJU.copy(), grid.blocked(), grid.origin[:2], grid.resolution_m)
    grown = plain.grown(pad)
    assert grown.circumradius_m == pytest.approx(plain.circumradius_m + pad, abs=GROWTH_ERROR * pad + 1e-9)
    poses = _random_poses(grid, rng, 400)
    clearance = np.array([brute_clearance(grid, ZJU, p, 1.0) for p in poses])
    hits = grown.collides_many(poses)
    near = np.abs(clearance - pad) <= GROWTH_ERROR * pad + 1e-9
    assert ((clearance < pad) & ~near).sum() > 15 and ((clearance > pad) & ~near).sum() > 15
    np.testing.assert_array_equal(hits[~near], clearance[~near] < pad)


def test_only_a_convex_footprint_is_grown() -> None:
    from lab.planning.referee import grown_polygon

    with pytest.raises(ValueError, match="convex"):
        grown_polygon(ARROW, 0.1)
    with pytest.raises(ValueError, match="pad"):
        grown_polygon(ZJU, -0.1)
    np.testing.assert_array_equal(grown_polygon(ZJU, 0.0), ZJU)
