"""Anytime planning (issue 21, item 6): after the first path, cheaper ones while the caller's time budget lasts.

With ``PlannerOptions.improve_until_s`` > 0, :meth:`HybridAStar.plan` hands its first path (already smoothed, and
the forward-only alternative already weighed) to :func:`improve`, which runs improvement rounds until
``improve_until_s`` seconds from the start of the plan — or the request's own time limit, when that comes first:

1. **greed g** for g in :data:`GREEDS` (0.5, 0.25, 0) below the options' ``greed``: a new search (the cached
   holonomic table of the first) with f = g + (1 + g)·h — ARA*'s schedule of falling weights, each search started
   afresh — pruned by the search cost of the cheapest path found so far (``kernels.P_BOUND``: a child whose
   g + h exceeds it is dropped, h never exceeding the cost-to-go); its path is smoothed as usual and kept when it
   is cheaper. A mostly-backwards shot it held back is its path instead when that costs less than the path it found
   (as for the first path; ``by`` then says ``"greed g, held shot"``). The searches stop early enough to leave the
   last round its time;
2. **smoothing**: the best path shortcut again in up to DENSE_PASSES passes with DENSE_TRIES × the candidate
   targets per knot (on knots every search step, as the usual later passes), a pass started only when the last
   one's time (the first: estimated from the first path's smoothing) still fits before the deadline.

Measured on the real-map bench (docs/planning.md): the greed rounds give most of the gain, (0.5, 0.25, 0) a little
more than (0.25, 0), (0.5, 0), (0.75, 0.5, 0.25, 0) or the dense smoothing alone.

"Cheaper" is :meth:`HybridAStar._travel_cost`, the measure by which the planner already chooses between its
reversing path and its forward alternative: the length with the reverse metres weighted by ``reverse_penalty`` and
``switch_cost_m`` per cusp (for a path that never reverses: its length). A candidate is kept only when it also
passes the same exact footprint check as the final path, so an improvement round can never turn a plan into a
failure, and the first path is never replaced by a dearer one.

A round that runs out of time ends the improvement: the best path so far is the answer (not an error; when the
request's limit comes first the rounds end FINISH_SHARE of it early, leaving the final checks their time); a search
is stopped between compiled chunks, a smoothing pass once started finishes (as the first path's smoothing does).
A cancel is still a cancel (:class:`~planner.errors.PlannerCancelled` goes up). The result's
``extra["improvements"]`` lists the first path and every path kept (``t_s`` since the start of the plan,
``length_m``, ``cost``, ``by``: what produced it), ``extra["improvement_stop"]`` says why the rounds stopped:
``"deadline"`` (``improve_until_s`` reached), ``"time limit"`` (the request's limit came first),
``"admissible search finished"`` (the greed-0 search ended, found or exhausted below the bound: the search has no
cheaper path left to find; then the last smoothing still runs) or ``"rounds done"``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from planner.errors import PlannerCancelled, PlannerTimedOut, PlanningError
from planner.hybrid_astar import kernels
from planner.termination import Clock

if TYPE_CHECKING:
    from planner.hybrid_astar.heuristics import HolonomicHeuristic

# (search.py's HybridAStar, _Search and PlannerOptions are typed Any here: this module may not import search.py,
# which imports it; two_ended.py does the same)
HybridAStar = Any
PlannerOptions = Any
Pose = tuple[float, float, float]
Motion = tuple[float, float, float]

GREEDS = (0.5, 0.25, 0.0)  # the re-searches' greed, falling (ARA*); only those below the options' greed run
DENSE_TRIES = 2  # the dense smoothing tries this many times the options' smooth_max_tries targets per knot
DENSE_PASSES = 6  # ... in at most this many passes
DENSE_PASSES_RESERVED = 2  # the re-searches leave the time of this many dense passes before the deadline
DENSE_PASS_FACTOR = 2.0  # one dense pass ≈ this × the first path's whole smoothing (measured 0.5–2.5×, 23 problems)
DENSE_PASS_MIN_S = 0.01  # ... and at least this
FINISH_SHARE = 0.1  # the rounds leave this share of the request's time limit for the final checks when it binds
MAX_IMPROVE_S = 3600.0  # the largest improve_until_s accepted (an hour: a plan is never meant to take longer)


class Improver:
    """The best path so far and the record of how it improved (one plan's improvement rounds)."""

    def __init__(self, planner: HybridAStar, start: Pose, goal: Pose, o: PlannerOptions, clock: Clock,
                 motions: list[Motion], bound: float, smooth_s: float, new_search: Callable[..., Any]) -> None:
        self.planner = planner
        self.new_search = new_search  # search.py's _Search(planner, start, goal, heuristic, options, reverse)
        self.start = start
        self.goal = goal
        self.o = o
        self.clock = clock
        # the improvement clock: improve_until_s from the plan's start; when the request's own limit comes first, the
        # rounds end FINISH_SHARE of it before, so the final checks (and a door's, which count the whole plan against
        # the limit) still fit and the best path is an answer, not a timeout
        finish_by = clock.deadline - FINISH_SHARE * clock.time_limit_s
        self.limit_binds = clock.t0 + o.improve_until_s >= finish_by
        self.until = Clock(clock.termination, clock.t0, finish_by if self.limit_binds else clock.t0 + o.improve_until_s)
        # time kept for the dense smoothing at the end: DENSE_PASSES_RESERVED passes, each estimated from the first
        # path's whole smoothing (up to smooth_passes passes with half the targets per knot of a dense pass)
        self.reserve = (DENSE_PASSES_RESERVED * max(DENSE_PASS_MIN_S, DENSE_PASS_FACTOR * smooth_s) if o.smooth
                        else 0.0)
        self.motions = motions
        self.cost = planner._travel_cost(start, motions, o)
        self.bound = bound  # the search cost (g) of the cheapest path the search has found
        self.expansions = 0
        self.analytic: int | None = None  # the analytic segments of the search whose path was kept last (None: first)
        self.stop = ""
        self.rounds: list[dict[str, Any]] = []
        self._record("first path")

    def extra(self) -> dict[str, Any]:
        """What the result says about the improvement (``PlanResult.extra``; plain JSON types)."""
        return {"improvements": self.rounds, "improvement_stop": self.stop,
                "improvement_expansions": self.expansions, "improve_until_s": self.o.improve_until_s}

    def _record(self, by: str) -> None:
        self.rounds.append({"t_s": round(self.clock.elapsed_s(), 6),
                            "length_m": round(self.planner._length(self.start, self.motions), 6),
                            "cost": round(self.cost, 6), "by": by})

    def binding(self) -> str:
        """Which limit ends the improvement: ``"time limit"`` when the request's own limit comes no later than
        ``improve_until_s``, else ``"deadline"``."""
        return "time limit" if self.limit_binds else "deadline"

    def offer(self, motions: list[Motion], by: str, analytic: int | None = None) -> bool:
        """Keep ``motions`` (with the analytic segments of the search that found them, None: the same search)
        when they cost less than the best path and pass the exact footprint check."""
        cost = self.planner._travel_cost(self.start, motions, self.o)
        if cost >= self.cost - 1e-6 or not self._valid(motions):
            return False
        self.motions, self.cost = motions, cost
        if analytic is not None:
            self.analytic = analytic
        self._record(by)
        return True

    def _valid(self, motions: list[Motion]) -> bool:
        """Rolled from the start the path ends at the goal and is free (:meth:`HybridAStar.reaches_free`, the final
        check of :meth:`HybridAStar.plan`, done here so a failed candidate is only dropped)."""
        return bool(self.planner.reaches_free(self.start, self.goal, motions))

    def dense_smooth(self, motions: list[Motion], p: Any) -> list[Motion]:
        """Shortcut passes on knots every search step with DENSE_TRIES × the targets per knot, while a pass
        shortens the path by more than a millimetre and the last pass's time still fits before the deadline (a
        compiled pass cannot be stopped half-way)."""
        pl, o = self.planner, self.o
        tries = min(1000, DENSE_TRIES * o.smooth_max_tries)
        length = pl._length(self.start, motions)
        took = self.reserve / DENSE_PASSES_RESERVED
        for _ in range(DENSE_PASSES):
            if self.until.remaining_s() < took:
                break
            t = time.perf_counter()
            candidate = pl._shortcut(self.start, pl._subdivide(motions), p, tries)
            took = time.perf_counter() - t
            new_length = pl._length(self.start, candidate)
            if new_length > length - 1e-3:
                break
            motions, length = candidate, new_length
        return motions

    def research(self, heur: HolonomicHeuristic, greed: float, until: Clock
                 ) -> tuple[list[Motion] | None, Any, bool, bool]:
        """One search with ``greed``, pruned by :attr:`bound`, until ``until``: its path (None when none was found),
        the search, whether it ran to its end (found or exhausted, not stopped by the clock or the iteration
        cap) and whether the path is the shot it held back (chosen as for the first path,
        ``HybridAStar._held_if_cheaper``). The path is smoothed as usual."""
        pl, o = self.planner, self.o
        run = self.new_search(pl, self.start, self.goal, heur, o, pl.reverse)
        run.p[kernels.P_GREED] = greed
        run.p[kernels.P_BOUND] = self.bound
        try:
            pl._drive(run, self.start, self.goal, o, until, fail_fast=False)
        except PlannerCancelled:
            raise
        except PlannerTimedOut:
            self.expansions += run.expansions
            return None, run, False, False
        except PlanningError:  # exhausted below the bound (no cheaper path), or the iteration cap
            self.expansions += run.expansions
            return None, run, run.expansions < self.clock.termination.max_iterations, False
        self.expansions += run.expansions
        self.bound = min(self.bound, pl._search_cost(run))
        # (out of time with a held-back shot, _drive returns that shot: a path, but not the search's end)
        finished = not until.expired()
        found = pl._smooth(self.start, pl._motions(run), run.p, o)
        held = pl._held_if_cheaper(self.start, run, found, o)
        return held or found, run, finished, held is not None


def improve(planner: HybridAStar, start: Pose, goal: Pose, heur: HolonomicHeuristic, o: PlannerOptions,
            clock: Clock, motions: list[Motion], bound: float, p: Any, smooth_s: float,
            new_search: Callable[..., Any]) -> Improver:
    """Improvement rounds on the first path ``motions`` (whose search cost is ``bound``) until ``o.improve_until_s``
    or the request's deadline; the returned :class:`Improver` holds the best path (``motions``), the rounds kept
    (``rounds``), why they stopped (``stop``) and the expansions they ran. ``p`` is the first search's parameter
    array (the smoothing's clearance and footprint settings), ``smooth_s`` the time the first path's smoothing
    took (the dense smoothing's time is reserved from it), ``new_search`` search.py's ``_Search``."""
    imp = Improver(planner, start, goal, o, clock, motions, bound, smooth_s, new_search)
    # the re-searches stop early enough to leave the dense smoothing of the best path its time
    searches = Clock(clock.termination, clock.t0, imp.until.deadline - imp.reserve)
    stop = None
    for greed in (g for g in GREEDS if g < o.greed):
        if searches.expired():
            stop = imp.binding()
            break
        found, run, finished, held = imp.research(heur, greed, searches)
        if found is not None:
            shots = int(run.counters[kernels.C_SHOT_SEGS])
            imp.offer(found, f"greed {greed:g}" + (", held shot" if held else ""), shots)
        if not finished:
            stop = imp.binding()
            break
        if greed == 0.0:
            stop = "admissible search finished"
    if o.greed == 0.0:
        stop = "admissible search finished"  # the first search was the admissible one
    if o.smooth and imp.until.remaining_s() > 0:
        imp.offer(imp.dense_smooth(imp.motions, p), "smoothing")
    if clock.cancelled():
        raise PlannerCancelled("planning was cancelled", planning_time_s=clock.elapsed_s(), expansions=imp.expansions)
    imp.stop = stop or ("rounds done" if imp.until.remaining_s() > 0 else imp.binding())
    return imp
