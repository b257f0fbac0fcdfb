"""The real-map benchmark: the problem sampler, the unreachability proof, the BIT* reference and the summary.

No timing assertions: the BIT* runs get small budgets and are judged only on what they found.
"""

from __future__ import annotations

import math
from dataclasses import asdict, replace

import numpy as np
import pytest

from lab.planning.real.problems import DrawSettings, RealProblem, draw_problems
from lab.planning.real.runs import (
    BIT_DUBINS,
    BIT_REEDS_SHEPP,
    BIT_ROOM_REEDS_SHEPP,
    SPHEREPLAN,
    RunRecord,
    _record,
    densify,
    run_reference,
    with_reference_lengths,
)
from lab.planning.real.summary import read_real_csv, summarise, write_real_csv
from lab.planning.referee import FootprintReferee
from planner.maps.nav2 import load_map
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from tests.polycheck import brute_collides

ROBOT = load_robot("zju-60")
SMOOTHERS = load_map("maps/real/smoothers_world.yaml")


def _room(width_m: float = 12.0, height_m: float = 6.0, res: float = 0.05) -> np.ndarray:
    """An empty occupancy array of this size (the map's edge is the only obstacle)."""
    return np.zeros((round(height_m / res), round(width_m / res)), dtype=bool)


def test_same_seed_same_problems_other_seed_others() -> None:
    a = draw_problems(SMOOTHERS, ROBOT, 5, np.random.default_rng(11))
    b = draw_problems(SMOOTHERS, ROBOT, 5, np.random.default_rng(11))
    c = draw_problems(SMOOTHERS, ROBOT, 5, np.random.default_rng(12))
    assert a == b
    assert [p.start for p in a] != [p.start for p in c]
    assert [p.index for p in a] == list(range(5)) and all(p.map_name == "smoothers_world" for p in a)


def test_drawn_poses_are_free_for_the_padded_polygon_inside_the_border_and_far_apart() -> None:
    settings = DrawSettings()
    problems = draw_problems(SMOOTHERS, ROBOT, 12, np.random.default_rng(5), settings=settings)
    poly = ROBOT.footprint_polygon
    border_m = settings.border_cells(SMOOTHERS) * SMOOTHERS.resolution_m
    min_d = settings.min_distance_m(SMOOTHERS)
    assert min_d == pytest.approx(3.0)  # 15 m map: 0.2 × 15 m = 3 m, Nav2's own minimum
    w, h = SMOOTHERS.size_m
    for p in problems:
        for pose in (p.start, p.goal):
            assert not brute_collides(SMOOTHERS, poly, np.array(pose), False), p
            assert border_m <= pose[0] <= w - border_m and border_m <= pose[1] <= h - border_m
            assert -math.pi <= pose[2] < math.pi
            # cell centres, like Nav2's cells (which it places at the corner; we use the centre)
            assert (pose[0] / SMOOTHERS.resolution_m) % 1 == pytest.approx(0.5)
        assert p.distance_m == pytest.approx(math.dist(p.start[:2], p.goal[:2]))
        assert p.distance_m >= min_d
    yaws = [p.start[2] for p in problems] + [p.goal[2] for p in problems]
    assert max(yaws) - min(yaws) > math.pi  # spread over the circle, not a constant


def test_min_distance_scales_with_the_map() -> None:
    field = load_map("maps/real/100by100_20.yaml")
    assert DrawSettings().min_distance_m(field) == pytest.approx(20.0)
    assert DrawSettings().border_cells(field) == 100  # Nav2's side_buffer on this very map
    problems = draw_problems(field, ROBOT, 3, np.random.default_rng(0))
    assert all(p.distance_m >= 20.0 for p in problems)


def test_unknown_cells_block_unless_allowed() -> None:
    data = np.full((120, 200), -1, dtype=np.int8)
    data[:, :40] = 0  # a free strip on the left; the rest unknown
    grid = OccupancyGrid(data=data, resolution_m=0.05, name="unknown")
    settings = DrawSettings(border_fraction=0.02, min_distance_floor_m=1.0, min_distance_fraction=0.0)
    strict = draw_problems(grid, ROBOT, 4, np.random.default_rng(1), settings=settings)
    assert all(p.start[0] < 2.0 and p.goal[0] < 2.0 for p in strict)
    lax = draw_problems(grid, ROBOT, 8, np.random.default_rng(1), settings=settings, allow_unknown=True)
    assert any(p.start[0] > 2.0 or p.goal[0] > 2.0 for p in lax)


def test_a_map_with_no_room_for_the_robot_is_bad_input() -> None:
    occ = _room(3.0, 3.0)
    occ[::8, :] = True  # slats 0.35 m apart: no pose fits
    grid = OccupancyGrid.from_occupied(occ, 0.05, name="slats")
    from planner.errors import InvalidInput

    with pytest.raises(InvalidInput, match="could not draw"):
        draw_problems(grid, ROBOT, 1, np.random.default_rng(0),
                      settings=DrawSettings(max_draws=2000, min_distance_floor_m=0.5))


