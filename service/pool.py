"""A supervised pool of worker processes: one job per worker, a dead worker is replaced at once.

:class:`SupervisedPool` is a :class:`concurrent.futures.Executor` the planning service queues its jobs
in. Unlike :class:`~concurrent.futures.ProcessPoolExecutor` (where one dead worker breaks the whole pool
and fails every job in it), each worker has its own pipe and its own supervising thread, so:

* a worker that dies, idle or busy, is logged and replaced (spawned and warmed) at once; only the job
  that was on it fails, with :class:`WorkerDied`; :attr:`SupervisedPool.ready_workers` counts the warmed
  workers that are alive and not stopped (``SIGSTOP``) or overrunning, so readiness says "not ready" while
  the pool is short;
* a worker acknowledges each job before it runs it, so a job handed to a worker that had died (or hung)
  while idle, before the supervisor saw it, is put back in the queue and runs on the replacement
  (at most ``MAX_HANDOVERS`` times) instead of failing;
* a job may carry a hard deadline (``submit_job(..., deadline_s=)``): a worker still busy with it
  ``KILL_GRACE_S`` after it is killed and replaced, and the job fails with :class:`WorkerHung` (a server
  fault, answered 503: every job checks its own deadline through :class:`planner.termination.Termination`
  and answers the timeout itself, so only a job that could not stop, or a stopped process, meets this);
* :meth:`SupervisedPool.cancel` ends a job: a queued one is dropped, a running one is asked to stop
  through a shared flag (the planner polls it between search chunks, see :func:`service.jobs.cancelled`)
  and its worker is killed and replaced if it has not stopped ``KILL_GRACE_S`` later;
* queued jobs start earliest deadline first (queued time + time limit), so a short plan waits for at
  most the plans already running, never behind queued long ones, and a long plan still starts once its
  own deadline is the earliest;
* each worker may get an address-space ceiling (``memory_limit_mb``) so that a runaway ends in a
  ``MemoryError`` the job answers cleanly instead of the machine's OOM killer.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import threading
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import Executor, Future
from dataclasses import dataclass, field
from multiprocessing.connection import Connection, wait
from typing import Any

from planner.errors import PlannerCancelled
from service.outcome import WorkerLost

log = logging.getLogger(__name__)

#: how long a running job may take to stop after a cancel or its deadline before its worker is killed (s)
KILL_GRACE_S = 1.0
#: how often a supervising thread looks at its worker while waiting (s)
POLL_S = 0.1
#: longest a new worker may take to start and warm up before it is replaced again (s)
START_TIMEOUT_S = 600.0
#: longest an idle worker may take to acknowledge a job it was sent before it is taken for hung (s)
ACK_TIMEOUT_S = 30.0
#: how many times a job that never started (its worker was found dead or hung) is handed to another worker
MAX_HANDOVERS = 3


class WorkerDied(WorkerLost):
    """The worker process running a job died (killed, crashed) before answering."""


class WorkerHung(WorkerLost):
    """The worker process running a job did not stop at the job's deadline (stopped, or stuck where it
    cannot look at its clock) and was killed."""


def _stopped(pid: int | None) -> bool:
    """True when process ``pid`` is stopped (``SIGSTOP``, traced): Linux ``/proc``; False where unknown."""
    if pid is None:
        return False
    try:
        with open(f"/proc/{pid}/stat", "rb") as stat:
            return stat.read().rsplit(b")", 1)[1].split()[0] in (b"T", b"t")
    except (OSError, IndexError):
        return False


@dataclass(eq=False)
class _Task:
    fn: Callable[..., Any]
    args: tuple[Any, ...]
    future: Future[Any]
    deadline_s: float | None = None  # seconds of running time, counted from when a worker takes it
    cancel_requested: bool = False
    started: float | None = field(default=None)
    handovers: int = 0  # times it was sent to a worker that turned out dead or hung before taking it
    queued_at: float = field(default_factory=time.monotonic)

    @property
    def due(self) -> float:
        """When the job would have to be done if it started now-ish: queued time + its deadline (the
        earliest-deadline-first order of the queue; jobs without a deadline go last, oldest first)."""
        return self.queued_at + (self.deadline_s if self.deadline_s is not None else 1e9)


def _worker_main(conn: Connection, cancel_flag: Any, initializer: Callable[[], None] | None,
                 warm_up: Callable[[], Any] | None, memory_limit_mb: int) -> None:
    """The loop of one worker process: receive (fn, args), send back ("ok", result) or ("error", exc)."""
    if memory_limit_mb > 0:
        import resource

        limit = memory_limit_mb * 1024 * 1024
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    from service import jobs

    jobs.set_cancel_flag(cancel_flag)
    if initializer is not None:
        initializer()
    if warm_up is not None:
        warm_up()
    conn.send(("ready", os.getpid()))
    while True:
        try:
            message = conn.recv()
        except (EOFError, OSError, KeyboardInterrupt):
            return
        if message is None:
            return
        fn, args = message
        try:
            conn.send(("started", None))
        except (EOFError, OSError):
            return
        try:
            reply: tuple[str, Any] = ("ok", fn(*args))
        except BaseException as exc:
            reply = ("error", exc)
        try:
            conn.send(reply)
        except (EOFError, OSError):
            return
        except Exception as exc:  # an unpicklable result or error
            conn.send(("error", RuntimeError(f"{type(exc).__name__} while sending a job's answer")))


class _Worker:
    """One worker process and the thread that supervises it."""

    def __init__(self, pool: SupervisedPool, index: int) -> None:
        self.pool = pool
        self.index = index
        self.proc: Any = None
        self.conn: Connection | None = None
        self.cancel_flag = pool._ctx.Value("b", 0, lock=False)
        self.ready = False
        self.overrunning = False  # its job is past its deadline: not ready until it answers or is replaced
        self.task: _Task | None = None
        self.thread = threading.Thread(target=self._run, name=f"sphereplan-worker-{index}", daemon=True)

    # ---------------------------------------------------------------- process

    def _spawn(self) -> bool:
        """Start and warm a new worker process; False if the pool is closing or it failed to start."""
        parent, child = self.pool._ctx.Pipe()
        proc = self.pool._ctx.Process(target=_worker_main, name=f"sphereplan-worker-{self.index}", daemon=True,
                                      args=(child, self.cancel_flag, self.pool._initializer, self.pool._warm_up,
                                            self.pool._memory_limit_mb))
        proc.start()
        child.close()
        self.proc, self.conn = proc, parent
        t0 = time.monotonic()
        while not self.pool._closed:
            if wait([parent, proc.sentinel], timeout=POLL_S):
                try:
                    kind, pid = parent.recv()
                except (EOFError, OSError):
                    break
                if kind == "ready":
                    log.info("worker %d (pid %d) ready in %.1f s", self.index, pid, time.monotonic() - t0)
                    return True
            if time.monotonic() - t0 > START_TIMEOUT_S:
                log.error("worker %d did not start within %g s", self.index, START_TIMEOUT_S)
                break
        self._kill()
        return False

    def _kill(self) -> None:
        proc, conn = self.proc, self.conn
        self.proc = self.conn = None
        self.ready = False
        self.overrunning = False
        if conn is not None:
            conn.close()
        if proc is not None:
            if proc.is_alive():
                proc.kill()
            proc.join(timeout=10)

    def alive(self) -> bool:
        return self.proc is not None and self.proc.is_alive()

    def healthy(self) -> bool:
        """Warmed, alive, not stopped and not overrunning a job: can take (or is doing) useful work."""
        return (self.ready and self.alive() and not self.overrunning
                and not _stopped(self.proc.pid if self.proc is not None else None))

    # ---------------------------------------------------------------- supervision

    def _run(self) -> None:
        failures = 0
        while not self.pool._closed:
            if self.proc is not None and not self.alive():
                log.error("worker %d (pid %s) died while idle (exit code %s); replacing it",
                          self.index, self.proc.pid, self.proc.exitcode)
                self._kill()
            elif self.proc is not None and _stopped(self.proc.pid):
                log.error("worker %d (pid %s) is stopped while idle; killing and replacing it", self.index,
                          self.proc.pid)
                self._kill()
            if not self.alive():
                if not self._spawn():
                    failures += 1
                    time.sleep(min(5.0, 0.2 * failures))
                    continue
                failures = 0
                self.ready = True
            task = self.pool._next_task(self)
            if task is None:
                continue
            self._execute(task)
        self._kill()

    def _execute(self, task: _Task) -> None:
        assert self.conn is not None and self.proc is not None
        self.cancel_flag.value = 0
        try:
            self.conn.send((task.fn, task.args))
        except Exception as exc:  # unpicklable arguments, or the worker just died
            if self.alive():
                self._finish(task, exc=exc)
            else:
                self._hand_back(task, "died while idle")
            return
        if not self._await_start(task):
            return
        task.started = time.monotonic()
        stop_at: float | None = None  # when the worker is killed if it has not answered
        reason: BaseException | None = None
        while True:
            if task.cancel_requested and stop_at is None:
                self.cancel_flag.value = 1
                stop_at, reason = time.monotonic() + KILL_GRACE_S, PlannerCancelled("the job was cancelled")
            if (task.deadline_s is not None and stop_at is None
                    and time.monotonic() > task.started + task.deadline_s):
                # no cancel flag here: the job's own deadline check answers a timeout if it can, in the grace
                stop_at = time.monotonic() + KILL_GRACE_S
                self.overrunning = True
                reason = WorkerHung(f"the worker did not stop at the job's deadline ({task.deadline_s:g} s); "
                                    "it was replaced")
            if self.pool._closed:
                self._finish(task, exc=RuntimeError("the pool is shut down"))
                return
            if stop_at is not None and time.monotonic() > stop_at:
                log.warning("worker %d (pid %s) overran a job (%s); killing and replacing it",
                            self.index, self.proc.pid, reason)
                self._kill()
                self._finish(task, exc=reason)
                return
            ready = wait([self.conn, self.proc.sentinel], timeout=POLL_S)
            if self.conn in ready:
                try:
                    kind, value = self.conn.recv()
                except (EOFError, OSError):
                    ready = [self.proc.sentinel]
                else:
                    if kind == "ok" and reason is not None:
                        # answered after the cancel or deadline: the answer stands unless it was cancelled
                        if isinstance(reason, PlannerCancelled):
                            self._finish(task, exc=reason)
                            return
                    self._finish(task, result=value) if kind == "ok" else self._finish(task, exc=value)
                    return
            if ready and not self.alive():
                log.error("worker %d (pid %s) died while running a job (exit code %s); replacing it",
                          self.index, self.proc.pid, self.proc.exitcode)
                self._kill()
                self._finish(task, exc=reason if isinstance(reason, WorkerHung) else
                             WorkerDied("a worker process died while running this job"))
                return

    def _await_start(self, task: _Task) -> bool:
        """Wait for the worker to acknowledge ``task``; hand the task back to the queue (False) if the worker
        turns out dead or does not answer within ``ACK_TIMEOUT_S`` (then it is killed)."""
        assert self.conn is not None and self.proc is not None
        end = time.monotonic() + ACK_TIMEOUT_S
        while not self.pool._closed:
            ready = wait([self.conn, self.proc.sentinel], timeout=POLL_S)
            if self.conn in ready:
                try:
                    kind, _ = self.conn.recv()
                except (EOFError, OSError):
                    self._hand_back(task, "died while idle")
                    return False
                if kind == "started":
                    return True
            if ready and not self.alive():
                self._hand_back(task, "died while idle")
                return False
            if time.monotonic() > end or _stopped(self.proc.pid):
                self._hand_back(task, "hung while idle")
                return False
        self._finish(task, exc=RuntimeError("the pool is shut down"))
        return False

    def _hand_back(self, task: _Task, what: str) -> None:
        """The worker took no part in ``task`` (it was dead or hung before it acknowledged it): replace the
        worker and queue the task again, ahead of the others (it keeps its place by deadline)."""
        assert self.proc is not None
        log.error("worker %d (pid %s) %s (exit code %s); replacing it and handing its job to the next worker",
                  self.index, self.proc.pid, what, self.proc.exitcode)
        self._kill()
        with self.pool._cv:
            self.task = None
        task.handovers += 1
        if task.handovers > MAX_HANDOVERS:
            self._finish(task, exc=WorkerDied(f"{task.handovers} worker processes died before running this job"))
            return
        self.pool._requeue(task)

    def _finish(self, task: _Task, result: Any = None, exc: BaseException | None = None) -> None:
        with self.pool._cv:
            self.task = None
            self.overrunning = False
        if task.future.done():
            return
        try:
            if exc is not None:
                task.future.set_exception(exc)
            else:
                task.future.set_result(result)
        except Exception:  # a concurrent cancel resolved it
            pass


class SupervisedPool(Executor):
    """``workers`` supervised worker processes (spawned); see the module docstring."""

    def __init__(self, workers: int, initializer: Callable[[], None] | None = None,
                 warm_up: Callable[[], Any] | None = None, memory_limit_mb: int = 0) -> None:
        self._ctx = multiprocessing.get_context("spawn")
        self._initializer = initializer
        self._warm_up = warm_up
        self._memory_limit_mb = memory_limit_mb
        self._cv = threading.Condition()
        self._queue: deque[_Task] = deque()
        self._tasks: dict[Future[Any], _Task] = {}
        self._closed = False
        self._workers = [_Worker(self, i) for i in range(workers)]
        for worker in self._workers:
            worker.thread.start()

    @property
    def ready_workers(self) -> int:
        """Workers started, warmed, alive, not stopped and not overrunning a job (fewer than asked for while
        one is being replaced or is hung)."""
        return sum(1 for w in self._workers if w.healthy())

    @property
    def size(self) -> int:
        return len(self._workers)

    def worker_pids(self) -> list[int | None]:
        """Process ids of the workers (None for one being replaced)."""
        return [w.proc.pid if w.proc is not None else None for w in self._workers]

    def busy_pids(self) -> list[int]:
        """Process ids of the workers that are running a job."""
        return [w.proc.pid for w in self._workers if w.task is not None and w.proc is not None]

    def wait_ready(self, timeout_s: float) -> bool:
        """Block until every worker is warmed (True) or ``timeout_s`` passed (False)."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            if self.ready_workers == self.size:
                return True
            time.sleep(POLL_S)
        return self.ready_workers == self.size

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future[Any]:
        if kwargs:
            raise TypeError("SupervisedPool jobs take positional arguments only")
        return self.submit_job(fn, args)

    def submit_job(self, fn: Callable[..., Any], args: tuple[Any, ...], deadline_s: float | None = None) -> Future[Any]:
        """Queue ``fn(*args)``; with ``deadline_s`` its worker is killed if it runs longer than that plus
        ``KILL_GRACE_S`` (the job then fails with :class:`WorkerHung`)."""
        future: Future[Any] = Future()
        task = _Task(fn, args, future, deadline_s)
        with self._cv:
            if self._closed:
                raise RuntimeError("cannot submit to a closed pool")
            self._queue.append(task)
            self._tasks[future] = task
            self._cv.notify()
        future.add_done_callback(self._forget)
        return future

    def _forget(self, future: Future[Any]) -> None:
        with self._cv:
            self._tasks.pop(future, None)

    def _next_task(self, worker: _Worker) -> _Task | None:
        """The next queued task for ``worker`` (None after a short wait, so the thread can check its process)."""
        with self._cv:
            if not self._queue:
                self._cv.wait(timeout=POLL_S * 5)
            while self._queue:
                task = min(self._queue, key=lambda t: t.due)  # earliest deadline first (the queue is short)
                self._queue.remove(task)
                if task.handovers or task.future.set_running_or_notify_cancel():
                    worker.task = task
                    return task
        return None

    def _requeue(self, task: _Task) -> None:
        with self._cv:
            if self._closed:
                closed = True
            else:
                closed = False
                self._queue.append(task)
                self._cv.notify()
        if closed and not task.future.done():
            task.future.set_exception(RuntimeError("the pool is shut down"))

    def cancel(self, future: Future[Any]) -> None:
        """End the job of ``future``: a queued one never runs, a running one is stopped (its future then
        fails with :class:`PlannerCancelled`)."""
        with self._cv:
            task = self._tasks.get(future)
            if task is None:
                return
            if task in self._queue:
                self._queue.remove(task)
                if task.handovers:  # already marked running: end it as cancelled
                    future.set_exception(PlannerCancelled("the job was cancelled"))
                else:
                    future.cancel()
                return
            task.cancel_requested = True

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """Stop every worker now; jobs not finished fail (queued ones are cancelled)."""
        with self._cv:
            if self._closed:
                return
            self._closed = True
            queued, self._queue = list(self._queue), deque()
            self._cv.notify_all()
        for task in queued:
            if task.handovers:
                task.future.set_exception(RuntimeError("the pool is shut down"))
            else:
                task.future.cancel()
        for worker in self._workers:
            conn = worker.conn
            if conn is not None and worker.task is None:
                try:
                    conn.send(None)
                except (OSError, ValueError):
                    pass
        if wait:
            for worker in self._workers:
                worker.thread.join(timeout=15)
