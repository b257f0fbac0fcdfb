"""One look for every picture sphereplan draws (plan, simulate, vpip schedule, tensegrity gait, reconfigure, bench).

The rules (issue #13): unknown, free, occupied and the clearance band each get a legend entry; forward and
reverse motion are drawn differently (solid vs dashed); a footprint in collision is red with the offending
cells marked; the view zooms to what matters with the map around it (and says so in the title); legends sit
outside the data (below or beside the axes); titles say what and where.

Everything here imports matplotlib lazily (``pyplot()``), so importing this module is cheap.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from planner.occupancy import OccupancyGrid
    from planner.robot import RobotProfile

#: map classes, in the order of the layer values 0..3
MAP_COLOURS = {"free": "#ffffff", "band": "#b9d6ea", "unknown": "#a8a8a8", "occupied": "#111111"}
#: forward: solid; reverse: dashed (the same everywhere)
FORWARD_LS: Any = "solid"
REVERSE_LS: Any = (0, (2, 1.5))
#: a footprint in collision and the blocked cells it overlaps
COLLISION_COLOUR = "red"
OFFENDING_COLOUR = "#ff7f0e"
START_COLOUR, GOAL_COLOUR = "green", "purple"


def pyplot() -> Any:
    """matplotlib.pyplot on the Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def map_extent(grid: OccupancyGrid) -> tuple[float, float, float, float]:
    ox, oy = grid.origin[0], grid.origin[1]
    w, h = grid.size_m
    return (ox, ox + w, oy, oy + h)


def draw_map(ax: Any, grid: OccupancyGrid, band_m: float | None = None) -> list[Any]:
    """The map as four classes (free, clearance band within ``band_m`` of a blocked cell, unknown, occupied);
    returns their legend handles. ``band_m`` None: no band (e.g. a map without a robot footprint)."""
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    layer = np.zeros(grid.data.shape, dtype=np.int8)
    handles = [Patch(fc=MAP_COLOURS["free"], ec="0.6", label="free")]
    if band_m is not None and band_m > 0:
        from planner.maps.clearance import ClearanceMap

        layer[ClearanceMap(grid).clearance < band_m] = 1
        handles.append(Patch(fc=MAP_COLOURS["band"], label=f"clearance band (< {band_m:.2f} m from a blocked cell)"))
    layer[grid.data < 0] = 2
    layer[grid.data >= grid.occupied_threshold] = 3
    handles += [Patch(fc=MAP_COLOURS["unknown"], label="unknown (blocked)"),
                Patch(fc=MAP_COLOURS["occupied"], label="occupied")]
    ax.imshow(layer, origin="lower", extent=map_extent(grid), cmap=ListedColormap(list(MAP_COLOURS.values())),
              vmin=-0.5, vmax=3.5, interpolation="nearest", zorder=0)
    return handles


def view_box(points: np.ndarray, extent: tuple[float, float, float, float] | None, min_margin_m: float = 3.0,
             frac: float = 0.15) -> tuple[float, float, float, float]:
    """(x0, x1, y0, y1): the points with a margin (``frac`` of their span, at least ``min_margin_m``) of the
    map around them, cut to the map's ``extent`` unless a point lies outside it (then it stays in view)."""
    pts = np.asarray(points, float).reshape(-1, 2)
    pts = pts[np.isfinite(pts).all(axis=1)]
    margin = max(min_margin_m, frac * float(np.ptp(pts, axis=0).max())) if len(pts) else min_margin_m
    x0, x1 = pts[:, 0].min() - margin, pts[:, 0].max() + margin
    y0, y1 = pts[:, 1].min() - margin, pts[:, 1].max() + margin
    if extent is not None:
        inside = ((pts[:, 0] >= extent[0]) & (pts[:, 0] <= extent[1])
                  & (pts[:, 1] >= extent[2]) & (pts[:, 1] <= extent[3])).all()
        if inside:
            x0, x1 = max(x0, extent[0]), min(x1, extent[1])
            y0, y1 = max(y0, extent[2]), min(y1, extent[3])
    return (x0, x1, y0, y1)


