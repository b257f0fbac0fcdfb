"""The grids requests plan on: map files and inline grids, cached per process, and a map as a PNG.

A worker process keeps the last few grids it loaded, keyed by file (and modification time) or by the
content of an inline grid, so repeated requests on a map hand the planner the same grid object and reuse
the Hybrid A* planner it cached for that grid (:func:`planner.hybrid_astar.plan.plan_path`).
"""

from __future__ import annotations

import hashlib
import io
import re
import threading
from collections import OrderedDict
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from planner.errors import InvalidInput, MapError, SpherePlanError
from planner.maps.nav2 import MESH_SUFFIXES, snap_resolution
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile, load_robot

if TYPE_CHECKING:
    from service.wire import InlineGrid

_GRIDS: OrderedDict[tuple[Any, ...], OccupancyGrid] = OrderedDict()
_GRID_CACHE_SIZE = 8
_GRID_LOCK = threading.Lock()


def _cached(key: tuple[Any, ...], make: Callable[[], OccupancyGrid]) -> OccupancyGrid:
    with _GRID_LOCK:
        grid = _GRIDS.get(key)
        if grid is not None:
            _GRIDS.move_to_end(key)
            return grid
    grid = make()
    with _GRID_LOCK:
        _GRIDS[key] = grid
        while len(_GRIDS) > _GRID_CACHE_SIZE:
            _GRIDS.popitem(last=False)
    return grid


_ABSOLUTE_PATH = re.compile(r"/[^\s'\"]+")


def read_map(path: Path | str, robot: RobotProfile | None, field: str = "map",
             hide_paths: bool = False) -> OccupancyGrid:
    """:func:`planner.maps.load.load_any`, with every way a map file can fail to load (a bad image, an
    image too large to decode, an unreadable file) raised as a :class:`MapError` naming ``field``; with
    ``hide_paths`` (the service: the client named the map, not its file) absolute paths in the message are
    cut down to file names."""
    from PIL import Image

    from planner.maps.load import load_any

    try:
        return load_any(path, robot)
    except SpherePlanError as exc:
        if not hide_paths:
            raise
        error: SpherePlanError = exc
    except (Image.DecompressionBombError, OSError, ValueError, MemoryError) as exc:
        error = MapError(field, f"map file {Path(path).name} cannot be loaded: {type(exc).__name__}: {exc}")
    if not hide_paths:
        raise error

    def hide(text: str) -> str:
        return _ABSOLUTE_PATH.sub(lambda m: Path(m.group()).name, text)

    if isinstance(error, InvalidInput):
        raise type(error)(error.field, hide(error.msg)) from None
    raise MapError(field, hide(str(error))) from None


def load_map_file(path: Path, robot: RobotProfile | None) -> OccupancyGrid:
    """A map file of the maps folder as a grid, cached per (file, modification time[, robot for meshes]: a mesh
    is sliced over the robot's height band; None = the default robot); errors never show the server's paths."""
    stat = path.stat()
    mesh = path.suffix.lower() in MESH_SUFFIXES
    if mesh and robot is None:
        robot = load_robot(None)
    key = ("file", str(path), stat.st_mtime_ns, stat.st_size, robot if mesh else None)
    return _cached(key, lambda: read_map(path, robot if mesh else None, hide_paths=True))


def inline_grid(spec: InlineGrid) -> OccupancyGrid:
    """An :class:`OccupancyGrid` from an inline grid (cached by content, so repeated inline requests
    reuse the planner built for it)."""
    data = np.asarray(spec.data, dtype=np.int8)
    origin = (float(spec.origin[0]), float(spec.origin[1]), float(spec.origin[2]))
    digest = hashlib.sha1(data.tobytes()).hexdigest()
    resolution = snap_resolution(float(spec.resolution_m))  # 0.05 sent as a float32 plans as 0.05 (planner.maps.nav2)
    key = ("inline", digest, data.shape, resolution, origin, spec.name)
    return _cached(key, lambda: OccupancyGrid(data=data, resolution_m=resolution, origin=origin, name=spec.name))


def load_grid(source: Path | InlineGrid, robot: RobotProfile | None) -> OccupancyGrid:
    """The grid of a request: a map file of the maps folder (:func:`load_map_file`) or an inline grid."""
    return load_map_file(source, robot) if isinstance(source, Path) else inline_grid(source)


def grid_png(grid: OccupancyGrid) -> bytes:
    """The grid as a greyscale PNG the way map_server images look: free white, occupied black,
    unknown grey, image row 0 at the top."""
    from PIL import Image

    data = grid.data
    pixels = np.where(data < 0, 205, 254 - (np.clip(data, 0, 100).astype(np.int32) * 254) // 100).astype(np.uint8)
    buf = io.BytesIO()
    Image.fromarray(pixels[::-1], mode="L").save(buf, format="PNG")
    return buf.getvalue()
