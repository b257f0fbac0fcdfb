"""When long work must stop: one object from the door to the loop (OMPL's ``PlannerTerminationCondition``).

A :class:`Termination` is what a caller asks for — a wall-clock time limit, an optional cancel flag and an
optional iteration cap. The Hybrid A* search polls its clock between compiled chunks; the other loops a
request can start (``simulate_plan``, ``plan_reconfiguration``, the VPIP schedule) call :meth:`Clock.check`
every few steps. It is built once where the request enters (the CLI's ``--time-limit``, the HTTP and
Zenoh ``time_limit_s``) and passed unchanged to every loop that can run long; the loop calls :meth:`start`
when its clock starts (after one-off compilation, so a limit is never spent compiling) and polls the
:class:`Clock` it gets back. A process pool cannot send a callable, so the door sends the termination without
``cancel`` and the worker attaches its own flag with :meth:`with_cancel`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace

from planner.errors import InvalidInput, PlannerCancelled, PlannerTimedOut

DEFAULT_TIME_LIMIT_S = 5.0
"""The time limit when the caller gives none (s), as Nav2's planner server's default ``expected_planner_frequency``
leaves a plan a few seconds."""

DEFAULT_MAX_ITERATIONS = 2_000_000
"""The iteration cap when the caller gives none (Hybrid A* expansions)."""


@dataclass(frozen=True)
class Termination:
    """Stop after ``time_limit_s`` seconds of wall clock, when ``cancel()`` says True, or after
    ``max_iterations`` iterations of the loop (for the Hybrid A*: node expansions), whichever comes first."""

    time_limit_s: float = DEFAULT_TIME_LIMIT_S
    cancel: Callable[[], bool] | None = None
    max_iterations: int = DEFAULT_MAX_ITERATIONS

    def __post_init__(self) -> None:
        limit = self.time_limit_s
        if isinstance(limit, bool) or not isinstance(limit, int | float) or not math.isfinite(limit) or limit <= 0:
            raise InvalidInput("time_limit_s", f"must be a finite number of seconds > 0, got {limit!r}")
        its = self.max_iterations
        if isinstance(its, bool) or not isinstance(its, int) or not 0 < its <= 50_000_000:
            raise InvalidInput("max_iterations", f"must be an integer in [1, 50 000 000], got {its!r}")

    def with_cancel(self, cancel: Callable[[], bool] | None) -> Termination:
        """The same limits with ``cancel`` polled too (a worker process attaches its own flag here)."""
        return replace(self, cancel=cancel)

    def start(self) -> Clock:
        """Start the clock now."""
        now = time.perf_counter()
        return Clock(self, now, now + float(self.time_limit_s))


@dataclass(frozen=True)
class Clock:
    """A started :class:`Termination`: ``t0`` and ``deadline`` on :func:`time.perf_counter`'s scale."""

    termination: Termination
    t0: float
    deadline: float

    @property
    def time_limit_s(self) -> float:
        return float(self.termination.time_limit_s)

    def elapsed_s(self) -> float:
        return time.perf_counter() - self.t0

    def remaining_s(self) -> float:
        return self.deadline - time.perf_counter()

    def expired(self) -> bool:
        """The time limit has passed."""
        return time.perf_counter() > self.deadline

    def cancelled(self) -> bool:
        """The caller asked to stop."""
        return self.termination.cancel is not None and bool(self.termination.cancel())

    def check(self, what: str) -> None:
        """For loops other than the search (a simulation, a rolled manoeuvre, a VPIP schedule): raise
        :class:`~planner.errors.PlannerCancelled` if the caller asked to stop, :class:`~planner.errors.PlannerTimedOut`
        if the time limit has passed; ``what`` names the loop in the message."""
        if self.cancelled():
            raise PlannerCancelled(f"{what} was cancelled", planning_time_s=self.elapsed_s())
        if self.expired():
            raise PlannerTimedOut(f"{what} did not finish within its time limit of {self.time_limit_s:g} s",
                                  planning_time_s=self.elapsed_s())

    def over_iterations(self, iterations: int) -> bool:
        """``iterations`` reached the cap."""
        return iterations >= self.termination.max_iterations

    def share(self, fraction: float) -> Clock:
        """A clock for a sub-step that may use ``fraction`` of this clock's limit from now, never past its
        deadline (the cancel flag and the cap carry over)."""
        now = time.perf_counter()
        return Clock(self.termination, now, min(self.deadline, now + fraction * self.time_limit_s))