def apply_view(ax: Any, box: tuple[float, float, float, float],
               extent: tuple[float, float, float, float] | None = None) -> str:
    """Set the limits (equal aspect, metres); returns " (view W × H m of the M × N m map)" when zoomed, else ""."""
    x0, x1, y0, y1 = box
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if extent is None:
        return ""
    w, h = extent[1] - extent[0], extent[3] - extent[2]
    if view_leaves_map(box, extent):
        from matplotlib.patches import Rectangle

        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fc="#f4f4f4", ec="0.75", hatch="//", lw=0, zorder=-1))
        return f" (view {_m(x1 - x0)} × {_m(y1 - y0)} m, beyond the {_m(w)} × {_m(h)} m map)"
    if x0 > extent[0] + 1e-9 or x1 < extent[1] - 1e-9 or y0 > extent[2] + 1e-9 or y1 < extent[3] - 1e-9:
        return f" (view {_m(x1 - x0)} × {_m(y1 - y0)} m of the {_m(w)} × {_m(h)} m map)"
    return ""


def _m(v: float) -> str:
    return f"{v:.0f}" if v >= 10 else f"{v:.1f}"


def figure_size(box: tuple[float, float, float, float], width_in: float = 10.0,
                extra_h_in: float = 1.8) -> tuple[float, float]:
    """A figure size whose map axes fit ``box`` at equal aspect, plus room for a legend below."""
    vw, vh = max(box[1] - box[0], 1e-6), max(box[3] - box[2], 1e-6)
    ratio = min(max(vh / vw, 0.35), 1.6)
    return (width_in, width_in * ratio + extra_h_in)


def outside_handle() -> Any:
    """Legend entry of the hatched area beyond the map's edge (drawn by :func:`apply_view`)."""
    from matplotlib.patches import Patch

    return Patch(fc="#f4f4f4", ec="0.75", hatch="//", label="outside the map")


def view_leaves_map(box: tuple[float, float, float, float], extent: tuple[float, float, float, float]) -> bool:
    """Whether the view ``box`` reaches beyond the map's ``extent``."""
    x0, x1, y0, y1 = box
    return x0 < extent[0] - 1e-9 or x1 > extent[1] + 1e-9 or y0 < extent[2] - 1e-9 or y1 > extent[3] + 1e-9


def legend_below(ax: Any, handles: Sequence[Any] | None = None, ncol: int = 3, fontsize: float = 8,
                 labels: Sequence[str] | None = None) -> Any:
    """The legend under the axes (below the x label, whatever the axes' height), never over the data."""
    from matplotlib.transforms import offset_copy

    below = offset_copy(ax.transAxes, fig=ax.figure, y=-34, units="points")
    kw: dict[str, Any] = {"loc": "upper center", "bbox_to_anchor": (0.5, 0.0), "bbox_transform": below,
                          "ncol": ncol, "fontsize": fontsize, "frameon": False}
    if handles is None:
        return ax.legend(**kw)
    return ax.legend(handles, labels, **kw) if labels is not None else ax.legend(handles=handles, **kw)


def legend_right(ax: Any, handles: Sequence[Any] | None = None, fontsize: float = 8) -> Any:
    """The legend beside the axes (right), never over the data."""
    kw: dict[str, Any] = {"loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "fontsize": fontsize,
                          "frameon": False, "borderaxespad": 0.0}
    if handles is None and not ax.get_legend_handles_labels()[0]:
        return None  # nothing labelled in this panel (e.g. no problem solved by both)
    return ax.legend(handles=handles, **kw) if handles is not None else ax.legend(**kw)


def legend_labels(fig: Any) -> list[str]:
    """Every legend label of every axes of ``fig`` (what the tests check)."""
    labels: list[str] = []
    for legend in [*(a.get_legend() for a in fig.axes), *fig.legends]:
        if legend is not None:
            labels += [t.get_text() for t in legend.get_texts()]
    return labels


def reverse_segments(v: np.ndarray) -> np.ndarray:
    """Per segment (len(v) - 1): whether the motion is reverse, from the speeds at the points. Points where
    v = 0 (start, cusps, roll changes on the spot, end) take the sign of the next move (the last ones: the
    previous)."""
    v = np.asarray(v, float).copy()
    for i in range(len(v) - 2, -1, -1):
        if v[i] == 0.0:
            v[i] = v[i + 1]
    for i in range(1, len(v)):
        if v[i] == 0.0:
            v[i] = v[i - 1]
    return v[:-1] < 0


