"""``sphereplan maps`` lists the shipped maps and problems; bad folders and problem sets exit 2."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from planner.maps.catalogue import default_maps_dir
from service.cli import main

MAPS = Path(__file__).resolve().parents[2] / "maps"


def run_json(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, dict]:
    code = main(argv)
    out = capsys.readouterr().out
    return code, (json.loads(out) if code == 0 else {})


def test_lists_shipped_maps_and_problems(capsys: pytest.CaptureFixture[str]) -> None:
    code, result = run_json(["maps", "--json"], capsys)
    assert code == 0
    maps = {m["file"]: m for m in result["maps"]}
    assert {"garage.yaml", "maze.yaml", "field.yaml", "bench20.yaml", "cave.yaml", "cave.stl"} <= set(maps)
    assert maps["garage.yaml"]["size_m"] == [40.0, 30.0] and maps["garage.yaml"]["resolution_m"] == 0.05
    assert maps["garage.yaml"]["kind"] == "grid"
    assert maps["cave.stl"]["kind"] == "mesh" and maps["cave.stl"]["resolution_m"] is None
    assert maps["cave.yaml"]["mesh"] == "cave.stl"
    assert all("error" not in m for m in result["maps"])
    problems = result["problems"]
    shipped = {"garage.yaml", "maze.yaml", "field.yaml", "bench20.yaml", "cave.yaml"}
    assert {p["map"] for p in problems} == shipped
    assert any(not p["solvable"] for p in problems) and any(p["solvable"] for p in problems)
    assert Path(result["maps_dir"]) == MAPS


def test_env_var_and_option_choose_the_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    shutil.copy(MAPS / "maze.yaml", tmp_path)
    shutil.copy(MAPS / "maze.pgm", tmp_path)
    monkeypatch.setenv("SPHEREPLAN_MAPS", str(tmp_path))
    assert default_maps_dir() == tmp_path
    code, result = run_json(["maps", "--json"], capsys)
    assert code == 0 and [m["name"] for m in result["maps"]] == ["maze"] and result["problems"] == []
    code, result = run_json(["maps", "--json", "--maps", str(MAPS)], capsys)
    assert code == 0 and len(result["maps"]) >= 6


def test_missing_folder_exits_2(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["maps", "--maps", str(tmp_path / "nope")]) == 2
    assert "maps:" in capsys.readouterr().err
    monkeypatch.setenv("SPHEREPLAN_MAPS", str(tmp_path / "gone"))
    assert main(["maps"]) == 2
    assert "SPHEREPLAN_MAPS" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("problem", "field"),
    [
        ({"map": "m.yaml", "start": [0, 0, 0], "goal": [1, 1, 0], "solvable": True,
          "time_limit_s": 1}, "name"),
        ({"name": "a", "map": "m.yaml", "start": [0, 0], "goal": [1, 1, 0], "solvable": True,
          "time_limit_s": 1}, "start"),
        ({"name": "a", "map": "m.yaml", "start": [0, 0, 0], "goal": [1, 1, 0], "solvable": "yes",
          "time_limit_s": 1}, "solvable"),
        ({"name": "a", "map": "m.yaml", "start": [0, 0, 0], "goal": [1, 1, 0], "solvable": True,
          "time_limit_s": -1}, "time_limit_s"),
        ({"name": "a", "map": "other.yaml", "start": [0, 0, 0], "goal": [1, 1, 0], "solvable": True,
          "time_limit_s": 1}, "map"),
    ],
)
def test_bad_problem_set_names_the_field(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], problem: dict, field: str
) -> None:
    (tmp_path / "problems").mkdir()
    (tmp_path / "m.yaml").write_text("image: m.pgm\n")
    (tmp_path / "problems" / "p.json").write_text(json.dumps([problem]))
    assert main(["maps", "--maps", str(tmp_path)]) == 2
    assert f"problems[0].{field}" in capsys.readouterr().err


def test_unreadable_map_is_listed_with_an_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "broken.yaml").write_text("image: missing.pgm\nresolution: 0.1\n")
    code, result = run_json(["maps", "--json", "--maps", str(tmp_path)], capsys)
    assert code == 0 and "error" in result["maps"][0]


def test_maps_prints_a_table_by_default(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["maps", "--maps", str(MAPS)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == f"maps in {MAPS.resolve()}"
    assert lines[1].split()[:3] == ["map", "file", "kind"]
    garage = next(line for line in lines if line.startswith("garage "))
    assert "40 × 30" in garage and "0.05" in garage


def test_binary_stl_bounds_read_directly_match_the_mesh_loader() -> None:
    from planner.maps.catalogue import _binary_stl_bounds
    from planner.maps.mesh_world import MeshWorld

    lo, hi = _binary_stl_bounds(MAPS / "cave.stl")
    assert [lo.tolist(), hi.tolist()] == MeshWorld.from_file(MAPS / "cave.stl").mesh.bounds.tolist()
