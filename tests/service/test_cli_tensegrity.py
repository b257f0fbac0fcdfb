"""The ``sphereplan tensegrity`` verb, called in-process."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from service.cli import main


def test_static_prints_four_states(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tensegrity", "static", "--theta1", "45", "--theta2", "10", "--degrees"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["radius_m"] == pytest.approx(0.2015)
    assert set(out["masses"]) == {"M1", "M2", "m1", "m2"}
    assert [s["state"] for s in out["states"]] == [1, 2, 3, 4]
    for s in out["states"]:
        assert {"state", "feasible", "phi1_rad", "phi2_rad", "z_b", "F_r1", "F_r2", "R_sb"} <= set(s)
        assert s["verified"]
    assert out["verified"]
    assert {s["state"] for s in out["states"] if s["feasible"]} == {1, 2}


def test_static_radians_without_verify(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tensegrity", "static", "--theta1", str(math.pi / 4), "--theta2", "0.2", "--no-verify"]) == 0
    assert "energy_minima" not in json.loads(capsys.readouterr().out)


def test_static_bad_angle_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tensegrity", "static", "--theta1", "200", "--theta2", "10", "--degrees"]) == 2
    assert "theta1" in capsys.readouterr().err


def test_gait_writes_json_and_plot(tmp_path: Path) -> None:
    out, png = tmp_path / "g.json", tmp_path / "g.png"
    assert (
        main(
            [
                "tensegrity",
                "gait",
                "--distance",
                "0.8",
                "--steps",
                "12",
                "--out",
                str(out),
                "--plot",
                str(png),
            ]
        )
        == 0
    )
    result = json.loads(out.read_text())
    assert result["net_displacement_m"] == pytest.approx(0.8)
    # "forward 0.8 m" is towards +x in the world frame
    assert result["steps"][-1]["centre_m"][0] - result["steps"][0]["centre_m"][0] == pytest.approx(0.8)
    assert result["state_sequence"][:2] == [1, 3]
    assert png.stat().st_size > 10_000


def test_gait_bad_input_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tensegrity", "gait", "--distance", "0", "--out", str(tmp_path / "g.json")]) == 2
    assert "distance" in capsys.readouterr().err
    assert main(["tensegrity", "gait", "--distance", "1"]) == 2
    assert "out" in capsys.readouterr().err


def test_formfind(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tensegrity", "formfind", "--fix-centre", "--starts", "2"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert len(out["cables"]) == 12
    assert out["rotation_error_deg_vs_eq3"] < 1e-3


def test_static_process_loads_no_scipy() -> None:
    """``tensegrity static`` as a process stays under 1 s CPU: it must not import scipy, numba or matplotlib
    (scipy.interpolate alone took ~0.4 s of start-up, via planner.robot)."""
    import subprocess
    import sys

    repo = Path(__file__).resolve().parents[2]
    code = (
        "import sys, io, contextlib\n"
        "from service.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    assert main(['tensegrity', 'static', '--theta1', '60', '--theta2', '10', '--degrees']) == 0\n"
        "heavy = {'scipy', 'numba', 'matplotlib', 'casadi'}\n"
        "print(sorted(heavy & {m.split('.')[0] for m in sys.modules}))\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], cwd=repo, capture_output=True, text=True, check=True)
    assert proc.stdout.strip().splitlines()[-1] == "[]"
