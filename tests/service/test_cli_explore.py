"""``sphereplan explore`` end to end on small worlds: a box the map lacks is found and driven around (no
collision, the goal reached, exit 0, plot and MCAP written), a sealed corridor is reported as no path (exit 3,
no collision), and bad input exits 2 naming the option."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from planner.maps.nav2 import save_map
from planner.occupancy import OccupancyGrid
from service.cli import main

RES = 0.05


def corridor(extra: tuple[float, float, float, float] | None = None, name: str = "corridor") -> OccupancyGrid:
    """12 m × 6 m, walls around; ``extra`` = (x0, x1, y0, y1) of a hidden block in metres."""
    occ = np.zeros((120, 240), dtype=bool)
    occ[[0, -1], :] = True
    occ[:, [0, -1]] = True
    if extra is not None:
        x0, x1, y0, y1 = extra
        occ[round(y0 / RES):round(y1 / RES), round(x0 / RES):round(x1 / RES)] = True
    return OccupancyGrid.from_occupied(occ, RES, name=name)


@pytest.fixture()
def maps(tmp_path: Path) -> Path:
    save_map(corridor(), tmp_path / "known.yaml")
    save_map(corridor((5.5, 6.5, 1.8, 4.2), "box"), tmp_path / "box.yaml")
    save_map(corridor((5.8, 6.1, 0.0, 6.0), "sealed"), tmp_path / "sealed.yaml")
    save_map(OccupancyGrid.from_occupied(np.zeros((60, 60), dtype=bool), 0.1), tmp_path / "small.yaml")
    return tmp_path


def explore(maps: Path, world: str, *extra: str) -> list[str]:
    return ["explore", "--map", str(maps / "known.yaml"), "--world", str(maps / world), "--start", "1.5", "3", "0",
            "--goal", "10.5", "3", "0", "--sensor-range", "3", "--tracker", "pursuit", "--seed", "3",
            "--plan-time-limit", "1", "-q", *extra]


def test_hidden_box_is_found_and_driven_around(maps: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(explore(maps, "box.yaml", "--plot", str(maps / "run.png")))
    result = json.loads(capsys.readouterr().out)
    m = result["metrics"]
    assert code == 0 and result["outcome"] == "reached"
    assert m["reached_goal"] and not m["collided"] and m["min_clearance_m"] > 0
    assert m["replans"] >= 1 and result["replans"][1]["reason"] == "blocked"
    assert m["replan_latency_p50_s"] > 0 and m["replan_latency_p95_s"] >= m["replan_latency_p50_s"]
    assert m["length_known_world_m"] is not None and m["length_m"] >= 0.9 * m["length_known_world_m"]
    assert len(result["paths"]) == len(result["replans"])
    end = result["trajectory"][-1]
    assert abs(end["x"] - 10.5) < 0.3 and abs(end["y"] - 3.0) < 0.3
    assert (maps / "run.png").stat().st_size > 10_000
    code = main(explore(maps, "box.yaml", "--out", str(maps / "run.mcap")))
    capsys.readouterr()
    assert code == 0 and (maps / "run.mcap").read_bytes()[:8] == b"\x89MCAP0\r\n"


def test_sealed_corridor_is_no_path(maps: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(explore(maps, "sealed.yaml"))
    result = json.loads(capsys.readouterr().out)
    assert code == 3 and result["outcome"] == "no_path"
    assert not result["metrics"]["collided"] and result["metrics"]["length_known_world_m"] is None
    assert result["replans"][-1]["error_code"] in (207, 208)  # proven, or none found with 4× the time limit


@pytest.mark.parametrize(("world", "extra", "field"), [
    ("missing.yaml", (), "--world"),
    ("small.yaml", (), "--world"),
    ("box.yaml", ("--sensor-range", "500"), "--sensor-range"),
])
def test_bad_input_exits_2_naming_the_option(maps: Path, capsys: pytest.CaptureFixture[str], world: str,
                                             extra: tuple[str, ...], field: str) -> None:
    assert main(explore(maps, world, *extra)) == 2
    assert field in capsys.readouterr().err
