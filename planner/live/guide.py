"""A second holonomic heuristic for live replanning: gaps the robot cannot roll through are closed.

The Hybrid A*'s holonomic heuristic (eq. 14g) lets its wavefront through every cell whose clearance admits the
disc *inscribed* in the footprint (:attr:`HybridAStar.centre_threshold_m`): that keeps it admissible, since the
robot could stand there at some yaw. But a sphere rolls along its heading, so to pass *through* a gap it must
carry its full lateral extent across it (zju-60: 0.74 m wide, only 0.64 m long). A live map makes such gaps
all the time: a hidden box seen in part, from afar and at a grazing angle, leaves a gap between the wall and the
first hit on the box that is wider than the footprint's length and narrower than its width. The admissible
heuristic then leads the search into the gap, and it has to exhaust every (x, y, yaw, roll) state in front of
it before it will consider the detour: in ``maze-top-left-boxes`` 2 million expansions in 60 s without a path,
where the same search finds the 26 m detour in 50 000 expansions once the gap is closed.

The *guide* is the same coarse cost grid with the passability threshold raised from the inscribed radius to
the footprint's lateral half-width (less the planner's own discretisation slack): a cell is
open only if a robot passing through it along its heading could fit. It is not admissible everywhere (a robot
may stand closer to a wall than its half-width while facing it), so the cells around the start and the goal
keep the ordinary multipliers, a guided search that fails proves nothing, and the session falls back to the
ordinary search (:meth:`planner.live.session.LiveSession.replan`). A path a guided search finds is checked
exactly as any other: only the order of expansion changes, never the collision check.

A gap can also be wide enough for the robot and still a trap: a half-seen wall's end 0.75 m from a pillar's
corner, then a 0.85 m slot behind it, which no turn of a 1.1 m radius threads (``garage-west-aisle``). A guide
``widen_m`` wider (:data:`WIDE_M`) closes those as well; the session tries it after the plain guide, with a small
expansion budget each (:class:`planner.live.session.ReplanPolicy`).

The guides are kept per planner and patched with the ordinary multipliers by :mod:`planner.live.refresh`.
"""

from __future__ import annotations

import math
import weakref
from collections import OrderedDict

import numpy as np

from planner.hybrid_astar.heuristics import coarse_cost_grid
from planner.hybrid_astar.search import HybridAStar, Pose
from planner.maps.clearance import inscribed_radius
from planner.result import PlanResult
from planner.termination import Termination

WIDE_M = 0.15
"""How much wider than the footprint the second guide's gaps must be (m)."""

_guides: weakref.WeakKeyDictionary[HybridAStar, dict[float, np.ndarray]] = weakref.WeakKeyDictionary()


def lateral_half_width_m(polygon: np.ndarray) -> float:
    """The smaller of the footprint's extents to the left and to the right of its heading axis (m)."""
    y = np.asarray(polygon, float)[:, 1]
    return float(min(y.max(), -y.min()))


def guide_threshold_m(planner: HybridAStar, widen_m: float = 0.0) -> float:
    """The guide's passability threshold on the stored clearance (m), ``widen_m`` above the lateral half-width
    less the slack; never below the planner's own."""
    # the planner's threshold is the inscribed radius less its slack: the same slack below the half-width
    slack = inscribed_radius(planner.polygon) - planner.centre_threshold_m
    return max(planner.centre_threshold_m, lateral_half_width_m(planner.polygon) + widen_m - slack)


def _coarse(planner: HybridAStar, fine: np.ndarray, widen_m: float) -> np.ndarray:
    o = planner.options
    return coarse_cost_grid(fine, guide_threshold_m(planner, widen_m), planner.footprint.radius_m,
                            max(o.proximity_range_m, planner.robot.preferred_clearance_m), o.cost_penalty,
                            planner.heuristic_factor)


def guide_mult(planner: HybridAStar, widen_m: float = 0.0) -> np.ndarray:
    """The planner's guide multipliers (same shape as ``planner.holonomic_mult``) for gaps ``widen_m`` wider than
    the footprint, built on first use and then kept up to date by :func:`patch_guide`."""
    guides = _guides.setdefault(planner, {})
    mult = guides.get(widen_m)
    if mult is None:
        mult = guides[widen_m] = _coarse(planner, planner.clearance.clearance, widen_m)
    return mult


def patch_guide(planner: HybridAStar, cy0: int, cy1: int, cx0: int, cx1: int, fine: np.ndarray) -> None:
    """Recompute the planner's guides (those built so far) on coarse cells [cy0, cy1) × [cx0, cx1) from their fine
    clearance ``fine``."""
    for widen_m, mult in _guides.get(planner, {}).items():
        mult[cy0:cy1, cx0:cx1] = _coarse(planner, fine, widen_m)


def _open_around(planner: HybridAStar, mult: np.ndarray, xy: tuple[float, float], radius_m: float) -> None:
    """Give the coarse cells within ``radius_m`` of ``xy`` their ordinary multipliers."""
    grid = planner.grid
    cell = grid.resolution_m * planner.heuristic_factor
    hc, wc = mult.shape
    cx = (xy[0] - grid.origin[0]) / cell
    cy = (xy[1] - grid.origin[1]) / cell
    r = radius_m / cell
    x0, x1 = max(0, int(math.floor(cx - r))), min(wc, int(math.ceil(cx + r)) + 1)
    y0, y1 = max(0, int(math.floor(cy - r))), min(hc, int(math.ceil(cy + r)) + 1)
    if x0 < x1 and y0 < y1:
        mult[y0:y1, x0:x1] = planner.holonomic_mult[y0:y1, x0:x1]


def guided_plan(planner: HybridAStar, start: Pose, goal: Pose, termination: Termination,
                widen_m: float = 0.0) -> PlanResult:
    """Plan with the guide (``widen_m``) in place of the holonomic multipliers (around the start and the goal,
    within the footprint's reach plus two coarse cells, the ordinary ones); the planner is left as it was.
    Raises the planner's errors like :meth:`HybridAStar.plan`."""
    mult = guide_mult(planner, widen_m).copy()
    reach = float(np.hypot(*np.asarray(planner.polygon, float).T).max()) + \
        2.0 * planner.grid.resolution_m * planner.heuristic_factor
    for xy in (start[:2], goal[:2]):
        _open_around(planner, mult, (float(xy[0]), float(xy[1])), reach)
    saved = planner.holonomic_mult, planner._heuristics
    planner.holonomic_mult, planner._heuristics = mult, OrderedDict()
    try:
        return planner.plan(start, goal, termination)
    finally:
        planner.holonomic_mult, planner._heuristics = saved


__all__ = ["WIDE_M", "guide_mult", "guide_threshold_m", "guided_plan", "lateral_half_width_m", "patch_guide"]
