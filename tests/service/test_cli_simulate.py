"""``sphereplan simulate`` in-process: exit codes, SIM.json shape, plot, bad input naming the field."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from planner.maps.nav2 import save_map
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from planner.synthetic_paths import s_curve_plan
from service.cli import main
from tests.contracts import SIM_METRIC_KEYS


@pytest.fixture
def field_map(tmp_path: Path) -> str:
    """A real map file (ROS YAML + PGM) of an open 8 m × 6 m field."""
    grid = OccupancyGrid.from_occupied(np.zeros((120, 160), dtype=bool), 0.05, (-2.0, -2.0, 0.0))
    return str(save_map(grid, tmp_path / "field.yaml"))


@pytest.fixture
def plan_file(tmp_path: Path) -> str:
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(s_curve_plan(load_robot("zju-60"))))
    return str(path)


def test_simulate_a_plan_writes_sim_json_and_plot(field_map: str, plan_file: str, tmp_path: Path) -> None:
    out, png = tmp_path / "sim.json", tmp_path / "sim.png"
    code = main(
        [
            "simulate",
            "--map",
            field_map,
            "--path",
            plan_file,
            "--seed",
            "3",
            "--noise",
            "none",
            "--out",
            str(out),
            "--plot",
            str(png),
        ]
    )
    assert code == 0
    sim = json.loads(out.read_text())
    assert SIM_METRIC_KEYS <= set(sim["metrics"])
    assert sim["metrics"]["final_position_error_m"] < 0.03 and not sim["metrics"]["collided"]
    assert {"trajectory", "estimate", "commands"} <= set(sim)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_track_without_map(tmp_path: Path) -> None:
    out = tmp_path / "track.json"
    code = main(["simulate", "--track", "--tracker", "pursuit", "--time-limit", "4", "--out", str(out)])
    assert code == 3  # stopped after 4 simulated seconds, short of the lap's end: written, and said to have failed
    sim = json.loads(out.read_text())
    assert sim["status"] == "failed" and "stopped at 4.0 s" in sim["error_msg"]
    assert sim["metrics"]["duration_s"] == pytest.approx(4.0)
    assert sim["metrics"]["mpc_solve_ms_p50"] is None  # no MPC ran


@pytest.mark.parametrize(
    ("argv", "field"),
    [
        (["--path", "missing.json"], "path"),
        (["--path", "{bad}"], "path"),
        (["--path", "{failed}"], "path"),
        (["--path", "{plan}"], "map"),
        (["--track", "--corner-radius", "0.5"], "corner_radius_m"),
        (["--track", "--robot", "no-such-robot"], "robot"),
        ([], "path"),
    ],
)
def test_bad_input_exits_2_naming_the_field(
    argv: list[str], field: str, tmp_path: Path, plan_file: str, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    failed = tmp_path / "failed.json"
    failed.write_text(json.dumps({"status": "failed", "error_code": 208, "states": []}))
    subst = {"{bad}": str(bad), "{failed}": str(failed), "{plan}": plan_file}
    args = [subst.get(a, a) for a in argv]
    assert main(["simulate", *args, "--out", str(tmp_path / "o.json")]) == 2
    assert f"{field}:" in capsys.readouterr().err


def test_argparse_rejects_bad_noise_and_seed() -> None:
    for argv in (["--noise", "loud"], ["--seed", "-1"], ["--rate", "0"]):
        assert main(["simulate", "--track", *argv]) == 2
