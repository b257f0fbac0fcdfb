"""``sphereplan controllers`` in-process: the result JSON, the plot, bad input exiting 2 naming the field."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from service.cli import main


def test_step_writes_json_and_plot(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out, png = tmp_path / "step.json", tmp_path / "step.png"
    code = main(["controllers", "step", "--controller", "lmpc", "--speed", "0.5", "--duration", "3",
                 "--out", str(out), "--plot", str(png)])
    assert code == 0
    res = json.loads(out.read_text())
    for key in ("rise_time_s", "overshoot", "settling_time_s", "steady_state_error", "series"):
        assert key in res
    assert res["controller"] == "lmpc" and res["floor"] == "tiled"
    assert set(res["series"][0]) == {"t", "v", "v_ref", "pitch", "torque"}
    assert res["series"][-1]["t"] == pytest.approx(3.0)
    assert 0.3 < res["rise_time_s"] < 1.5
    assert png.stat().st_size > 10_000
    summary = json.loads(capsys.readouterr().out)
    assert "series" not in summary and summary["rise_time_s"] == res["rise_time_s"]


def test_roll_step_prints_json(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["controllers", "roll", "--controller", "pid", "--speed", "0.5", "--roll", "6", "--degrees",
                 "--duration", "2"])
    assert code == 0
    res = json.loads(capsys.readouterr().out)
    assert res["roll_rad"] == pytest.approx(0.10472, abs=1e-5)
    assert set(res["series"][0]) == {"t", "roll", "roll_ref", "pendulum_roll", "torque", "v"}


@pytest.mark.parametrize(
    ("argv", "field"),
    [
        (["step", "--controller", "lmpc", "--speed", "9"], "speed"),
        (["step", "--controller", "lmpc", "--speed", "0"], "speed"),
        (["step", "--controller", "pid", "--speed", "0.5", "--floor", "ice"], "floor"),
        (["step", "--controller", "lmpc", "--speed", "0.5", "--robot", "daedalus"], "dynamics"),
        (["roll", "--controller", "rslqr", "--speed", "1", "--roll", "0.5"], "roll"),
        (["roll", "--controller", "rslqr", "--speed", "1", "--roll", "nan"], "--roll"),
        (["step", "--controller", "mpc", "--speed", "1"], "--controller"),
        (["figures", "--out-dir", "/dev/null/folder"], "--out-dir"),  # a missing folder is made; a file in the way
        (["patrol", "--goal", "3.5", "8.05", "0"], "goal"),
    ],
)
def test_bad_input_exits_2_naming_the_field(argv: list[str], field: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["controllers", *argv]) == 2
    assert field in capsys.readouterr().err
