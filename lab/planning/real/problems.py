"""Drawing the real-map benchmark's problems the way Nav2's planner benchmark draws them.

A uniformly random cell away from the map's border and a uniformly random yaw for the start, then the same for
the goal at least a minimum distance away; a draw is kept only when the padded footprint polygon
(:attr:`~planner.robot.RobotProfile.footprint_polygon`) is free there by the exact check of
:mod:`lab.planning.referee`. Every problem also gets a proof of unreachability where one is cheap: start and
goal in different connected parts of the space the footprint's inscribed disc can reach.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import ndimage

from lab.planning.referee import FootprintReferee
from planner.errors import (
    InvalidInput,
)
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile

log = logging.getLogger(__name__)

Pose = tuple[float, float, float]


BIG_MAP_CELLS = 1_000_000  # maps at least this large get the longer default time limit
DEFAULT_TIME_LIMIT_S = 5.0
DEFAULT_TIME_LIMIT_BIG_S = 10.0


def real_maps_dir() -> Path:
    """The folder of the shipped Nav2 maps, ``<maps>/real`` (see ``maps/real/README.md``)."""
    from planner.maps.catalogue import default_maps_dir

    return default_maps_dir() / "real"


def default_time_limit_s(grid: OccupancyGrid) -> float:
    """The default time limit (s) for a map: 10 s from a million cells up, 5 s below."""
    return DEFAULT_TIME_LIMIT_BIG_S if grid.width * grid.height >= BIG_MAP_CELLS else DEFAULT_TIME_LIMIT_S


def real_map_names() -> list[str]:
    """The maps the benchmark runs by default: every map YAML in :func:`real_maps_dir`, sorted by name."""
    return sorted(p.stem for p in real_maps_dir().glob("*.yaml"))


def resolve_map(spec: str) -> Path:
    """A map by name in :func:`real_maps_dir` (``depot``) or by path to its YAML."""
    path = Path(spec)
    if spec.endswith((".yaml", ".yml")) or path.is_file():
        if not path.is_file():
            raise InvalidInput("--real-maps", f"map file {spec!r} does not exist")
        return path
    candidate = real_maps_dir() / f"{spec}.yaml"
    if not candidate.is_file():
        raise InvalidInput("--real-maps", f"no real map named {spec!r}; shipped: {', '.join(real_map_names())}")
    return candidate



# ------------------------------------------------------------------------------------------------ problems


@dataclass(frozen=True)
class DrawSettings:
    """How problems are drawn (Nav2's benchmark, scaled to the map).

    Parameters
    ----------
    border_fraction : float
        Start and goal cells keep this fraction of the map's smaller side (in cells) from every border; Nav2
        uses 100 cells on its 2000-cell field, i.e. 0.05.
    min_distance_fraction : float
        The goal lies at least this fraction of the map's smaller side (m) from the start ...
    min_distance_floor_m : float
        ... and never less than this (m); Nav2 uses 3 m.
    max_draws : int
        Give up (``InvalidInput``) after this many rejected draws for one pose.
    """

    border_fraction: float = 0.05
    min_distance_fraction: float = 0.2
    min_distance_floor_m: float = 3.0
    max_draws: int = 200_000

    def border_cells(self, grid: OccupancyGrid) -> int:
        """Cells kept clear of each border by the drawn cells."""
        return max(1, round(self.border_fraction * min(grid.width, grid.height)))

    def min_distance_m(self, grid: OccupancyGrid) -> float:
        """Smallest start–goal distance (m) on this map."""
        return max(self.min_distance_floor_m, self.min_distance_fraction * min(grid.size_m))


@dataclass(frozen=True)
class RealProblem:
    """One drawn problem. Poses are (x m, y m, yaw rad in [−π, π)) in the map frame.

    ``disconnected`` is a proof that no motion joins start and goal: the positions where even the
    footprint's inscribed disc is free fall apart into pieces, and the two lie in different pieces.
    """

    map_name: str
    index: int
    start: Pose
    goal: Pose
    distance_m: float
    disconnected: bool

    @property
    def name(self) -> str:
        return f"{self.map_name}#{self.index}"


def disc_components(grid: OccupancyGrid, checker: FootprintReferee) -> np.ndarray:
    """Labels (height, width) of the 8-connected pieces of cells that may hold a free inscribed-disc centre.

    A cell is kept when its centre is at least ``r_in − res·√2/2`` from every blocked cell centre and from
    the map's outside (``r_in``: the polygon's inradius). That is a superset of the cells containing a
    position where the disc — and so a fortiori the footprint — is free, and any continuous motion passes
    through 8-adjacent kept cells; so different labels at start and goal prove the problem unsolvable.
    Label 0 is "not kept".
    """
    padded = np.pad(checker.blocked, 1, constant_values=True)
    dist = ndimage.distance_transform_edt(~padded)[1:-1, 1:-1] * grid.resolution_m
    kept = dist >= checker.inradius_m - grid.resolution_m * math.sqrt(0.5)
    labels, _ = ndimage.label(kept, structure=np.ones((3, 3), dtype=bool))
    return np.asarray(labels)


def _cell_of(grid: OccupancyGrid, pose: Pose) -> tuple[int, int]:
    ix, iy = grid.world_to_cell(pose[0], pose[1])
    return iy, ix


def _draw_pose(grid: OccupancyGrid, checker: FootprintReferee, rng: np.random.Generator, border: int,
               settings: DrawSettings, away_from: Pose | None = None, min_distance_m: float = 0.0) -> Pose:
    """A uniformly random free cell centre inside the border band with a uniformly random yaw whose padded
    footprint is free (and, with ``away_from``, at least ``min_distance_m`` from it)."""
    res = grid.resolution_m
    ox, oy = grid.origin[0], grid.origin[1]
    blocked = checker.blocked
    for _ in range(settings.max_draws):
        row = int(rng.integers(border, grid.height - border))
        col = int(rng.integers(border, grid.width - border))
        yaw = float(rng.uniform(-math.pi, math.pi))
        if blocked[row, col]:
            continue
        x, y = ox + (col + 0.5) * res, oy + (row + 0.5) * res
        if away_from is not None and math.hypot(x - away_from[0], y - away_from[1]) < min_distance_m:
            continue
        if not checker.collides(x, y, yaw):
            return x, y, yaw
    what = "a goal" if away_from is not None else "a start"
    raise InvalidInput("maps", f"could not draw {what} with a free footprint on {grid.name!r} in "
                               f"{settings.max_draws} draws (map too small or too full?)")


def draw_problems(grid: OccupancyGrid, robot: RobotProfile, n: int, rng: np.random.Generator, *,
                  map_name: str | None = None, allow_unknown: bool = False,
                  settings: DrawSettings | None = None,
                  checker: FootprintReferee | None = None) -> list[RealProblem]:
    """Draw ``n`` problems on ``grid`` with ``rng`` (the same generator state gives the same problems).

    Parameters
    ----------
    grid : the map.
    robot : its footprint polygon (padding included) must be free at every start and goal.
    n : number of problems.
    rng : the only source of randomness.
    map_name : label of the problems (default ``grid.name``).
    allow_unknown : unknown cells do not block (the planner's option of the same name).
    settings : border, minimum distance, draw cap (default :class:`DrawSettings`).
    checker : a :class:`FootprintReferee` for this grid and robot, if one exists already.
    """
    if n < 1:
        raise InvalidInput("--per-map", f"must be ≥ 1, got {n}")
    s = settings or DrawSettings()
    check = checker or FootprintReferee.for_robot(grid, robot, allow_unknown)
    border = s.border_cells(grid)
    if 2 * border >= min(grid.width, grid.height):
        raise InvalidInput("maps", f"{grid.name!r} is too small for a {border}-cell border")
    min_d = s.min_distance_m(grid)
    labels = disc_components(grid, check)
    out: list[RealProblem] = []
    for i in range(n):
        start = _draw_pose(grid, check, rng, border, s)
        goal = _draw_pose(grid, check, rng, border, s, away_from=start, min_distance_m=min_d)
        disconnected = bool(labels[_cell_of(grid, start)] != labels[_cell_of(grid, goal)])
        out.append(RealProblem(map_name or grid.name, i, start, goal,
                               math.hypot(goal[0] - start[0], goal[1] - start[1]), disconnected))
    return out