@pytest.mark.parametrize(("gap_m", "split"), [(0.40, True), (1.50, False)])
def test_disconnected_only_when_the_inscribed_disc_cannot_pass(gap_m: float, split: bool) -> None:
    occ = _room(12.0, 6.0)
    occ[:, 118:122] = True  # a wall at x = 5.9–6.1 m ...
    g0 = round((3.0 - gap_m / 2) / 0.05)
    occ[g0:g0 + round(gap_m / 0.05), 118:122] = False  # ... with a gap in the middle
    grid = OccupancyGrid.from_occupied(occ, 0.05, name="wall")
    settings = DrawSettings(min_distance_floor_m=0.5, min_distance_fraction=0.0)
    problems = draw_problems(grid, ROBOT, 30, np.random.default_rng(4), settings=settings)
    across = [p for p in problems if (p.start[0] < 6.0) != (p.goal[0] < 6.0)]
    same = [p for p in problems if (p.start[0] < 6.0) == (p.goal[0] < 6.0)]
    assert across and same
    assert all(p.disconnected == split for p in across)
    assert not any(p.disconnected for p in same)


def _problem(grid: OccupancyGrid, start: tuple[float, float, float], goal: tuple[float, float, float]) -> RealProblem:
    return RealProblem(grid.name, 0, start, goal, math.dist(start[:2], goal[:2]), False)


def test_reference_finds_the_straight_path_on_an_open_map() -> None:
    grid = OccupancyGrid.from_occupied(_room(12.0, 2.0), 0.05, name="open")
    checker = FootprintReferee.for_robot(grid, ROBOT)
    problem = _problem(grid, (2.0, 1.0, 0.0), (10.0, 1.0, 0.0))
    for planner in (BIT_DUBINS, BIT_REEDS_SHEPP):
        rec = run_reference(problem, grid, ROBOT, checker, planner, 0.5)
        assert rec.solved and rec.valid and rec.status == "solved"
        assert rec.length_m == pytest.approx(8.0, abs=1e-6)  # the straight line is the optimum
        assert rec.shift_m == pytest.approx(0.0, abs=1e-9) and rec.first_shift_m >= 0.0
        assert rec.min_clearance_m == pytest.approx(1.0 - 0.37, abs=1e-6)  # 2 m corridor, padded half-width 0.37 m
        assert not rec.reverses


def test_reference_goes_around_a_block_and_a_sealed_goal_stays_unsolved() -> None:
    occ = _room()
    occ[40:80, 100:140] = True  # a 2 m block at x 5–7 m, y 2–4 m, on the straight line
    grid = OccupancyGrid.from_occupied(occ, 0.05, name="block")
    checker = FootprintReferee.for_robot(grid, ROBOT)
    rec = run_reference(_problem(grid, (2.0, 3.0, 0.0), (10.0, 3.0, 0.0)), grid, ROBOT, checker, BIT_DUBINS, 1.5)
    assert rec.solved and rec.valid
    assert 8.5 < rec.length_m < 16.0 and rec.length_m <= rec.first_length_m
    assert 0.0 < rec.min_clearance_m < 1.0
    # a sphere rolling the way round the block pays the shifts of its turns
    assert rec.shift_m > 0.0 and rec.first_shift_m > 0.0
    # with no time to optimise, the final path is the first: its shift is the first solution's
    once = run_reference(_problem(grid, (2.0, 3.0, 0.0), (10.0, 3.0, 0.0)), grid, ROBOT, checker, BIT_DUBINS, 1.5,
                         optimise_s=0.0)
    assert once.solved and once.length_m == once.first_length_m
    assert once.first_shift_m == pytest.approx(once.shift_m, abs=1e-12)

    sealed = occ.copy()
    sealed[10:110, 200:204] = True  # a box around the goal at x = 10–12 m
    sealed[10:14, 200:] = True
    sealed[106:110, 200:] = True
    grid2 = OccupancyGrid.from_occupied(sealed, 0.05, name="sealed")
    rec2 = run_reference(_problem(grid2, (2.0, 3.0, 0.0), (11.0, 3.0, 0.0)), grid2, ROBOT,
                         FootprintReferee.for_robot(grid2, ROBOT), BIT_REEDS_SHEPP, 0.3)
    assert rec2.status == "unsolved" and not rec2.solved and rec2.time_s == 0.3


def test_densify_keeps_the_ends_and_the_spacing() -> None:
    poses = np.array([[0.0, 0.0, 3.0], [1.0, 0.0, -3.0], [1.0, 0.05, -3.0]])
    dense = densify(poses, 0.1)
    assert np.allclose(dense[0], poses[0]) and np.allclose(dense[-1], poses[-1])
    assert np.hypot(*np.diff(dense[:, :2], axis=0).T).max() <= 0.1 + 1e-12
    assert len(dense) == 12
    # the yaw turns the short way through ±π, never through 0
    assert np.all(np.abs(dense[:, 2]) >= 3.0 - 1e-12)


def _rec(problem: int, planner: str, status: str, time_s: float, *, length: float = math.nan,
         clear: float = math.nan, valid: bool = True, disconnected: bool = False,
         reported: float = math.nan) -> RunRecord:
    p = RealProblem("m", problem, (1.0, 1.0, 0.0), (5.0, 1.0, 0.0), 4.0, disconnected)
    return _record(p, planner, status, time_s, 5.0, valid=valid, first_length_m=length, length_m=length,
                   min_clearance_m=clear, reported_clearance_m=reported)


