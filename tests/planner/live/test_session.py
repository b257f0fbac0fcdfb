"""Refreshing a planner for the changed cells plans exactly as a rebuilt one; a session replans when an
observation blocks its path (checked with the footprint), reports why and how long, and fails typed."""

from __future__ import annotations

import time

import numpy as np
import pytest

from planner.errors import InvalidInput, PlannerTimedOut
from planner.hybrid_astar.search import HybridAStar, PlannerOptions
from planner.live import LiveMap, LiveSession, ObstacleLayerParams, PointObservation, ReplanPolicy
from planner.live.refresh import cap_m, capped, exact_reach_m, refresh
from planner.live.session import SPLICE_SHARE
from planner.maps.clearance import least_footprint_distance
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot

ROBOT = load_robot("zju-60")
START, GOAL = (1.5, 5.0, 0.0), (18.5, 5.0, 0.0)


def corridor() -> OccupancyGrid:
    """20 m × 10 m at 0.05 m, walls around."""
    occ = np.zeros((200, 400), dtype=bool)
    occ[[0, -1], :] = True
    occ[:, [0, -1]] = True
    return OccupancyGrid.from_occupied(occ, 0.05, name="corridor")


def wall_points(x: float, y0: float, y1: float) -> np.ndarray:
    ys = np.arange(y0, y1, 0.02)
    return np.stack([np.full_like(ys, x), ys, np.full_like(ys, 0.3)], axis=1)


def test_refresh_equals_rebuild() -> None:
    live = LiveMap(corridor(), ObstacleLayerParams.for_robot(ROBOT))
    opts = PlannerOptions(allow_unknown=True)
    planner = capped(HybridAStar(live.grid, ROBOT, opts))
    for x, y0, y1 in ((9.0, 2.0, 8.0), (14.0, 0.5, 4.0)):
        upd = live.apply(PointObservation(wall_points(x, y0, y1), np.array([x - 5.0, 5.0, 0.3])))
        assert upd.changed is not None
        planner, _, how = refresh(planner, list(upd.regions), max_share=1.0)
        assert how == "patched"
    rebuilt = HybridAStar(live.snapshot(), ROBOT, opts)
    assert cap_m(planner) >= exact_reach_m(planner)
    # the truth, capped: never above it (the search skips ahead by the clearance), exact below the cap
    assert np.allclose(planner.clearance.clearance, np.minimum(rebuilt.clearance.clearance, cap_m(planner)))
    assert np.array_equal(planner.clearance.blocked, rebuilt.clearance.blocked)
    finite = np.isfinite(rebuilt.holonomic_mult)
    assert np.array_equal(finite, np.isfinite(planner.holonomic_mult))
    assert np.allclose(planner.holonomic_mult[finite], rebuilt.holonomic_mult[finite])
    p1, p2 = planner.plan(START, GOAL), rebuilt.plan(START, GOAL)
    assert p1.length_m == pytest.approx(p2.length_m)


def test_a_refreshed_planner_admits_a_goal_the_updated_map_opens() -> None:
    """The reachability labels (refusing a goal no motion reaches) are cached per map: a refresh says the blocked
    cells changed. A wall seen across the corridor refuses the goal (the labels computed with it); seen gone again,
    the goal is admitted and planned to, not refused by the labels of the walled map."""
    from planner.errors import NoValidPathFound

    live = LiveMap(corridor(), ObstacleLayerParams.for_robot(ROBOT))
    opts = PlannerOptions(allow_unknown=True)
    planner = capped(HybridAStar(live.grid, ROBOT, opts))
    wall = live.apply(PointObservation(wall_points(9.0, 0.0, 10.0), np.array([4.0, 5.0, 0.3])))
    planner, _, how = refresh(planner, list(wall.regions), max_share=1.0)
    assert how == "patched"
    with pytest.raises(NoValidPathFound) as err:
        planner.plan(START, GOAL)
    assert err.value.expansions == 0
    # the wall is gone: rays through it to the far wall clear its cells
    far = np.stack([np.full(200, 18.0), np.linspace(0.3, 9.7, 200), np.full(200, 0.3)], axis=1)
    gone = live.apply(PointObservation(far, np.array([4.0, 5.0, 0.3])))
    planner, _, how = refresh(planner, list(gone.regions), max_share=1.0)
    assert how == "patched"
    assert planner.plan(START, GOAL).length_m > 0


