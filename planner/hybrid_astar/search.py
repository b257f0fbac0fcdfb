"""Spherical Hybrid A* (paper 001 §4.1, eq. 14, with the corrections listed in docs/references.md).

The search state is (x, y, yaw, roll). A child holds one roll from a discrete set spread evenly in
curvature over [−φmax, φmax]; switching roll first rolls the shell sideways by r·Δφ (eq. 1), then the
child rolls one exact arc of eq. 1 whose length is at least a cell diagonal (and long enough for the
tightest turn to change heading by one yaw bin). Nodes are closed on (cell, yaw bin, roll index).

g sums length (sideways shifts included) × (1 + cost_penalty·proximity), a non-straight multiplier,
a roll-change cost, a reverse multiplier and a direction-switch cost (eq. 14f, with Nav2 Smac's terms);
h = max(holonomic cost-to-go with obstacles, Dubins distance at the minimum turning radius; the Reeds–Shepp
distance near the goal with reversing) (eq. 14g–i); f = g + h·(1 + greed) (eq. 14j). Every few expansions an
analytic Dubins shot to the goal is tried, turned into roll-held segments whose sideways shifts are compensated,
and collision-checked. With reversing, compiled Reeds–Shepp shots (:mod:`planner.hybrid_astar.reeds_shepp`: the
cheapest word under the reverse and cusp weights, else the shortest) are tried from each node a tenth closer to
the goal and every 256 expansions from the closest node; a shot that would make the path roll mostly backwards is
held back for a few thousand expansions while the search looks for a path that turns round.

The loop runs compiled (:mod:`planner.hybrid_astar.kernels`) in chunks; between chunks this driver checks the
deadline, the iteration cap and cancellation, and grows the node storage.

Algorithm outline (numbered like the compiled loop):
 1. pop the cheapest open node; skip it if its (cell, yaw bin, roll) key is closed; sweep its motion from its parent
    (lazily: a child is checked only at its end pose when pushed) and drop it if that collides, else close it;
 2. goal test (after returning the roll to 0);
 3. analytic expansion: Dubins every max(1, h / ratio) expansions, Reeds–Shepp as above (3b, 3c);
 4. expand children (each roll, forward and optionally reverse), their end poses checked (the motion is swept at
    ≤ half a cell when the child is popped, 1);
 5. cost them and push them.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections import OrderedDict
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from functools import cached_property
from typing import Any

import numpy as np

from planner.errors import (
    GoalOccupied,
    GoalOutsideMap,
    InvalidInput,
    NoValidPathFound,
    PlannerCancelled,
    PlannerTimedOut,
    PlanningError,
    StartOccupied,
    StartOutsideMap,
)
from planner.hybrid_astar import closed_set, kernels, meet, smoothing
from planner.hybrid_astar.anytime import MAX_IMPROVE_S, improve
from planner.hybrid_astar.dubins import dubins_distance
from planner.hybrid_astar.heuristics import (
    GOAL_SIDE_STOP_FACTOR,
    STOP_FACTOR,
    HolonomicHeuristic,
    auto_downsample,
    coarse_cost_grid,
    reeds_shepp_table,
)
from planner.hybrid_astar.two_ended import GoalSide, goal_side_possible
from planner.kinematics import densify_motions, motion_knots, subdivide, wrap
from planner.maps.clearance import CircleFootprint, ClearanceMap, convex_turn, inscribed_radius
from planner.maps.reachability import refuse_unreachable
from planner.occupancy import OccupancyGrid
from planner.result import PlanResult, build_states
from planner.robot import RobotProfile
from planner.termination import Clock, Termination

log = logging.getLogger(__name__)

RS_CELL_M = 0.1  # sampling of the Reeds–Shepp heuristic table (m)
MAX_STEP_M = 10.0  # longest expansion a request may ask for (options.step_m): its collision samples grow with it
CHUNK_SAMPLES = 200_000  # collision samples per compiled chunk at most, so the clock is polled at least that often
CLEARANCE_REACH_M = 2.0  # the reported min_clearance_m is capped here (farther obstacles do not matter)
HEURISTIC_CACHE_SIZE = 8  # holonomic tables kept per planner (one per goal cell)
GOAL_CHECK_AFTER = 20_000  # expansions without a path before the goal's surroundings are searched (fail fast)
GOAL_CHECK_BUDGET = 40_000  # expansions that search may take
GOAL_CHECK_SHARE = 0.15  # ... and at most this share of the time limit
# The budgets counted in expansions marked (×bins) were measured at BUDGET_BINS heading bins; a search at n bins
# gets n / BUDGET_BINS of each: the step follows the bin, so the same metres of search (issue 21's thirteenth round:
# at the default 36 bins, half the budgets of 72 took 17 % fewer expansions on the real-map problems of seeds 0–7 for
# the same total length; halving GOAL_SIDE_AFTER and the turn searches' budgets cost more than it spared, and halving
# FALLBACK_WAIT, the wait for a shot that keeps the room asked, took room from 6 of those 480 paths).
BUDGET_BINS = 72
GOAL_SIDE_AFTER = 500  # expansions without a path before the goal side's search joins in (two_ended.py)
MEET_AFTER = 2_000  # expansions of both sides before shots try to join their trees (meet.py) (×bins)
FINER_BINS = 72  # a search that runs out of states at fewer heading bins is run again at this many (plan)
ROOT_SHOT_AT_ONCE = True  # the start's own cheapest shot is the path at once, even rolling backwards (kernels 3c)
HOLD_EXPANSIONS = 4_000  # a held-back shot (kernels 3c, P_HOLD_WAIT) waits this many for a path that rolls forwards
# more (×bins)
FORWARD_RETRY_PER_M = 250  # expansions a forward-only search may take to find a cheaper path, per metre start–goal
# (×bins, as are the next two),
FORWARD_RETRY_MIN = 1_000  # ... at least this many
FORWARD_RETRY_MAX = 20_000  # ... and at most this many (docs/planning.md: the budgets the accepted paths needed)
FORWARD_RETRY_SHARE = 0.5  # ... tried when the path found rolls more than this share of its length backwards
FORWARD_RETRY_TIMES = 3  # ... and at most this many × the plan's expansions before it
NO_HOLD_SHARE = 2.0  # P_BACK_SHARE with prefer_forward off: no shot rolls more than this share backwards, so none
# is held back (3c) or kept as a mostly-backwards fallback (3d)
FORWARD_CHECK_BUDGET = 600  # ... and this many more for its goal side, which proves there is no forward path
# cheaper when it runs out of states (×bins)
FORWARD_SLICE = 100  # ... the two sides taking turns of this many expansions (issue 21's eighteenth round)
_LOOP = threading.local()  # the current thread's plan: its clock, its seconds in the compiled loop (search_loop_time_s)
GROWTH_MARGIN = 2.5  # a search's storage grows only when this × its last growth's time still fits before the deadline
# Smoothing's recheck rule (kernels.shortcut): a target whose shot failed from a knot just before is retried only
# every this many knots, in the later passes and in the first (1 = every candidate from every knot). On the 180
# real-map problems of seeds 0–2 it cuts the smoothing time by a third for paths 0.03–0.07 % shorter in all
# (issue 21, sixth round). It was off from the third round to the sixth: the explore sweep's warehouse-aisle world
# collided with it, which it no longer does since the fifth round's margins (docs/planning.md).
SMOOTH_RECHECK = 3
SMOOTH_RECHECK_FIRST = 2
# The later smoothing passes (on the path subdivided to the search step) try this share of smooth_max_tries targets
# per knot: on the 60 real-map problems half the targets cut the smoothing time by a third (the median plan by a
# quarter) for paths 0.26 % longer in all (docs/planning.md, fourth round).
LATER_PASS_TRIES = 0.5


@dataclass(frozen=True)
class PlannerOptions:
    """Parameters of the spherical Hybrid A* (SI units, radians). Defaults follow Nav2 Smac where the
    paper is silent."""

    n_rolls: int = 7                  # discrete held rolls in [−φmax, φmax] (odd, ≥ 5), even in curvature
    n_yaw_bins: int = 36              # closed-set heading bins (10°)
    n_roll_bins: int = 3              # closed-set roll bins (left/upright/right; 0 = one per held roll)
    step_m: float = 0.0               # arc length per expansion; 0 = automatic (see ``resolved_step``)
    open_step_factor: int = 3         # in the open (clearance > footprint reach + the longer arc), steps this long
    allow_reverse: bool | None = None  # None = the robot's own ``reversible`` (true for the spheres)
    dead_end_check: bool = True       # search from the goal too (two_ended.py): finds the path or proves a dead end
    n_circles: int = 3                # covering circles of the footprint (paper 001 Fig. 6)
    allow_unknown: bool = False
    goal_tolerance_m: float = 0.1
    goal_tolerance_yaw_rad: float = math.radians(5.0)
    non_straight_penalty: float = 1.03
    change_penalty: float = 0.1       # per metre of sideways shift caused by a roll change
    reverse_penalty: float = 1.2       # a sphere rolls backwards as well as forwards (Nav2 uses 2.0 for cars)
    switch_cost_m: float = 1.0
    cost_penalty: float = 2.0         # proximity weight (Nav2 ``cost_penalty``, same default)
    proximity_range_m: float = 1.0    # proximity cost fades to 0 this far beyond the inflated obstacles
    greed: float = 1.0               # eq. 14j; 0 = admissible A* (slow); smoothing recovers length
    analytic_ratio_m: float = 3.5     # try a Dubins shot every max(1, h / ratio) expansions
    heuristic_downsample: int = 0     # holonomic grid coarsening; 0 = auto (≥ 2, at most ~50k coarse cells)
    chunk_expansions: int = 500
    state_spacing_m: float = 0.04     # spacing of the returned states (≤ 5 cm, docs/contracts.md)
    smooth: bool = True               # shortcut the search's path with collision-checked rollable Dubins shots
    smooth_max_tries: int = 24        # candidate shortcut targets tried per path knot (half in the later passes)
    smooth_passes: int = 3            # shortcut passes; later passes re-subdivide the path (≈ 2 % shorter)
    prefer_forward: bool = True       # with reversing: hold back a mostly-backwards shot for a path that turns round
    # and try a bounded forward-only search, the cheaper kept (false: neither, the search's path as it finds it)
    weighted_rs_heuristic: bool = False  # with reversing: the Reeds–Shepp heuristic prices reversing and cusps
    improve_until_s: float = 0.0      # anytime: look for cheaper paths until this many s from the start (0 = off)

    def __post_init__(self) -> None:
        """Every option set is checked when it is made: raise :class:`InvalidInput` naming the first bad option."""
        def need(ok: bool, name: str, msg: str) -> None:
            if not ok:
                raise InvalidInput(f"options.{name}", msg)

        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, float):
                need(math.isfinite(value), f.name, f"must be finite, got {value!r}")
        need(5 <= self.n_rolls <= 31 and self.n_rolls % 2 == 1, "n_rolls", "must be an odd number in [5, 31]")
        need(8 <= self.n_yaw_bins <= 720, "n_yaw_bins", "must be in [8, 720]")
        need(self.n_roll_bins == 0 or (3 <= self.n_roll_bins <= self.n_rolls and self.n_roll_bins % 2 == 1),
             "n_roll_bins", "must be 0 (one per held roll) or an odd number in [3, n_rolls]")
        need(0 <= self.step_m <= MAX_STEP_M, "step_m", f"must be in [0, {MAX_STEP_M:g}] m (0 = automatic)")
        need(1 <= self.n_circles <= 16, "n_circles", "must be in [1, 16]")
        need(1 <= self.open_step_factor <= 8, "open_step_factor", "must be in [1, 8] (1 = every step the same)")
        need(self.goal_tolerance_m > 0, "goal_tolerance_m", "must be > 0")
        need(self.goal_tolerance_yaw_rad > 0, "goal_tolerance_yaw_rad", "must be > 0")
        for name in ("non_straight_penalty", "reverse_penalty"):
            need(getattr(self, name) >= 1.0, name, "must be ≥ 1")
        for name in ("change_penalty", "switch_cost_m", "cost_penalty", "proximity_range_m", "greed"):
            need(getattr(self, name) >= 0.0, name, "must be ≥ 0")
        need(self.analytic_ratio_m > 0, "analytic_ratio_m", "must be > 0")
        need(0 <= self.heuristic_downsample <= 8, "heuristic_downsample", "must be in [0, 8] (0 = auto)")
        need(1 <= self.chunk_expansions <= 1_000_000, "chunk_expansions", "must be in [1, 1 000 000]")
        need(0 < self.state_spacing_m <= 0.05, "state_spacing_m", "must be in (0, 0.05]")
        need(1 <= self.smooth_max_tries <= 1000, "smooth_max_tries", "must be in [1, 1000]")
        need(1 <= self.smooth_passes <= 20, "smooth_passes", "must be in [1, 20]")
        need(0 <= self.improve_until_s <= MAX_IMPROVE_S, "improve_until_s",
             f"must be in [0, {MAX_IMPROVE_S:g}] s from the start of the plan (0 = return the first path)")

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> PlannerOptions:
        """Options from a JSON object; unknown keys and wrong types are rejected by name."""
        known = {f.name: f for f in fields(cls)}
        values: dict[str, Any] = {}
        for key, value in data.items():
            if key in ("time_limit_s", "max_iterations"):
                raise InvalidInput(f"options.{key}", "is not a planner option: when to stop is the request's own "
                                                     f"{key} (CLI --time-limit), one value for every door")
            if key not in known:
                raise InvalidInput(f"options.{key}", f"unknown option; known: {', '.join(sorted(known))}")
            default = getattr(cls(), key)
            if default is None:  # an optional switch (None = the robot decides)
                if value is not None and not isinstance(value, bool):
                    raise InvalidInput(f"options.{key}", f"must be true, false or null, got {value!r}")
                values[key] = value
                continue
            if isinstance(default, bool):
                if not isinstance(value, bool):
                    raise InvalidInput(f"options.{key}", f"must be true or false, got {value!r}")
            elif isinstance(default, int):
                if isinstance(value, bool) or not isinstance(value, int):
                    raise InvalidInput(f"options.{key}", f"must be an integer, got {value!r}")
            elif isinstance(value, bool) or not isinstance(value, int | float):
                raise InvalidInput(f"options.{key}", f"must be a number, got {value!r}")
            try:
                values[key] = type(default)(value)
            except OverflowError:  # an integer too large for a float (1 followed by 400 zeros)
                raise InvalidInput(f"options.{key}", f"must be a finite number, got an integer of "
                                                     f"{len(str(abs(value)))} digits") from None
        return cls(**values)


Pose = tuple[float, float, float]


def rs_table_for(robot: RobotProfile, o: PlannerOptions, clock: Clock | None = None) -> np.ndarray:
    """The Reeds–Shepp heuristic table a reversing search with options ``o`` uses (cached per process).

    By default the words' plain length (the Reeds–Shepp distance). With ``o.weighted_rs_heuristic`` their cost
    under the search's own ``reverse_penalty`` and ``switch_cost_m``: measured on the 60 real-map problems it finds
    paths 0.3 % shorter and 0.4 % cheaper, but a greedy search (greed 1) then floods the tight pockets where
    the car's table asks for a cusp the sphere's sideways roll shift does not need (pockets#2: 18 k → 230 k
    expansions), so it is not the default (docs/planning.md).
    """
    weights = (o.reverse_penalty, o.switch_cost_m) if o.weighted_rs_heuristic else (1.0, 0.0)
    return reeds_shepp_table(robot.min_turning_radius_m, o.n_yaw_bins, RS_CELL_M, clock=clock,
                             reverse_penalty=weights[0], switch_cost_m=weights[1])

_compiled = False


def warm_up() -> float:
    """Compile (or load from numba's on-disk cache) every kernel of the search by planning once on a small
    open map, so that no plan's time limit is spent compiling. Runs once per process; returns the seconds
    it took (0 when already done)."""
    global _compiled
    if _compiled:
        return 0.0
    _compiled = True
    t0 = time.perf_counter()
    from planner.robot import load_robot

    occupied = np.zeros((80, 80), dtype=bool)
    occupied[30:50, 38:42] = True
    grid = OccupancyGrid.from_occupied(occupied, 0.1, name="warm-up")
    robot = load_robot()
    for reverse in (False, True):
        planner = HybridAStar(grid, robot, PlannerOptions(allow_reverse=reverse))
        planner.plan((1.5, 1.5, 0.0), (6.5, 6.5, math.pi / 2))
    # a shot from Python, as the goal side's searches shoot (two_ended, meet), and a held or fallback shot taken from
    # Python: the search's own calls do not compile these signatures for Python, and a plan that first needed one
    # spent up to a second compiling it
    run = _Search(planner, (1.5, 1.5, 0.0), (6.5, 6.5, 0.0), planner.holonomic((6.5, 6.5)), planner.options, True)
    kernels.try_shot(planner.clearance.clearance, planner.clearance.blocked, run.p, planner.footprint.offsets_x,
                     planner.footprint.offsets_y, planner._px, planner._py, 1.5, 1.5, 0.0, 0.0, 6.5, 6.5, 0.0, 0.0,
                     run.seg_roll, run.seg_curv, run.seg_len, 10.0, 0.0, kernels.SHOT_WEIGHTED)
    kernels.take_held(run.counters, run.seg_roll, run.seg_curv, run.seg_len)  # as _held_if_cheaper and _take_kept
    kernels.take_fallback(run.counters, run.seg_roll, run.seg_curv, run.seg_len)
    dubins_distance(1.5, 1.5, 0.0, 6.5, 6.5, 0.0, robot.min_turning_radius_m)  # the forward alternative's bound
    motions = [(0.0, 0.0, 1.0), (0.0, 0.0, 1.0)]
    planner._shortcut((1.5, 1.5, 0.0), motions, run.p, 1)  # one pass, as anytime.py runs
    planner._knots((1.5, 1.5, 0.0), planner._subdivide(motions))  # anytime.py and the joins' checks, from Python
    _cusps(motions)  # _travel_cost's, from Python
    meet.warm_up()
    took = time.perf_counter() - t0
    log.info("compiled the search kernels in %.2f s (once per process)", took)
    return took


def _cusps(motions: list[tuple[float, float, float]]) -> int:
    """Changes of travel direction along the motions (:func:`planner.hybrid_astar.smoothing.cusps`)."""
    return smoothing.cusps(np.array(motions, float).reshape(-1, 3))


def _as_motions(rows: np.ndarray) -> list[tuple[float, float, float]]:
    """Motion rows (held roll, curvature, signed length) as the list of tuples the planner passes around."""
    return [(h, c, v) for h, c, v in rows.tolist()]


CLEAR_BYTES_PER_NODE = 150  # a finished search's bitset is cleared node by node below this many bytes a node
FALLBACK_WAIT = 400  # kernels 3d: expansions a shot that keeps less room than asked waits for one that keeps it
BACK_FALLBACK_WAIT = 1.5  # ... this × as many when the shot makes the path roll mostly backwards (kernels P_BACK_WAIT)


def _take_kept(run: _Search) -> bool:
    """Make the shot ``run`` holds back (kernels 3c), else the one it keeps to fall back on (3d), its result; False
    when it has neither."""
    if run.counters[kernels.C_HELD_SEGS] > 0:
        kernels.take_held(run.counters, run.seg_roll, run.seg_curv, run.seg_len)
        return True
    if run.counters[kernels.C_FALL_SEGS] > 0:
        kernels.take_fallback(run.counters, run.seg_roll, run.seg_curv, run.seg_len)
        return True
    return False


class SearchRanOut(NoValidPathFound):
    """The search ran out of states: from the start, or (the dead-end checks) from the goal. At its heading bins and
    step that is no proof: :meth:`HybridAStar.plan` searches again at FINER_BINS (the caller sees NoValidPathFound)."""


class _Search:
    """The arrays of one search (open heap, nodes, closed set) and chunked calls of the compiled loop."""

    def __init__(self, planner: HybridAStar, start: Pose, goal: Pose, heur: HolonomicHeuristic,
                 o: PlannerOptions, reverse: bool) -> None:
        self.planner = planner
        self.heur = heur
        self.reverse = reverse
        self.chunk = planner.chunk_expansions(o)
        p = planner._params(goal, reverse)
        p[kernels.P_HOX], p[kernels.P_HOY] = heur.origin_xy
        p[kernels.P_HCELL] = heur.cell_m
        p[kernels.P_BEST_H] = math.inf
        p[kernels.P_CLOSER_H] = math.inf
        p[kernels.P_HELD_COST] = math.inf
        p[kernels.P_BACK_SHARE] = FORWARD_RETRY_SHARE if o.prefer_forward else NO_HOLD_SHARE
        p[kernels.P_BOUND] = math.inf
        self.p = p
        self.turns = planner.child_turns(p)
        grid = planner.grid
        n_keys = grid.width * grid.height * o.n_yaw_bins * planner.n_roll_bins
        cap = 1 << 16
        # a bitset (one of the planner's finished searches' when it has one), else a hash set (closed_set)
        self.closed, self.closed_table = closed_set.new_sets(n_keys, cap, planner.bitset_pool)
        self._width = planner.clearance.clearance.shape[1]  # the keys' row length, for __del__'s clearing
        self.node_f = np.empty((cap, 5))
        self.node_i = np.empty((cap, 3), dtype=np.int64)
        self.heap_keys = np.empty(cap * 2)
        self.heap_vals = np.empty(cap * 2, dtype=np.int64)
        self.heap_size = np.zeros(1, dtype=np.int64)
        self.grow_s = 0.0  # how long the node storage's last growth took (s)
        self.counters = np.zeros(kernels.N_COUNTERS, dtype=np.int64)
        self.counters[kernels.C_TRIED] = -1
        # the shot found (first third), a shot held back (second, kernels.search_chunk 3c) and a fallback shot (3d)
        self.seg_roll, self.seg_curv, self.seg_len = (np.zeros(3 * kernels.MAX_SHOT_SEGS) for _ in range(3))
        self.node_f[0] = (*start, 0.0, 0.0)
        self.node_i[0] = (-1, o.n_rolls // 2, 0)
        self.counters[kernels.C_NODES] = 1
        kernels.heap_push(self.heap_keys, self.heap_vals, self.heap_size, heur(start[0], start[1]), 0)

    @property
    def expansions(self) -> int:
        return int(self.counters[kernels.C_EXPANSIONS])

    def __del__(self) -> None:
        # A finished search's bitset goes back to its planner's pool, cleared where this search closed keys (or
        # whole, when that is cheaper: a byte per node against about 150 bytes of zeroing).
        try:
            bits = self.closed
            if bits.size == 0:
                return
            n_nodes = int(self.counters[kernels.C_NODES])
            if n_nodes * CLEAR_BYTES_PER_NODE < bits.size:
                pl = self.planner
                kernels.clear_closed(bits, self.p, self._width, self.node_f, self.node_i, n_nodes, pl.roll_bins,
                                     pl.n_roll_bins)
            else:
                bits.fill(0)
            self.planner.bitset_pool.give_back(bits)
        except Exception:  # at interpreter exit the modules may be gone: the bitset is then simply dropped
            pass

    def step(self, budget: int) -> int:
        """Run up to ``budget`` expansions; returns the compiled loop's status (FULL is handled here). Its time is
        added to the current thread's plan's ``extra.search_loop_time_s``."""
        t0 = time.perf_counter()
        try:
            return self._step(budget)
        finally:
            _LOOP.s = getattr(_LOOP, "s", 0.0) + time.perf_counter() - t0

    def run_for(self, budget: int, clock: Clock) -> int:
        """Step a chunk at a time until the search finds its goal or exhausts, has made ``budget`` expansions in
        all, or ``clock`` runs out or is cancelled; returns the last status (RUNNING when stopped by the budget or
        the clock). The bounded searches of a plan (the dead-end checks, a turn between two trees) run this way."""
        status = kernels.RUNNING
        while self.expansions < budget and not (clock.expired() or clock.cancelled()):
            status = self.step(min(self.chunk, budget - self.expansions))
            if status != kernels.RUNNING:
                break
        return status

    def _step(self, budget: int) -> int:
        pl = self.planner
        while True:
            status = int(kernels.search_chunk(
                pl.clearance.clearance, pl.clearance.blocked, self.heur.table, pl.rs_table, self.p,
                pl.footprint.offsets_x, pl.footprint.offsets_y, pl._px, pl._py,
                pl.rolls, pl.curvatures, pl.roll_bins, pl.n_roll_bins, self.node_f, self.node_i, self.heap_keys,
                self.heap_vals, self.heap_size, self.closed, self.closed_table, self.counters, budget,
                self.seg_roll, self.seg_curv, self.seg_len, self.turns,
            ))
            if status != kernels.FULL:
                return status
            # Growing copies every array (a million nodes: 100 MB, 0.1–0.2 s on a loaded machine) and cannot be cut
            # short: when the last growth's time, doubled with the size, would run past the plan's deadline, the
            # plan is out of time now rather than after it (an anytime round then ends with the best path so far).
            clock = getattr(_LOOP, "clock", None)
            if clock is not None and time.perf_counter() + GROWTH_MARGIN * self.grow_s > clock.deadline:
                raise PlannerTimedOut(
                    f"no path found within the time limit of {clock.time_limit_s:g} s ({self.expansions} expansions; "
                    f"the search's storage of {self.node_f.shape[0]} nodes was full)",
                    planning_time_s=clock.elapsed_s(), expansions=self.expansions)
            t0 = time.perf_counter()
            self.node_f = np.concatenate([self.node_f, np.empty_like(self.node_f)])
            self.node_i = np.concatenate([self.node_i, np.empty_like(self.node_i)])
            self.heap_keys = np.concatenate([self.heap_keys, np.empty_like(self.heap_keys)])
            self.heap_vals = np.concatenate([self.heap_vals, np.empty_like(self.heap_vals)])
            if self.closed.size == 0:  # the hash set: twice the node capacity, so never over half full
                table = closed_set.new_table(self.node_f.shape[0])
                closed_set.rehash(self.closed_table, table)
                self.closed_table = table
            self.grow_s = time.perf_counter() - t0


class HybridAStar:
    """Plans rollable paths for one robot on one map; reuse it for many queries on the same map.

    ``HybridAStar(grid, robot, options).plan(start, goal)`` returns a :class:`PlanResult` or raises a
    :class:`~planner.errors.PlanningError` subclass carrying the Nav2 error code.
    """

    def __init__(self, grid: OccupancyGrid, robot: RobotProfile, options: PlannerOptions | None = None, *,
                 clearance: ClearanceMap | None = None, holonomic_mult: np.ndarray | None = None,
                 rs_table: np.ndarray | None = None) -> None:
        """``clearance``, ``holonomic_mult`` and ``rs_table``, when given, are another planner's for the same grid,
        robot and options but the heading bins (:meth:`finer`): shared, not computed again (the Reeds–Shepp table is
        looked up at its own heading bins, a lower bound at any)."""
        self.options = options or PlannerOptions()
        n_bins = self.options.n_roll_bins or self.options.n_rolls
        self.grid = grid
        self.robot = robot
        self.footprint = CircleFootprint.for_robot(robot, self.options.n_circles)
        self.polygon = robot.footprint_polygon
        self._px = np.ascontiguousarray(self.polygon[:, 0])
        self._py = np.ascontiguousarray(self.polygon[:, 1])
        self.clearance = clearance if clearance is not None else ClearanceMap(grid, self.options.allow_unknown)
        kmax = robot.max_curvature
        kappas = np.linspace(-kmax, kmax, self.options.n_rolls)
        kappas[self.options.n_rolls // 2] = 0.0
        self.curvatures = kappas
        self.rolls = np.asarray(robot.roll_model.roll_for_curvature(kappas), dtype=float)
        self.rolls[-1], self.rolls[0] = robot.max_roll_rad, -robot.max_roll_rad
        # roll index → closed-set bin: equal curvature intervals, upright always in the middle bin
        self.roll_bins = np.rint((kappas / kmax + 1.0) / 2.0 * (n_bins - 1)).astype(np.int64)
        self.n_roll_bins = n_bins
        # A pose is only free where the disc inscribed in the polygon around the centre p is free. With a the
        # centre of p's cell and b the nearest blocked cell centre (d = |a − b|), the nearest blocked square
        # is at most |p − b| − res/2 ≤ d + res·(1/√2 − 1/2) from p; the stored clearance is d − √2·res. So
        # a free pose needs stored clearance ≥ r_in − (√2 + 1/√2 − 1/2)·res (admissible for the heuristic).
        self.centre_threshold_m = inscribed_radius(self.polygon) - 1.63 * grid.resolution_m
        # the reverse problem with the heading turned by π is this problem (two_ended.py): decided once per planner
        self.goal_side_ok = goal_side_possible(self)
        o = self.options
        self.reverse = robot.reversible if o.allow_reverse is None else o.allow_reverse
        self.rs_table = rs_table if rs_table is not None else rs_table_for(robot, o) if self.reverse else np.zeros(
            (1, 1, 1))
        self.heuristic_factor = o.heuristic_downsample or auto_downsample(grid.data.shape)
        #: closed-set bitsets of finished searches, cleared, for the next ones (closed_set.BitsetPool)
        self.bitset_pool = closed_set.BitsetPool()
        self._base_params: dict[tuple[bool, PlannerOptions], np.ndarray] = {}  # _params without the goal
        self._child_turns: dict[tuple[float, float], np.ndarray] = {}  # child_turns per (step, long steps)
        self._heuristics: OrderedDict[tuple[int, int], HolonomicHeuristic] = OrderedDict()
        self._finer: HybridAStar | None = None  # this planner at FINER_BINS, made when first needed (finer)
        self.holonomic_mult = holonomic_mult if holonomic_mult is not None else coarse_cost_grid(
            self.clearance.clearance, self.centre_threshold_m, self.footprint.radius_m,
            max(o.proximity_range_m, robot.preferred_clearance_m), o.cost_penalty, self.heuristic_factor)

    def holonomic(self, goal_xy: tuple[float, float], start_xy: tuple[float, float] | None = None,
                  stop_factor: float = STOP_FACTOR, cache: bool = True) -> HolonomicHeuristic:
        """The holonomic cost-to-go table towards ``goal_xy`` (eq. 14g), computed exactly only around the way to
        ``start_xy`` when it is given (:class:`HolonomicHeuristic`, ``stop_factor`` its extent). A cached table
        towards the start's cell (the forward one, when this is the goal side's table towards the start) guides
        the wavefront: it is a lower bound of the cost to the start, tighter than the straight distance.

        Tables are cached per goal cell (Nav2 caches its obstacle heuristic the same way): a replan towards
        the same goal reuses the table when it is exact along the new start's cheapest way (any table is
        admissible everywhere; beyond its exact part it is only less informed). ``cache`` False neither reads
        nor keeps one (a search for a turn between two trees must not push the plan's own tables out).
        """
        cell = self.grid.resolution_m * self.heuristic_factor
        ox, oy = self.clearance.origin_x, self.clearance.origin_y
        key = (math.floor((goal_xy[0] - ox) / cell), math.floor((goal_xy[1] - oy) / cell))
        cached = self._heuristics.get(key) if cache else None
        if cached is not None and (start_xy is None or cached.covers(start_xy)):
            self._heuristics.move_to_end(key)
            return cached
        towards_start = None if start_xy is None else self._heuristics.get(
            (math.floor((start_xy[0] - ox) / cell), math.floor((start_xy[1] - oy) / cell)))
        heur = HolonomicHeuristic(self.holonomic_mult, (ox, oy), cell, goal_xy, start_xy, stop_factor,
                                  guide=None if towards_start is None else towards_start.table)
        if not cache:
            return heur
        self._heuristics[key] = heur
        while len(self._heuristics) > HEURISTIC_CACHE_SIZE:
            self._heuristics.popitem(last=False)
        return heur

    def forget_heuristics(self) -> None:
        """Drop the cached holonomic tables (after a map change, or to time a plan as the first towards its goal)."""
        self._heuristics.clear()

    @cached_property
    def resolved_step_m(self) -> float:
        """Arc length of one expansion: the option, or max(cell diagonal, R_min × yaw bin) (a planner's options,
        grid and robot do not change: worked out once)."""
        if self.options.step_m > 0:
            return max(self.options.step_m, math.sqrt(2) * self.grid.resolution_m)
        yaw_bin = 2 * math.pi / self.options.n_yaw_bins
        return max(math.sqrt(2) * self.grid.resolution_m, self.robot.min_turning_radius_m * yaw_bin)

    @cached_property
    def closed_cell_m(self) -> float:
        """Side of the closed set's cells: the map cell × the whole number nearest half the step, at least 1 (two
        nodes a step apart never share a cell; at the default 36 heading bins on a 5 cm map, 10 cm; at 72, the map
        cell). Issue 21's eighteenth round: 5 cm cells at 36 bins held states 5 cm apart as different, and a search
        in a tight place expanded them all. A step set by option ``step_m`` keeps the map cell: a long step would
        make cells that merge states the search must tell apart (a 10 m step, 5 m cells: a search that ran dry)."""
        res = self.grid.resolution_m
        if self.options.step_m > 0:
            return res
        return res * max(1, round(self.resolved_step_m / (2.0 * res)))

    @property
    def budget_scale(self) -> float:
        """The share of the budgets marked (×bins) this planner's searches get: n_yaw_bins / BUDGET_BINS."""
        return self.options.n_yaw_bins / BUDGET_BINS

    def budget(self, expansions: int) -> int:
        """A budget marked (×bins), measured at BUDGET_BINS heading bins, for this planner's bins (0 stays 0, which
        turns a wait off; any other at least 1)."""
        return 0 if expansions == 0 else max(1, round(expansions * self.budget_scale))

    def chunk_expansions(self, o: PlannerOptions) -> int:
        """Expansions per compiled chunk: ``o.chunk_expansions``, fewer when each expansion samples many points
        (a long ``step_m``), so the clock is polled after at most ``CHUNK_SAMPLES`` collision samples."""
        per_expansion = self.options.n_rolls * (2 if self.reverse else 1) * (
            self.resolved_step_m / (0.5 * self.grid.resolution_m) + 1)
        return max(1, min(o.chunk_expansions, int(CHUNK_SAMPLES / per_expansion)))

    def child_turns(self, p: np.ndarray) -> np.ndarray:
        """:func:`kernels.child_turns` for a search's parameters, kept per step and long-step count (a planner's
        held curvatures are fixed; it cost 40 µs a search)."""
        key = (float(p[kernels.P_STEP]), float(p[kernels.P_LONG]))
        turns = self._child_turns.get(key)
        if turns is None:
            turns = self._child_turns[key] = kernels.child_turns(self.curvatures, p)  # (shared: never written)
        return turns

    def footprint_margin(self, pose: Pose) -> float:
        """Footprint margin (m) at a pose: ≥ 0 means free (circles first, the exact polygon where they touch)."""
        return float(self.clearance.footprint_margins(self.footprint, self.polygon, np.array([pose]))[0])

    def _params(self, goal: Pose, reverse: bool) -> np.ndarray:
        """The compiled search's parameters (kernels.P_*) towards ``goal``: the planner's own, computed once per
        direction and options (a sixth of a short search's setup), with the goal's."""
        key = (reverse, self.options)
        base = self._base_params.get(key)
        if base is None:
            base = self._base_params[key] = self._params_without_goal(reverse)
        p = base.copy()
        p[kernels.P_GX], p[kernels.P_GY], p[kernels.P_GYAW] = goal
        p[kernels.P_GCOS], p[kernels.P_GSIN] = math.cos(goal[2]), math.sin(goal[2])
        return p

    def _params_without_goal(self, reverse: bool) -> np.ndarray:
        o = self.options
        p = np.zeros(kernels.N_PARAMS)
        p[kernels.P_OX], p[kernels.P_OY] = self.clearance.origin_x, self.clearance.origin_y
        p[kernels.P_RES] = self.grid.resolution_m
        p[kernels.P_CLOSED_CELL] = self.closed_cell_m
        p[kernels.P_RC] = self.footprint.radius_m
        p[kernels.P_RHO] = self.robot.min_turning_radius_m
        p[kernels.P_TOL_XY], p[kernels.P_TOL_YAW] = o.goal_tolerance_m, o.goal_tolerance_yaw_rad
        p[kernels.P_RADIUS] = self.robot.radius_m
        p[kernels.P_STEP] = self.resolved_step_m
        p[kernels.P_SPACING] = 0.5 * self.grid.resolution_m
        p[kernels.P_NON_STRAIGHT], p[kernels.P_CHANGE] = o.non_straight_penalty, o.change_penalty
        p[kernels.P_REVERSE], p[kernels.P_SWITCH] = o.reverse_penalty, o.switch_cost_m
        p[kernels.P_COST_PENALTY] = o.cost_penalty
        # the proximity cost reaches at least as far as the room the robot would like to keep
        p[kernels.P_PROX_RANGE] = max(o.proximity_range_m, self.robot.preferred_clearance_m)
        p[kernels.P_PREFERRED] = self.robot.preferred_clearance_m
        p[kernels.P_REACH] = float(np.hypot(self.footprint.offsets_x, self.footprint.offsets_y).max())
        res = self.grid.resolution_m
        p[kernels.P_REJECT] = inscribed_radius(self.polygon) - (math.sqrt(2.0) + math.sqrt(0.5)) * res - 1e-6
        # (the same for the polygon turned by π, smoothing.turned_round: a rotation keeps convexity and orientation)
        p[kernels.P_CONVEX] = convex_turn(self._px, self._py)
        p[kernels.P_GREED], p[kernels.P_SHOT_RATIO] = o.greed, o.analytic_ratio_m
        p[kernels.P_MAX_ROLL] = self.robot.max_roll_rad
        p[kernels.P_HOLD_WAIT] = self.budget(HOLD_EXPANSIONS)
        p[kernels.P_USE_DUBINS] = 0.0 if reverse else 1.0
        p[kernels.P_USE_RS] = 1.0 if reverse else 0.0
        p[kernels.P_RS_CELL] = RS_CELL_M
        p[kernels.P_RS_HALF] = self.rs_table.shape[2] // 2
        p[kernels.P_ALLOW_REVERSE] = 1.0 if reverse else 0.0
        p[kernels.P_N_YAW] = o.n_yaw_bins
        p[kernels.P_LONG] = float(o.open_step_factor)
        # the held turns gentler than the sharpest, gentlest first, at most MAX_GENTLE spread evenly over them: a
        # shortcut may be rolled with one (kernels._gentler)
        held = np.arange(len(self.rolls) // 2 + 1, len(self.rolls) - 1)
        gentle = [int(held[i]) for i in np.unique(np.rint(np.linspace(0, len(held) - 1, kernels.MAX_GENTLE)))
                  .astype(int)] if len(held) > kernels.MAX_GENTLE else [int(k) for k in held]
        p[kernels.P_GENTLE_N] = len(gentle)
        for g, k in enumerate(gentle):
            p[kernels.P_GENTLE + 2 * g] = 1.0 / self.curvatures[k]
            p[kernels.P_GENTLE + 2 * g + 1] = self.rolls[k]
        return p

    def _check_endpoint(self, pose: Pose, which: str) -> None:
        for v in pose:
            if not math.isfinite(v):
                raise InvalidInput(which, f"must be three finite numbers, got {list(pose)!r}")
        if not self.grid.contains(pose[0], pose[1]):
            cls = StartOutsideMap if which == "start" else GoalOutsideMap
            raise cls(f"{which} ({pose[0]:.3f}, {pose[1]:.3f}) is outside the map {self.grid.name!r}")
        margin = self.footprint_margin(pose)
        if margin < 0:
            cls2 = StartOccupied if which == "start" else GoalOccupied
            why = ("the footprint (padded by "
                   f"{self.robot.footprint_padding_m:g} m) overlaps an obstacle or the map's edge")
            raise cls2(f"{which} ({pose[0]:.3f}, {pose[1]:.3f}) is in collision: {why}")

    def plan(self, start: Pose, goal: Pose, termination: Termination | None = None) -> PlanResult:
        """Plan from ``start`` to ``goal`` (x, y, yaw in the map frame; the sphere starts and ends upright).

        ``termination`` (default :class:`~planner.termination.Termination`'s) says when to give up; its clock
        starts after the one-off compilation (:func:`warm_up`), so the limit is the search's own.
        """
        warm_up()
        _LOOP.s = 0.0
        clock = (termination or Termination()).start()
        _LOOP.clock = clock  # (a search outside a plan, as the tests run them, grows without this check)
        try:
            try:
                return self._plan(start, goal, clock)
            except SearchRanOut as coarse:
                return self._plan_finer(start, goal, clock, coarse)
        finally:
            _LOOP.clock = None

    def _plan_finer(self, start: Pose, goal: Pose, clock: Clock, coarse: SearchRanOut) -> PlanResult:
        """The plan at FINER_BINS heading bins (:meth:`finer`) after the search at this planner's ran out of states
        (``coarse``), within what is left of ``clock``: at 36 bins a step rolls 0.2 m and the closed set's cells are
        10 cm, and a start a few centimetres from a wall (depot#1 of the real bench's seed 0 at three problems a map:
        6 cm) may have no step that stays free, where a step of half that escapes (a path of 18 m in 2 114 expansions
        after the first search's 7; BIT* finds one too). The answer says so (``extra.finer_search``); when that
        search runs out as well, the plan raises NoValidPathFound with both counts."""
        finer = self.finer()
        if finer is None or clock.expired() or clock.cancelled():
            raise NoValidPathFound(coarse.msg, planning_time_s=coarse.planning_time_s,
                                   expansions=coarse.expansions) from None
        try:
            result = finer._plan(start, goal, clock)
        except SearchRanOut as again:
            raise NoValidPathFound(
                f"{again.msg} at {finer.options.n_yaw_bins} heading bins, as at {self.options.n_yaw_bins} "
                f"({coarse.expansions} expansions)",
                planning_time_s=time.perf_counter() - clock.t0, expansions=coarse.expansions + again.expansions,
            ) from None
        except PlanningError as exc:
            exc.expansions += coarse.expansions
            raise
        result.expansions += coarse.expansions
        result.extra["finer_search"] = {"n_yaw_bins": finer.options.n_yaw_bins,
                                        "coarse_expansions": coarse.expansions, "coarse_reason": coarse.msg}
        return result

    def finer(self) -> HybridAStar | None:
        """This planner at FINER_BINS heading bins (its step and closed-set cells follow), sharing its clearance map,
        its coarse cost grid, its holonomic tables as they are now (a live map's updates and a guided plan's swapped
        grid included: none depends on the bins) and its Reeds–Shepp table (not built again at 72 bins: a second);
        None when this one has that many or more."""
        if self.options.n_yaw_bins >= FINER_BINS:
            return None
        finer = self._finer
        if finer is None or finer.clearance is not self.clearance:
            finer = self._finer = HybridAStar(self.grid, self.robot, replace(self.options, n_yaw_bins=FINER_BINS),
                                              clearance=self.clearance, holonomic_mult=self.holonomic_mult,
                                              rs_table=self.rs_table)
        finer.holonomic_mult, finer._heuristics = self.holonomic_mult, self._heuristics
        return finer

    def _plan(self, start: Pose, goal: Pose, clock: Clock) -> PlanResult:
        t0 = clock.t0
        o = self.options
        start = (float(start[0]), float(start[1]), wrap(float(start[2])))
        goal = (float(goal[0]), float(goal[1]), wrap(float(goal[2])))
        self._check_endpoint(start, "start")
        self._check_endpoint(goal, "goal")
        refuse_unreachable(self.clearance, self.polygon, start, goal, o.goal_tolerance_m, t0)  # flood fill, ~ms
        heur = self.holonomic(goal[:2], start[:2])
        if not math.isfinite(heur(start[0], start[1])):
            raise NoValidPathFound(
                f"no path: the goal ({goal[0]:.2f}, {goal[1]:.2f}) cannot be reached from the start "
                f"({start[0]:.2f}, {start[1]:.2f}) by any route wide enough for the robot",
                planning_time_s=time.perf_counter() - t0,
            )
        run = _Search(self, start, goal, heur, o, self.reverse)
        run.p[kernels.P_ROOT_SHOT] = 1.0 if ROOT_SHOT_AT_ONCE else 0.0
        run.p[kernels.P_FALL_WAIT] = FALLBACK_WAIT
        run.p[kernels.P_BACK_WAIT] = BACK_FALLBACK_WAIT
        side = self._drive(run, start, goal, o, clock)
        goal_path = None if side is None else side.motions
        met = side is not None and side.met_segments > 0  # a shot joined the two searches' trees (meet.py)
        found = run if goal_path is None or side is None else side.run  # the search that found the path
        motions = self._motions(run) if goal_path is None else list(goal_path)
        raw_length = self._length(start, motions)
        t_search = time.perf_counter() - t0
        smoothed = self._smooth(start, motions, run.p, o)
        held = self._held_if_cheaper(start, run, smoothed, o)
        turned_dearer = held is not None and not self._mostly_backwards(start, motions)  # it turned round, dearer
        if held is None:
            motions = smoothed
        else:  # the held shot is now the search's result: its unsmoothed path is _motions(run)
            motions, met, found, raw_length = held, False, run, self._length(start, self._motions(run))
        t_smooth = time.perf_counter() - t0 - t_search
        extra: dict[str, Any] = {"unsmoothed_length_m": raw_length, "search_time_s": t_search,
                                 "smoothing_time_s": t_smooth,
                                 "found_from": "both" if met else "start" if found is run else "goal"}
        if held is not None:
            extra["held_shot_taken"] = True
        if found is run and run.counters[kernels.C_FELL_BACK]:
            extra["fallback_shot_taken"] = True  # the path keeps less room than preferred where its last shot passes
        analytic = side.met_segments if met and side is not None else int(found.counters[kernels.C_SHOT_SEGS])
        expansions = run.expansions
        if side is not None:
            expansions += side.expansions
            extra["goal_side_expansions"] = side.expansions
            if side.turns:
                extra["turn_searches"] = side.turns
                extra["turn_expansions"] = side.turn_expansions
        bound = side.met_cost if met and side is not None else self._search_cost(found)
        if self.reverse and o.prefer_forward and not turned_dearer:
            # (not when the search found a path that turns round and it cost more than the shot that rolls backwards)
            checked: list[int] = []
            fwd, forward = self._forward_alternative(start, goal, heur, o, clock, motions, bound,
                                                     checked, expansions)
            if checked:
                expansions += checked[0]
                extra["forward_check_expansions"] = checked[0]
            if fwd is not None:
                expansions += fwd.expansions
                extra["forward_alternative_expansions"] = fwd.expansions
            if fwd is not None and forward is not None:
                motions = forward
                analytic = int(fwd.counters[kernels.C_SHOT_SEGS])
                extra["forward_alternative"] = True
                bound = min(bound, self._search_cost(fwd))
        if o.improve_until_s > 0:
            # anytime (anytime.py): cheaper paths until improve_until_s, the request's own limit still first
            better = improve(self, start, goal, heur, o, clock, motions, bound, run.p, t_smooth, _Search)
            extra.update(better.extra())
            expansions += better.expansions
            motions = better.motions
            if better.analytic is not None:  # the path kept came from a re-search with reversing as configured
                analytic = better.analytic
                extra.pop("forward_alternative", None)
        poses = self._densify(start, motions, o.state_spacing_m)
        fine = self._checked_poses(start, motions)
        margins, measured = self.clearance.path_margins(self.footprint, self.polygon, fine[:, :3])
        if margins.min() < 0:
            raise NoValidPathFound("internal check failed: the exact re-check of the final path found a collision")
        # The circles' margin is a lower bound of the polygon's clearance: only poses whose bound could beat
        # the best exact distance found so far are measured exactly.
        clearance_m = self.clearance.least_footprint_distance(self.polygon, fine[:, :3], margins, CLEARANCE_REACH_M,
                                                              self.footprint, measured)
        length = self._length(start, motions)
        # issue 21's measure of how directly the search heads for the goal: all searches' expansions per metre
        # (None for a path of no length: the result is sent as JSON, which has no NaN)
        extra["expansions_per_m"] = expansions / length if length > 0 else None
        # the time in the compiled search loop alone (every search of this plan), for expansions/s as Nav2 counts them
        extra["search_loop_time_s"] = _LOOP.s
        elapsed = time.perf_counter() - t0
        return PlanResult(
            status="exact",
            error_code=0,
            error_msg="",
            planning_time_s=elapsed,
            expansions=expansions,
            robot=self.robot,
            map_name=self.grid.name,
            start=start,
            goal=goal,
            states=build_states(poses, self.robot),
            min_clearance_m=clearance_m,
            analytic_segments=analytic,
            extra=extra,
        )

    def _drive(self, run: _Search, start: Pose, goal: Pose, o: PlannerOptions, clock: Clock,
               fail_fast: bool = True, cap: int | None = None) -> GoalSide | None:
        """Run the search in compiled chunks until it finds the goal; raise the planning error otherwise.

        With ``fail_fast`` and a centrally symmetric footprint, the goal side's search (:mod:`two_ended`) joins in
        after GOAL_SIDE_AFTER expansions, a chunk after each of this search's; it is returned when it ran (its
        ``motions`` set when it found the path first)."""
        checked_goal = not (fail_fast and o.dead_end_check)
        side: GoalSide | None = None
        t0 = clock.t0
        cap = clock.termination.max_iterations if cap is None else min(cap, clock.termination.max_iterations)
        while True:
            try:
                status = run.step(min(self.chunk_expansions(o), cap - run.expansions))
            except PlannerTimedOut:
                if _take_kept(run):  # out of time with a shot held back or kept to fall back on: it is the path
                    return side
                raise
            if status == kernels.FOUND:
                return side
            if status == kernels.EXHAUSTED:
                raise SearchRanOut(
                    f"no valid path: the search exhausted every state reachable from the start "
                    f"({run.expansions} expansions)", planning_time_s=time.perf_counter() - t0,
                    expansions=run.expansions)
            if not checked_goal and run.expansions >= GOAL_SIDE_AFTER and self.goal_side_ok:
                checked_goal = True  # the goal side's search is the dead-end check (5b) as well
                side = GoalSide(self, start, goal, o, _Search)
            if side is not None and (side.step(min(self.chunk_expansions(o), cap - side.expansions))
                                     or (run.expansions + side.expansions >= self.budget(MEET_AFTER)
                                         and side.meet(run, clock))):
                if side.motions is not None:
                    return side
                raise SearchRanOut(
                    f"no valid path: the goal pose ({goal[0]:.2f}, {goal[1]:.2f}, yaw {goal[2]:.2f}) can be "
                    f"reached from only {side.expansions} states around it, none of them the start's (a dead end "
                    f"or a heading into an obstacle)", planning_time_s=time.perf_counter() - t0,
                    expansions=run.expansions + side.expansions)
            if not checked_goal and run.expansions >= GOAL_CHECK_AFTER and (self.reverse or self.goal_side_ok):
                # 5b. Fail fast: a bounded search of the reverse problem (from the goal, every motion run
                # backwards) that exhausts proves the goal pose cannot be approached at all.
                checked_goal = True
                back = self._reverse_search(start, goal, o, clock.share(GOAL_CHECK_SHARE))
                if back is not None:
                    raise SearchRanOut(
                        f"no valid path: the goal pose ({goal[0]:.2f}, {goal[1]:.2f}, yaw {goal[2]:.2f}) can be "
                        f"reached from only {back} states around it, none of them the start's (a dead end or a "
                        f"heading into an obstacle)", planning_time_s=time.perf_counter() - t0,
                        expansions=run.expansions)
            if (run.expansions >= cap or clock.expired()) and _take_kept(run):
                # out of time or expansions with a mostly-backwards shot held back, or a shot kept to fall back on:
                # it is the path
                return side
            if run.expansions >= cap:
                raise NoValidPathFound(f"no valid path within the iteration cap of {cap} expansions",
                                       planning_time_s=time.perf_counter() - t0, expansions=run.expansions)
            if clock.cancelled():
                raise PlannerCancelled("planning was cancelled", planning_time_s=time.perf_counter() - t0,
                                       expansions=run.expansions)
            if clock.expired():
                raise PlannerTimedOut(
                    f"no path found within the time limit of {clock.time_limit_s:g} s ({run.expansions} expansions)",
                    planning_time_s=time.perf_counter() - t0, expansions=run.expansions)

    def _smooth(self, start: Pose, motions: list[tuple[float, float, float]], p: np.ndarray, o: PlannerOptions,
                counts: np.ndarray | None = None) -> list[tuple[float, float, float]]:
        """Shortcut passes (:meth:`_shortcut`'s) while they shorten the path by more than a millimetre; the later
        passes run on the path subdivided to the search step and try LATER_PASS_TRIES × ``smooth_max_tries`` targets
        per knot. A target whose shot failed from a knot just before is tried again only every SMOOTH_RECHECK_FIRST
        knots in the first pass (on the search's motions) and every SMOOTH_RECHECK knots in the later ones, see
        ``kernels.shortcut``. ``counts`` (int64, 4), when given, is added to as ``kernels.shortcut`` says. The passes
        run in one compiled call (:func:`planner.hybrid_astar.smoothing.smooth_path`)."""
        if not o.smooth:
            return motions
        counts = np.zeros(4, dtype=np.int64) if counts is None else counts
        rows = np.array(motions, float).reshape(-1, 3)
        later = max(1, round(o.smooth_max_tries * LATER_PASS_TRIES))
        out = smoothing.smooth_path(
            self.clearance.clearance, self.clearance.blocked, p, *self._footprint_arrays(), float(start[0]),
            float(start[1]), float(start[2]), rows, o.smooth_passes, o.smooth_max_tries, later, SMOOTH_RECHECK_FIRST,
            SMOOTH_RECHECK, self.resolved_step_m, counts, self.robot.radius_m, *self._curvature_table(rows))
        return motions if out is rows else _as_motions(out)

    def _held_if_cheaper(self, start: Pose, run: _Search, smoothed: list[tuple[float, float, float]],
                         o: PlannerOptions) -> list[tuple[float, float, float]] | None:
        """The path of the shot ``run`` still holds back (kernels 3c), smoothed, when it costs less by
        :meth:`_travel_cost` than ``smoothed``, the path found meanwhile smoothed; the held shot is then made the
        search's result. Else None. The hold waits for a path that turns round, not for a dearer one. (Both are
        smoothed first: the held path rolls mostly backwards, and smoothing may leave one of them so and not the
        other, which decides whether the forward alternative runs.)"""
        if run.counters[kernels.C_HELD_SEGS] == 0:
            return None
        held = self._smooth(start, self._motions(run, held=True), run.p, o)
        if self._travel_cost(start, held, o) >= self._travel_cost(start, smoothed, o):
            return None
        kernels.take_held(run.counters, run.seg_roll, run.seg_curv, run.seg_len)
        return held

    def _mostly_backwards(self, start: Pose, motions: list[tuple[float, float, float]]) -> bool:
        """The path rolls more than FORWARD_RETRY_SHARE of its length backwards."""
        return sum(-s for _, _, s in motions if s < 0) > FORWARD_RETRY_SHARE * self._length(start, motions)

    def _travel_cost(self, start: Pose, motions: list[tuple[float, float, float]], o: PlannerOptions) -> float:
        """The path's length with the search's direction terms: reverse metres × ``reverse_penalty`` and
        ``switch_cost_m`` per cusp (the terms by which the search prefers rolling forwards)."""
        backwards = sum(-s for _, _, s in motions if s < 0)
        return self._length(start, motions) + (o.reverse_penalty - 1.0) * backwards + o.switch_cost_m * _cusps(motions)

    def _forward_alternative(
        self, start: Pose, goal: Pose, heur: HolonomicHeuristic, o: PlannerOptions, clock: Clock,
        motions: list[tuple[float, float, float]], bound: float = math.inf,
        checked: list[int] | None = None, spent: int = 0,
    ) -> tuple[_Search | None, list[tuple[float, float, float]] | None]:
        """The forward-only search run (None when not tried) and its path when it costs less than ``motions``
        by :meth:`_travel_cost` (else None).

        The search with reversing is weighted (f = g + (1 + greed)·h) and its Reeds–Shepp heuristic does not
        see the reverse penalty, so where reversing looks as good as turning round it may roll most of the way
        backwards although turning round costs less. When the path it found rolls most of its length backwards
        (more than FORWARD_RETRY_SHARE; backing out of a dead end is fine) and a forward path could be cheaper
        (the Dubins distance is below its cost), a forward-only search (whose Dubins heuristic does
        see the turn) gets FORWARD_RETRY_PER_M expansions per metre from start to goal, at most
        FORWARD_RETRY_TIMES × the plan's ``spent`` expansions (:meth:`forward_budget`) and what is left of the time
        limit; the cheaper of the two paths is returned. Both it and the search of the reverse problem from the goal
        (its goal side, rolling forwards too) prune what costs more than ``bound``, and take turns
        (:meth:`_forward_both_ends`) with FORWARD_CHECK_BUDGET more expansions between them: where the start is the
        hard end (a start facing a wall, a turn the holonomic heuristic does not see), the goal side finds the path;
        where either side runs out of states, no forward path costs less. The goal side's expansions are appended
        to ``checked``. (Until issue 21's eighteenth round the goal side was only a check run first, up to
        FORWARD_CHECK_BUDGET expansions, that let the start's side alone search when it did not run dry.)
        """
        if not self._mostly_backwards(start, motions):
            return None, None
        cost = self._travel_cost(start, motions, o)
        if dubins_distance(*start, *goal, self.robot.min_turning_radius_m) >= cost:
            return None, None
        cap = self.forward_budget(start, goal, spent, self.budget_scale)
        run = _Search(self, start, goal, heur, o, False)
        run.p[kernels.P_BOUND] = bound
        if self.goal_side_ok:
            found = self._forward_both_ends(run, start, goal, o, clock, cap + self.budget(FORWARD_CHECK_BUDGET),
                                            bound, checked)
        else:  # (a footprint that is not centrally symmetric: the start's side alone)
            try:
                self._drive(run, start, goal, o, clock, fail_fast=False, cap=cap)
                found = self._motions(run)
            except PlannerCancelled:
                raise
            except PlanningError:
                found = None
        if found is None:
            return run, None
        forward = self._smooth(start, found, run.p, o)
        if self._travel_cost(start, forward, o) >= cost:
            return run, None
        # a path joined from the two sides may pass closer than the search's own shots do (meet.py): it is taken only
        # when it keeps the room the first path keeps, or at least LEAST_KEPT_MARGIN_M (a lower bound of the room,
        # as a shot keeps it: issue 21's eighteenth round)
        keep = min(self._least_margin(start, motions), kernels.LEAST_KEPT_MARGIN_M)
        return run, (forward if self._least_margin(start, forward) >= keep - 1e-6 else None)

    def _least_margin(self, start: Pose, motions: list[tuple[float, float, float]]) -> float:
        """The least footprint margin along the path at the final check's spacing (the covering circles' margin, a
        lower bound of its clearance, 0 where only the exact polygon fits: :meth:`ClearanceMap.footprint_margins`)."""
        fine = self._checked_poses(start, motions)
        return float(self.clearance.footprint_margins(self.footprint, self.polygon, fine[:, :3]).min())

    def _forward_both_ends(self, run: _Search, start: Pose, goal: Pose, o: PlannerOptions, clock: Clock, total: int,
                           bound: float, checked: list[int] | None) -> list[tuple[float, float, float]] | None:
        """The forward-only search ``run`` and its goal side (:class:`GoalSide`, rolling forwards only), both
        bounded by ``bound``, in turns of FORWARD_SLICE expansions, ``total`` expansions between them at most: the
        motions of the path either finds (or a shot joining their trees, as in :meth:`_drive`), else None. When
        either side runs out of states below the bound, no forward path costs less. The goal side's expansions are
        appended to ``checked``. The start's side goes first: with the goal side first, the budget split evenly
        from the first expansion, 3 of the 15 forward paths found over seeds 0–7 of the real bench were lost."""
        # the goal side is set up (its own holonomic table, a wavefront) only when the start's side has not ended
        # within its first turn: a forward path found or refuted in FORWARD_SLICE expansions needs none
        side: GoalSide | None = None
        meet_every = self.chunk_expansions(o)
        next_meet = self.budget(MEET_AFTER)
        found = False
        try:
            while True:
                spent = run.expansions + (side.expansions if side is not None else 0)
                if total - spent <= 0 or clock.expired() or clock.cancelled():
                    break
                status = run.step(min(FORWARD_SLICE, total - spent))
                if status != kernels.RUNNING:
                    found = status == kernels.FOUND
                    break
                if side is None:
                    side = GoalSide(self, start, goal, o, _Search, reverse=False)
                    side.run.p[kernels.P_BOUND] = bound
                if side.step(min(FORWARD_SLICE, total - run.expansions - side.expansions)):
                    break
                if run.expansions + side.expansions >= next_meet:
                    next_meet = run.expansions + side.expansions + meet_every
                    if side.meet(run, clock):
                        break
        except PlannerCancelled:
            raise
        except PlanningError:  # out of time: no forward path, as when the budget runs out
            pass
        side_expansions = side.expansions if side is not None else 0
        if checked is not None:
            checked.append(side_expansions)
        if clock.cancelled():
            raise PlannerCancelled("planning was cancelled", expansions=run.expansions + side_expansions)
        if side is not None and side.motions is not None:
            return side.motions
        return self._motions(run) if found else None

    @staticmethod
    def forward_budget(start: Pose, goal: Pose, spent: int = 0, scale: float = 1.0) -> int:
        """Expansions the forward-only alternative search may take: FORWARD_RETRY_PER_M per metre of the straight
        start–goal distance, at least FORWARD_RETRY_MIN and at most FORWARD_RETRY_MAX, all × ``scale`` (the plan's
        :attr:`budget_scale`); and at most FORWARD_RETRY_TIMES × ``spent`` (the expansions the plan made before it,
        when given), below that floor too.

        Measured on 480 real-map problems (seeds 0–7 of the real bench): the 17 forward paths accepted took 7–371
        expansions per metre (one above 240), on the open 4-million-cell field mostly; in the bays, pockets and
        smoothers' rooms the searches that found nothing cheaper all ran into the old flat 20 000 (150–250 ms each).
        Issue 21's tenth round: on seeds 0–3 the forward paths accepted took 0.2–1.8 × the plan's expansions before
        them, while the searches that found nothing cheaper ran up to 17 810 expansions after a search of 1 800 (a
        forward search stuck before a gap the holonomic heuristic passes and the footprint does not).
        """
        d = math.hypot(goal[0] - start[0], goal[1] - start[1])
        cap = scale * min(float(FORWARD_RETRY_MAX), max(float(FORWARD_RETRY_MIN), FORWARD_RETRY_PER_M * d))
        if spent:
            cap = min(cap, FORWARD_RETRY_TIMES * spent)
        return int(cap)

    def _search_cost(self, run: _Search) -> float:
        """A lower bound of the search's own cost (g) of the path ``run`` found: the result node's g and the
        analytic shot's length with its reverse and switch terms (its proximity and turning terms left out)."""
        k, n = int(run.counters[kernels.C_RESULT]), int(run.counters[kernels.C_SHOT_SEGS])
        return float(run.node_f[k, 4]) + float(kernels._shot_cost(run.p, int(run.node_i[k, 2]), run.seg_len, n))

    def _reverse_search(self, start: Pose, goal: Pose, o: PlannerOptions, clock: Clock, reverse: bool | None = None,
                        budget: int = GOAL_CHECK_BUDGET, spent: list[int] | None = None) -> int | None:
        """Search the reverse problem within ``budget`` expansions: from the goal to the start with every motion
        run backwards. A path run backwards is rolled by the same kinematics with the heading turned by π (and the
        roll mirrored, which maps the symmetric roll set onto itself); a reversible robot's motion set is its own
        reverse, a forward-only one's is forward-only with the heading turned by π. ``reverse`` (default the
        planner's) says which motions the path may use. Returns the number of states from which the goal can be
        reached when that search exhausts them all (so the start is not among them), else None (also when
        ``clock`` runs out). Its expansions are appended to ``spent`` when given."""
        reverse = self.reverse if reverse is None else reverse
        flip = 0.0 if reverse else math.pi
        back_start = (goal[0], goal[1], wrap(goal[2] + flip))
        back_goal = (start[0], start[1], wrap(start[2] + flip))
        if self.footprint_margin(back_start) < 0:
            return None
        heur = self.holonomic(back_goal[:2], back_start[:2], GOAL_SIDE_STOP_FACTOR)
        run = _Search(self, back_start, back_goal, heur, o, reverse)
        status = run.run_for(budget, clock)
        if spent is not None:
            spent.append(run.expansions)
        return run.expansions if status == kernels.EXHAUSTED else None

    def reaches_free(self, start: Pose, goal: Pose, motions: list[tuple[float, float, float]]) -> bool:
        """Rolled from ``start`` the motions end within the goal tolerance of ``goal`` and the footprint is free at
        a quarter-cell spacing (the exact check of the final path): how a path found some other way than the forward
        search's goal test (from the goal side, by a join, by an improvement round) is accepted."""
        o = self.options
        end = self._knots(start, motions)[-1]
        if (math.hypot(end[0] - goal[0], end[1] - goal[1]) > o.goal_tolerance_m
                or abs(wrap(float(end[2]) - goal[2])) > o.goal_tolerance_yaw_rad):
            return False
        fine = self._checked_poses(start, motions)
        return bool(self.clearance.path_margins(self.footprint, self.polygon, fine[:, :3])[0].min() >= 0)

    def _knots(self, start: Pose, motions: list[tuple[float, float, float]], roll: float = 0.0) -> np.ndarray:
        """Pose (x, y, yaw, roll) and distance travelled at the start and after every motion: (n+1, 5)."""
        return motion_knots(float(start[0]), float(start[1]), float(start[2]), float(roll),
                            np.array(motions, float).reshape(-1, 3), self.robot.radius_m)

    def _subdivide(self, motions: list[tuple[float, float, float]]) -> list[tuple[float, float, float]]:
        """Split motions longer than one search step into equal pieces (more knots to shortcut from)."""
        return subdivide(motions, self.resolved_step_m)

    def _length(self, start: Pose, motions: list[tuple[float, float, float]]) -> float:
        return float(smoothing.path_length(float(start[0]), float(start[1]), float(start[2]),
                                           np.array(motions, float).reshape(-1, 3), self.robot.radius_m))

    def _shortcut(
        self, start: Pose, motions: list[tuple[float, float, float]], p: np.ndarray, max_tries: int,
        recheck: int = 1, counts: np.ndarray | None = None,
    ) -> list[tuple[float, float, float]]:
        """One shortcut pass (:func:`planner.hybrid_astar.smoothing.shortcut_path`): forward shots over the whole
        path, then reverse shots where it rolls backwards. ``recheck`` and ``counts`` are ``kernels.shortcut``'s."""
        counts = np.zeros(4, dtype=np.int64) if counts is None else counts
        rows = np.array(motions, float).reshape(-1, 3)
        out = smoothing.shortcut_path(
            self.clearance.clearance, self.clearance.blocked, p, *self._footprint_arrays(), float(start[0]),
            float(start[1]), float(start[2]), rows, max_tries, recheck, counts, self.robot.radius_m,
            *self._curvature_table(rows))
        return motions if out is rows else _as_motions(out)

    def _curvature_table(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The robot's curvature at every roll a knot of the smoothed ``rows`` can hold (the compiled smoother's
        lookup for the roll model)."""
        return smoothing.curvature_table(rows, self.rolls, self.robot.roll_model.curvature)

    def _footprint_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Covering-circle offsets (x, y) and polygon (x, y) in the robot frame (the smoother turns them by π for a
        mirrored reverse stretch: :func:`planner.hybrid_astar.smoothing.turned_round`)."""
        return self.footprint.offsets_x, self.footprint.offsets_y, self._px, self._py

    def _motions(self, run: _Search, held: bool = False) -> list[tuple[float, float, float]]:
        """The path as a list of (held roll, curvature, signed arc length) motions, ending upright: the search's
        result, or with ``held`` the path of the shot it holds back (kernels 3c)."""
        seg_roll, seg_curv, seg_len = run.seg_roll, run.seg_curv, run.seg_len
        off = kernels.MAX_SHOT_SEGS if held else 0
        n_shot = int(run.counters[kernels.C_HELD_SEGS if held else kernels.C_SHOT_SEGS])
        motions = self._chain(run, int(run.counters[kernels.C_HELD_NODE if held else kernels.C_RESULT]))
        motions += [(float(seg_roll[off + i]), float(seg_curv[off + i]), float(seg_len[off + i]))
                    for i in range(n_shot)]
        motions.append((0.0, 0.0, 0.0))
        return motions

    def _chain(self, run: _Search, k: int) -> list[tuple[float, float, float]]:
        """The motions from the search's first node to its node ``k`` (held roll, curvature, signed length)."""
        node_f, node_i = run.node_f, run.node_i
        chain = []
        while node_i[k, 0] >= 0:
            chain.append(k)
            k = int(node_i[k, 0])
        chain.reverse()
        step = self.resolved_step_m
        return [(float(node_f[k, 3]), float(self.curvatures[node_i[k, 1]]), float(node_i[k, 2]) * step)
                for k in chain]

    def _checked_poses(self, start: Pose, motions: list[tuple[float, float, float]]) -> np.ndarray:
        """The poses the exact check of a path looks at: :meth:`_densify` at a quarter cell (the final check, a path
        found some other way than the search's goal test, the forward alternative's room rule)."""
        return self._densify(start, motions, self.grid.resolution_m / 4)

    def _densify(self, start: Pose, motions: list[tuple[float, float, float]], spacing: float) -> np.ndarray:
        """Dense poses (x, y, yaw, roll, direction) along the motions, ≤ ``spacing`` apart."""
        return densify_motions(np.array(start, float), np.array(motions, float).reshape(-1, 3),
                               self.robot.radius_m, spacing)