def runs(reverse: np.ndarray) -> list[tuple[int, int, bool]]:
    """Maximal runs of equal direction over segments: (first point, last point, reverse) index triples, so
    that each run is drawn as one polyline (a dash pattern restarts on every line: per-segment lines of a
    dense path would never show their gaps)."""
    rev = np.asarray(reverse, bool)
    out: list[tuple[int, int, bool]] = []
    i = 0
    while i < len(rev):
        j = i
        while j + 1 < len(rev) and rev[j + 1] == rev[i]:
            j += 1
        out.append((i, j + 1, bool(rev[i])))
        i = j + 1
    return out


def path_line(ax: Any, xy: np.ndarray, reverse: np.ndarray | None, colour: Any, lw: float = 1.5,
              label: str | None = None, zorder: float = 3) -> list[Any]:
    """A path with forward runs solid and reverse runs dashed; returns legend handles (the path, and
    "… (forward)"/"… (reverse)" when it reverses). ``reverse``: per segment (len(xy) - 1), or None."""
    from matplotlib.lines import Line2D

    xy = np.asarray(xy, float).reshape(-1, 2)
    if len(xy) < 2:
        return []
    rev = np.zeros(len(xy) - 1, bool) if reverse is None else np.asarray(reverse, bool)[: len(xy) - 1]
    if len(rev) < len(xy) - 1:
        rev = np.concatenate([rev, np.full(len(xy) - 1 - len(rev), rev[-1] if len(rev) else False)])
    for a, b, backwards in runs(rev):
        ax.plot(xy[a:b + 1, 0], xy[a:b + 1, 1], color=colour, lw=lw, ls=REVERSE_LS if backwards else FORWARD_LS,
                zorder=zorder)
    name = label or "path"
    if not rev.any():
        return [Line2D([], [], color=colour, lw=lw, label=name)]
    handles = [Line2D([], [], color=colour, lw=lw, ls=REVERSE_LS, label=f"{name} (reverse)")]
    if (~rev).any():
        handles.insert(0, Line2D([], [], color=colour, lw=lw, label=f"{name} (forward)"))
    return handles


