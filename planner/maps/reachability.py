"""Refusing an unreachable goal in milliseconds: a flood fill with the footprint's inscribed disc.

Wherever the robot's footprint polygon is free, so is the disc of radius r_in (the polygon's inradius about
the robot's centre, :func:`~planner.maps.clearance.inscribed_radius`) around its centre, whatever the
footprint's shape. The cells whose centre lies at least r_in − res·√2/2 from every blocked cell centre (and
from the ring of cells outside the map) are therefore a superset of the cells a free footprint's centre can
be in, and a continuous motion — or the search's motions, sampled at most half a cell apart, sideways
roll shifts included — passes only through 8-adjacent such cells
(:meth:`~planner.maps.clearance.ClearanceMap.disc_components`). If no cell within the goal tolerance (plus
a cell) of the goal is in the start's 8-connected piece, no path exists: the planner says so at once
(:class:`~planner.errors.NoValidPathFound`, Nav2 code 208) instead of searching until its time limit.

The labels are computed once per clearance map and inradius (``scipy.ndimage.label``, ≈ 50 ms on a
4-million-cell map) and kept while the map's blocked cells stay the same: they are cached by the clearance map's
``revision``, which the live map's in-place update counts (:meth:`ClearanceMap.write_blocked`), so an updated
map is relabelled, never trusted stale. (Until issue 21's ninth round each query compared a CRC of the blocked
cells instead: 0.9 ms a plan on a 4-million-cell map, a tenth of an easy plan there.)
The check never refuses a goal the search could reach (tested against the search on the shipped problems
and on drawn real-map problems); goals it lets through may still be unreachable (a heading that does not
fit, a turn too tight), which the search's own dead-end check and time limit handle.
"""

from __future__ import annotations

import math
import threading
import time
import weakref

import numpy as np

from planner.errors import NoValidPathFound
from planner.maps.clearance import ClearanceMap, inscribed_radius

Pose = tuple[float, float, float]

_LOCK = threading.Lock()
# per clearance map and inradius: the blocked array and revision the labels were computed from, and the labels
_LABELS: weakref.WeakKeyDictionary[ClearanceMap, dict[float, tuple[np.ndarray, int, np.ndarray]]] = (
    weakref.WeakKeyDictionary())


def components(clearance: ClearanceMap, inradius_m: float) -> np.ndarray:
    """The disc components of ``clearance`` for this inradius (int32 labels, 0 = no disc centre), cached
    while its blocked cells are unchanged (the same array, the same revision)."""
    key = round(float(inradius_m), 9)
    blocked, revision = clearance.blocked, clearance.revision
    with _LOCK:
        entry = _LABELS.get(clearance, {}).get(key)
    if entry is not None and entry[0] is blocked and entry[1] == revision:
        return entry[2]
    labels = clearance.disc_components(inradius_m)
    with _LOCK:
        _LABELS.setdefault(clearance, {})[key] = (blocked, revision, labels)
    return labels


def prepare(clearance: ClearanceMap, polygon: np.ndarray) -> None:
    """Compute (and cache) the labels for this footprint ahead of the first query (a map's preprocessing)."""
    components(clearance, inscribed_radius(polygon))


def _cell(clearance: ClearanceMap, x: float, y: float) -> tuple[int, int]:
    res = clearance.resolution_m
    return math.floor((y - clearance.origin_y) / res), math.floor((x - clearance.origin_x) / res)


def goal_reachable(clearance: ClearanceMap, polygon: np.ndarray, start: Pose, goal: Pose,
                   goal_tolerance_m: float) -> bool:
    """False only when it is proven that no motion of the footprint joins ``start`` to within
    ``goal_tolerance_m`` of ``goal`` (see the module docstring); True otherwise (including when the start's
    cell holds no disc centre, which a free start cannot do)."""
    labels = components(clearance, inscribed_radius(polygon))
    h, w = labels.shape
    sy, sx = _cell(clearance, start[0], start[1])
    if not (0 <= sy < h and 0 <= sx < w):
        return True
    mine = labels[sy, sx]
    if mine == 0:
        return True
    res = clearance.resolution_m
    reach = goal_tolerance_m + res  # the search ends within the tolerance; a cell centre within half a diagonal
    gy0, gx0 = _cell(clearance, goal[0] - reach, goal[1] - reach)
    gy1, gx1 = _cell(clearance, goal[0] + reach, goal[1] + reach)
    gy0, gx0, gy1, gx1 = max(gy0, 0), max(gx0, 0), min(gy1, h - 1), min(gx1, w - 1)
    if gy0 > gy1 or gx0 > gx1:
        return True
    window = labels[gy0:gy1 + 1, gx0:gx1 + 1]
    ys = clearance.origin_y + (np.arange(gy0, gy1 + 1) + 0.5) * res
    xs = clearance.origin_x + (np.arange(gx0, gx1 + 1) + 0.5) * res
    near = np.hypot(xs[None, :] - goal[0], ys[:, None] - goal[1]) <= reach
    return bool((window[near] == mine).any())


def refuse_unreachable(clearance: ClearanceMap, polygon: np.ndarray, start: Pose, goal: Pose,
                       goal_tolerance_m: float, t0: float) -> None:
    """Raise :class:`~planner.errors.NoValidPathFound` (code 208) naming the reason when
    :func:`goal_reachable` proves the goal out of reach; ``t0`` is the plan's start (``time.perf_counter``)."""
    if goal_reachable(clearance, polygon, start, goal, goal_tolerance_m):
        return
    r_in = inscribed_radius(polygon)
    raise NoValidPathFound(
        f"no path: the goal ({goal[0]:.2f}, {goal[1]:.2f}) lies in a part of the map the robot cannot reach from "
        f"the start ({start[0]:.2f}, {start[1]:.2f}): every way between them narrows below the "
        f"{2 * r_in:.2f} m disc inscribed in its footprint (flood fill of the free space)",
        planning_time_s=time.perf_counter() - t0, expansions=0,
    )
