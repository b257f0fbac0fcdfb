"""The BIT* reference in a child process, so that a crash inside OMPL costs one reference run, not the bench.

OMPL's BIT* can die with a segmentation fault inside its second ``solve()`` (the optimising one after
``setStopOnSolnImprovement(True)`` returned the first solution; seen with ``--per-map 6 --seed 21``). Every
reference run therefore goes to a worker process started with the ``spawn`` method (a fresh interpreter, no
forked numba or OMPL state). The worker keeps the maps it was sent, runs one reference at a time, reports the
first solution as soon as it has it and then the finished :class:`~lab.planning.real.runs.RunRecord`.

When the worker dies (a signal, ``os._exit``) or stops answering (``time limit + HANG_MARGIN_S``), the run is
recorded with status ``crashed`` — not solved, but with the first solution's time and length when the worker
had reported them — and the next run starts a new worker. A Python exception inside the run is recorded with
status ``error``. Either way the message says what happened.
"""

from __future__ import annotations

import logging
import multiprocessing
import signal
import time
from collections.abc import Callable
from multiprocessing.connection import Connection
from typing import Any

from lab.planning.real.problems import RealProblem
from lab.planning.real.runs import RunRecord, _record, run_reference
from lab.planning.referee import FootprintReferee
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile

log = logging.getLogger(__name__)

HANG_MARGIN_S = 60.0  # a worker silent this long past the run's own limit is taken for hung and killed
START_TIMEOUT_S = 120.0  # first answer of a fresh worker (imports numba, OMPL; compiles or loads the kernels)

#: what a worker runs: (problem, grid, robot, checker, planner, time_limit_s, optimise_s, on_first) -> RunRecord
Runner = Callable[..., RunRecord]


def _worker_main(conn: Connection, ompl_seed: int, runner: Runner) -> None:
    """The child's loop: receive (map key, (grid, checker) or None, problem, robot, planner, limit, optimise, room)
    tuples (``room`` > 0: the checker grown by that much, :meth:`FootprintReferee.grown`), answer
    ``("first", (t, length))`` then ``("done", record)`` or ``("error", text)``; None stops."""
    try:
        from ompl import util as ou

        ou.setLogLevel(ou.LOG_ERROR)
        ou.RNG.setSeed(ompl_seed)  # before OMPL's first random number in this process
    except ImportError:  # a stub runner in the tests needs no OMPL
        pass
    maps: dict[str, tuple[OccupancyGrid, FootprintReferee]] = {}
    conn.send(("ready", None))
    while True:
        msg = conn.recv()
        if msg is None:
            return
        key, payload, problem, robot, planner, limit, optimise, room = msg
        if payload is not None:
            maps[key] = payload
        grid, checker = maps[key]
        if room > 0:
            checker = checker.grown(room)

        def on_first(t: float, length: float) -> None:
            conn.send(("first", (t, length)))

        try:
            record = runner(problem, grid, robot, checker, planner, limit, optimise, on_first)
        except Exception as exc:
            conn.send(("error", f"{type(exc).__name__}: {exc}"))
            continue
        conn.send(("done", record))


def _how_it_died(exitcode: int | None) -> str:
    if exitcode is None:
        return "stopped answering and was killed"
    if exitcode < 0:
        try:
            return f"died of {signal.Signals(-exitcode).name}"
        except ValueError:
            return f"died of signal {-exitcode}"
    return f"exited with code {exitcode}"