def test_summary_counts_and_medians() -> None:
    records = [
        # 0: everyone solves; sphereplan 10 % longer than the better (Reeds–Shepp) reference
        _rec(0, SPHEREPLAN, "solved", 0.2, length=11.0, clear=0.3, reported=0.05),
        _rec(0, BIT_DUBINS, "solved", 0.4, length=10.5),
        _rec(0, BIT_REEDS_SHEPP, "solved", 0.6, length=10.0),
        # 1: only Reeds–Shepp solves; sphereplan times out
        _rec(1, SPHEREPLAN, "timeout", 5.0),
        _rec(1, BIT_DUBINS, "unsolved", 5.0),
        _rec(1, BIT_REEDS_SHEPP, "solved", 1.0, length=9.0),
        # 2: a free goal refused
        _rec(2, SPHEREPLAN, "goal_refused", 0.001),
        _rec(2, BIT_DUBINS, "solved", 0.3, length=7.0),
        _rec(2, BIT_REEDS_SHEPP, "solved", 0.2, length=7.0),
        # 3: nobody solves, proven disconnected; sphereplan gives up after 0.5 s
        _rec(3, SPHEREPLAN, "no_path", 0.5, disconnected=True),
        _rec(3, BIT_DUBINS, "unsolved", 5.0, disconnected=True),
        _rec(3, BIT_REEDS_SHEPP, "unsolved", 5.0, disconnected=True),
        # 4: sphereplan's path fails the exact check
        _rec(4, SPHEREPLAN, "solved", 0.1, length=5.0, valid=False),
        _rec(4, BIT_DUBINS, "solved", 0.1, length=5.0),
        _rec(4, BIT_REEDS_SHEPP, "solved", 0.1, length=5.0),
    ]
    grid = OccupancyGrid.from_occupied(_room(), 0.05, name="m")
    checkers = {"m": FootprintReferee.for_robot(grid, ROBOT)}
    for reverse, missed, ratio in ((False, 2, 11.0 / 10.5), (True, 3, 11.0 / 10.0)):
        final = with_reference_lengths(records, reverse)
        (s,) = summarise(final, checkers, reverse, {"m": 0.1}, {"m": "240×120"})
        assert (s.problems, s.disconnected, s.bit_dubins, s.bit_reeds_shepp, s.bit_solved) == (5, 1, 3, 4, 4)
        assert (s.sphereplan, s.missed, s.refused_free, s.timeouts, s.bad_paths) == (1, missed, 1, 1, 1)
        assert s.time_p50_s == pytest.approx(0.2) and s.both_sphereplan_p50_s == pytest.approx(0.2)
        assert s.both_bit_first_p50_s == pytest.approx(0.4)  # problem 0: the faster allowed reference (Dubins)
        assert (s.unsolved, s.unsolved_time_p50_s) == (1, 0.5)
        assert s.length_ratio_median == pytest.approx(ratio) and s.length_ratio_max == pytest.approx(ratio)
        assert s.clearance_median_m == pytest.approx(0.3) and s.reported_clearance_median_m == pytest.approx(0.05)
        assert math.isnan(s.shift_share_median) and math.isnan(s.rolled_ratio_median)  # no shifts recorded
        assert math.isnan(s.backwards_share)  # nor metres backwards
    # with shifts: sphereplan's 0.44 m of 11 m; the references as a sphere would roll them, 10.5 + 0.3 (Dubins)
    # and 10.0 + 0.9 (Reeds–Shepp, more turns): the shortest rolled is Dubins's even where Reeds–Shepp is allowed
    shifts = {(0, SPHEREPLAN): 0.44, (0, BIT_DUBINS): 0.3, (0, BIT_REEDS_SHEPP): 0.9}
    records = [replace(r, shift_m=shifts.get((r.problem, r.planner), math.nan)) for r in records]
    for reverse in (False, True):
        (s,) = summarise(with_reference_lengths(records, reverse), checkers, reverse, {"m": 0.1}, {"m": "240×120"})
        assert s.shift_share_median == pytest.approx(0.04) and s.rolled_ratio_median == pytest.approx(11.0 / 10.8)
        assert math.isnan(s.rolled_first_ratio_median) and math.isnan(s.longer_than_rolled_first)  # none recorded
        assert s.longer_than_first == 1.0  # 11 m against first solutions of 10.5 m (and 10.0 m)
    # BIT*'s first solutions as a sphere would roll them (their own shifts, not the final paths'): 10.5 + 0.6
    # (Dubins) and 10.0 + 1.2 (Reeds–Shepp); sphereplan's 11 m is shorter than both, in the car's metric longer
    first_shifts = {(0, SPHEREPLAN): 0.44, (0, BIT_DUBINS): 0.6, (0, BIT_REEDS_SHEPP): 1.2}
    records = [replace(r, first_shift_m=first_shifts.get((r.problem, r.planner), math.nan)) for r in records]
    for reverse in (False, True):
        (s,) = summarise(with_reference_lengths(records, reverse), checkers, reverse, {"m": 0.1}, {"m": "240×120"})
        assert s.rolled_first_ratio_median == pytest.approx(11.0 / 11.1) and s.longer_than_rolled_first == 0.0
        assert s.longer_than_first == 1.0 and s.rolled_ratio_median == pytest.approx(11.0 / 10.8)
    # metres rolled backwards: sphereplan's solved path only (the invalid path of problem 4 is not solved), ÷ length
    backwards = {(0, SPHEREPLAN): 4.4, (4, SPHEREPLAN): 5.0, (0, BIT_REEDS_SHEPP): 10.0}
    records = [replace(r, backwards_m=backwards.get((r.problem, r.planner), math.nan)) for r in records]
    (s,) = summarise(with_reference_lengths(records, True), checkers, True, {"m": 0.1}, {"m": "240×120"})
    assert s.backwards_share == pytest.approx(0.4)


