"""The guide heuristic of live replanning closes gaps wider than the footprint's length but narrower than its
width (what a half-seen box leaves), so the search goes round at once where the admissible heuristic floods the
space in front of the gap; a guided search that finds nothing falls back to the ordinary one; the guide is
patched with the planner's multipliers and equals a rebuilt one."""

from __future__ import annotations

import numpy as np
import pytest

from planner.errors import InvalidInput, NoValidPathFound, PlannerTimedOut
from planner.hybrid_astar.search import HybridAStar, PlannerOptions
from planner.live import LiveMap, LiveSession, ObstacleLayerParams, PointObservation, ReplanPolicy
from planner.live import session as session_module
from planner.live.guide import WIDE_M, guide_mult, guide_threshold_m, guided_plan, lateral_half_width_m
from planner.live.refresh import capped, refresh
from planner.maps.clearance import inscribed_radius, least_footprint_distance
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from planner.termination import Termination

ROBOT = load_robot("zju-60")
START, GOAL = (1.5, 1.35, 0.0), (18.5, 1.35, 0.0)
RES = 0.05


def gap_map() -> OccupancyGrid:
    """20 m × 10 m, walls around; a wall across at x = 10 m with a 0.70 m gap at y 1.0–1.7 m (wider than
    zju-60's 0.64 m length, narrower than its 0.74 m width) and a wide opening at y 8–10 m."""
    occ = np.zeros((200, 400), dtype=bool)
    occ[[0, -1], :] = True
    occ[:, [0, -1]] = True
    occ[0:20, 200:202] = True
    occ[34:160, 200:202] = True
    return OccupancyGrid.from_occupied(occ, RES, name="gap")


def test_guide_threshold_is_the_lateral_half_width() -> None:
    planner = HybridAStar(gap_map(), ROBOT, PlannerOptions(allow_unknown=True))
    lateral = lateral_half_width_m(planner.polygon)
    assert lateral == pytest.approx(0.37)
    assert lateral > inscribed_radius(planner.polygon)
    assert guide_threshold_m(planner) == pytest.approx(lateral - 1.63 * RES)
    assert guide_threshold_m(planner) > planner.centre_threshold_m


