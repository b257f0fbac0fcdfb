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
    the cell size; the grid carries the loaded :class:`planner.maps.mesh_world.MeshWorld` so that paths are
    re-checked exactly against it without reading the mesh again.
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix in YAML_SUFFIXES:
        return load_map(p)
    if suffix in MESH_SUFFIXES:
        from planner.maps.mesh_world import MeshWorld

        return MeshWorld.from_file(p).to_grid(resolution_m, robot)
    raise MapError("map", f"{p.name}: unknown map type {suffix!r} (use .yaml/.yml or .stl/.obj/.ply)")
