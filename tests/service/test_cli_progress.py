"""The command line's cross-cutting behaviour: progress and summaries on stderr only, -q, --degrees."""

from __future__ import annotations

import io
import json
import math
from collections.abc import Iterator
from pathlib import Path

import pytest

from planner.robot import load_robot
from planner.synthetic_paths import circle_plan
from service.cli import _io as cli_io
from service.cli import build_parser, main
from service.cli import plan as plan_verb


@pytest.fixture(autouse=True)
def _reset_verbosity() -> Iterator[None]:
    yield
    cli_io.set_verbosity(0)


def test_stages_write_one_line_per_stage_off_a_terminal_and_nothing_with_q() -> None:
    stream = io.StringIO()
    with cli_io.Stages("demo", ["load", "work"], stream=stream) as stages:
        stages.start("load")
        stages.start("work")
    assert stream.getvalue().splitlines() == ["sphereplan demo: [1/2] load", "sphereplan demo: [2/2] work"]
    cli_io.set_verbosity(-1)
    quiet = io.StringIO()
    with cli_io.Stages("demo", ["load"], stream=quiet) as stages:
        stages.start("load")
    assert quiet.getvalue() == ""


def test_verbose_adds_stage_times() -> None:
    cli_io.set_verbosity(1)
    stream = io.StringIO()
    with cli_io.Stages("demo", ["a", "b"], stream=stream) as stages:
        stages.start("a")
        stages.start("b")
    lines = stream.getvalue().splitlines()
    assert "previous stage" in lines[1] and lines[-1].startswith("sphereplan demo: done in")


def test_json_on_stdout_stays_clean_and_q_silences_stderr(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["-q", "vpip", "radius", "--roll", "10", "--degrees"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["roll_rad"] == pytest.approx(math.radians(10)) and err == ""
    assert main(["vpip", "-q", "radius", "--roll", "10", "--degrees"]) == 0  # -q after the verb too
    assert capsys.readouterr().err == ""


def test_talk_flags_after_a_sub_verb_work_like_before_the_verb(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """``sphereplan vpip schedule … -q`` (issue #13): the flags after the sub-verb, on every sub-verb."""
    parser = build_parser()
    for argv in (["vpip", "radius", "--roll", "10"], ["tensegrity", "static", "--theta1", "1", "--theta2", "1"],
                 ["vpip", "schedule", "--path", "p.json", "--out", "s.json"],
                 ["tensegrity", "gait", "--distance", "1", "--out", "g.json"]):
        assert parser.parse_args([*argv, "-q"]).quiet is True
        assert parser.parse_args([*argv, "-vv"]).verbose == 2
        assert parser.parse_args(["-q", *argv]).quiet is True  # before the verb: unchanged
        assert parser.parse_args(["-v", *argv]).verbose == 1  # a sub-verb's copy does not reset it
    out = tmp_path / "g.json"
    assert main(["tensegrity", "gait", "--distance", "0.3", "--steps", "4", "--out", str(out), "-q"]) == 0
    assert capsys.readouterr().err == "" and out.is_file()
    assert main(["tensegrity", "gait", "--distance", "0.3", "--steps", "4", "--out", str(out)]) == 0
    assert "plan the gait" in capsys.readouterr().err


def test_plan_degrees_reads_yaw_in_degrees() -> None:
    args = build_parser().parse_args(
        ["plan", "--map", "m.yaml", "--start", "0", "0", "90", "--goal", "1", "1", "-180", "--degrees"]
    )
    query = plan_verb._query(args)
    assert query.start[2] == pytest.approx(math.pi / 2) and query.goal[2] == pytest.approx(-math.pi)
    plain = plan_verb._query(build_parser().parse_args(
        ["plan", "--map", "m.yaml", "--start", "0", "0", "1.5", "--goal", "1", "1", "0"]))
    assert plain.start[2] == 1.5


def test_every_angle_taking_command_has_degrees() -> None:
    parser = build_parser()
    for argv in (["plan", "--map", "m", "--start", "0", "0", "0", "--goal", "1", "1", "0"],
                 ["reconfigure", "--start", "0", "0", "--goal", "1", "1"],
                 ["vpip", "rods", "--phi-vpip", "0", "--theta-vpip", "0"], ["vpip", "radius", "--roll", "1"],
                 ["tensegrity", "static", "--theta1", "1", "--theta2", "1"],
                 ["tensegrity", "gait", "--distance", "1", "--corner", "45"]):
        assert parser.parse_args([*argv, "--degrees"]).degrees is True


def test_vpip_schedule_uses_daedalus_not_the_plans_robot(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(circle_plan(load_robot("zju-60"), 1.2, 0.2)))  # a zju-60 plan: no [vpip]
    out = tmp_path / "sched.json"
    code = main(["-q", "vpip", "schedule", "--path", str(plan), "--out", str(out)])
    capsys.readouterr()
    assert code == 0 and json.loads(out.read_text())["robot"] == "daedalus"


def test_vpip_schedule_that_does_not_reach_the_end_exits_3_and_says_so(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """The README's garage U-turn, forward only: daedalus cannot follow its turns and runs out of time."""
    maps = Path(__file__).resolve().parents[2] / "maps"
    plan = tmp_path / "plan.json"
    assert main(["-q", "plan", "--map", str(maps / "garage.yaml"), "--start", "12", "8.05", "0", "--goal", "12",
                 "23.55", "180", "--degrees", "--forward-only", "--out", str(plan)]) == 0
    out = tmp_path / "sched.json"
    code = main(["-q", "vpip", "schedule", "--path", str(plan), "--out", str(out)])
    stdout, stderr = capsys.readouterr()
    summary = json.loads(stdout)
    assert code == 3 and not summary["reached_end"] and out.is_file()
    assert "did not reach the end of the path" in stderr
