"""Mesh worlds: band slicing into a grid and the exact fcl re-check, on a hand-made room of known geometry.

The room is a 10 × 6 × 3 m box seen from inside (a cavity, inward normals) with its floor at z = 0;
a 1 × 1 m pillar stands at (5, 3); a 2 × 2 m plate 5 cm high lies at (2, 1.5) (below the default 10 cm
clearance, so the sphere rolls over it); a shelf hangs at z 0.5–1.0 over (8, 1.5) (inside the zju-60
band [0.1, 0.7] m) and a beam at z 1.5–2 over (8, 4.5) (above the band).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import trimesh

from planner.errors import MapError
from planner.maps.load import load_any
from planner.maps.mesh_world import MeshWorld
from planner.maps.nav2 import load_map, save_map
from planner.robot import load_robot


def _box(size: tuple[float, float, float], centre: tuple[float, float, float]) -> trimesh.Trimesh:
    b = trimesh.creation.box(size)
    b.apply_translation(centre)
    return b


def room_mesh(with_plate: bool = True) -> trimesh.Trimesh:
    room = _box((10, 6, 3), (5, 3, 1.5))
    room.invert()
    parts = [room, _box((1, 1, 3), (5, 3, 1.5)), _box((1, 1, 0.5), (8, 1.5, 0.75)),
             _box((1, 1, 0.5), (8, 4.5, 1.75))]
    if with_plate:
        parts.append(_box((2, 2, 0.05), (2, 1.5, 0.025)))
    return trimesh.util.concatenate(parts)


@pytest.fixture(scope="module")
def world() -> MeshWorld:
    return MeshWorld.from_mesh(room_mesh(), floor_z=0.0, name="room")


@pytest.fixture(scope="module")
def robot():  # type: ignore[no-untyped-def]
    return load_robot("zju-60")


def test_band_is_the_lifted_sphere(robot) -> None:  # type: ignore[no-untyped-def]
    assert MeshWorld.band(robot, 0.1) == pytest.approx((0.1, 0.7))


def test_slicing_marks_exactly_the_known_cells(world: MeshWorld, robot) -> None:  # type: ignore[no-untyped-def]
    grid = world.to_grid(0.1, robot)
    assert grid.origin == (-0.2, -0.2, 0.0)
    occ = grid.blocked()

    def at(x: float, y: float) -> bool:
        ix, iy = grid.world_to_cell(x, y)
        return bool(occ[iy, ix])

    # Cells are occupied exactly where their centres lie inside the pillar [4.5, 5.5] x [2.5, 3.5].
    xs = grid.origin[0] + (np.arange(grid.width) + 0.5) * grid.resolution_m
    ys = grid.origin[1] + (np.arange(grid.height) + 0.5) * grid.resolution_m
    X, Y = np.meshgrid(xs, ys)
    pillar = (np.abs(X - 5) < 0.5) & (np.abs(Y - 3) < 0.5)
    shelf = (np.abs(X - 8) < 0.5) & (np.abs(Y - 1.5) < 0.5)
    outside = (X < 0) | (X > 10) | (Y < 0) | (Y > 6)
    assert np.array_equal(occ, pillar | shelf | outside)
    # The low plate and the high beam are not obstacles in the band.
    assert not at(2.0, 1.5) and not at(8.0, 4.5)
    assert at(-0.1, 3.0) and not at(0.05, 3.0)
    assert grid.source["robot"] == "zju-60" and grid.source["floor_z"] == 0.0


def test_solid_only_world_is_free_outside(robot) -> None:  # type: ignore[no-untyped-def]
    world = MeshWorld.from_mesh(_box((1, 1, 2), (0, 0, 1)))
    occ, origin = world.occupied(0.1, robot)
    assert origin == (-0.7, -0.7, 0.0)
    assert occ.sum() == 100  # the 10 x 10 cells under the 1 x 1 m box
    assert not occ[0, 0] and occ[7, 7]


def test_higher_clearance_drops_low_obstacles(robot) -> None:  # type: ignore[no-untyped-def]
    world = MeshWorld.from_mesh(_box((1, 1, 0.3), (0, 0, 0.15)))  # floor = its own bottom, z 0..0.3
    assert world.occupied(0.1, robot, clearance_m=0.1)[0].any()
    assert not world.occupied(0.1, robot, clearance_m=0.35)[0].any()


def test_fcl_free_path_distance_is_the_nearest_gap(robot) -> None:  # type: ignore[no-untyped-def]
    world = MeshWorld.from_mesh(room_mesh(with_plate=False), floor_z=0.0)
    # Along y = 2.1 heading +x the footprint box (half-width 0.35 m) passes the pillar face y = 2.5 at 0.05 m.
    xs = np.linspace(1.0, 4.0, 31) + 0.05
    hit, first, dist = world.path_collides(xs, np.full_like(xs, 2.1), np.zeros_like(xs), robot)
    assert not hit and first is None
    # Nearest: the floor 0.1 m below the lifted sphere, until the pillar comes within 0.05 m.
    xs2 = np.linspace(4.6, 5.4, 9)
    hit2, _, dist2 = world.path_collides(xs2, np.full_like(xs2, 2.1), np.zeros_like(xs2), robot)
    assert not hit2 and dist2 == pytest.approx(0.05, abs=1e-6)
    assert dist == pytest.approx(0.1, abs=1e-6)


def test_fcl_reports_first_colliding_pose(robot) -> None:  # type: ignore[no-untyped-def]
    world = MeshWorld.from_mesh(room_mesh(with_plate=False), floor_z=0.0)
    xs = 1.05 + 0.1 * np.arange(60)
    hit, first, dist = world.path_collides(xs, np.full_like(xs, 3.0), np.zeros_like(xs), robot)
    # The box front (x + 0.3) first passes the pillar face x = 4.5 at x = 4.25 (index 32).
    assert hit and first == 32 and dist == 0.0


def test_fcl_footprint_turns_with_yaw(robot) -> None:  # type: ignore[no-untyped-def]
    world = MeshWorld.from_mesh(room_mesh(with_plate=False), floor_z=0.0)
    # At y = 2.18 the 0.70 m-wide box heading +x reaches y = 2.53 (inside the pillar); turned by 90° its
    # 0.60 m length along y reaches 2.48 and the sphere 2.48 too: free.
    pose = (np.array([5.0]), np.array([2.18]))
    assert world.path_collides(*pose, np.array([0.0]), robot)[0]
    assert not world.path_collides(*pose, np.array([math.pi / 2]), robot)[0]


def test_mesh_files_round_trip_through_load_any(tmp_path: Path, robot) -> None:  # type: ignore[no-untyped-def]
    stl = tmp_path / "room.stl"
    stl.write_bytes(room_mesh().export(file_type="stl"))
    grid = load_any(stl, robot, resolution_m=0.1)
    assert grid.name == "room" and grid.mesh_path == stl.resolve()
    assert grid.mesh_world is not None and grid.mesh_world.path == stl  # the sliced world travels with the grid
    # floor_z defaults to the lowest vertex (the room's floor at z = 0).
    assert grid.source["floor_z"] == 0.0
    saved = save_map(grid, tmp_path / "room.yaml")
    again = load_any(saved)
    assert np.array_equal(again.data, grid.data) and again.mesh_path == stl.resolve()
    assert again.mesh_world is None  # loaded lazily (and cached) by the exact re-check


def test_mesh_errors(tmp_path: Path) -> None:
    with pytest.raises(MapError) as info:
        MeshWorld.from_file(tmp_path / "none.stl")
    assert info.value.field == "mesh"
    (tmp_path / "junk.stl").write_bytes(b"not a mesh at all")
    with pytest.raises(MapError):
        MeshWorld.from_file(tmp_path / "junk.stl")
    with pytest.raises(MapError) as info:
        load_any(tmp_path / "map.txt")
    assert info.value.field == "map"
    with pytest.raises(MapError):
        load_map(tmp_path / "junk.stl")