def reverse_overlay(ax: Any, xy: np.ndarray, reverse: np.ndarray, lw: float = 1.0, zorder: float = 3.5) -> None:
    """White dashes along the reverse runs of a line that is coloured per segment (e.g. by roll): reverse
    shows as a broken line whatever the colours."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    for a, b, backwards in runs(np.asarray(reverse, bool)[: len(xy) - 1]):
        if backwards:
            ax.plot(xy[a:b + 1, 0], xy[a:b + 1, 1], color="white", lw=lw, ls=(0, (3, 3)), zorder=zorder)


def footprint_world(robot: RobotProfile | np.ndarray, pose: Sequence[float] | np.ndarray) -> np.ndarray:
    """The padded footprint polygon (n, 2) at ``pose`` (x, y, yaw) in the world (``robot``: a profile or its
    padded polygon in the body frame, e.g. a result JSON's ``robot.footprint``)."""
    poly = np.asarray(robot, float) if isinstance(robot, np.ndarray) else robot.footprint_polygon
    x, y, yaw = float(pose[0]), float(pose[1]), float(pose[2])
    c, s = math.cos(yaw), math.sin(yaw)
    return np.column_stack([x + c * poly[:, 0] - s * poly[:, 1], y + s * poly[:, 0] + c * poly[:, 1]])


def offending_cells(grid: OccupancyGrid, polygon: np.ndarray) -> np.ndarray:
    """(k, 2) indices (row, col) of the blocked cells whose square meets ``polygon`` (world metres)."""
    from matplotlib.path import Path as MplPath

    res = grid.resolution_m
    ox, oy = grid.origin[0], grid.origin[1]
    lo, hi = polygon.min(axis=0), polygon.max(axis=0)
    c0, c1 = max(0, math.floor((lo[0] - ox) / res) - 1), min(grid.width, math.ceil((hi[0] - ox) / res) + 1)
    r0, r1 = max(0, math.floor((lo[1] - oy) / res) - 1), min(grid.height, math.ceil((hi[1] - oy) / res) + 1)
    if c0 >= c1 or r0 >= r1:
        return np.zeros((0, 2), int)
    rows, cols = np.mgrid[r0:r1, c0:c1]
    rows, cols = rows.ravel(), cols.ravel()
    blocked = grid.blocked()[rows, cols]
    rows, cols = rows[blocked], cols[blocked]
    if not len(rows):
        return np.zeros((0, 2), int)
    path = MplPath(polygon)
    hit = np.zeros(len(rows), bool)
    for fx, fy in ((0.5, 0.5), (0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)):
        pts = np.column_stack([ox + (cols + fx) * res, oy + (rows + fy) * res])
        hit |= path.contains_points(pts)
    # a polygon vertex inside a cell square
    vc = np.floor((polygon[:, 0] - ox) / res).astype(int)
    vr = np.floor((polygon[:, 1] - oy) / res).astype(int)
    vertex_cells = set(zip(vr.tolist(), vc.tolist(), strict=True))
    hit |= np.array([(r, c) in vertex_cells for r, c in zip(rows.tolist(), cols.tolist(), strict=True)])
    return np.column_stack([rows[hit], cols[hit]])


def draw_footprint(ax: Any, grid: OccupancyGrid | None, robot: RobotProfile | np.ndarray,
                   pose: Sequence[float] | np.ndarray, colour: Any, label: str, collided: bool = False,
                   lw: float = 1.2) -> list[Any]:
    """The footprint at ``pose``; when ``collided``, red and filled with the blocked cells it overlaps marked
    (and whether it leaves the map). Returns legend handles."""
    from matplotlib.patches import Patch, Polygon, Rectangle

    world = footprint_world(robot, pose)
    if not collided:
        ax.add_patch(Polygon(world, closed=True, fill=False, lw=lw, ec=colour, zorder=4))
        return [Patch(fill=False, ec=colour, lw=lw, label=label)]
    ax.add_patch(Polygon(world, closed=True, fc=COLLISION_COLOUR, alpha=0.25, ec="none", zorder=4))
    ax.add_patch(Polygon(world, closed=True, fill=False, lw=1.8, ec=COLLISION_COLOUR, zorder=6))
    red = Patch(fc=(1, 0, 0, 0.25), ec=COLLISION_COLOUR, lw=1.8, label=f"{label} (in collision)")
    handles: list[Any] = [red]
    if grid is not None:
        cells = offending_cells(grid, world)
        res = grid.resolution_m
        for r, c in cells:
            ax.add_patch(Rectangle((grid.origin[0] + c * res, grid.origin[1] + r * res), res, res,
                                   fc=OFFENDING_COLOUR, ec=COLLISION_COLOUR, lw=0.5, zorder=5))
        if len(cells):
            handles.append(Patch(fc=OFFENDING_COLOUR, ec=COLLISION_COLOUR,
                                 label=f"blocked cells it overlaps ({len(cells)})"))
        ext = map_extent(grid)
        if (world[:, 0].min() < ext[0] or world[:, 0].max() > ext[1] or world[:, 1].min() < ext[2]
                or world[:, 1].max() > ext[3]):
            ax.add_patch(Rectangle((ext[0], ext[2]), ext[1] - ext[0], ext[3] - ext[2], fill=False,
                                   ec=COLLISION_COLOUR, ls=":", lw=1.0, zorder=5))
            handles.append(Patch(fill=False, ec=COLLISION_COLOUR, ls=":", label="map edge (the footprint leaves it)"))
            if not len(cells):
                red.set_label(f"{label} (outside the map)")
    return handles


def draw_pose(ax: Any, pose: Sequence[float], colour: Any, label: str, arrow_m: float = 0.8,
              marker: str = "o") -> Any:
    """A pose as a dot and a heading arrow; returns its legend handle."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import FancyArrow

    x, y, yaw = float(pose[0]), float(pose[1]), float(pose[2])
    ax.plot([x], [y], marker, color=colour, ms=7, zorder=7)
    ax.add_patch(FancyArrow(x, y, arrow_m * math.cos(yaw), arrow_m * math.sin(yaw), width=0.075 * arrow_m,
                            color=colour, zorder=7))
    return Line2D([], [], marker=marker, color=colour, ls="", label=label)


def save(fig: Any, out: str | Path, dpi: int = 110) -> Path:
    """Write ``fig`` to ``out`` (bbox tight, so legends outside the axes are kept) and close it."""
    out = Path(out)
    fig.savefig(out, dpi=dpi, bbox_inches="tight")
    pyplot().close(fig)
    return out
