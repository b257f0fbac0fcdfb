"""Stand-ins for the BIT* reference that misbehave, run in the reference worker by the tests (module-level so a
spawned process can import them)."""

from __future__ import annotations

import ctypes
import os
import signal
from collections.abc import Callable
from typing import Any

from lab.planning.real.runs import RunRecord, _record


def segfaults_after_first(problem: Any, grid: Any, robot: Any, checker: Any, planner: str, limit: float,
                          optimise: float | None, on_first: Callable[[float, float], None]) -> RunRecord:
    """Reports a first solution, then dies of SIGSEGV as OMPL's BIT* did in its second solve()."""
    on_first(0.012, 7.5)
    os.kill(os.getpid(), signal.SIGSEGV)
    ctypes.string_at(0)  # not reached
    raise AssertionError("unreachable")


def raises(problem: Any, grid: Any, robot: Any, checker: Any, planner: str, limit: float,
           optimise: float | None, on_first: Callable[[float, float], None]) -> RunRecord:
    raise RuntimeError("OMPL said no")


def solves(problem: Any, grid: Any, robot: Any, checker: Any, planner: str, limit: float,
           optimise: float | None, on_first: Callable[[float, float], None]) -> RunRecord:
    """A well-behaved stub: 'solves' at once (only the bookkeeping is under test)."""
    on_first(0.001, 5.0)
    return _record(problem, planner, "solved", 0.001, limit, valid=True, first_length_m=5.0, length_m=4.5,
                   message=f"pid {os.getpid()}")


def by_planner(problem: Any, grid: Any, robot: Any, checker: Any, planner: str, limit: float,
               optimise: float | None, on_first: Callable[[float, float], None]) -> RunRecord:
    """Crashes on Dubins, raises on Reeds–Shepp: what ``run_real_bench`` must survive."""
    if planner.endswith("dubins"):
        return segfaults_after_first(problem, grid, robot, checker, planner, limit, optimise, on_first)
    return raises(problem, grid, robot, checker, planner, limit, optimise, on_first)



CALLS: list[tuple[str, float | None]] = []  # (planner, optimise) of every call of timed_runs in this process


def timed_runs(problem: Any, grid: Any, robot: Any, checker: Any, planner: str, limit: float,
               optimise: float | None, on_first: Callable[[float, float], None]) -> RunRecord:
    """'Solves' in 60 ms when asked to optimise after its first solution, else in 10 and 20 ms in turn; the first
    length says which call of this planner it was."""
    k = sum(1 for p, _ in CALLS if p == planner)
    quick = sum(1 for p, o in CALLS if p == planner and o == 0.0)
    CALLS.append((planner, optimise))
    t = (0.010, 0.020)[quick % 2] if optimise == 0.0 else 0.060
    on_first(t, 5.0 + k)
    return _record(problem, planner, "solved", t, limit, valid=True, first_length_m=5.0 + k, length_m=4.5)


def reports_the_grown_polygon(problem: Any, grid: Any, robot: Any, checker: Any, planner: str, limit: float,
                              optimise: float | None, on_first: Callable[[float, float], None]) -> RunRecord:
    """'Solves' with a path whose clearance is the checker's polygon's circumradius, capped at 2 m as the referee caps
    it: what the bench makes of a room-matched run's clearance (the worker grows the polygon before this runs)."""
    import numpy as np

    on_first(0.001, 5.0)
    clearance = min(float(np.hypot(checker.polygon[:, 0], checker.polygon[:, 1]).max()), 2.0)
    if planner.startswith("bitstar-room") and problem.index == 1:
        clearance = 2.0  # a path in the open: the cap
    return _record(problem, planner, "solved", 0.001, limit, valid=True, first_length_m=5.0, length_m=4.5,
                   min_clearance_m=clearance)
