"""The planning service: :class:`PlanningService`, the one object the HTTP app and the Zenoh node call.

Each capability is one ``submit_*`` method: it checks the request against this server (map and robot
names, limits), builds the planner's own typed objects from it (a :class:`~service.pipeline.PlanQuery`,
the Spherobot ``ReconfigureRequest``, ``SimulationOptions``, angles in radians) and queues one job of
:mod:`service.jobs` in a process pool (planning is CPU-bound), returning a future
:class:`~service.outcome.Outcome`. So a bad request is refused in the calling process before a job is
queued. The pool is warmed at start-up so the first request does not pay for imports and compiled-code
loading; each job carries its own deadline (the planner's time limit) and at most ``max_in_flight`` jobs
are queued or running, beyond that a submit raises :class:`~service.outcome.ServiceBusy`. Map names are
looked up in a listing of the maps folder, never joined onto a path, so a request can only reach a map
file that is in that folder.
"""

from __future__ import annotations

import logging
import math
import multiprocessing
import threading
import time
from collections.abc import Callable
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from concurrent.futures import TimeoutError as FuturesTimeout
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any

from planner.errors import InvalidInput, NotFound, SpherePlanError
from planner.hybrid_astar.search import PlannerOptions
from planner.maps.catalogue import default_maps_dir, list_maps, map_files
from planner.maps.nav2 import MESH_SUFFIXES
from planner.occupancy import OccupancyGrid
from planner.robot import DEFAULT_ROBOT, builtin_robots, load_robot
from planner.spherobot.request import ReconfigureRequest
from service.grids import grid_png, load_map_file
from service.jobs import (
    plan_job,
    reconfigure_job,
    simulate_job,
    tensegrity_static_job,
    vpip_rods_job,
    vpip_schedule_job,
    warm_up_job,
    worker_init,
)
from service.outcome import Outcome, ServiceBusy, error_outcome, outcome_of_exception
from service.pipeline import PlanQuery
from service.settings import ServiceSettings
from service.wire import (
    InlineGrid,
    PlanIn,
    PlanRequest,
    ReconfigureIn,
    RosOccupancyGrid,
    SimulateRequest,
    TensegrityStaticRequest,
    VpipRodsRequest,
    VpipScheduleRequest,
)

log = logging.getLogger(__name__)

#: farthest reconfiguration goal, in sphere radii from the start (paper 004's examples are a few radii)
MAX_RECONFIGURE_RADII = 200


def _radians(angle: float, degrees: bool) -> float:
    return math.radians(angle) if degrees else float(angle)


