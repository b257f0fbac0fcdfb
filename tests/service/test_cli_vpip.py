"""``sphereplan vpip`` in-process: exit codes and JSON."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from planner.robot import load_robot
from planner.synthetic_paths import circle_plan
from planner.vpip.api import rods_report
from service.cli import main


def _run(capsys: pytest.CaptureFixture[str], argv: list[str]) -> tuple[int, dict]:
    code = main(argv)
    out = capsys.readouterr().out
    return code, (json.loads(out) if code == 0 else {})


def test_rods_prints_the_api_result(capsys: pytest.CaptureFixture[str]) -> None:
    code, out = _run(
        capsys,
        [
            "vpip",
            "rods",
            "--phi-vpip",
            "5",
            "--theta-vpip",
            "20",
            "--roll",
            "2",
            "--pitch-phase",
            "10",
            "--degrees",
        ],
    )
    assert code == 0
    assert out == rods_report(math.radians(5), math.radians(20), math.radians(2), math.radians(10))
    assert len(out["rods"]) == 16 and {r["side"] for r in out["rods"]} == {"left", "right"}
    assert set(out["params"]) >= {"r_m", "r_s", "l_max"}


def test_radius_and_roll(capsys: pytest.CaptureFixture[str]) -> None:
    code, out = _run(capsys, ["vpip", "radius", "--roll", "15", "--degrees"])
    assert code == 0 and out["radius_m"] == pytest.approx(0.85)
    code, out = _run(capsys, ["vpip", "roll", "--radius", "1.0"])
    assert code == 0 and out["roll_deg"] == pytest.approx(10.0, abs=1e-4)
    code, out = _run(capsys, ["vpip", "radius", "--roll", "0"])
    assert code == 0 and out["radius_m"] is None


def test_bad_input_exits_2(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    for argv in (
        ["vpip", "rods", "--phi-vpip", "nan", "--theta-vpip", "0"],
        ["vpip", "roll", "--radius", "-1"],
    ):
        assert main(argv) == 2
    assert main(["vpip", "rods", "--phi-vpip", "100", "--theta-vpip", "0", "--degrees"]) == 2
    assert main(["vpip", "rods", "--phi-vpip", "0", "--theta-vpip", "0", "--robot", "zju-60"]) == 2
    assert (
        main(["vpip", "schedule", "--path", str(tmp_path / "none.json"), "--out", str(tmp_path / "o.json")])
        == 2
    )
    bad = tmp_path / "bad.json"
    bad.write_text('{"states": [{"x": 0}]}')
    assert main(["vpip", "schedule", "--path", str(bad), "--out", str(tmp_path / "o.json")]) == 2
    err = capsys.readouterr().err
    assert "path.states" in err


def test_calibrate_writes_a_loadable_profile(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    runs = tmp_path / "runs.csv"
    runs.write_text("roll_deg,diameter_m\n4,3.0\n8,2.2\n12,1.8\n")
    prof = tmp_path / "mine.toml"
    code, out = _run(capsys, ["vpip", "calibrate", "--runs", str(runs), "--out", str(prof)])
    assert code == 0 and out["roll_model"]["diameter_m"] == pytest.approx([3.0, 2.2, 1.8])
    mine = load_robot(str(prof))
    assert mine.roll_model.turning_radius(math.radians(8)) == pytest.approx(1.1)
    assert mine.extra["vpip"] == load_robot("daedalus").extra["vpip"]
    bad = tmp_path / "bad.csv"
    bad.write_text("roll,d\n1,2\n")
    assert main(["vpip", "calibrate", "--runs", str(bad)]) == 2


def test_schedule_writes_series_and_plot(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(circle_plan(load_robot("daedalus"), 1.2, 0.2)))
    out_json, png = tmp_path / "sched.json", tmp_path / "sched.png"
    code, summary = _run(
        capsys, ["vpip", "schedule", "--path", str(plan), "--out", str(out_json), "--plot", str(png)]
    )
    assert code == 0 and summary["reached_end"]
    result = json.loads(out_json.read_text())
    assert result["driver"] == "vpip" and "surrogate" in result["plant"]["note"]
    assert len(result["series"]["rod_length_m"][0]) == 16
    assert png.stat().st_size > 10_000


def test_circle_verb_and_calibrate_from_its_output(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    outs = []
    for roll in ("5", "15"):
        out = tmp_path / f"c{roll}.json"
        code, summary = _run(
            capsys,
            ["vpip", "circle", "--roll-deg", roll, "--plant", "surrogate", "--duration", "20", "--out", str(out)],
        )
        assert code == 0 and summary["plant"] == "surrogate" and "table" in summary["diameter_source"]
        # the surrogate turns by the profile's own table: its circle reproduces the table (circular by design)
        want = 2 * load_robot("daedalus").roll_model.turning_radius(math.radians(float(roll)))
        assert summary["diameter_m"] == pytest.approx(want, rel=0.1)
        assert summary["commanded_rod_rate"]["max_m_s"] <= 0.1 + 1e-9
        # every circle run splits its turn; the surrogate's spin is what its table implies beyond the lean
        assert "implied" in summary["spin_source"] and summary["held_roll_deg"] == summary["mean_roll_deg"]
        assert summary["mean_spin_rad_s"] + summary["mean_no_spin_yaw_rate_rad_s"] == pytest.approx(
            summary["mean_yaw_rate_rad_s"]
        )
        held = math.radians(summary["held_roll_deg"])
        assert summary["no_spin_diameter_m"] == pytest.approx(2 * 0.232 / math.tan(held))
        assert summary["mean_spin_rad_s"] > 0  # the paper's table is tighter than 2r/tan(roll)
        outs.append(str(out))
    # --heading-deg only turns the start: on the surrogate the same circle, started 90 deg to the left
    out = tmp_path / "c15h.json"
    code, turned = _run(
        capsys,
        [
            *("vpip", "circle", "--roll-deg", "15", "--plant", "surrogate", "--duration", "20"),
            *("--heading-deg", "90", "--out", str(out)),
        ],
    )
    assert code == 0 and turned["start_heading_rad"] == pytest.approx(math.pi / 2)
    assert turned["diameter_m"] == pytest.approx(summary["diameter_m"], rel=1e-6)
    series = json.loads(out.read_text())["series"]
    assert series["yaw"][0] == pytest.approx(math.pi / 2)
    prof = tmp_path / "cal.toml"
    code, cal = _run(capsys, ["vpip", "calibrate", "--circles", *outs, "--out", str(prof)])
    assert code == 0 and cal["roll_model"]["roll_deg"] == [5.0, 15.0]
    assert load_robot(str(prof)).roll_model.kind == "calibrated"


def test_circle_and_calibrate_bad_input_exit_2(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    out = str(tmp_path / "c.json")
    assert main(["vpip", "circle", "--roll-deg", "40", "--out", out]) == 2
    assert "roll" in capsys.readouterr().err
    assert main(["vpip", "circle", "--roll-deg", "5", "--duration", "-3", "--out", out]) == 2
    assert main(["vpip", "circle", "--roll-deg", "5", "--plant", "gazebo", "--out", out]) == 2
    assert main(["vpip", "calibrate"]) == 2
    assert "runs" in capsys.readouterr().err
    assert main(["vpip", "calibrate", "--rolls", "5,abc"]) == 2
    assert "rolls" in capsys.readouterr().err
    bad = tmp_path / "bad.json"
    bad.write_text('{"summary": {"roll_desired_deg": 5, "diameter_m": null}}')
    assert main(["vpip", "calibrate", "--circles", str(bad)]) == 2
    assert "circles[0].summary.diameter_m" in capsys.readouterr().err


def test_circle_and_calibrate_take_a_contact_setting(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    """``--contact paper`` reaches the MuJoCo model and the summary carries the spin/lean split (issue 24)."""
    out = tmp_path / "c.json"
    code, summary = _run(
        capsys,
        ["vpip", "circle", "--roll-deg", "10", "--duration", "3", "--contact", "paper", "--out", str(out)],
    )
    assert code == 0 and summary["contact"] == "paper" and summary["gains"] == "rod-rate"
    for key in ("diameter_m", "mean_omega_rad_s", "mean_roll_deg", "mean_spin_rad_s", "no_spin_diameter_m"):
        assert key in summary
    written = json.loads(out.read_text())
    assert written["plant"]["ground_friction"] == 100.0 and written["plant"]["ground_torsional_friction_m"] == 0.0
    assert written["summary"]["held_roll_deg"] == summary["mean_roll_deg"]
    code, table1 = _run(
        capsys,
        [*("vpip", "circle", "--roll-deg", "10", "--duration", "3", "--gains", "table1"), "--out", str(out)],
    )
    assert code == 0 and table1["contact"] == "regolith" and table1["gains"] == "table1"
    assert json.loads(out.read_text())["plant"]["ground_torsional_friction_m"] == pytest.approx(0.03)
    # calibrate --rolls runs its circles on the contact asked for and says so beside the table
    prof = tmp_path / "paper.toml"
    code, cal = _run(
        capsys,
        [*("vpip", "calibrate", "--rolls", "15", "--duration", "8", "--contact", "paper"), "--out", str(prof)],
    )
    assert code == 0 and cal["contact"] == "paper" and cal["roll_model"]["roll_deg"] == [15.0]
    assert [c["contact"] for c in cal["circles"]] == ["paper"]
    assert cal["roll_model"]["diameter_m"] == [cal["circles"][0]["diameter_m"]]
    assert load_robot(str(prof)).roll_model.turning_radius(math.radians(15)) == pytest.approx(
        cal["roll_model"]["diameter_m"][0] / 2
    )
    # a name the profile does not offer is refused by the door, naming the flag
    assert main(["vpip", "circle", "--roll-deg", "10", "--contact", "gazebo", "--out", str(out)]) == 2
    assert "--contact" in capsys.readouterr().err
