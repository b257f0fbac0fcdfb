"""Shipped maps equal what tools/generate_maps.py makes, load by the nav2 rules, and their problems make sense."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage

from planner.maps.mesh_world import MeshWorld
from planner.maps.nav2 import load_map
from planner.maps.problems import list_problems, load_problem_set
from planner.robot import load_robot
from tools import generate_maps

MAPS = Path(__file__).resolve().parents[2] / "maps"
EXPECTED = {  # name: (width cells, height cells, resolution)
    "garage": (800, 600, 0.05),
    "maze": (400, 400, 0.05),
    "field": (600, 400, 0.05),
    "bench20": (400, 400, 0.05),
}


def test_regenerating_gives_byte_identical_files(tmp_path: Path) -> None:
    written = generate_maps.generate(tmp_path, with_preview=False)
    assert "cave.stl" in written and "problems/garage.json" in written
    for name in written:
        assert (tmp_path / name).read_bytes() == (MAPS / name).read_bytes(), f"{name} differs"


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_shipped_grid_sizes(name: str) -> None:
    grid = load_map(MAPS / f"{name}.yaml")
    width, height, res = EXPECTED[name]
    assert (grid.width, grid.height, grid.resolution_m) == (width, height, res)
    assert grid.origin == (0.0, 0.0, 0.0)
    assert set(np.unique(grid.data).tolist()) <= {0, 100}


def test_cave_grid_comes_from_its_mesh() -> None:
    grid = load_map(MAPS / "cave.yaml")
    assert grid.resolution_m == 0.1 and grid.source["robot"] == "zju-60"
    mesh = grid.mesh_path
    assert mesh == (MAPS / "cave.stl").resolve()
    w, h = grid.size_m
    assert 50 <= w <= 65 and 35 <= h <= 45
    world = MeshWorld.from_file(mesh)
    sliced = world.to_grid(0.1, load_robot("zju-60"), clearance_m=float(grid.source["clearance_m"]))
    assert np.array_equal(sliced.data, grid.data)


def _clearance(blocked: np.ndarray, res: float) -> np.ndarray:
    free = np.pad(~blocked, 1, constant_values=False)
    return ndimage.distance_transform_edt(free)[1:-1, 1:-1] * res


def test_problem_sets_are_sensible() -> None:
    problems = list_problems(MAPS)
    by_map: dict[str, list] = {}
    for p in problems:
        by_map.setdefault(p.map, []).append(p)
    assert set(by_map) == {"garage.yaml", "maze.yaml", "field.yaml", "bench20.yaml", "cave.yaml"}
    for map_file, items in by_map.items():
        solvable = [p for p in items if p.solvable]
        assert 3 <= len(solvable) <= 5, map_file
        assert len(items) - len(solvable) >= 2, map_file
        grid = load_map(MAPS / map_file)
        dist = _clearance(grid.blocked(), grid.resolution_m)
        wide, _ = ndimage.label(dist >= 0.45)
        narrow, _ = ndimage.label(dist > 0.25)
        for p in items:
            (sx, sy), (gx, gy) = (grid.world_to_cell(*p.start[:2]), grid.world_to_cell(*p.goal[:2]))
            assert dist[sy, sx] >= 0.8 and dist[gy, gx] >= 0.8, p.name
            assert all(-np.pi <= yaw < np.pi for yaw in (p.start[2], p.goal[2])), p.name  # OMPL's SO2
            if p.solvable:
                assert wide[sy, sx] == wide[gy, gx] != 0, p.name
            else:
                assert narrow[sy, sx] != narrow[gy, gx], p.name


def test_cave_problem_poses_are_clear_of_the_mesh() -> None:
    robot = load_robot("zju-60")
    world = MeshWorld.from_file(MAPS / "cave.stl")
    poses = [pose for p in load_problem_set(MAPS / "problems" / "cave.json") for pose in (p.start, p.goal)]
    xs, ys, yaws = (np.array(v) for v in zip(*poses, strict=True))
    hit, first, dist = world.path_collides(xs, ys, yaws, robot)
    assert not hit and first is None and dist > 0.05
