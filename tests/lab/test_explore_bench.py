"""A small subset of the exploration sweep: the worlds are built as described (hidden cells on the known
route, the start and goal kept clear) and explored with the right outcome."""

from __future__ import annotations

import json

import numpy as np
import pytest

from lab.explore_bench import format_table, run_world
from lab.explore_worlds import KEEP_CLEAR_M, build_world, pinned_segments, spec_key, sweep_specs
from planner.closed_loop.explore import ExploreOptions
from planner.robot import load_robot

ROBOT = load_robot()


def test_sweep_has_at_least_20_worlds_of_every_kind_on_shipped_and_real_maps() -> None:
    specs = sweep_specs()
    assert len(specs) >= 20 and len({s.name for s in specs}) == len(specs)
    assert {s.kind for s in specs} == {"boxes", "aisle", "door"}
    assert any("/real/" in s.map for s in specs) and any("/real/" not in s.map for s in specs)


@pytest.mark.parametrize("pinned", [True, False], ids=["pinned", "made-afresh"])
def test_world_hides_obstacles_on_the_route_only(pinned) -> None:
    spec = next(s for s in sweep_specs() if s.name == "field-around-boxes")
    world = build_world(spec, ROBOT, pinned=pinned)
    added = world.true.data != world.known.data
    assert world.hidden_cells == int(added.sum()) > 0
    assert np.all(world.true.data[added] == 100)
    iy, ix = np.nonzero(added)
    xy = np.stack([ix, iy], axis=1) * world.known.resolution_m
    for end in (spec.start, spec.goal):
        assert np.hypot(*(xy - end[:2]).T).min() > KEEP_CLEAR_M


def test_the_sweep_worlds_are_pinned_data(tmp_path) -> None:
    """Every world's hidden obstacles are read from lab/explore_worlds.json (``python -m lab.explore_worlds --pin``),
    not put on a route planned now: a planner change does not move a door to where a detour remains. An entry made
    for another problem is not used."""
    for spec in sweep_specs():
        assert pinned_segments(spec), spec.name
    spec = next(s for s in sweep_specs() if s.name == "bench-around-door")
    segments = pinned_segments(spec)
    other = dict(spec_key(spec), start=[17.0, 4.5, 1.5707963267948966])
    path = tmp_path / "pinned.json"
    path.write_text(json.dumps({spec.name: {"spec": other, "segments": segments}}))
    assert pinned_segments(spec, path) is None
    path.write_text(json.dumps({spec.name: {"spec": spec_key(spec), "segments": segments}}))
    assert pinned_segments(spec, path) == segments


def test_subset_explored_with_the_right_outcome() -> None:
    options = ExploreOptions(tracker="pursuit")
    rows = [run_world(s, ROBOT, options) for s in sweep_specs() if s.name in ("field-around-boxes",
                                                                              "bench-around-door")]
    assert [r.has_path for r in rows] == [True, False]
    for r in rows:
        assert r.correct, (r.spec.name, r.outcome, r.metrics)
    table = format_table(rows, {"test": [0.001, 0.002]})
    assert "right outcome in 2/2" in table
    # every replan is counted under its reason, and the table says why each world replanned
    for r in rows:
        assert sum(r.metrics["replan_reasons"].values()) == r.metrics["replans"]
        assert r.metrics["replans_failed"] <= r.metrics["replans"]
    replanned = [r for r in rows if r.metrics["replans"]]
    assert replanned
    for r in replanned:
        line = next(ln for ln in table.splitlines() if ln.startswith(r.spec.name))
        assert all(f"{k} {v}" in line for k, v in r.metrics["replan_reasons"].items())


def test_the_cli_says_what_the_sweep_found(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    """`sphereplan bench --suite explore` exits with the sweep's own code (1 when a world's outcome is wrong, not
    0), names a --problems that matches no world, and refuses --csv / --png, which the suite does not write."""
    import lab.explore_bench as explore_bench
    from service.cli import main

    asked = []

    def sweep(robot_name: str | None = None, tracker: str = "mpc", only: str = "", quiet: bool = False) -> int:
        asked.append(only)
        return 1  # a world collided

    monkeypatch.setattr(explore_bench, "main", sweep)
    assert main(["bench", "--suite", "explore", "--problems", "garage-lane1-boxes"]) == 1
    assert asked == ["garage-lane1-boxes"]
    assert main(["bench", "--suite", "explore", "--problems", "no-such-world"]) == 2
    assert "--problems" in capsys.readouterr().err
    for flag in ("--csv", "--png"):
        assert main(["bench", "--suite", "explore", flag, "out.file"]) == 2
        assert flag in capsys.readouterr().err
    assert main(["bench", "--suite", "mpc", "--csv", "mpc.csv"]) == 2
    assert asked == ["garage-lane1-boxes"]  # no sweep ran for the refused calls