def test_guide_closes_the_narrow_gap_and_the_search_goes_round() -> None:
    planner = HybridAStar(gap_map(), ROBOT, PlannerOptions(allow_unknown=True))
    f = planner.heuristic_factor
    gap = (int(1.35 / RES) // f, 200 // f)
    assert np.isfinite(planner.holonomic_mult[gap])  # the admissible heuristic leads through the gap
    guide = guide_mult(planner)
    assert np.isinf(guide[gap])
    assert np.isfinite(guide[int(9.0 / RES) // f, 200 // f])  # the wide opening stays open
    assert np.all(guide >= planner.holonomic_mult)  # the guide only closes cells, never opens or cheapens them
    saved = planner.holonomic_mult.copy()
    result = guided_plan(planner, START, GOAL, Termination(60.0, max_iterations=20_000))
    assert np.array_equal(planner.holonomic_mult, saved) and not planner._heuristics  # the planner is as it was
    states = result.states
    assert states[:, 1].max() > 8.0  # round through the opening
    assert least_footprint_distance(planner.grid, ROBOT, states[:, :3]) > 0
    # the ordinary search spends the same expansion budget in front of the gap and finds nothing
    with pytest.raises(NoValidPathFound, match="iteration cap"):
        planner.plan(START, GOAL, Termination(60.0, max_iterations=20_000))


def test_session_replans_guided_and_falls_back(monkeypatch: pytest.MonkeyPatch) -> None:
    session = LiveSession(LiveMap(gap_map()), ROBOT, policy=ReplanPolicy(time_limit_s=30.0))
    session.set_pose(START)
    event = session.set_goal(GOAL)
    assert event.ok and event.method == "guided" and event.to_json()["method"] == "guided"
    assert session.path is not None and session.path.states[:, 1].max() > 8.0

    # a guided search that finds nothing proves nothing: the ordinary search answers (here an open corridor)
    def fails(*args: object, **kwargs: object) -> None:
        raise PlannerTimedOut("guided search ran out", planning_time_s=0.0)

    monkeypatch.setattr(session_module, "guided_plan", fails)
    occ = np.zeros((200, 400), dtype=bool)
    occ[[0, -1], :] = True
    occ[:, [0, -1]] = True
    open_session = LiveSession(LiveMap(OccupancyGrid.from_occupied(occ, RES)), ROBOT)
    open_session.set_pose(START)
    fallback = open_session.set_goal(GOAL)
    assert fallback.ok and fallback.method == "ordinary"
    assert ReplanPolicy(guided=False).guided is False


def test_wide_guide_closes_gaps_a_little_wider_than_the_robot() -> None:
    occ = np.zeros((200, 400), dtype=bool)
    occ[[0, -1], :] = True
    occ[:, [0, -1]] = True
    occ[0:20, 200:202] = True
    occ[37:160, 200:202] = True  # a 0.85 m gap: wide enough for the footprint's 0.74 m, not 0.15 m more on each side
    planner = HybridAStar(OccupancyGrid.from_occupied(occ, RES), ROBOT, PlannerOptions(allow_unknown=True))
    f = planner.heuristic_factor
    gap = (int(1.4 / RES) // f, 200 // f)
    assert guide_threshold_m(planner, WIDE_M) == pytest.approx(guide_threshold_m(planner) + WIDE_M)
    assert np.isfinite(guide_mult(planner)[gap]) and np.isinf(guide_mult(planner, WIDE_M)[gap])
    assert np.all(guide_mult(planner, WIDE_M) >= guide_mult(planner))


def test_session_tries_the_guides_in_order_with_an_expansion_budget(monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[tuple[float, int]] = []
    real = session_module.guided_plan

    def first_fails(planner: HybridAStar, start: object, goal: object, termination: Termination,
                    widen_m: float = 0.0) -> object:
        calls.append((widen_m, termination.max_iterations))
        if widen_m == 0.0:
            raise NoValidPathFound("the plain guide's search found nothing", planning_time_s=0.0)
        return real(planner, start, goal, termination, widen_m)  # type: ignore[arg-type]

    monkeypatch.setattr(session_module, "guided_plan", first_fails)
    policy = ReplanPolicy(time_limit_s=30.0, guide_expansions=4000)
    session = LiveSession(LiveMap(gap_map()), ROBOT, policy=policy)
    session.set_pose(START)
    event = session.set_goal(GOAL)
    assert calls == [(0.0, 4000), (WIDE_M, 4000)]
    assert event.ok and event.method == f"guided+{WIDE_M:g}m"
    with pytest.raises(InvalidInput):
        ReplanPolicy(guide_levels_m=(0.0, -0.1))
    with pytest.raises(InvalidInput):
        ReplanPolicy(guide_expansions=0)


def test_guide_is_patched_like_a_rebuilt_one() -> None:
    live = LiveMap(gap_map(), ObstacleLayerParams.for_robot(ROBOT))
    opts = PlannerOptions(allow_unknown=True)
    planner = capped(HybridAStar(live.grid, ROBOT, opts))
    guide_mult(planner)  # built before the change: refresh must patch them
    guide_mult(planner, WIDE_M)
    ys = np.arange(3.0, 6.0, 0.02)
    upd = live.apply(PointObservation(np.stack([np.full_like(ys, 15.0), ys, np.full_like(ys, 0.3)], axis=1),
                                      np.array([12.0, 4.5, 0.3])))
    assert upd.changed is not None
    planner, _, how = refresh(planner, list(upd.regions), max_share=1.0)
    assert how == "patched"
    rebuilt = capped(HybridAStar(live.snapshot(), ROBOT, opts))
    for widen in (0.0, WIDE_M):
        a, b = guide_mult(planner, widen), guide_mult(rebuilt, widen)
        assert np.array_equal(np.isinf(a), np.isinf(b))
        finite = np.isfinite(b)
        assert np.allclose(a[finite], b[finite])
    a = guide_mult(planner)
    assert np.isinf(a[int(4.5 / RES) // planner.heuristic_factor, int(15.0 / RES) // planner.heuristic_factor])