class ReferenceWorker:
    """Runs :func:`~lab.planning.real.runs.run_reference` (or ``runner``) in a spawned child process.

    ``ompl_seed`` seeds OMPL's RNG in each worker (a replacement worker after a crash gets the next seed).
    Use as a context manager, or call :meth:`close`.
    """

    def __init__(self, ompl_seed: int = 1, runner: Runner = run_reference) -> None:
        self._ctx = multiprocessing.get_context("spawn")
        self._seed = ompl_seed
        self._runner = runner
        self._proc: Any = None
        self._conn: Connection | None = None
        self._sent: set[str] = set()
        self.crashes = 0

    def __enter__(self) -> ReferenceWorker:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _start(self) -> None:
        parent, child = self._ctx.Pipe()
        proc = self._ctx.Process(target=_worker_main, args=(child, self._seed + self.crashes, self._runner),
                                 name="bitstar-reference", daemon=True)
        proc.start()
        child.close()  # the parent keeps only its end, so a dead child reads as EOF
        self._proc, self._conn = proc, parent
        self._sent.clear()
        if not parent.poll(START_TIMEOUT_S):
            self._stop(kill=True)
            raise RuntimeError("the reference worker did not start")
        try:
            parent.recv()
        except EOFError:
            self._stop(kill=True)
            raise RuntimeError("the reference worker died while starting") from None

    def _stop(self, kill: bool) -> int | None:
        proc, conn = self._proc, self._conn
        self._proc, self._conn = None, None
        self._sent.clear()
        if proc is None:
            return None
        if kill and proc.is_alive():
            proc.kill()  # only this worker, which this object started
        proc.join(5.0)
        if conn is not None:
            conn.close()
        return proc.exitcode

    def close(self) -> None:
        """Stop the worker (politely, then by force)."""
        if self._conn is not None and self._proc is not None and self._proc.is_alive():
            try:
                self._conn.send(None)
                self._proc.join(5.0)
            except (BrokenPipeError, OSError):
                pass
        self._stop(kill=True)

    def run(self, problem: RealProblem, grid: OccupancyGrid, robot: RobotProfile, checker: FootprintReferee,
            planner: str, time_limit_s: float, optimise_s: float | None = None, map_key: str | None = None,
            room_m: float = 0.0) -> RunRecord:
        """One reference run in the worker; a crash, a hang or an exception becomes a record, never a raise.

        ``map_key`` names the map (default ``grid.name``): a worker is sent each map once. ``room_m`` > 0 grows the
        checker's polygon by that much in the worker (:meth:`FootprintReferee.grown`, the room-matched reference)."""
        key = map_key or grid.name
        if self._proc is None or not self._proc.is_alive():
            if self._proc is not None:
                self._stop(kill=True)
            self._start()
        assert self._conn is not None
        conn = self._conn
        payload = None if key in self._sent else (grid, checker)
        try:
            conn.send((key, payload, problem, robot, planner, time_limit_s, optimise_s, room_m))
        except (BrokenPipeError, OSError):
            return self._crashed(problem, planner, time_limit_s, None)
        self._sent.add(key)
        budget = max(time_limit_s, optimise_s or 0.0) + HANG_MARGIN_S
        deadline = time.monotonic() + budget
        first: tuple[float, float] | None = None
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return self._crashed(problem, planner, time_limit_s, first, hung=True)
            try:
                if not conn.poll(min(remaining, 1.0)):
                    if not self._proc.is_alive():
                        return self._crashed(problem, planner, time_limit_s, first)
                    continue
                kind, data = conn.recv()
            except (EOFError, OSError):
                return self._crashed(problem, planner, time_limit_s, first)
            if kind == "first":
                first = data
            elif kind == "done":
                return data
            else:
                log.warning("%s %s raised in the worker: %s", problem.name, planner, data)
                return _record(problem, planner, "error", time_limit_s, time_limit_s,
                               first_length_m=first[1] if first else float("nan"),
                               message=f"the reference raised {data}")

    def _crashed(self, problem: RealProblem, planner: str, time_limit_s: float, first: tuple[float, float] | None,
                 hung: bool = False) -> RunRecord:
        code = self._stop(kill=True)
        self.crashes += 1
        how = _how_it_died(None if hung else code)
        when = (f"after its first solution ({first[0]:.3f} s, {first[1]:.2f} m), while optimising" if first
                else "before any solution")
        log.warning("%s %s: the reference worker %s %s; recorded as a reference failure", problem.name, planner,
                    how, when)
        return _record(problem, planner, "crashed", first[0] if first else time_limit_s, time_limit_s,
                       first_length_m=first[1] if first else float("nan"),
                       message=f"the BIT* worker process {how} {when}; not counted as solved")