def test_real_figure_marks_unsolvable_and_explains_the_dashed_line() -> None:
    """bench_real.png (issue #13): proved-unsolvable problems labelled, 1.05 line explained, legends outside."""
    from lab.planning.real.figure import real_figure
    from planner.plotstyle import legend_labels

    records = with_reference_lengths([
        _rec(0, SPHEREPLAN, "solved", 0.2, length=11.0, clear=0.3, reported=0.05),
        _rec(0, BIT_DUBINS, "solved", 0.4, length=10.5),
        _rec(1, SPHEREPLAN, "no_path", 0.5, disconnected=True),
        _rec(1, BIT_DUBINS, "unsolved", 5.0, disconnected=True),
    ], False)
    fig = real_figure(records, [], "title")
    labels = legend_labels(fig)
    assert "5 % longer than the reference" in labels
    assert not any("room" in label for label in labels)
    # with the room-matched reference: its own marks, named
    room = real_figure([*records, _rec(0, BIT_ROOM_REEDS_SHEPP, "solved", 0.3, length=10.8, clear=0.31)], [], "t")
    assert f"{BIT_ROOM_REEDS_SHEPP} (BIT*: first solution)" in legend_labels(room)
    assert "roomRS" in room.axes[0].get_title() and "roomRS" in [t.get_text() for t in room.axes[0].texts]
    assert any(label.startswith("unsolvable") for label in labels)
    assert [t.get_text() for t in fig.axes[1].get_xticklabels()] == ["m#0", "m#1 (unsolvable)"]
    fig.canvas.draw()
    for ax in fig.axes:
        legend = ax.get_legend()
        if legend is not None:  # beside the axes, not over the data
            assert legend.get_window_extent().x0 >= ax.get_window_extent().x1


def test_refused_pose_that_truly_collides_is_not_counted_as_refused_free() -> None:
    occ = _room()
    occ[:, :30] = True  # a wall over x < 1.5 m: the goal at (1, 1) below is inside it
    grid = OccupancyGrid.from_occupied(occ, 0.05, name="m")
    p = RealProblem("m", 0, (5.0, 3.0, 0.0), (1.0, 1.0, 0.0), 4.5, False)
    rec = replace(_record(p, SPHEREPLAN, "goal_refused", 0.001, 5.0), map="m")
    (s,) = summarise([rec], {"m": FootprintReferee.for_robot(grid, ROBOT)}, False, {}, {})
    assert s.refused_free == 0


def test_csv_round_trip(tmp_path) -> None:
    records = [_rec(0, SPHEREPLAN, "solved", 0.2, length=11.0, clear=0.3, reported=0.05),
               _rec(0, BIT_DUBINS, "unsolved", 5.0, disconnected=True)]
    records = with_reference_lengths(records, False)
    write_real_csv(records, tmp_path / "r.csv")
    back = read_real_csv(tmp_path / "r.csv")
    for a, b in zip(records, back, strict=True):
        for key, value in asdict(a).items():
            other = getattr(b, key)
            assert type(other) is type(value), key
            assert (value == other) or (isinstance(value, float) and math.isnan(value) and math.isnan(other)), key


def test_a_reference_that_crashes_or_raises_is_recorded_and_the_worker_comes_back() -> None:
    """Each BIT* run happens in a spawned worker: a segfault (as OMPL's second solve() did with --per-map 6
    --seed 21) becomes a 'crashed' record keeping the first solution it reported, an exception an 'error'
    record, and the next run gets a fresh worker."""
    from lab.planning.real.isolated import ReferenceWorker
    from tests.lab.planning import reference_stubs

    grid = OccupancyGrid.from_occupied(_room(4.0, 2.0), 0.05, name="tiny")
    checker = FootprintReferee.for_robot(grid, ROBOT)
    problem = _problem(grid, (1.0, 1.0, 0.0), (3.0, 1.0, 0.0))
    with ReferenceWorker(runner=reference_stubs.segfaults_after_first) as worker:
        rec = worker.run(problem, grid, ROBOT, checker, BIT_DUBINS, 2.0)
        assert (rec.status, rec.solved, rec.planner) == ("crashed", False, BIT_DUBINS)
        assert "SIGSEGV" in rec.message and "after its first solution" in rec.message
        assert (rec.time_s, rec.first_length_m) == (0.012, 7.5)
        assert worker.crashes == 1
        again = worker.run(problem, grid, ROBOT, checker, BIT_REEDS_SHEPP, 2.0)  # a new worker, same fate
        assert again.status == "crashed" and worker.crashes == 2
    with ReferenceWorker(runner=reference_stubs.raises) as worker:
        rec = worker.run(problem, grid, ROBOT, checker, BIT_REEDS_SHEPP, 2.0)
        assert (rec.status, rec.solved) == ("error", False) and "OMPL said no" in rec.message
        assert worker.crashes == 0
    with ReferenceWorker(runner=reference_stubs.solves) as worker:
        first = worker.run(problem, grid, ROBOT, checker, BIT_DUBINS, 2.0)
        second = worker.run(problem, grid, ROBOT, checker, BIT_REEDS_SHEPP, 2.0)
        assert first.solved and second.solved and first.message == second.message  # one worker for both runs


