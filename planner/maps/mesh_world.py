"""Mesh worlds: a triangle mesh (``.stl/.obj/.ply``) sliced into an occupancy grid; exact fcl re-checks.

A sphere of radius r rolling on a floor at height ``floor_z`` occupies the height band
``[floor_z + c, floor_z + c + 2r]`` where ``c`` is the clearance (floor unevenness the shell rolls over,
default 0.10 m); the sphere's centre is at ``floor_z + c + r``. :meth:`MeshWorld.occupied` slices the mesh
with horizontal planes across that band (``trimesh.intersections.mesh_plane``: the cross-section as line
segments) and rasterises every cross-section with the even-odd rule at the cell centres; a cell is
occupied if it is inside rock in *any* slice of the band (the union, so a wall that leans in counts at
its narrowest).

"Inside rock" is decided per connected body of the mesh from its orientation (signed volume):

* a body with outward normals (positive volume: a boulder, a pillar) is a *solid*: its inside is rock;
* a body with inward normals (negative volume: a cave tube, a room) is a *cavity*: its inside is free
  and everything outside all cavities is rock.

So a cell is occupied if it lies inside any solid, or (when the mesh has cavities) outside every cavity.
Solids may poke into cavity walls and cavities may overlap; the union is what is free.

The grid is conservative only to the resolution of the slicing: :meth:`MeshWorld.path_collides` re-checks
a path exactly with python-fcl: the sphere (``fcl.Sphere(r)``, centre ``floor_z + c + r``) and the
footprint box (``footprint_length × footprint_width × 0.05 m`` at the centre height, turned by the yaw)
against a BVH of the whole mesh.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from planner.errors import MapError
from planner.extras import MissingExtra

try:  # the [mesh] extra: trimesh slices the mesh, python-fcl re-checks paths against it
    import fcl
    import trimesh
except ImportError:
    raise MissingExtra("map", "mesh", "a mesh map (.stl/.obj/.ply)") from None
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile, load_robot

DEFAULT_CLEARANCE_M = 0.10
FOOTPRINT_BOX_HEIGHT_M = 0.05


@dataclass(frozen=True, eq=False)
class MeshWorld:
    """A triangle mesh world in the ``map`` frame (metres, z up).

    Parameters
    ----------
    mesh : the world's triangles (may hold several bodies; see the module docstring for solids/cavities).
    floor_z : ground level in metres (default when built from a file: the lowest vertex of the mesh).
    name : label used for the grid made from it.
    path : the file it came from, if any.
    """

    mesh: trimesh.Trimesh
    floor_z: float
    name: str = "mesh"
    path: Path | None = None

    @classmethod
    def from_mesh(cls, mesh: trimesh.Trimesh, floor_z: float | None = None, name: str = "mesh",
                  path: Path | None = None) -> MeshWorld:
        if len(mesh.faces) == 0:
            raise MapError("mesh", "the mesh has no triangles")
        floor = float(mesh.bounds[0][2]) if floor_z is None else float(floor_z)
        if not math.isfinite(floor):
            raise MapError("floor_z", f"must be finite, got {floor_z!r}")
        return cls(mesh=mesh, floor_z=floor, name=name, path=path)

    @classmethod
    def from_file(cls, path: str | Path, floor_z: float | None = None) -> MeshWorld:
        """Load ``.stl``/``.obj``/``.ply`` with trimesh (several bodies are concatenated into one mesh)."""
        p = Path(path)
        if not p.is_file():
            raise MapError("mesh", f"mesh file {str(p)!r} does not exist")
        try:
            loaded = trimesh.load(p, force="mesh")
        except Exception as exc:  # trimesh raises many types for unreadable files
            raise MapError("mesh", f"cannot read {p.name} as a mesh: {exc}") from None
        if not isinstance(loaded, trimesh.Trimesh):
            raise MapError("mesh", f"{p.name} did not load as a triangle mesh")
        return cls.from_mesh(loaded, floor_z=floor_z, name=p.stem, path=p)

    # ------------------------------------------------------------------------------------------ slicing

    @staticmethod
    def band(robot: RobotProfile, clearance_m: float = DEFAULT_CLEARANCE_M) -> tuple[float, float]:
        """Height band (above the floor, metres) the rolling sphere occupies: [c, c + 2r]."""
        return clearance_m, clearance_m + 2.0 * robot.radius_m

    def _bodies(self) -> list[tuple[trimesh.Trimesh, bool]]:
        """Connected bodies and whether each is a cavity (inward normals, negative signed volume)."""
        bodies = self.mesh.split(only_watertight=False)
        if len(bodies) == 0:
            bodies = [self.mesh]
        return [(b, float(b.volume) < 0.0) for b in bodies]

    def occupied(
        self,
        resolution_m: float,
        robot: RobotProfile | None = None,
        clearance_m: float = DEFAULT_CLEARANCE_M,
        slices: int | None = None,
        margin_cells: int = 2,
    ) -> tuple[np.ndarray, tuple[float, float, float]]:
        """Rasterise the robot's height band: (bool occupied[iy, ix] with row 0 at the bottom, origin).

        The grid covers the mesh's x-y bounds plus ``margin_cells``, aligned to multiples of the
        resolution. ``slices`` planes are spread evenly over the band (default: one per half cell of
        height, at least 3).
        """
        if not (math.isfinite(resolution_m) and resolution_m > 0):
            raise MapError("resolution", f"must be a finite number > 0, got {resolution_m!r}")
        if not (math.isfinite(clearance_m) and clearance_m >= 0):
            raise MapError("clearance_m", f"must be a finite number >= 0, got {clearance_m!r}")
        robot = robot or load_robot()
        lo, hi = self.band(robot, clearance_m)
        n = slices or max(3, math.ceil((hi - lo) / (0.5 * resolution_m)) + 1)
        heights = self.floor_z + np.linspace(lo, hi, n)
        (x0, y0, _), (x1, y1, _) = self.mesh.bounds
        ox = round((math.floor(x0 / resolution_m) - margin_cells) * resolution_m, 9)
        oy = round((math.floor(y0 / resolution_m) - margin_cells) * resolution_m, 9)
        width = math.ceil((x1 - ox) / resolution_m) + margin_cells
        height = math.ceil((y1 - oy) / resolution_m) + margin_cells
        bodies = self._bodies()
        has_cavity = any(cav for _, cav in bodies)
        occupied = np.zeros((height, width), dtype=bool)
        for z in heights:
            in_solid = np.zeros((height, width), dtype=bool)
            in_cavity = np.zeros((height, width), dtype=bool)
            for body, cavity in bodies:
                bz0, bz1 = body.bounds[0][2], body.bounds[1][2]
                if not bz0 < z < bz1:
                    continue
                segments = trimesh.intersections.mesh_plane(body, plane_normal=[0, 0, 1],
                                                             plane_origin=[0, 0, z])
                inside = _even_odd_fill(np.asarray(segments)[:, :, :2], (ox, oy), resolution_m, width, height)
                if cavity:
                    in_cavity |= inside
                else:
                    in_solid |= inside
            occupied |= in_solid
            if has_cavity:
                occupied |= ~in_cavity
        return occupied, (ox, oy, 0.0)

    def to_grid(
        self,
        resolution_m: float,
        robot: RobotProfile | None = None,
        clearance_m: float = DEFAULT_CLEARANCE_M,
        mesh_ref: str | None = None,
    ) -> OccupancyGrid:
        """The band slice as an :class:`OccupancyGrid` (0 free / 100 occupied).

        ``source`` records how it was made (``mesh``: ``mesh_ref`` or the mesh path, ``floor_z``,
        ``clearance_m``, ``robot``) so that it can be saved as a map_server YAML and re-checked later.
        """
        robot = robot or load_robot()
        occ, origin = self.occupied(resolution_m, robot, clearance_m)
        grid = OccupancyGrid.from_occupied(occ, resolution_m, origin, name=self.name)
        mesh = mesh_ref if mesh_ref is not None else (str(self.path) if self.path else None)
        source: dict[str, object] = {"mode": "trinary", "occupied_thresh": 0.65, "free_thresh": 0.196}
        if mesh:
            source["mesh"] = mesh
        source.update({"floor_z": round(self.floor_z, 6), "clearance_m": clearance_m, "robot": robot.name})
        return OccupancyGrid(data=grid.data, resolution_m=grid.resolution_m, origin=grid.origin,
                             name=self.name, source=source,
                             mesh_path=self.path.resolve() if self.path else None, mesh_world=self)

    # ------------------------------------------------------------------------------------------ exact check

    def _bvh(self) -> fcl.BVHModel:
        model = fcl.BVHModel()
        verts = np.asarray(self.mesh.vertices, dtype=np.float64)
        tris = np.asarray(self.mesh.faces, dtype=np.int32)
        model.beginModel(len(verts), len(tris))
        model.addSubModel(verts, tris)
        model.endModel()
        return model

    def path_collides(
        self,
        xs: np.ndarray,
        ys: np.ndarray,
        yaws: np.ndarray,
        robot: RobotProfile,
        clearance_m: float = DEFAULT_CLEARANCE_M,
        distance_every: int = 1,
    ) -> tuple[bool, int | None, float]:
        """Check poses against the mesh exactly (python-fcl).

        At each pose (x, y in metres, yaw in radians) the sphere ``fcl.Sphere(r)`` is placed at
        ``(x, y, floor_z + c + r)`` together with the footprint box (length along the heading × width ×
        0.05 m, same centre). Returns ``(collides, first colliding index or None, min distance in m)``;
        the minimum distance is 0 when something touches. Every pose gets the exact collision test; the
        (slower) distance query runs on every ``distance_every``-th pose only.
        """
        xs, ys, yaws = (np.asarray(a, dtype=float).ravel() for a in (xs, ys, yaws))
        if not (xs.shape == ys.shape == yaws.shape):
            sizes = f"{xs.size}, {ys.size}, {yaws.size}"
            raise MapError("path", f"xs, ys, yaws must have equal lengths, got {sizes}")
        world = fcl.CollisionObject(self._bvh(), fcl.Transform())
        zc = self.floor_z + clearance_m + robot.radius_m
        sphere = fcl.CollisionObject(fcl.Sphere(robot.radius_m), fcl.Transform())
        footprint = fcl.Box(robot.footprint_length_m, robot.footprint_width_m, FOOTPRINT_BOX_HEIGHT_M)
        box = fcl.CollisionObject(footprint, fcl.Transform())
        first: int | None = None
        min_dist = math.inf
        for i, (x, y, yaw) in enumerate(zip(xs, ys, yaws, strict=True)):
            c, s = math.cos(yaw), math.sin(yaw)
            rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
            pos = np.array([x, y, zc])
            sphere.setTransform(fcl.Transform(pos))
            box.setTransform(fcl.Transform(rot, pos))
            for obj in (sphere, box):
                hit = fcl.collide(obj, world, fcl.CollisionRequest(), fcl.CollisionResult()) > 0
                if hit:
                    dist = 0.0
                elif i % distance_every:
                    continue
                else:
                    dres = fcl.DistanceResult()
                    dist = max(0.0, float(fcl.distance(obj, world, fcl.DistanceRequest(), dres)))
                min_dist = min(min_dist, dist)
                if hit and first is None:
                    first = i
        return first is not None, first, (min_dist if math.isfinite(min_dist) else math.inf)


def _even_odd_fill(
    segments: np.ndarray, origin: tuple[float, float], resolution_m: float, width: int, height: int
) -> np.ndarray:
    """Cells whose centres lie inside the closed polylines made of ``segments`` (n, 2, 2), even-odd rule.

    For each cell row the crossings of its centre line y = oy + (iy + ½)·res with every segment are
    found (half-open in y so a shared end point counts once); each crossing toggles the parity of all
    cells whose centre lies to its right, and a cumulative sum along the row gives inside/outside.
    """
    inside = np.zeros((height, width), dtype=bool)
    if len(segments) == 0:
        return inside
    ox, oy = origin
    p0, p1 = segments[:, 0, :], segments[:, 1, :]
    ylo = np.minimum(p0[:, 1], p1[:, 1])
    yhi = np.maximum(p0[:, 1], p1[:, 1])
    # rows whose centre yc satisfies ylo <= yc < yhi
    first_row = np.ceil((ylo - oy) / resolution_m - 0.5).astype(np.int64)
    last_row = np.ceil((yhi - oy) / resolution_m - 0.5).astype(np.int64) - 1
    first_row = np.clip(first_row, 0, height)
    last_row = np.clip(last_row, -1, height - 1)
    counts = np.maximum(last_row - first_row + 1, 0)
    if counts.sum() == 0:
        return inside
    seg_idx = np.repeat(np.arange(len(segments)), counts)
    offsets = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    rows = first_row[seg_idx] + offsets
    yc = oy + (rows + 0.5) * resolution_m
    a, b = p0[seg_idx], p1[seg_idx]
    t = (yc - a[:, 1]) / (b[:, 1] - a[:, 1])
    xc = a[:, 0] + t * (b[:, 0] - a[:, 0])
    # first cell whose centre is right of the crossing
    cols = np.ceil((xc - ox) / resolution_m - 0.5).astype(np.int64)
    cols = np.clip(cols, 0, width)
    toggles = np.zeros((height, width + 1), dtype=np.int32)
    np.add.at(toggles, (rows, cols), 1)
    inside = (np.cumsum(toggles[:, :width], axis=1) % 2).astype(bool)
    return inside
