"""Open any map file by its extension: a ROS map_server YAML grid or a mesh world sliced over the robot's band."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from planner.errors import MapError
from planner.maps.nav2 import MESH_SUFFIXES, YAML_SUFFIXES, load_map
from planner.occupancy import OccupancyGrid

if TYPE_CHECKING:
    from planner.robot import RobotProfile


def load_any(path: str | Path, robot: RobotProfile | None = None, resolution_m: float = 0.1) -> OccupancyGrid:
    """Load a map by extension: ``.yaml/.yml`` → :func:`load_map`; ``.stl/.obj/.ply`` → a sliced mesh world.

    For meshes the robot (default ``zju-60``) sets the height band that is sliced and ``resolution_m``
    the cell size; ``grid.source["mesh"]`` holds the mesh path so that paths can be re-checked exactly
    with :class:`planner.maps.mesh_world.MeshWorld`.
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix in YAML_SUFFIXES:
        return load_map(p)
    if suffix in MESH_SUFFIXES:
        from planner.maps.mesh_world import MeshWorld

        return MeshWorld.from_file(p).to_grid(resolution_m, robot)
    raise MapError("map", f"{p.name}: unknown map type {suffix!r} (use .yaml/.yml or .stl/.obj/.ply)")


def mesh_path_of(grid: OccupancyGrid) -> Path | None:
    """The mesh a grid was sliced from (``mesh`` key of its YAML, relative to the YAML), or None."""
    mesh = grid.source.get("mesh")
    if not mesh:
        return None
    mesh_path = Path(str(mesh))
    if not mesh_path.is_absolute() and grid.source.get("yaml_path"):
        mesh_path = Path(str(grid.source["yaml_path"])).parent / mesh_path
    return mesh_path
