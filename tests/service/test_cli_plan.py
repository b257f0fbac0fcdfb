"""``sphereplan plan``: exit codes, JSON contract, plot."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from planner.maps.catalogue import default_maps_dir
from service.cli import main

GARAGE = str(default_maps_dir() / "garage.yaml")
REPO = Path(__file__).resolve().parents[2]


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_plan_prints_the_result_contract(capsys, tmp_path):
    png = tmp_path / "plan.png"
    code, out, _ = run(capsys, "plan", "--map", GARAGE, "--start", "3.5", "8.05", "0", "--goal", "20", "8.05", "0",
                       "--plot", str(png))
    assert code == 0
    data = json.loads(out)
    assert data["status"] == "exact" and data["error_code"] == 0
    for key in ("planning_time_s", "length_m", "expansions", "robot", "states", "path"):
        assert key in data
    assert {"radius_m", "max_roll_rad", "footprint_length_m", "footprint_width_m"} <= set(data["robot"])
    assert set(data["states"][0]) == {"x", "y", "yaw", "roll", "v", "t", "s", "curvature"}
    assert data["path"]["header"]["frame_id"] == "map"
    assert len(data["path"]["poses"]) == len(data["states"])
    assert png.stat().st_size > 10_000


def test_out_file_and_robot_option(capsys, tmp_path):
    out = tmp_path / "p.json"
    code, stdout, _ = run(capsys, "plan", "--map", GARAGE, "--start", "3.5", "8.05", "0", "--goal", "12", "8.05", "0",
                          "--robot", "daedalus", "--out", str(out))
    assert code == 0 and stdout == ""
    assert json.loads(out.read_text())["robot"]["name"] == "daedalus"


@pytest.mark.parametrize(
    ("argv", "field"),
    [
        (["--start", "3.5", "8.05", "nan", "--goal", "12", "8.05", "0"], "--start"),
        (["--start", "3.5", "8.05", "0", "--goal", "12", "8.05"], "--goal"),
        (["--start", "3.5", "8.05", "0", "--goal", "12", "8.05", "0", "--robot", "nope"], "robot"),
        (["--start", "3.5", "8.05", "0", "--goal", "12", "8.05", "0", "--time-limit", "-1"], "--time-limit"),
        (["--start", "3.5", "8.05", "0", "--goal", "12", "8.05", "0", "--options", "{\"n_rolls\": 2}"], "n_rolls"),
        (["--start", "-50", "8.05", "0", "--goal", "12", "8.05", "0"], "start"),
        (["--start", "3.5", "8.05", "0", "--goal", "0.05", "0.05", "0"], "goal"),
    ],
)
def test_bad_input_exits_2_naming_the_field(capsys, argv, field):
    code, _, err = run(capsys, "plan", "--map", GARAGE, *argv) if "--map" not in argv else (None, "", "")
    assert code == 2
    assert field in err
    assert "Traceback" not in err


def test_missing_map_and_bad_map(capsys, tmp_path):
    code, _, err = run(capsys, "plan", "--map", str(tmp_path / "none.yaml"), "--start", "1", "1", "0",
                       "--goal", "2", "2", "0")
    assert code == 2 and "map" in err
    bad = tmp_path / "bad.yaml"
    bad.write_text("image: x.pgm\nresolution: -1\norigin: [0, 0, 0]\n")
    code, _, err = run(capsys, "plan", "--map", str(bad), "--start", "1", "1", "0", "--goal", "2", "2", "0")
    assert code == 2 and "resolution" in err


def test_no_path_exits_3_and_timeout_exits_4(capsys):
    code, out, err = run(capsys, "plan", "--map", GARAGE, "--start", "20", "23.55", "0", "--goal", "12.5", "28.3", "0")
    assert code == 3 and json.loads(out)["error_code"] == 208 and "no path" in err
    code, out, _ = run(capsys, "plan", "--map", GARAGE, "--start", "12", "8.05", "0", "--goal", "12", "23.55", "3.1416",
                       "--time-limit", "0.001", "--options", "{\"greed\": 0.0, \"chunk_expansions\": 10}")
    failed = json.loads(out)
    assert code == 4 and failed["error_code"] == 207
    # a failed result reports the time and expansions it really spent
    assert failed["planning_time_s"] > 0 and failed["expansions"] >= 10


def test_first_plan_with_an_empty_compile_cache_succeeds_within_the_default_limit(tmp_path):
    """The one-off numba compilation happens before the search's clock starts (README's first command)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba-cache")}
    proc = subprocess.run(
        [sys.executable, "-m", "service.cli", "plan", "--map", GARAGE, "--start", "12", "8.05", "0", "--goal", "12",
         "23.55", "3.1416"], capture_output=True, text=True, env=env, timeout=1800, cwd=REPO)
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout)
    assert result["status"] == "exact"
    assert any((tmp_path / "numba-cache").rglob("*.nbi"))  # it really compiled into the empty cache


def test_version_flag_prints_the_package_version(capsys) -> None:
    import planner
    from service.cli import main

    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"sphereplan {planner.__version__}"


@pytest.mark.parametrize(
    ("endpoints", "exit_code", "words"),
    [
        (["--start", "12", "8.05", "0", "--goal", "12", "16.0", "1.57"], 2, "goal in collision"),
        (["--start", "-50", "8.05", "0", "--goal", "12", "8.05", "0"], 2, "start outside the map"),
        (["--start", "20", "23.55", "0", "--goal", "12.5", "28.3", "0"], 3, "no path exists"),
    ],
)
def test_failed_plan_still_writes_the_plot(capsys, tmp_path, monkeypatch, endpoints, exit_code, words):
    """Issue #13: --plot on exit 2/3 draws start and goal footprints, the colliding one red with its cells."""
    from planner.hybrid_astar import plot as plan_plot
    from planner.plotstyle import legend_labels

    figures = []
    make = plan_plot.plan_figure

    def keep(*args, **kwargs):
        figures.append(make(*args, **kwargs))
        return figures[-1]

    monkeypatch.setattr(plan_plot, "plan_figure", keep)
    png = tmp_path / "fail.png"
    code, _, _ = run(capsys, "plan", "--map", GARAGE, *endpoints, "--plot", str(png))
    assert code == exit_code and png.stat().st_size > 10_000
    fig = figures[-1]
    labels = legend_labels(fig)
    assert words in fig.axes[0].get_title()
    assert {"free", "occupied", "unknown (blocked)"} <= set(labels)
    assert any(label.startswith("start footprint") for label in labels)
    assert any(label.startswith("goal footprint") for label in labels)
    if words == "goal in collision":
        assert "goal footprint (in collision)" in labels
        assert any(label.startswith("blocked cells it overlaps") for label in labels)
    if words == "start outside the map":
        assert "start footprint (outside the map)" in labels and "outside the map" in labels
    if exit_code == 3:
        assert not any("in collision" in label for label in labels)
