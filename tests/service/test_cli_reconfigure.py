"""``sphereplan reconfigure``: exit codes, the JSON contract, --degrees, --map and --plot."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import service.cli.reconfigure as verb
from planner.occupancy import OccupancyGrid
from planner.spherobot.reconfigure import plan_reconfiguration
from service.cli import main
from tests.reconfigcheck import check_result

EXAMPLE = [
    "reconfigure",
    "--radius",
    "1",
    "--start",
    "4.33",
    "2.5",
    "--start-tilt",
    "30",
    "75",
    "--degrees",
    "--goal",
    "0",
    "0",
    "--alpha-final",
    "180",
]


def _run(capsys, argv):
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse rejects the option before the verb runs
        code = int(exc.code or 0)
    out, err = capsys.readouterr()
    return code, (json.loads(out) if code == 0 and out.strip() else None), err


def test_paper_example_json_contract(capsys):
    code, res, _ = _run(capsys, EXAMPLE)
    assert code == 0
    for key in (
        "radius_m",
        "method",
        "segments",
        "samples",
        "final",
        "length_m",
        "theta_prime_rad",
        "alpha_prime_rad",
    ):
        assert key in res
    assert round(math.degrees(res["theta_prime_rad"]), 1) == 75.6
    assert round(math.degrees(res["alpha_prime_rad"]), 1) == 50.9
    seg = res["segments"][2]
    for key in (
        "kind",
        "action",
        "start",
        "end",
        "heading_rad",
        "length_m",
        "center",
        "radius_m",
        "omega_body_rad_s",
        "omega_xp_rad_s",
        "omega_yp_rad_s",
        "duration_s",
    ):
        assert key in seg
    assert set(res["samples"][0]) == {"t", "x", "y", "qw", "qx", "qy", "qz"}
    check_result(res, (0.0, 0.0), None)


def test_cli_prints_exactly_the_api_result(capsys):
    _, res, _ = _run(capsys, EXAMPLE)
    api = plan_reconfiguration(
        {
            "method": "arc",
            "radius_m": 1.0,
            "start": [4.33, 2.5],
            "start_tilt": [30, 75],
            "degrees": True,
            "goal": [0, 0],
            "alpha_final": 180,
        }
    )
    res.pop("planning_time_s")
    api.pop("planning_time_s")
    assert json.loads(json.dumps(api)) == res


def test_triangle_complete_with_radians_and_out_file(capsys, tmp_path):
    out = tmp_path / "r.json"
    code, _, _ = _run(
        capsys,
        [
            "reconfigure",
            "--method",
            "triangle",
            "--radius",
            "0.3",
            "--start",
            "1",
            "-2",
            "--start-tilt",
            "2.0",
            "-1.0",
            "--start-spin",
            "0.4",
            "--goal",
            "-0.5",
            "0.5",
            "--goal-heading",
            "2.5",
            "--out",
            str(out),
        ],
    )
    assert code == 0
    res = json.loads(out.read_text())
    assert res["method"] == "triangle" and res["mode"] == "complete" and len(res["triangles"]) <= 2
    check_result(res, (-0.5, 0.5), 2.5)


def test_plot_is_written(capsys, tmp_path):
    png = tmp_path / "r.png"
    code, _, _ = _run(capsys, [*EXAMPLE, "--plot", str(png)])
    assert code == 0 and png.stat().st_size > 10_000
    assert png.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize(
    ("extra", "field"),
    [
        (["--start-tilt", "200", "0", "--degrees"], "start_tilt"),
        (["--method", "triangle", "--alpha-final", "1"], "alpha_final"),
        (["--goal-heading", "1", "--alpha-final", "1"], "alpha_final"),
        (["--radius", "-1"], "--radius"),
        (["--start-spin", "nan"], "--start-spin"),
        (["--method", "walk"], "--method"),
    ],
)
def test_bad_input_exits_2_naming_the_field(capsys, extra, field):
    code, _, err = _run(capsys, ["reconfigure", "--start", "0", "0", "--goal", "1", "1", *extra])
    assert code == 2
    assert field in err


def test_alpha_final_towards_f_is_bad_input(capsys):
    code, _, err = _run(
        capsys, ["reconfigure", "--start", "3", "0", "--goal", "0", "0", "--alpha-final", "0"]
    )
    assert code == 2 and "alpha_final" in err


def test_unreadable_map_is_bad_input(capsys, tmp_path):
    code, _, err = _run(
        capsys,
        ["reconfigure", "--start", "0", "0", "--goal", "1", "1", "--map", str(tmp_path / "missing.yaml")],
    )
    assert code == 2 and "map" in err


def _boxed_grid() -> OccupancyGrid:
    res = 0.1
    xs = -4 + (np.arange(120) + 0.5) * res
    X, Y = np.meshgrid(xs, xs)
    free = ((np.abs(X) <= 0.75) & (np.abs(Y) <= 0.75)) | ((X >= 3) & (np.abs(Y) <= 2))
    return OccupancyGrid.from_occupied(~free, res, (-4.0, -4.0, 0.0), name="box")


def test_map_where_everything_collides_exits_3_with_the_reason(capsys, monkeypatch):
    monkeypatch.setattr(verb, "_load_map", lambda path: _boxed_grid())
    code, _, err = _run(
        capsys,
        [
            "reconfigure",
            "--radius",
            "0.5",
            "--start",
            "0",
            "0",
            "--start-tilt",
            "1",
            "0.5",
            "--goal",
            "5",
            "0",
            "--goal-heading",
            "0.3",
            "--map",
            "box.yaml",
        ],
    )
    assert code == 3
    assert "collide" in err and "obstacle" in err


def test_map_with_room_succeeds_and_reports_the_check(capsys, monkeypatch):
    grid = OccupancyGrid.from_occupied(np.zeros((200, 200), bool), 0.1, (-10.0, -10.0, 0.0), name="open")
    monkeypatch.setattr(verb, "_load_map", lambda path: grid)
    code, res, _ = _run(capsys, [*EXAMPLE, "--map", "open.yaml"])
    assert code == 0
    assert res["map"]["name"] == "open" and res["map"]["alternatives_tried"] == 1
    # an empty map: the clearance is the distance to the map's edge, less the radius (within two cells)
    edge = min(min(s["x"] + 10, 10 - s["x"], s["y"] + 10, 10 - s["y"]) for s in res["samples"]) - res["radius_m"]
    assert edge - 2 * 0.1 <= res["map"]["min_clearance_m"] <= edge + 1e-9


def test_start_on_an_obstacle_is_bad_input_like_plan(capsys, monkeypatch):
    monkeypatch.setattr(verb, "_load_map", lambda path: _boxed_grid())
    code, _, err = _run(capsys, ["reconfigure", "--radius", "0.5", "--start", "-3", "-3", "--goal", "0", "0",
                                 "--map", "box.yaml"])
    assert code == 2
    assert "error:" in err and "start" in err and "obstacle" in err
