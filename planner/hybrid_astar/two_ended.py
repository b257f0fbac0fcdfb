"""The goal side of a two-ended search: the reverse problem searched alongside the forward one.

Some problems trap the forward search at the start (a pocket whose way out the holonomic heuristic does not
see) while the same search started from the goal finds a path in a few thousand expansions. :class:`GoalSide`
runs the reverse problem (from the goal to the start, every motion run backwards) in chunks interleaved with
the forward search's (:meth:`HybridAStar._drive`); whichever finds a path first wins, and when the reverse
problem runs out of states that is the proof that the goal pose is a dead end.

The reverse problem is posed with the heading turned by π. Eq. 1 is unchanged under
(yaw, φ, κ, s) → (yaw + π, −φ, −κ, −s), and a motion (shift to the held roll φ, then an arc of curvature κ and
signed length s) run backwards in time is the arc (κ, −s) followed by the shift back. So a path of motions
m_1 … m_N (held roll φ_i, curvature κ_i, length s_i) from (goal, yaw + π) to (start, yaw + π), upright at both
ends, is rolled from the start to the goal by (−φ_N, −κ_N, s_N), …, (−φ_1, −κ_1, s_1) and a last return to
upright (:func:`goal_side_motions`): it rolls forwards where the reverse-problem path rolled forwards, so the
search's forward preference (reverse multiplier, held-back mostly-backwards shots) carries over unchanged.
The footprint turns with the heading: the reverse problem is only the same problem for a footprint that is
centrally symmetric (:func:`centrally_symmetric`); for any other the goal side is not searched.

A path found from the goal starts within the goal tolerance of the start only, unless its last motions are an
analytic shot (which lands within 0.1 mm). A path that ends on a tolerance hit is closed with a shot to the
exact start from its end or one of its last nodes, else dropped (the search goes on). The converted path is
rolled from the true start and checked with the exact footprint before it is returned.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from planner.hybrid_astar import kernels
from planner.hybrid_astar.heuristics import GOAL_SIDE_STOP_FACTOR
from planner.hybrid_astar.meet import YAW_BINS, Meeting, find_turn
from planner.hybrid_astar.reeds_shepp import MAX_SHOT_M
from planner.kinematics import wrap
from planner.termination import Clock

# (search.py's HybridAStar, _Search and PlannerOptions are typed Any here: this module may not import search.py,
# which imports it)
Pose = tuple[float, float, float]
Motion = tuple[float, float, float]

TURN_BUDGET = 1_000  # expansions of one search for a turn between the trees (meet.find_turn)
TURN_TRIES = 12  # ... and at most this many such searches per plan
TURN_AFTER = 6_000  # expansions of both sides before the first look for a place to turn between the trees
TURN_LOOK_EVERY = 4_000  # expansions of both sides between two looks for such a place that found none
GAP_NODES = 12  # nodes back along a tolerance-hit path from which a shot to the exact start is tried


def goal_side_motions(motions: list[Motion]) -> list[Motion]:
    """Motions of a reverse-problem path (from the goal with the heading turned by π, starting upright) as the
    path that rolls from the start to the goal: order reversed, held roll and curvature negated, signed
    length kept; ends upright."""
    out = [(-h + 0.0, -c + 0.0, s) for h, c, s in reversed(motions)]
    while out and out[0][0] == 0.0 and out[0][2] == 0.0:  # returns to upright at its end: nothing to do at ours
        out.pop(0)
    out.append((0.0, 0.0, 0.0))
    return out


def centrally_symmetric(x: np.ndarray, y: np.ndarray, tol: float = 1e-9) -> bool:
    """True when the points (x, y) are the same set turned by π about the origin."""
    pts = np.column_stack([x, y])
    if len(pts) == 0:
        return True
    d = np.hypot(pts[:, None, 0] + pts[None, :, 0], pts[:, None, 1] + pts[None, :, 1])
    return bool(d.min(axis=1).max() <= tol * max(1.0, float(np.abs(pts).max())))


def goal_side_possible(planner: Any) -> bool:
    """The reverse problem with the heading turned by π is the same problem: the footprint polygon and its
    covering circles are centrally symmetric."""
    fp = planner.footprint
    return centrally_symmetric(planner._px, planner._py) and centrally_symmetric(fp.offsets_x, fp.offsets_y)


class GoalSide:
    """The reverse problem's search, stepped a chunk at a time; :attr:`motions` is the path it found (from the
    start to the goal), :attr:`exhausted` says it ran out of states (the goal pose is a dead end).

    ``new_search(planner, start, goal, heuristic, options, reverse)`` makes the search (search.py's ``_Search``);
    ``reverse`` (default the planner's) says whether its motions may roll backwards: the forward-only alternative's
    goal side rolls forwards only (:meth:`HybridAStar._forward_both_ends`).
    """

    def __init__(self, planner: Any, start: Pose, goal: Pose, o: Any, new_search: Callable[..., Any],
                 reverse: bool | None = None) -> None:
        self.planner = planner
        self.reverse = planner.reverse if reverse is None else reverse
        self.o = o
        self.start = start
        self.goal = goal
        self.back_start = (goal[0], goal[1], wrap(goal[2] + math.pi))
        self.back_goal = (start[0], start[1], wrap(start[2] + math.pi))
        heur = planner.holonomic(self.back_goal[:2], self.back_start[:2], GOAL_SIDE_STOP_FACTOR)
        self.run = new_search(planner, self.back_start, self.back_goal, heur, o, self.reverse)
        self.motions: list[Motion] | None = None
        self.exhausted = False
        self.closed_gaps = 0
        self.dropped = 0
        self.meeting: Meeting | None = None
        #: the path joins the two trees (meet.py): the shot's segment count and the search cost of the join
        self.met_segments = 0
        self.met_cost = math.inf
        self.new_search = new_search
        #: searches for a turn between the trees (:meth:`_turn`) and their expansions
        self.turns = 0
        self.turn_expansions = 0
        self._turn_tried: np.ndarray | None = None
        self._turn_look_at = TURN_AFTER  # both sides' expansions before which no place for a turn is looked for again

    @property
    def expansions(self) -> int:
        """This side's expansions, its searches for a turn between the trees included."""
        return self.run.expansions + self.turn_expansions

    @property
    def analytic(self) -> int:
        return int(self.run.counters[kernels.C_SHOT_SEGS])

    def step(self, budget: int) -> bool:
        """Up to ``budget`` expansions; True when a path was found (:attr:`motions`) or the search exhausted."""
        if budget <= 0 or self.exhausted or self.motions is not None:
            return self.exhausted or self.motions is not None
        status = self.run.step(budget)
        if status == kernels.EXHAUSTED:
            self.exhausted = True
            return True
        if status == kernels.FOUND:
            if self.run.counters[kernels.C_SHOT_SEGS] == 0 and not self._close_gap():
                self.dropped += 1
                return False
            motions = goal_side_motions(self.planner._motions(self.run))
            if self._valid(motions):
                self.motions = motions
                return True
            self.dropped += 1
        return False

    def meet(self, forward: Any, clock: Clock) -> bool:
        """One round of :class:`~planner.hybrid_astar.meet.Meeting` between ``forward`` (the forward search) and
        this side's tree; True (and :attr:`motions` set) when a shot joins them into a path that passes the exact
        check."""
        if self.motions is not None or self.exhausted:
            return self.motions is not None
        if self.meeting is None:
            self.meeting = Meeting(self.planner)
        hit = self.meeting.round(forward, self.run)
        if hit is None:
            return self._turn(forward, clock)
        i, j, n = hit
        mt, pl = self.meeting, self.planner
        shot = [(float(mt.seg_roll[m]), float(mt.seg_curv[m]), float(mt.seg_len[m])) for m in range(n)]
        motions = pl._chain(forward, i) + shot + [(0.0, 0.0, 0.0)] + goal_side_motions(pl._chain(self.run, j))
        if not self._valid(motions):
            self.dropped += 1
            return False
        self.motions = motions
        self.met_segments = n
        self.met_cost = (float(forward.node_f[i, 4]) + float(self.run.node_f[j, 4])
                         + float(kernels._shot_cost(forward.p, int(forward.node_i[i, 2]), mt.seg_len, n)))
        return True

    def _turn(self, forward: Any, clock: Clock) -> bool:
        """No shot joined the trees this round: where they hold nodes in one cell with opposite headings (each side
        rolled the shared way the other way round), search the turn between them, the roomiest such cell first
        (:func:`meet.find_turn`), each within TURN_BUDGET expansions, at most TURN_TRIES per plan; when there is no
        such cell, none is looked for again until both sides have made TURN_LOOK_EVERY more expansions (a look scans
        every bucket of the forward tree; until issue 21's nineteenth round every bucket of the map, 1.4 ms on a
        100 m map). The search runs with the planner's own motions from the forward
        node's pose to the goal-side node's (turned into the forward frame) and ends only on an exact shot to it (no
        tolerance), so the goal side's chain follows on exactly; the plan's ``clock`` stops them like the plan. True
        (and :attr:`motions` set) when a turn joins them into a path that passes the exact check."""
        mt, pl = self.meeting, self.planner
        assert mt is not None
        if self._turn_tried is None:
            self._turn_tried = np.zeros(mt.nx * mt.ny, dtype=np.bool_)
        total = forward.expansions + self.run.expansions
        if total < self._turn_look_at:
            return False
        while self.turns < TURN_TRIES and not (clock.expired() or clock.cancelled()):
            i, j, cell = find_turn(mt.forward.keys, mt.forward.nodes, mt.back.keys, mt.back.nodes, forward.node_f,
                                   forward.node_i, mt.upright, YAW_BINS,
                                   pl.clearance.clearance, pl.clearance.origin_x, pl.clearance.origin_y,
                                   pl.grid.resolution_m, self._turn_tried)
            if i < 0:
                self._turn_look_at = total + TURN_LOOK_EVERY
                return False
            self.turns += 1
            self._turn_tried[cell] = True
            start = (float(forward.node_f[i, 0]), float(forward.node_f[i, 1]), float(forward.node_f[i, 2]))
            bx, by, byaw = (float(v) for v in self.run.node_f[j, :3])
            goal = (bx, by, wrap(byaw + math.pi))
            run = self.new_search(pl, start, goal, pl.holonomic(goal[:2], start[:2], cache=False), self.o,
                                  self.reverse)
            run.p[kernels.P_TOL_XY] = 0.0
            run.p[kernels.P_TOL_YAW] = 0.0
            status = run.run_for(TURN_BUDGET, clock)
            self.turn_expansions += run.expansions
            if status != kernels.FOUND:
                continue
            motions = pl._chain(forward, i) + pl._motions(run) + goal_side_motions(pl._chain(self.run, j))
            if not self._valid(motions):
                self.dropped += 1
                continue
            self.motions = motions
            self.met_segments = max(1, int(run.counters[kernels.C_SHOT_SEGS]))
            self.met_cost = float(forward.node_f[i, 4]) + float(self.run.node_f[j, 4]) + pl._search_cost(run)
            return True
        return False

    def _close_gap(self) -> bool:
        """The search ended within the goal tolerance of the start: shoot to the exact start from the node it
        ended on or one of the GAP_NODES before it; True (and the result replaced) when a shot is free."""
        run, pl = self.run, self.planner
        kinds = ((kernels.SHOT_WEIGHTED, kernels.SHOT_SHORTEST) if run.p[kernels.P_ALLOW_REVERSE] > 0.5
                 else (kernels.SHOT_DUBINS,))
        gx, gy, gyaw = self.back_goal
        k = int(run.counters[kernels.C_RESULT])
        for _ in range(GAP_NODES):
            x, y, yaw, roll = (float(v) for v in run.node_f[k, :4])
            for kind in kinds:
                n = kernels.try_shot(pl.clearance.clearance, pl.clearance.blocked, run.p, pl.footprint.offsets_x,
                                     pl.footprint.offsets_y, pl._px, pl._py, x, y, yaw, roll, gx, gy, gyaw, 0.0,
                                     run.seg_roll, run.seg_curv, run.seg_len, MAX_SHOT_M, 0.0, kind)
                if n > 0:
                    run.counters[kernels.C_RESULT] = k
                    run.counters[kernels.C_SHOT_SEGS] = n
                    self.closed_gaps += 1
                    return True
            k = int(run.node_i[k, 0])
            if k < 0:
                break
        return False

    def _valid(self, motions: list[Motion]) -> bool:
        """Rolled from the true start the path ends at the goal and is free (:meth:`HybridAStar.reaches_free`)."""
        return bool(self.planner.reaches_free(self.start, self.goal, motions))