class PlanningService:
    """Does the work behind every transport.

    ``start()`` opens (and warms) the pool; ``close()`` stops it, ending running jobs. ``executor_factory``
    replaces the process pool (tests use a thread pool). Thread-safe: HTTP handlers and Zenoh callbacks
    submit from different threads.
    """

    def __init__(self, settings: ServiceSettings | None = None,
                 executor_factory: Callable[[int], Executor] | None = None) -> None:
        self.settings = settings or ServiceSettings()
        self.maps_dir = Path(self.settings.maps_dir) if self.settings.maps_dir else default_maps_dir()
        self._executor_factory = executor_factory or self._process_pool
        self._executor: Executor | None = None
        self._lock = threading.Lock()
        self._in_flight = 0
        self._ready = False
        self.started_at = time.time()
        self.warm_up_s = 0.0

    # ---------------------------------------------------------------- life cycle

    @staticmethod
    def _process_pool(workers: int) -> Executor:
        # spawn, not fork: the parent runs threads (Zenoh, the event loop) that fork would copy mid-flight
        return ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                                   initializer=worker_init)

    def start(self) -> None:
        """Open the pool and, if ``settings.warm_up``, run one warm-up job per worker (blocking)."""
        t0 = time.perf_counter()
        self._executor = self._executor_factory(self.settings.workers)
        if self.settings.warm_up:
            jobs = [self._executor.submit(warm_up_job) for _ in range(self.settings.workers)]
            pids = {job.result() for job in jobs}
            log.info("warmed %d worker process(es) %s", len(pids), sorted(pids))
        self.warm_up_s = time.perf_counter() - t0
        self._ready = True

    def close(self) -> None:
        """Stop the pool now: queued jobs are cancelled and running workers terminated."""
        self._ready = False
        executor, self._executor = self._executor, None
        if executor is None:
            return
        processes = []
        if isinstance(executor, ProcessPoolExecutor) and executor._processes:
            processes = list(executor._processes.values())
        executor.shutdown(wait=False, cancel_futures=True)
        for proc in processes:
            if proc.is_alive():
                proc.terminate()
        for proc in processes:
            proc.join(timeout=5)

    @property
    def ready(self) -> bool:
        return self._ready and self._executor is not None

    @property
    def in_flight(self) -> int:
        return self._in_flight

    # ---------------------------------------------------------------- job submission

    def _submit(self, fn: Callable[..., Outcome], *args: Any) -> Future[Outcome]:
        """Queue ``fn(*args)`` in the pool, counting it against the in-flight cap."""
        with self._lock:
            if self._executor is None:
                raise ServiceBusy(self._in_flight, self.settings.retry_after_s)
            if self._in_flight >= self.settings.in_flight_cap:
                raise ServiceBusy(self._in_flight, self.settings.retry_after_s)
            self._in_flight += 1
            executor = self._executor
            try:
                inner = executor.submit(fn, *args)
            except RuntimeError:  # shut down meanwhile
                self._in_flight -= 1
                raise ServiceBusy(self._in_flight, self.settings.retry_after_s) from None
        outer: Future[Outcome] = Future()

        def done(job: Future[Outcome]) -> None:
            with self._lock:
                self._in_flight -= 1
            if job.cancelled():
                outer.set_result(error_outcome(ServiceBusy, "the service is shutting down"))
                return
            exc = job.exception()
            if exc is None:
                outer.set_result(job.result())
            elif isinstance(exc, BrokenProcessPool):
                log.error("a worker process died: %s; restarting the pool", exc)
                self._restart_pool(executor)
                outer.set_result(error_outcome(BrokenProcessPool, "a worker process died while planning"))
            else:
                outer.set_result(outcome_of_exception(exc))

        inner.add_done_callback(done)
        return outer

    def _restart_pool(self, broken: Any) -> None:
        """Replace the pool ``broken`` once (every job it failed calls this) and warm the new one."""
        with self._lock:
            if self._executor is None or not self._ready or self._executor is not broken:
                return
            self._executor = self._executor_factory(self.settings.workers)
            fresh = self._executor
        broken.shutdown(wait=False, cancel_futures=True)
        if self.settings.warm_up:
            for _ in range(self.settings.workers):
                fresh.submit(warm_up_job)

    # ---------------------------------------------------------------- capabilities

    def resolve_map(self, name: str) -> Path:
        """The file of map ``name`` in the maps folder, or :class:`NotFound`."""
        index = map_files(self.maps_dir)
        path = index.get(name)
        if path is None:
            shown = ", ".join(sorted(index)) or "none"
            raise NotFound("map", f"no map named {name!r} in the maps folder (available: {shown})")
        return path

    def resolve_robot(self, name: str | None) -> None:
        """Raise :class:`NotFound` unless ``name`` is None or a built-in profile (no file paths)."""
        if name is not None and name not in builtin_robots():
            raise NotFound("robot", f"unknown robot {name!r}; built-in: {', '.join(builtin_robots())}")

    def submit_plan(self, request: PlanRequest) -> Future[Outcome]:
        """Check ``request`` against this service (robot, options, limits, map) and queue the plan.

        Raises :class:`NotFound`/:class:`InvalidInput` for a bad request and :class:`ServiceBusy`.
        """
        self.resolve_robot(request.robot)
        options = request.options or {}
        query = PlanQuery(request.start.as_pose(), request.goal.as_pose(), PlannerOptions.from_dict(options),
                          request.time_limit_s)
        limit = self.settings.max_time_limit_s
        if query.time_limit_s is not None and query.time_limit_s > limit:
            raise InvalidInput("time_limit_s", f"must be ≤ {limit:g} s on this server")
        if "time_limit_s" in options and query.options.time_limit_s > limit:
            raise InvalidInput("options.time_limit_s", f"must be ≤ {limit:g} s on this server")
        return self._submit(plan_job, query, request.robot, self._map_source(request.map))

    def _map_source(self, map_spec: str | InlineGrid | RosOccupancyGrid) -> Path | InlineGrid:
        """The file of a named map (checked now), or the inline grid (size checked now); a
        ``nav_msgs/OccupancyGrid`` is taken as the inline grid it describes."""
        if isinstance(map_spec, str):
            return self.resolve_map(map_spec)
        if isinstance(map_spec, RosOccupancyGrid):
            map_spec = map_spec.as_inline()
        cells = len(map_spec.data) * len(map_spec.data[0])
        if cells > self.settings.max_inline_cells:
            limit = self.settings.max_inline_cells
            raise InvalidInput("map.data", f"{cells} cells; this server accepts at most {limit}")
        return map_spec

    def _plan_robot(self, robot: str | None, path: PlanIn, default: str) -> str:
        """The robot a plan-consuming request uses: its own, else the plan's (built-in only), else ``default``."""
        if robot is None:
            robot = path.robot.name if path.robot is not None else default
            if robot not in builtin_robots():
                raise NotFound("path.robot.name", f"the plan's robot {robot!r} is not a built-in profile; "
                                                  f"give robot (one of {', '.join(builtin_robots())})")
        self.resolve_robot(robot)
        return robot

    def submit_simulate(self, request: SimulateRequest) -> Future[Outcome]:
        """Queue a closed-loop simulation of ``request.path`` (robot: the request's, else the plan's)."""
        from planner.closed_loop.simulate import SimulationOptions
        from planner.closed_loop.tracker import MPCParams

        robot = self._plan_robot(request.robot, request.path, DEFAULT_ROBOT)
        options = SimulationOptions(control_rate_hz=request.rate_hz, tracker=request.tracker,
                                    mpc=MPCParams(horizon=request.horizon), time_limit_s=request.time_limit_s)
        return self._submit(simulate_job, request.path.model_dump(mode="json"), self._map_source(request.map), robot,
                            request.seed, request.noise, options)

    def submit_reconfigure(self, request: ReconfigureIn) -> Future[Outcome]:
        """Queue a Spherobot reconfiguration (optionally checked against a map). The goal may be at most
        ``MAX_RECONFIGURE_RADII`` sphere radii from the start: the rolled result is sampled along the way,
        so its size and cost grow with distance / radius."""
        problem = ReconfigureRequest.from_dict(request.model_dump(exclude={"map"}))
        assert problem.radius_m is not None
        distance, farthest = math.dist(problem.start, problem.goal), MAX_RECONFIGURE_RADII * problem.radius_m
        if distance > farthest:
            raise InvalidInput("goal", f"is {distance:.3g} m from the start; this server rolls at most "
                                       f"{MAX_RECONFIGURE_RADII} sphere radii ({farthest:.3g} m)")
        return self._submit(reconfigure_job, problem, None if request.map is None else self._map_source(request.map))

    def submit_vpip_rods(self, request: VpipRodsRequest) -> Future[Outcome]:
        """Queue one eq. 18 rod-length evaluation."""
        self.resolve_robot(request.robot)
        angles = (request.phi_vpip, request.theta_vpip, request.roll, request.pitch_phase)
        return self._submit(vpip_rods_job, *(_radians(a, request.degrees) for a in angles), request.robot)

    def submit_vpip_schedule(self, request: VpipScheduleRequest) -> Future[Outcome]:
        """Queue a 100 Hz VPIP schedule along ``request.path`` (robot: the request's, the plan's, daedalus)."""
        robot = self._plan_robot(request.robot, request.path, "daedalus")
        return self._submit(vpip_schedule_job, request.path.model_dump(mode="json"), robot, request.driver)

    def submit_tensegrity_static(self, request: TensegrityStaticRequest) -> Future[Outcome]:
        """Queue the TeXploR static-state computation."""
        self.resolve_robot(request.robot)
        return self._submit(tensegrity_static_job, _radians(request.theta1, request.degrees),
                            _radians(request.theta2, request.degrees), request.robot, request.verify)

    def plan(self, request: PlanRequest, timeout_s: float | None = None) -> Outcome:
        """Blocking plan: the :class:`Outcome`, with request errors and busy mapped to outcomes too."""
        try:
            return self.submit_plan(request).result(timeout=timeout_s)
        except FuturesTimeout:
            return error_outcome(ServiceBusy, f"no answer within {timeout_s} s (the plan keeps its worker until its "
                                 "own time limit ends)")
        except (ServiceBusy, SpherePlanError) as exc:
            return outcome_of_exception(exc)

    def maps(self) -> list[dict[str, Any]]:
        """Every map a request may name (:func:`planner.maps.catalogue.list_maps` entries: name, file, kind, size_m,
        resolution_m); where a grid YAML and a mesh share a name, the YAML is the one served."""
        index = map_files(self.maps_dir)
        return [entry for entry in list_maps(self.maps_dir) if index.get(entry["name"], Path()).name == entry["file"]]

    def map_grid(self, name: str) -> OccupancyGrid:
        return load_map_file(self.resolve_map(name), None)

    def map_info(self, name: str) -> dict[str, Any]:
        """Metadata of map ``name``: size, resolution, origin, file, and the fraction of blocked cells."""
        path = self.resolve_map(name)
        grid = load_map_file(path, None)
        info = grid.metadata()
        info.update(name=name, file=path.name, kind="mesh" if path.suffix.lower() in MESH_SUFFIXES else "grid",
                    occupied_fraction=float(grid.blocked(False).mean()))
        return info

    def map_png(self, name: str) -> bytes:
        return grid_png(self.map_grid(name))

    def robots(self) -> list[dict[str, Any]]:
        """Every built-in robot profile as the result JSON carries it."""
        return [load_robot(name).to_json() for name in builtin_robots()]

    def health(self) -> dict[str, Any]:
        return {"status": "ok" if self.ready else "starting", "workers": self.settings.workers,
                "in_flight": self._in_flight, "max_in_flight": self.settings.in_flight_cap,
                "warm_up_s": round(self.warm_up_s, 3), "uptime_s": round(time.time() - self.started_at, 3)}