def test_the_bench_survives_reference_failures(monkeypatch: pytest.MonkeyPatch) -> None:
    """run_real_bench with a reference that segfaults (Dubins) and raises (Reeds–Shepp): every sphereplan run
    still happens, the failures are rows with their status, and the table counts them in ``ref×``."""
    from lab.planning.real import bench, isolated
    from lab.planning.real.summary import format_real_table
    from tests.lab.planning import reference_stubs

    class Stubbed(isolated.ReferenceWorker):
        def __init__(self, ompl_seed: int = 1) -> None:
            super().__init__(ompl_seed, runner=reference_stubs.by_planner)

    monkeypatch.setattr(bench, "ReferenceWorker", Stubbed)
    result = bench.run_real_bench(["smoothers_world"], ROBOT, 2, 21, time_limit_s=0.5)
    by_planner = {p: [r for r in result.records if r.planner == p] for p in (SPHEREPLAN, BIT_DUBINS, BIT_REEDS_SHEPP)}
    assert [len(v) for v in by_planner.values()] == [2, 2, 2]
    assert all(r.status == "crashed" and "SIGSEGV" in r.message for r in by_planner[BIT_DUBINS])
    assert all(r.status == "error" for r in by_planner[BIT_REEDS_SHEPP])
    assert all(r.status != "crashed" for r in by_planner[SPHEREPLAN])
    (summary,) = result.summaries
    assert summary.ref_failed == 4 and summary.bit_solved == 0
    assert "ref×" in format_real_table(result.summaries)


def test_repeated_runs_keep_the_median_time_and_the_first_runs_path(monkeypatch: pytest.MonkeyPatch) -> None:
    """--repeat: BIT*'s first solution is timed that many times (the extra runs stop at their first solution) and
    sphereplan's plan as well, each as the first towards its goal; the time kept is the median, the lengths the
    first run's. A repeat below 1 is refused."""
    from lab.planning.real import bench, isolated, runs
    from tests.lab.planning import reference_stubs

    class Stubbed(isolated.ReferenceWorker):
        def __init__(self, ompl_seed: int = 1) -> None:
            super().__init__(ompl_seed, runner=reference_stubs.timed_runs)

    class Clock:  # sphereplan's three runs of the problem take 10, 20 and 60 ms by runs.py's clock
        ticks = iter([0.0, 0.010, 1.0, 1.020, 2.0, 2.060])

        @classmethod
        def perf_counter(cls) -> float:
            return next(cls.ticks)

    forgotten = []
    real_forget = runs.planner_for(SMOOTHERS, ROBOT, bench.PlannerOptions()).forget_heuristics
    monkeypatch.setattr(type(runs.planner_for(SMOOTHERS, ROBOT, bench.PlannerOptions())), "forget_heuristics",
                        lambda self: (forgotten.append(1), real_forget()))
    monkeypatch.setattr(bench, "ReferenceWorker", Stubbed)
    monkeypatch.setattr(runs, "time", Clock)
    result = bench.run_real_bench(["smoothers_world"], ROBOT, 1, 21, time_limit_s=0.5, repeat=3)
    mine, dubins, rs = (next(r for r in result.records if r.planner == p)
                        for p in (SPHEREPLAN, BIT_DUBINS, BIT_REEDS_SHEPP))
    assert mine.solved and mine.time_s == pytest.approx(0.020) and len(forgotten) == 3
    for rec in (dubins, rs):
        # the median of 60 ms (the first run, which optimises after) and 10 and 20 ms (runs that stop at the first)
        assert rec.time_s == pytest.approx(0.020)
        assert rec.first_length_m == 5.0 and rec.length_m == 4.5  # the first run's
    with pytest.raises(ValueError, match="repeat"):
        bench.run_real_bench(["smoothers_world"], ROBOT, 1, 21, repeat=0)


