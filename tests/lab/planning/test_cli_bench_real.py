"""``sphereplan bench --suite real``: on a small map with tiny budgets it writes the documented CSV, a PNG and
a table, and exits 0; bad input exits 2."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import pytest

from lab.planning.real.problems import real_map_names
from lab.planning.real.runs import CSV_COLUMNS
from service.cli import main

DOCUMENTED_COLUMNS = (
    "map", "problem", "start_x", "start_y", "start_yaw", "goal_x", "goal_y", "goal_yaw", "distance_m",
    "disconnected", "planner", "status", "solved", "time_s", "time_limit_s", "first_length_m", "length_m",
    "reference_length_m", "length_ratio", "min_clearance_m", "reported_clearance_m", "valid", "reverses",
    "expansions", "message", "search_loop_s", "shift_m", "first_shift_m", "backwards_m",
)


def test_documented_columns_are_the_csv_columns() -> None:
    assert CSV_COLUMNS == DOCUMENTED_COLUMNS
    doc = (Path(__file__).resolve().parents[3] / "docs" / "planning.md").read_text()
    section = doc[doc.index("## The real-map benchmark"):]
    for column in DOCUMENTED_COLUMNS:
        assert f"`{column}`" in section, column
    assert {"warehouse", "depot", "smoothers_world", "100by100_20"} <= set(real_map_names())


def test_the_default_draw_is_at_least_60_problems_over_6_maps() -> None:
    import argparse

    from service.cli import bench

    parser = argparse.ArgumentParser()
    bench.add_arguments(parser)
    args = parser.parse_args(["--suite", "real"])
    assert len(real_map_names()) >= 6 and args.per_map * len(real_map_names()) >= 60
    assert args.seed == 0 and args.reference_time is None  # seeded; BIT* gets the documented 3 s budget


def test_real_suite_on_a_small_map(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out_csv, out_png = tmp_path / "real.csv", tmp_path / "real.png"
    code = main(["bench", "--suite", "real", "--real-maps", "smoothers_world", "--per-map", "2", "--seed", "3",
                 "--time-limit", "0.3", "--csv", str(out_csv), "--png", str(out_png)])
    assert code == 0
    captured = capsys.readouterr()
    assert "smoothers_world" in captured.out and "BIT*RS" in captured.out and "missed" in captured.out
    assert "÷rolled" in captured.out and ">1st rolled" in captured.out and " back" in captured.out
    assert "\r" not in captured.err  # progress bars only on a terminal (stderr is captured here)
    with out_csv.open() as fh:
        reader = csv.DictReader(fh)
        assert tuple(reader.fieldnames or ()) == DOCUMENTED_COLUMNS
        rows = list(reader)
    assert len(rows) == 6
    assert sorted((r["problem"], r["planner"]) for r in rows) == sorted(
        (str(i), p) for i in range(2) for p in ("sphereplan", "bitstar-dubins", "bitstar-reeds-shepp"))
    for r in rows:
        assert r["map"] == "smoothers_world" and float(r["time_limit_s"]) == 0.3
        assert math.dist((float(r["start_x"]), float(r["start_y"])), (float(r["goal_x"]), float(r["goal_y"]))) >= 3.0
        assert r["solved"] in ("True", "False") and r["status"]
        if r["solved"] == "True":
            assert float(r["length_m"]) > 0 and float(r["min_clearance_m"]) >= 0
            assert 0.0 <= float(r["shift_m"]) < float(r["length_m"])  # every path here turns somewhere
            assert float(r["shift_m"]) > 0.0
    assert out_png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out_png.stat().st_size > 20_000


def test_real_suite_without_reference_and_with_options(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out_csv = tmp_path / "real.csv"
    code = main(["bench", "--suite", "real", "--real-maps", "smoothers_world", "--per-map", "1", "--time-limit",
                 "0.2", "--no-reference", "--options", '{"allow_reverse": true}', "--csv", str(out_csv),
                 "--png", str(tmp_path / "real.png")])
    assert code == 0
    assert "reversing sphereplan" in capsys.readouterr().out
    with out_csv.open() as fh:
        assert [r["planner"] for r in csv.DictReader(fh)] == ["sphereplan"]


def test_real_suite_with_the_room_matched_reference(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """--room-reference: on every problem sphereplan solved, BIT* on its space with the footprint grown by the room
    sphereplan's path keeps (at most the preferred 0.3 m, less 5 mm): the row records that room, and a path it finds
    keeps it by the exact polygon."""
    out_csv = tmp_path / "real.csv"
    code = main(["bench", "--suite", "real", "--real-maps", "smoothers_world", "--per-map", "2", "--seed", "3",
                 "--time-limit", "0.5", "--reference-time", "0.5", "--room-reference", "--csv", str(out_csv),
                 "--png", str(tmp_path / "real.png")])
    assert code == 0
    out = capsys.readouterr().out
    assert "x room" in out and "keeping sphereplan's room" in out
    with out_csv.open() as fh:
        rows = list(csv.DictReader(fh))
    mine = {r["problem"]: r for r in rows if r["planner"] == "sphereplan"}
    room = {r["problem"]: r for r in rows if r["planner"] == "bitstar-room-reeds-shepp"}
    assert room and set(room) == {p for p, r in mine.items() if r["solved"] == "True"}
    for p, r in room.items():
        asked = float(r["reported_clearance_m"])
        assert asked == pytest.approx(max(0.0, min(0.3, float(mine[p]["min_clearance_m"])) - 0.005), abs=1e-12)
        if r["solved"] == "True":
            assert float(r["min_clearance_m"]) >= asked - 0.002 * asked - 1e-9
            assert float(r["first_length_m"]) > 0


@pytest.mark.parametrize(("argv", "field"), [
    (["--room-reference", "--no-reference"], "--room-reference"),
    (["--room-reference", "--robot", "{robot}"], "--room-reference"),
    (["--per-map", "0"], "--per-map"),
    (["--real-maps", "atlantis"], "--real-maps"),
    (["--real-maps", "nowhere/map.yaml"], "--real-maps"),
    (["--options", "{not json"], "--options"),
    (["--options", '{"warp": 9}'], "options.warp"),
    (["--reference-time", "-1"], "--reference-time"),
    (["--repeat", "0"], "--repeat"),
])
def test_real_suite_bad_input_exits_2(argv: list[str], field: str, capsys: pytest.CaptureFixture[str],
                                      tmp_path: Path) -> None:
    robot = tmp_path / "arrow.toml"  # a footprint that is not convex cannot be grown by a room
    zju = (Path(__file__).resolve().parents[3] / "planner" / "robots" / "zju-60.toml").read_text()
    robot.write_text(zju.replace('name = "zju-60"', 'name = "arrow"\n'
                                 'footprint = [[0.45, 0.0], [-0.3, 0.35], [-0.1, 0.0], [-0.3, -0.35]]'))
    assert main(["bench", "--suite", "real", *[a.replace("{robot}", str(robot)) for a in argv]]) == 2
    assert field in capsys.readouterr().err


def test_time_limit_must_be_positive(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "--suite", "real", "--time-limit", "0"]) == 2
    assert "--time-limit" in capsys.readouterr().err
