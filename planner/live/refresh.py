"""Refresh a planner for a changed part of its map instead of rebuilding it.

A :class:`~planner.hybrid_astar.search.HybridAStar` precomputes, per map, the blocked cells, the clearance
(a Euclidean distance transform, :class:`planner.maps.clearance.ClearanceMap`) and the coarse cost multipliers
of its holonomic heuristic. The search also *skips ahead* by the clearance when it checks a motion, so a
stored clearance may be smaller than the truth, never larger.

A live planner's clearance is therefore capped at ``C`` (:func:`cap_m`, a little above every clearance the
search compares against: the covering circles' radius plus the proximity range and preferred clearance, and
the reported clearance's cap), after which a change in a rectangle R can only alter cells within ``C`` of R.
Those (R grown by ``C``) are recomputed from a distance transform over R grown by 2·``C`` (every obstacle within
``C`` of them lies inside it) and capped again. The result is min(true clearance, ``C``) everywhere, exactly
what a rebuilt planner holds after the same cap, so a refreshed planner plans as a rebuilt one. The coarse
multipliers are rebuilt on the coarse cells over the recomputed cells and the cached heuristic tables are
dropped (the goal's wavefront is recomputed on the next plan, exact around the way to the start as usual).

The guide of :mod:`planner.live.guide` (the same multipliers with the gaps the robot cannot roll through
closed) is patched on the same coarse cells.

The interface to the planner is narrow on purpose: the grid (a view the live map updates in place), the
changed rectangles, and the planner's public ``clearance``, ``holonomic_mult`` and heuristic cache.
"""

from __future__ import annotations

import math
import time
import weakref
from collections.abc import Sequence

import numpy as np
from scipy.ndimage import distance_transform_edt

from planner.hybrid_astar.heuristics import coarse_cost_grid
from planner.hybrid_astar.search import CLEARANCE_REACH_M, HybridAStar
from planner.live.guide import patch_guide
from planner.live.live_map import CellRect

PATCH_SHARE_LIMIT = 0.35
"""When the window to recompute covers more than this share of the map, rebuild the planner instead."""


def exact_reach_m(planner: HybridAStar) -> float:
    """The clearance (m) up to which a refreshed planner's clearance must be exact (see the module docstring)."""
    o = planner.options
    res = planner.grid.resolution_m
    r_c = planner.footprint.radius_m
    needed = max(CLEARANCE_REACH_M + r_c,
                 r_c + max(o.proximity_range_m, planner.robot.preferred_clearance_m)
                 + planner.robot.preferred_clearance_m,
                 planner.centre_threshold_m)
    return needed + 2.0 * math.sqrt(2.0) * res


def cap_m(planner: HybridAStar) -> float:
    """The clearance cap C (m) of a live planner: whole cells, at least :func:`exact_reach_m`."""
    res = planner.grid.resolution_m
    return (math.ceil(exact_reach_m(planner) / res) + 1) * res


_capped: weakref.WeakSet[HybridAStar] = weakref.WeakSet()


def capped(planner: HybridAStar) -> HybridAStar:
    """Cap ``planner``'s clearance at :func:`cap_m` in place (once per planner); returns it."""
    if planner not in _capped:
        np.minimum(planner.clearance.clearance, cap_m(planner), out=planner.clearance.clearance)
        _capped.add(planner)
    return planner


def refresh(planner: HybridAStar, changed: Sequence[CellRect],
            max_share: float = PATCH_SHARE_LIMIT) -> tuple[HybridAStar, float, str]:
    """Bring ``planner`` up to date with its grid after the cells in the rectangles ``changed`` changed.

    Returns (the planner to use, seconds it took, how: ``"patched"`` or ``"rebuilt"``). Rectangles whose
    windows overlap are patched together with one distance transform over their windows' bounding box; when
    those boxes together cover more than ``max_share`` of the map a new planner is built instead.
    """
    t0 = time.perf_counter()
    grid = planner.grid
    h, w = grid.data.shape
    capped(planner)
    n_reach = int(round(cap_m(planner) / grid.resolution_m)) + 2
    groups = _groups([rect for rect in changed if rect.cells > 0], n_reach, w, h)
    if sum(box.cells for box, _ in groups) > max_share * w * h:
        return capped(HybridAStar(grid, planner.robot, planner.options)), time.perf_counter() - t0, "rebuilt"
    for box, members in groups:
        _patch(planner, box, members, n_reach)
    planner.forget_heuristics()
    return planner, time.perf_counter() - t0, "patched"