def _car_path(pieces: list[tuple[float, float]], direction: float = 1.0, ds: float = 0.01,
              then_back: list[tuple[float, float]] = ()) -> np.ndarray:
    """Dense poses of a car path from the origin: (curvature, length) pieces rolled in ``direction``, then the
    pieces ``then_back`` rolled the other way (after a cusp)."""
    x = y = yaw = 0.0
    out = [(x, y, yaw)]
    for kappa, length, direction in [(k, s, direction) for k, s in pieces] + [(k, s, -direction) for k, s in then_back]:
        for _ in range(round(length / ds)):
            yaw += direction * kappa * ds  # eq. 1: the heading turns with the signed distance
            x += direction * ds * math.cos(yaw)
            y += direction * ds * math.sin(yaw)
            out.append((x, y, yaw))
    return np.array(out)


def test_a_car_path_rolled_by_the_sphere_pays_a_shift_at_every_turn_end() -> None:
    """A Dubins-like path (straight, left at the sharpest, straight, right, straight) rolled by the sphere changes
    roll four times by φmax: 0 → +φ → 0 → −φ → 0, so 4·r·φmax of sideways shift, whichever way it rolls;
    an arc straight into the opposite arc changes by 2 φmax at once; a straight path pays nothing."""
    from lab.planning.real.runs import rolled_shift_m

    k, phi, r = ROBOT.max_curvature, ROBOT.max_roll_rad, ROBOT.radius_m
    dubins = [(0.0, 2.0), (k, 1.0), (0.0, 1.0), (-k, 0.5), (0.0, 1.0)]
    for direction in (1.0, -1.0):
        assert rolled_shift_m(_car_path(dubins, direction), ROBOT) == pytest.approx(4 * r * phi, rel=1e-3)
    assert rolled_shift_m(_car_path([(k, 1.0), (-k, 1.0)]), ROBOT) == pytest.approx(4 * r * phi, rel=1e-3)
    assert rolled_shift_m(_car_path([(0.0, 3.0)]), ROBOT) == pytest.approx(0.0, abs=1e-9)
    # a cusp keeps the roll: left forwards, then left backwards (the heading turns the other way) is one roll
    assert rolled_shift_m(_car_path([(k, 1.0)], then_back=[(k, 1.0)]), ROBOT) == pytest.approx(2 * r * phi, rel=1e-3)
    half = ROBOT.roll_model.roll_for_curvature(k / 2)  # a gentler arc: its own roll, not the sharpest
    assert rolled_shift_m(_car_path([(0.0, 1.0), (k / 2, 1.0), (0.0, 1.0)]), ROBOT) == pytest.approx(
        2 * r * half, rel=1e-3)