def test_blocked_path_is_replanned_from_the_current_pose() -> None:
    live = LiveMap(corridor(), ObstacleLayerParams.for_robot(ROBOT))
    session = LiveSession(live, ROBOT, policy=ReplanPolicy(time_limit_s=5.0))
    heard = []
    session.listeners.append(heard.append)
    session.set_pose(START)
    first = session.set_goal(GOAL)
    assert first.ok and first.reason == "goal" and first.seq == 1
    session.set_pose((3.0, 5.0, 0.0))
    # a wall across the corridor with a gap at the top: the straight path is blocked
    update, event = session.observe(PointObservation(wall_points(10.0, 0.05, 7.5), np.array([4.0, 5.0, 0.3])))
    assert update.changed is not None
    assert event is not None and event.ok and event.reason == "blocked"
    assert event.blocked_at is not None and abs(event.blocked_at[0] - 10.0) < 0.6
    assert event.latency_s >= event.planning_time_s > 0
    # rolling at the path's speed, the robot is replanned from the state it reaches after the lead time and
    # braking (0.5 m/s · 0.5 s + 0.5²/(2 · 0.5) m = 0.5 m ahead), and the new path keeps the old one up to there
    assert event.spliced_m == pytest.approx(0.5, abs=0.05)
    assert event.start[0] == pytest.approx(3.0 + event.spliced_m, abs=0.1) and event.start[1] == pytest.approx(5.0)
    assert session.path is not None and session.path.extra["spliced_m"] == event.spliced_m
    head = session.path.states
    assert np.hypot(head[0, 0] - 3.0, head[0, 1] - 5.0) < 0.05 and head[0, 5] == head[0, 6] == 0.0
    assert np.all(np.diff(head[:, 6]) >= 0) and np.all(np.diff(head[:, 5]) >= 0)
    assert np.hypot(*np.diff(head[:, :2], axis=0).T).max() <= 0.05 + 1e-9  # no jump where the paths meet
    assert heard == [first, event]
    assert session.path is not None and session.blocked_index() is None
    states = session.path.states
    assert least_footprint_distance(live.grid, ROBOT, states[:, :3]) > 0
    assert states[:, 1].max() > 7.5  # through the gap
    # an observation away from the path does not replan
    _, none = session.observe(PointObservation(np.array([[2.0, 1.0, 0.3]]), np.array([3.0, 5.0, 0.3])))
    assert none is None
    # closing the gap: no path; the failure is typed and kept
    _, fail = session.observe(PointObservation(wall_points(10.0, 7.4, 9.96), np.array([4.0, 8.0, 0.3])))
    assert fail is not None and not fail.ok and fail.error_code == 208
    assert session.path is None and session.status()["state"] == "no_path"


def test_timer_replans_and_goal_needs_a_pose() -> None:
    now = [0.0]
    session = LiveSession(LiveMap(corridor()), ROBOT, policy=ReplanPolicy(period_s=1.0), clock=lambda: now[0])
    with pytest.raises(InvalidInput) as err:
        session.set_goal(GOAL)
    assert err.value.field == "pose"
    session.set_pose(START)
    session.set_goal(GOAL)
    now[0] = 0.5
    assert session.set_pose((2.0, 5.0, 0.0)) is None
    now[0] = 1.2
    event = session.set_pose((2.5, 5.0, 0.0))
    assert event is not None and event.reason == "timer" and event.ok
    with pytest.raises(InvalidInput) as err:
        session.set_pose((1.0, 1.0, 100.0))
    assert err.value.field == "pose.yaw"


