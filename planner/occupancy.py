"""The occupancy grid every planner consumes, in the convention of ``nav_msgs/OccupancyGrid``.

``data[iy, ix]`` holds 0..100 (occupancy probability in percent) or −1 (unknown). Row ``iy = 0`` is the
*bottom* of the map (y = origin y), i.e. the image read by the loader is flipped so that rows grow with
y (REP-103). Cell (ix, iy) covers [ox + ix·res, ox + (ix+1)·res) × [oy + iy·res, oy + (iy+1)·res).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from planner.errors import MapError

if TYPE_CHECKING:
    from planner.robot import RobotProfile


class ExactWorld(Protocol):
    """The exact geometry a grid was sliced from (:class:`planner.maps.mesh_world.MeshWorld`): it re-checks a
    path against the real surfaces. Declared here so the grid can carry one without importing the mesh code."""

    def path_collides(self, xs: np.ndarray, ys: np.ndarray, yaws: np.ndarray, robot: RobotProfile,
                      clearance_m: float = ..., distance_every: int = ...) -> tuple[bool, int | None, float]: ...

OCCUPIED = 100
FREE = 0
UNKNOWN = -1


@dataclass(frozen=True, eq=False)
class OccupancyGrid:
    """A 2-D occupancy grid in the ``map`` frame.

    Parameters
    ----------
    data : int8 array (height, width); 0..100 or −1, row 0 at the bottom.
    resolution_m : cell side in metres (> 0).
    origin : (x, y, yaw) of the lower-left corner of cell (0, 0) in metres / radians.
    occupied_threshold : a cell with ``data >= occupied_threshold`` blocks the robot (percent).
    name : label used in results and plots.
    source : free-form metadata from the file it came from (YAML fields), kept for round-trips.
    mesh_path : the mesh world this grid was sliced from (absolute), if any: plans on it are re-checked
        exactly against that mesh.
    mesh_world : the loaded mesh world itself when the grid was sliced in this process (saves reading the
        mesh again for the re-check); None when only ``mesh_path`` is known.
    """

    data: np.ndarray
    resolution_m: float
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    occupied_threshold: int = 65
    name: str = "map"
    source: dict[str, Any] = field(default_factory=dict)
    mesh_path: Path | None = None
    mesh_world: ExactWorld | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.resolution_m) and self.resolution_m > 0):
            raise MapError("resolution", f"must be a finite number > 0, got {self.resolution_m!r}")
        if self.data.ndim != 2 or self.data.size == 0:
            raise MapError("image", f"must be a non-empty 2-D grid, got shape {self.data.shape}")
        if len(self.origin) != 3 or not all(math.isfinite(v) for v in self.origin):
            raise MapError("origin", f"must be three finite numbers [x, y, yaw], got {self.origin!r}")

    @classmethod
    def from_occupied(
        cls, occupied: np.ndarray, resolution_m: float, origin: tuple[float, float, float] = (0.0, 0.0, 0.0),
        name: str = "map",
    ) -> OccupancyGrid:
        """Build a grid from a boolean array (row 0 at the bottom): True = occupied, False = free."""
        data = np.where(np.asarray(occupied, dtype=bool), OCCUPIED, FREE).astype(np.int8)
        return cls(data=data, resolution_m=float(resolution_m), origin=origin, name=name)

    @property
    def height(self) -> int:
        return int(self.data.shape[0])

    @property
    def width(self) -> int:
        return int(self.data.shape[1])

    @property
    def size_m(self) -> tuple[float, float]:
        return self.width * self.resolution_m, self.height * self.resolution_m

    def blocked(self, allow_unknown: bool = False) -> np.ndarray:
        """Boolean (height, width) array: True where the robot may not be (occupied, or unknown unless allowed)."""
        occ = self.data >= self.occupied_threshold
        if not allow_unknown:
            occ = occ | (self.data < 0)
        return occ

    def world_to_cell(self, x: float, y: float) -> tuple[int, int]:
        """(ix, iy) of the cell containing world point (x, y); may lie outside the grid."""
        return (
            math.floor((x - self.origin[0]) / self.resolution_m),
            math.floor((y - self.origin[1]) / self.resolution_m),
        )

    def contains(self, x: float, y: float) -> bool:
        ix, iy = self.world_to_cell(x, y)
        return 0 <= ix < self.width and 0 <= iy < self.height

    def metadata(self) -> dict[str, Any]:
        """Map metadata as results and ``GET /v1/maps/{name}`` report it."""
        return {
            "name": self.name,
            "resolution_m": self.resolution_m,
            "width": self.width,
            "height": self.height,
            "origin": list(self.origin),
            "size_m": list(self.size_m),
        }