def test_a_repeat_that_runs_out_of_time_is_counted_not_fatal(monkeypatch: pytest.MonkeyPatch) -> None:
    """--repeat on sphereplan: a repeat that fails (here its second run times out) does not end the bench; the
    path is the first run's and the time the median of all three."""
    from lab.planning.real import runs
    from planner.errors import PlannerTimedOut

    calls = []
    real_plan = runs.plan_path

    def flaky(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise PlannerTimedOut("no path found within the time limit", planning_time_s=0.5, expansions=7)
        return real_plan(*args, **kwargs)

    monkeypatch.setattr(runs, "plan_path", flaky)
    checker = FootprintReferee.for_robot(SMOOTHERS, ROBOT)
    problem = draw_problems(SMOOTHERS, ROBOT, 1, np.random.default_rng(4), map_name="smoothers_world",
                            checker=checker)[0]
    rec = runs.run_sphereplan(problem, SMOOTHERS, ROBOT, checker, runs.PlannerOptions(), 5.0, repeat=3)
    assert len(calls) == 3 and rec.solved and rec.status == "solved"


def test_the_search_loops_time_is_the_median_of_the_repeats_as_the_time_is(monkeypatch: pytest.MonkeyPatch) -> None:
    """With --repeat, search_loop_s (the bench's loop exp/s) is the median of the runs' loop times, as time_s is the
    median of their times: not the first run's alone, which follows the reference planner's run."""
    from lab.planning.real import runs

    loops = iter([0.5, 0.1, 0.2])
    real_plan = runs.plan_path

    def timed(*args, **kwargs):
        result = real_plan(*args, **kwargs)
        result.extra["search_loop_time_s"] = next(loops)
        return result

    monkeypatch.setattr(runs, "plan_path", timed)
    checker = FootprintReferee.for_robot(SMOOTHERS, ROBOT)
    problem = draw_problems(SMOOTHERS, ROBOT, 1, np.random.default_rng(4), map_name="smoothers_world",
                            checker=checker)[0]
    rec = runs.run_sphereplan(problem, SMOOTHERS, ROBOT, checker, runs.PlannerOptions(), 5.0, repeat=3)
    assert rec.solved and rec.search_loop_s == 0.2


def test_the_shift_of_held_rolls_counts_every_change_from_upright_and_back() -> None:
    from lab.planning.real import runs

    assert runs.shift_of_rolls(np.array([0.1, -0.2]), 0.3) == pytest.approx(0.3 * (0.1 + 0.3 + 0.2))


def test_summary_expansions_per_metre_is_the_median_over_solved_problems() -> None:
    """Issue 21 item 3: expansions ÷ path length per solved problem (unknown counts and failures left out)."""
    from lab.planning.real.summary import format_real_table

    records = [
        replace(_rec(0, SPHEREPLAN, "solved", 0.2, length=11.0, clear=0.3), expansions=220),  # 20 per metre
        replace(_rec(1, SPHEREPLAN, "solved", 0.1, length=3.0, clear=0.3), expansions=90),  # 30 per metre
        replace(_rec(2, SPHEREPLAN, "solved", 0.1, length=3.0, clear=0.3), expansions=-1),  # unknown: left out
        replace(_rec(3, SPHEREPLAN, "timeout", 5.0), expansions=9000),  # not solved: left out
    ]
    grid = OccupancyGrid.from_occupied(_room(), 0.05, name="m")
    (s,) = summarise(records, {"m": FootprintReferee.for_robot(grid, ROBOT)}, False, {}, {})
    assert s.expansions_per_m == pytest.approx(25.0)
    head, _, row = format_real_table([s]).splitlines()[:3]
    end = head.index("exp/m") + len("exp/m")  # the columns are right-aligned under their heads
    assert row[:end].split()[-1] == "25"


def test_summary_back_is_the_share_of_metres_rolled_backwards_over_all_solved_paths() -> None:
    """Column back: metres backwards ÷ length summed over the solved paths (not a median of shares); a row that
    does not record them (a CSV from before the column) and an unsolved run are left out."""
    from lab.planning.real.summary import format_real_table

    records = [
        replace(_rec(0, SPHEREPLAN, "solved", 0.2, length=10.0, clear=0.3), backwards_m=1.0),
        replace(_rec(1, SPHEREPLAN, "solved", 0.1, length=2.0, clear=0.3), backwards_m=2.0),  # all backwards
        replace(_rec(2, SPHEREPLAN, "solved", 0.1, length=3.0, clear=0.3)),  # not recorded: left out
        replace(_rec(3, SPHEREPLAN, "timeout", 5.0), backwards_m=9.0),  # not solved: left out
    ]
    grid = OccupancyGrid.from_occupied(_room(), 0.05, name="m")
    (s,) = summarise(records, {"m": FootprintReferee.for_robot(grid, ROBOT)}, False, {}, {})
    assert s.backwards_share == pytest.approx(0.25)  # (1 + 2) / (10 + 2); the median of the shares would be 0.55
    head, _, row = format_real_table([s]).splitlines()[:3]
    end = head.index(" back") + len(" back")  # the columns are right-aligned under their heads
    assert row[:end].split()[-1] == "0.25"


def test_summary_loop_expansions_per_second_counts_the_search_loop_time_only() -> None:
    """Issue 21: expansions ÷ the compiled loop's time (what Nav2 reports), beside ÷ the whole planning time."""
    from lab.planning.real.summary import format_real_table

    records = [
        replace(_rec(0, SPHEREPLAN, "solved", 0.2, length=11.0, clear=0.3), expansions=3000, search_loop_s=0.02),
        replace(_rec(1, SPHEREPLAN, "solved", 0.1, length=3.0, clear=0.3), expansions=1000, search_loop_s=0.02),
        replace(_rec(2, SPHEREPLAN, "solved", 0.1, length=3.0, clear=0.3), expansions=500),  # loop time unknown
        replace(_rec(3, SPHEREPLAN, "timeout", 5.0), expansions=9000, search_loop_s=5.0),  # not solved: left out
    ]
    grid = OccupancyGrid.from_occupied(_room(), 0.05, name="m")
    (s,) = summarise(records, {"m": FootprintReferee.for_robot(grid, ROBOT)}, False, {}, {})
    assert s.loop_expansions_per_s == pytest.approx(100_000.0)
    assert s.expansions_per_s == pytest.approx(4500 / 0.4)
    head, _, row = format_real_table([s]).splitlines()[:3]
    end = head.index("loop exp/s") + len("loop exp/s")
    assert row[:end].split()[-1] == "100000"


def test_the_room_matched_reference_is_timed_against_not_counted_as_a_reference() -> None:
    """--room-reference rows: sphereplan's time is divided by theirs (x room), and they count in no BIT* column:
    a problem only they solve is not "missed", their lengths are no reference, their first solutions no ÷first."""
    records = [
        _rec(0, SPHEREPLAN, "solved", 0.02, length=11.0, clear=0.3),
        _rec(0, BIT_REEDS_SHEPP, "solved", 0.001, length=10.0),
        _rec(0, BIT_ROOM_REEDS_SHEPP, "solved", 0.010, length=6.0, reported=0.295),
        _rec(1, SPHEREPLAN, "solved", 0.03, length=8.0, clear=0.1),
        _rec(1, BIT_REEDS_SHEPP, "solved", 0.002, length=8.0),
        _rec(1, BIT_ROOM_REEDS_SHEPP, "solved", 0.060, length=4.0, reported=0.095),
        _rec(2, SPHEREPLAN, "timeout", 5.0),
        _rec(2, BIT_REEDS_SHEPP, "unsolved", 5.0),
        _rec(2, BIT_ROOM_REEDS_SHEPP, "solved", 0.1, length=3.0),  # (never run after a failure; counted anyway)
        _rec(3, SPHEREPLAN, "solved", 0.04, length=5.0, clear=0.2),
        _rec(3, BIT_REEDS_SHEPP, "solved", 0.004, length=5.0),
        _rec(3, BIT_ROOM_REEDS_SHEPP, "crashed", 5.0),
    ]
    grid = OccupancyGrid.from_occupied(_room(), 0.05, name="m")
    (s,) = summarise(with_reference_lengths(records, True), {"m": FootprintReferee.for_robot(grid, ROBOT)}, True,
                     {"m": 0.1}, {"m": "240×120"})
    assert (s.bit_reeds_shepp, s.bit_solved, s.missed, s.sphereplan, s.ref_failed) == (3, 3, 0, 3, 1)
    assert (s.room_runs, s.room_solved) == (4, 3)
    # problems 0 and 1 (sphereplan and the room reference solved): 0.02 / 0.010 = 2 and 0.03 / 0.060 = 0.5
    assert s.room_ratio_median == pytest.approx(1.25) and s.room_ratio_p90 == pytest.approx(1.85)
    assert s.both_ratio_median == pytest.approx(15.0)  # against plain BIT*: 20, 15 and 10
    assert s.first_ratio_median == pytest.approx(1.0) and s.length_ratio_median == pytest.approx(1.0)
    from lab.planning.real.summary import format_real_table

    table = format_real_table([s])
    assert "x room" in table and "3/4" in table and "1.25" in table
    assert "x room" not in format_real_table(summarise(with_reference_lengths(
        [r for r in records if r.planner != BIT_ROOM_REEDS_SHEPP], True), {}, True, {"m": 0.1}, {"m": ""}))


def test_the_room_run_gets_the_grown_checker_and_reports_the_true_clearance(monkeypatch: pytest.MonkeyPatch) -> None:
    """run_real_bench(room_reference=True): the worker's checker is grown by the room asked (the stub reports the
    polygon's circumradius as its clearance), the row reports that room and the grown clearance plus the room, capped
    at the referee's 2 m as every clearance is."""
    from lab.planning.real import bench, isolated
    from lab.planning.real.runs import room_asked_m
    from lab.planning.referee import DEFAULT_REACH_M
    from tests.lab.planning import reference_stubs

    class Stubbed(isolated.ReferenceWorker):
        def __init__(self, ompl_seed: int = 1) -> None:
            super().__init__(ompl_seed, runner=reference_stubs.reports_the_grown_polygon)

    monkeypatch.setattr(bench, "ReferenceWorker", Stubbed)
    result = bench.run_real_bench(["smoothers_world"], ROBOT, 2, 21, time_limit_s=1.0, room_reference=True)
    plain = FootprintReferee.for_robot(SMOOTHERS, ROBOT)
    for i in range(2):
        mine = next(r for r in result.records if r.problem == i and r.planner == SPHEREPLAN)
        room = next(r for r in result.records if r.problem == i and r.planner == BIT_ROOM_REEDS_SHEPP)
        assert mine.solved and room.reported_clearance_m == room_asked_m(mine, ROBOT) > 0
        grown = plain.circumradius_m + room.reported_clearance_m  # what the worker's grown polygon reaches
        expected = DEFAULT_REACH_M if i == 1 else grown + room.reported_clearance_m
        assert room.min_clearance_m == pytest.approx(expected, abs=1e-3)
    with pytest.raises(ValueError, match="reference"):
        bench.run_real_bench(["smoothers_world"], ROBOT, 1, 21, reference=False, room_reference=True)


@pytest.mark.parametrize("prefer_forward", [True, False])
def test_the_metres_rolled_backwards_are_those_the_path_moves_against_its_heading(prefer_forward: bool) -> None:
    """backwards_m (the table's ``back``), the plan's own ``extra.reverse_length_m``, checked against the geometry
    of the poses alone: the steps that move against the heading (more than 120° from it: a roll change shifts the
    sphere sideways, eq. 1, at 90°). depot#20 of the seed-0 draw at 40 a map rolls
    almost all its 23 m backwards, whether the search held its shot back or not; forwards only, nothing."""
    from lab.planning.real import runs

    depot = load_map("maps/real/depot.yaml")
    checker = FootprintReferee.for_robot(depot, ROBOT)
    start, goal = (1.725, 7.575, 3.060120748362473), (24.225, 8.975, -2.3643296132075022)
    problem = RealProblem("depot", 20, start, goal, math.dist(start[:2], goal[:2]), False)
    for options, share in ((runs.PlannerOptions(prefer_forward=prefer_forward), 0.9),
                           (runs.PlannerOptions(allow_reverse=False), 0.0)):
        rec = runs.run_sphereplan(problem, depot, ROBOT, checker, options, 5.0)
        result = runs.plan_path(depot, ROBOT, start, goal, options)
        xy, yaw = result.states[:, :2], result.states[:, 2]
        step = np.diff(xy, axis=0)
        length = np.hypot(step[:, 0], step[:, 1])
        against = step[:, 0] * np.cos(yaw[:-1]) + step[:, 1] * np.sin(yaw[:-1]) < -0.5 * length
        geometric = float(length[against].sum())
        assert rec.solved and rec.backwards_m == pytest.approx(geometric, rel=0.01, abs=1e-6)
        assert rec.backwards_m >= share * rec.length_m
        if share == 0.0:
            assert rec.backwards_m == 0.0