def test_live_options_default_and_yield_to_given_ones() -> None:
    from planner.closed_loop.explore import ExploreOptions
    from planner.live import live_options
    from planner.live.session import LIVE_OPTION_DEFAULTS

    session = LiveSession(LiveMap(corridor()), ROBOT)
    assert session.options.allow_unknown is True
    assert session.options.greed == LIVE_OPTION_DEFAULTS["greed"] != PlannerOptions().greed
    # one step per expansion live (long steps made two explore worlds collide), long steps one-off
    assert session.options.open_step_factor == 1 < PlannerOptions().open_step_factor
    given = live_options({"allow_unknown": False, "n_rolls": 9})
    assert (given.allow_unknown, given.n_rolls, given.greed) == (False, 9, LIVE_OPTION_DEFAULTS["greed"])
    assert live_options({"greed": 0.5}).greed == 0.5
    with pytest.raises(InvalidInput) as err:
        live_options({"greedy": 1.0})
    assert err.value.field == "options.greedy"
    assert ExploreOptions().planner == live_options()


def test_a_spliced_replan_keeps_its_time_limit(monkeypatch: pytest.MonkeyPatch) -> None:
    """The search from the splice point gets SPLICE_SHARE of the limit; when it runs out, the search from the robot
    gets the rest (not a quarter of the limit more): the replan as a whole keeps about its limit."""
    live = LiveMap(corridor(), ObstacleLayerParams.for_robot(ROBOT))
    session = LiveSession(live, ROBOT, policy=ReplanPolicy(time_limit_s=0.4))
    session.set_pose(START)
    assert session.set_goal(GOAL).ok
    session.set_pose((3.0, 5.0, 0.0))
    limits: list[float] = []
    real = session._search

    def search(start: tuple[float, float, float], goal: tuple[float, float, float], limit: float) -> object:
        limits.append(limit)
        if len(limits) == 1:  # the splice point's search uses its whole budget and finds nothing
            time.sleep(limit)
            raise PlannerTimedOut("no path found within the time limit", planning_time_s=limit)
        return real(start, goal, limit)

    monkeypatch.setattr(session, "_search", search)
    _, event = session.observe(PointObservation(wall_points(10.0, 0.05, 7.5), np.array([4.0, 5.0, 0.3])))
    assert event is not None and event.ok and event.spliced_m == 0.0 and event.start == (3.0, 5.0, 0.0)
    assert limits[0] == pytest.approx(SPLICE_SHARE * 0.4)
    assert limits[1] == pytest.approx((1 - SPLICE_SHARE) * 0.4, abs=0.02)  # the rest, not 0.25 × the limit more


def test_a_still_robot_or_no_lead_replans_from_the_current_pose() -> None:
    for policy in (ReplanPolicy(time_limit_s=5.0, splice_lead_s=0.0), ReplanPolicy(time_limit_s=5.0)):
        live = LiveMap(corridor(), ObstacleLayerParams.for_robot(ROBOT))
        session = LiveSession(live, ROBOT, policy=policy)
        session.set_pose(START)
        session.set_goal(GOAL)
        # with no lead: at 3 m on the path; with the default lead: at the start, where the path's speed is 0
        pose = (3.0, 5.0, 0.0) if policy.splice_lead_s == 0 else START
        session.set_pose(pose)
        _, event = session.observe(PointObservation(wall_points(10.0, 0.05, 7.5), np.array([4.0, 5.0, 0.3])))
        assert event is not None and event.ok and event.reason == "blocked"
        assert event.start == pose and event.spliced_m == 0.0
    with pytest.raises(InvalidInput):
        ReplanPolicy(splice_lead_s=-1.0)


def test_no_splice_across_a_stop_on_the_path() -> None:
    """A stretch with a stop on it (a cusp, or the roll-in at the head of a path spliced before) is not kept:
    splices must not pile up, so the replan starts from the robot."""
    live = LiveMap(corridor(), ObstacleLayerParams.for_robot(ROBOT))
    session = LiveSession(live, ROBOT, policy=ReplanPolicy(time_limit_s=5.0))
    session.set_pose(START)
    session.set_goal(GOAL)
    session.set_pose((3.0, 5.0, 0.0))
    assert session.path is not None
    states = session.path.states
    i = session._progress.index
    stop = i + int(np.searchsorted(states[i:, 6], states[i, 6] + 0.2))
    states[stop, 4] = 0.0
    _, event = session.observe(PointObservation(wall_points(10.0, 0.05, 7.5), np.array([4.0, 5.0, 0.3])))
    assert event is not None and event.ok and event.spliced_m == 0.0 and event.start == (3.0, 5.0, 0.0)