def _groups(rects: list[CellRect], n_reach: int, w: int, h: int) -> list[tuple[CellRect, list[CellRect]]]:
    """Rectangles whose 2·reach windows overlap, merged: (the windows' bounding box, the rectangles)."""
    groups: list[tuple[CellRect, list[CellRect]]] = [(r.expanded(2 * n_reach, w, h), [r]) for r in rects]
    merged = True
    while merged:
        merged = False
        for i in range(len(groups)):
            for j in range(i + 1, len(groups)):
                a, b = groups[i][0], groups[j][0]
                if a.ix0 < b.ix1 and b.ix0 < a.ix1 and a.iy0 < b.iy1 and b.iy0 < a.iy1:
                    groups[i] = (a.union(b), groups[i][1] + groups[j][1])
                    del groups[j]
                    merged = True
                    break
            if merged:
                break
    return groups


def _patch(planner: HybridAStar, outer: CellRect, members: list[CellRect], n_reach: int) -> None:
    """One distance transform over ``outer``; blocked cells, clearance and coarse multipliers rewritten around
    each changed rectangle of ``members`` (all of whose 2·reach windows lie in ``outer``)."""
    grid = planner.grid
    h, w = grid.data.shape
    res = grid.resolution_m
    cap = cap_m(planner)
    cm = planner.clearance
    allow_unknown = planner.options.allow_unknown
    sl = outer.slices()
    blocked_outer = grid.data[sl] >= grid.occupied_threshold
    if not allow_unknown:
        blocked_outer |= grid.data[sl] < 0
    for rect in members:
        cm.write_blocked(rect.slices(), blocked_outer[rect.iy0 - outer.iy0:rect.iy1 - outer.iy0,
                                                      rect.ix0 - outer.ix0:rect.ix1 - outer.ix0])
    # the ring outside the map counts as blocked (ClearanceMap's convention); other window edges do not
    pad = ((1 if outer.iy0 == 0 else 0, 1 if outer.iy1 == h else 0),
           (1 if outer.ix0 == 0 else 0, 1 if outer.ix1 == w else 0))
    padded = np.pad(blocked_outer, pad, constant_values=True)
    edt: np.ndarray = (np.asarray(distance_transform_edt(~padded), dtype=float) if padded.any()
                       else np.full(padded.shape, np.inf))
    edt = edt[pad[0][0]:edt.shape[0] - pad[0][1], pad[1][0]:edt.shape[1] - pad[1][1]]
    # exact wherever ≤ the cap: an obstacle outside the window is farther than the cap from every written cell
    edt = np.minimum(edt * res - math.sqrt(2.0) * res, cap)
    for rect in members:
        inner = rect.expanded(n_reach, w, h)
        cm.clearance[inner.slices()] = edt[inner.iy0 - outer.iy0:inner.iy1 - outer.iy0,
                                           inner.ix0 - outer.ix0:inner.ix1 - outer.ix0]
        _refresh_coarse(planner, inner)


def _refresh_coarse(planner: HybridAStar, inner: CellRect) -> None:
    """Recompute the heuristic's coarse multipliers on the coarse cells covering ``inner``."""
    f = planner.heuristic_factor
    o = planner.options
    h, w = planner.clearance.clearance.shape
    cy0, cx0 = inner.iy0 // f, inner.ix0 // f
    cy1, cx1 = -(-inner.iy1 // f), -(-inner.ix1 // f)
    fine = planner.clearance.clearance[cy0 * f:min(h, cy1 * f), cx0 * f:min(w, cx1 * f)]
    planner.holonomic_mult[cy0:cy1, cx0:cx1] = coarse_cost_grid(
        fine, planner.centre_threshold_m, planner.footprint.radius_m,
        max(o.proximity_range_m, planner.robot.preferred_clearance_m), o.cost_penalty, f)
    patch_guide(planner, cy0, cy1, cx0, cx1, fine)
