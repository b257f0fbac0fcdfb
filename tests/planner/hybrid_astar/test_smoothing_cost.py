"""The smoother's shortcut kernel skips most of the shots that failed from the knot before (kernels.shortcut,
``recheck``; on by default since issue 21's sixth round, search.SMOOTH_RECHECK): with it, it must build far fewer
shots than trying every candidate from every knot, and its path may be at most 1 % longer than that exhaustive
smoothing's (skipped candidates can hold a slightly better shortcut; on the 60 real-map problems of seed 0,
measured when the rule was made, no path was more than 0.2 % longer and the total 0.26 % shorter)."""

import math

import numpy as np
import pytest

from planner.hybrid_astar import search
from planner.hybrid_astar.search import HybridAStar, PlannerOptions
from planner.maps.load import load_map
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from tests.pathcheck import check_path

ROBOT = load_robot()
PROBLEMS = {  # map, start, goal
    "garage": ("maps/garage.yaml", (12.0, 8.05, 0.0), (12.0, 23.55, math.pi)),  # the README's garage U-turn
    # issue 21's real-map problems (bench --suite real, seed 0) whose smoothing cost most
    "bays#4": ("maps/real/bays.yaml", (1.725, 10.775, 1.4577), (21.625, 13.725, -2.7264)),
    "warehouse#0": ("maps/real/warehouse.yaml", (5.255, 11.615, 0.5371), (-1.015, 3.965, -1.3398)),
}


class _Counting(HybridAStar):
    """Adds up kernels.shortcut's counts over every smoothing of a plan."""

    counts: np.ndarray

    def _smooth(self, start, motions, p, o, counts=None):  # type: ignore[no-untyped-def]
        return super()._smooth(start, motions, p, o, self.counts)


def _plan(name: str) -> tuple[float, np.ndarray]:
    path, start, goal = PROBLEMS[name]
    grid = load_map(path)
    planner = _Counting(grid, ROBOT, PlannerOptions())
    planner.counts = np.zeros(4, dtype=np.int64)
    result = planner.plan(start, goal)
    assert check_path(grid, ROBOT, result.states, start, goal) == []
    return result.length_m, planner.counts


@pytest.mark.parametrize("name", sorted(PROBLEMS))
def test_smoothing_skips_shots_without_lengthening_the_path(name, monkeypatch) -> None:
    assert (search.SMOOTH_RECHECK, search.SMOOTH_RECHECK_FIRST) == (3, 2)  # the default
    length, counts = _plan(name)
    with monkeypatch.context() as m:  # every candidate from every knot
        m.setattr(search, "SMOOTH_RECHECK", 1)
        m.setattr(search, "SMOOTH_RECHECK_FIRST", 1)
        every_length, every = _plan(name)
    assert every[2] == 0
    assert counts[2] > 0
    assert counts[0] < 0.6 * every[0]
    assert length <= 1.01 * every_length


def _corridor_wiggle(half_width_m: float):
    """A 20 × 10 m map with a corridor of 2 × ``half_width_m`` along y = 5 m, and a 6 m path down its middle that
    wiggles (held rolls ±0.33 φmax every 0.6 m): its footprint margin is the same everywhere along it."""
    occ = np.zeros((200, 400), bool)
    occ[:, :2] = occ[:, -2:] = True
    occ[:round((5.0 - half_width_m) / 0.05)] = True
    occ[round((5.0 + half_width_m) / 0.05):] = True
    planner = HybridAStar(OccupancyGrid.from_occupied(occ, 0.05, name="corridor"), ROBOT)
    held = 0.33 * ROBOT.max_roll_rad
    motions = [(h, ROBOT.roll_model.curvature(h), 0.1) for h in
               (held if ((k + 3) // 6) % 2 == 0 else -held for k in range(60))] + [(0.0, 0.0, 0.0)]
    return planner, (4.0, 5.0, 0.0), motions


def _least_margin(planner, start, motions) -> float:
    fine = planner._densify(start, motions, planner.grid.resolution_m / 4)
    return float(planner.clearance.footprint_margins(planner.footprint, planner.polygon, fine[:, :3]).min())


@pytest.mark.parametrize(("half_width", "margin", "shortened"), [(0.75, 0.298, True), (0.7, 0.248, True),
                                                                   (0.6, 0.148, False)])
def test_a_stretch_closer_than_the_preferred_clearance_is_shortcut_keeping_its_own_margin(half_width, margin,
                                                                                        shortened) -> None:
    """A shortcut keeps the preferred clearance (0.3 m for zju-60) unless the stretch it replaces came closer; then it
    keeps that stretch's least knot margin, and never less than kernels.LEAST_KEPT_MARGIN_M (0.2 m). The knots'
    margins were once measured with a motion of length 0 (no pose sampled, so +inf), which made every shortcut keep
    0.3 m: a path down a corridor with 0.298 m or 0.248 m of margin was never straightened."""
    from planner.hybrid_astar import kernels

    planner, start, motions = _corridor_wiggle(half_width)
    assert _least_margin(planner, start, motions) == pytest.approx(margin, abs=0.005)
    counts = np.zeros(4, dtype=np.int64)
    out = planner._shortcut(start, motions, planner._params((10.0, 5.0, 0.0), True), 24, 1, counts)
    before, after = planner._length(start, motions), planner._length(start, out)
    if shortened:
        assert counts[3] >= 1 and after < before - 0.3
        assert _least_margin(planner, start, out) >= min(margin, ROBOT.preferred_clearance_m) - 0.005
    else:  # the stretch's own margin is under the floor: no shortcut may come that close
        assert margin < kernels.LEAST_KEPT_MARGIN_M
        assert counts[3] == 0 and after == before


def test_the_smallest_knot_margin_between_two_knots_is_the_range_minimum() -> None:
    """The smoother asks for the smallest knot margin between the shot's two knots (a shortcut keeps at least that
    room): a sparse table answers it for any pair, as a scan of the range does (lengths 1 to 300, every pair of
    the short ones; ties and negative margins included)."""
    from planner.hybrid_astar.kernels import _range_min, _range_min_table

    rng = np.random.default_rng(3)
    for n in (1, 2, 3, 5, 8, 17, 64, 300):
        values = np.round(rng.normal(0.2, 0.3, n), 2)
        table = _range_min_table(values)
        pairs = [(i, j) for i in range(n) for j in range(i, n)] if n <= 64 else \
            [tuple(sorted(rng.integers(0, n, 2))) for _ in range(2000)]
        for i, j in pairs:
            assert _range_min(table, int(i), int(j)) == values[i:j + 1].min()
