"""The planning service: :class:`PlanningService`, the one object the HTTP app and the Zenoh node call.

Each capability is one ``submit_*`` method: it checks the request against this server (map and robot
names, limits), builds the planner's own typed objects from it (a :class:`~service.pipeline.PlanQuery`,
the Spherobot ``ReconfigureRequest``, ``SimulationOptions``, angles in radians) and queues one job of
:mod:`service.jobs` in the supervised process pool (:mod:`service.pool`; planning is CPU-bound),
returning a future :class:`~service.outcome.Outcome`. So a bad request is refused in the calling process
before a job is queued. The pool is warmed at start-up so the first request does not pay for imports
and compiled-code loading; each job carries its own deadline (a plan's time limit, covering the whole
job) and at most ``max_in_flight`` jobs are queued or running, beyond that a submit raises
:class:`~service.outcome.ServiceBusy`. A job's slot is freed when it ends or is cancelled
(:meth:`PlanningService.cancel`: a client gone, a goal superseded, shutdown). Map names are
looked up in a listing of the maps folder, never joined onto a path, so a request can only reach a map
file that is in that folder.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from concurrent.futures import Executor, Future
from concurrent.futures import TimeoutError as FuturesTimeout
from pathlib import Path
from typing import Any

from planner.errors import InvalidInput, NotFound, PlannerCancelled, SpherePlanError
from planner.hybrid_astar.search import PlannerOptions
from planner.maps.catalogue import default_maps_dir, list_maps, map_files
from planner.maps.nav2 import MESH_SUFFIXES
from planner.occupancy import OccupancyGrid
from planner.robot import DEFAULT_ROBOT, RobotProfile, builtin_robots, load_robot
from planner.spherobot.request import ReconfigureRequest
from planner.termination import Termination
from service.grids import grid_png, load_map_file
from service.jobs import (
    PERCEIVE_FIELDS,
    perceive_job,
    plan_job,
    reconfigure_job,
    simulate_job,
    tensegrity_static_job,
    vpip_rods_job,
    vpip_schedule_job,
    warm_up_job,
    worker_init,
)
from service.outcome import Outcome, ServiceBusy, WorkerLost, error_outcome, outcome_of_exception
from service.pipeline import MAX_RESULT_STATES, PlanQuery
from service.pool import START_TIMEOUT_S, SupervisedPool
from service.settings import ServiceSettings
from service.wire import (
    InlineGrid,
    PerceiveRequest,
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

#: added to a plan's time limit for the pool's hard deadline: loading the map (a mesh's first load) is not
#: part of the time limit, the search, smoothing and result building are (the job checks those itself)
MAP_LOAD_ALLOWANCE_S = 10.0
#: how long past its own wall-clock termination a job may run before the pool kills its worker (s): the loops
#: check their clock every few steps, so only a job stuck where it cannot look at it meets this
JOB_STOP_ALLOWANCE_S = 5.0
#: widest inline grid a plan may use (m, diagonal): cells × resolution, so a few cells cannot span a continent
MAX_INLINE_EXTENT_M = 2_000.0


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
        self._closing = False
        self._jobs: dict[Future[Outcome], Future[Outcome]] = {}  # the service's future → the pool's
        self.started_at = time.time()
        self.warm_up_s = 0.0

    # ---------------------------------------------------------------- life cycle

    def _process_pool(self, workers: int) -> Executor:
        # spawned, supervised processes: a dead worker is replaced and fails only the job it was running
        return SupervisedPool(workers, initializer=worker_init, warm_up=warm_up_job if self.settings.warm_up else None,
                              memory_limit_mb=self.settings.worker_memory_mb)

    def start(self) -> None:
        """Open the pool and, if ``settings.warm_up``, wait until every worker is warmed (blocking)."""
        t0 = time.perf_counter()
        self._executor = self._executor_factory(self.settings.workers)
        if isinstance(self._executor, SupervisedPool):
            self._executor.wait_ready(START_TIMEOUT_S)
            log.info("warmed %d worker process(es) %s", self._executor.ready_workers, self._executor.worker_pids())
        elif self.settings.warm_up:
            jobs = [self._executor.submit(warm_up_job) for _ in range(self.settings.workers)]
            pids = {job.result() for job in jobs}
            log.info("warmed %d worker process(es) %s", len(pids), sorted(pids))
        self.warm_up_s = time.perf_counter() - t0
        self._ready = True

    def begin_shutdown(self) -> None:
        """Refuse new jobs and answer every job in flight now with the JSON 503 "shutting down" (the HTTP
        server calls this on SIGTERM/Ctrl-C, before it stops waiting for open requests)."""
        with self._lock:
            self._ready = False
            self._closing = True
            pending = list(self._jobs.items())
        for outer, inner in pending:
            self._cancel_inner(inner)
            self._resolve(outer, error_outcome(ServiceBusy, "the service is shutting down"))

    def close(self) -> None:
        """Stop the pool now: jobs in flight are answered "shutting down" and running workers ended."""
        self.begin_shutdown()
        executor, self._executor = self._executor, None
        if executor is not None:
            executor.shutdown(wait=isinstance(executor, SupervisedPool), cancel_futures=True)

    @property
    def ready(self) -> bool:
        """Started, not stopping, and (with the supervised pool) no worker missing."""
        executor = self._executor
        if not self._ready or executor is None:
            return False
        return not isinstance(executor, SupervisedPool) or executor.ready_workers == executor.size

    @property
    def in_flight(self) -> int:
        return self._in_flight

    # ---------------------------------------------------------------- job submission

    def _submit(self, fn: Callable[..., Outcome], *args: Any, deadline_s: float | None = None) -> Future[Outcome]:
        """Queue ``fn(*args)`` in the pool, counting it against the in-flight cap until it ends or is
        cancelled (:meth:`cancel`). ``deadline_s`` (default: the server's ``max_job_s``) bounds the job's
        whole run: the pool ends a job still running ``KILL_GRACE_S`` after it."""
        deadline = self.settings.max_job_s if deadline_s is None else deadline_s
        with self._lock:
            if self._executor is None or self._closing:
                raise ServiceBusy(self._in_flight, self.settings.retry_after_s)
            if self._in_flight >= self.settings.in_flight_cap:
                raise ServiceBusy(self._in_flight, self.settings.retry_after_s)
            self._in_flight += 1
            executor = self._executor
            try:
                if isinstance(executor, SupervisedPool):
                    inner = executor.submit_job(fn, args, deadline_s=deadline)
                else:
                    inner = executor.submit(fn, *args)
            except RuntimeError:  # shut down meanwhile
                self._in_flight -= 1
                raise ServiceBusy(self._in_flight, self.settings.retry_after_s) from None
            outer: Future[Outcome] = Future()
            outer.set_running_or_notify_cancel()  # only the service ends it (cancel(), shutdown, the job)
            self._jobs[outer] = inner

        def done(job: Future[Outcome]) -> None:
            if job.cancelled():
                outcome = error_outcome(ServiceBusy, "the service is shutting down")
            elif (exc := job.exception()) is None:
                outcome = job.result()
            elif isinstance(exc, WorkerLost):  # a server fault: 503, the request may be sent again
                log.error("job %s failed: %s", getattr(fn, "__name__", fn), exc)
                outcome = outcome_of_exception(exc)
            elif isinstance(exc, RuntimeError) and self._closing:
                outcome = error_outcome(ServiceBusy, "the service is shutting down")
            else:
                outcome = outcome_of_exception(exc)
            self._resolve(outer, outcome)

        inner.add_done_callback(done)
        return outer

    def _resolve(self, outer: Future[Outcome], outcome: Outcome) -> None:
        """Answer ``outer`` once and free its slot (whichever of the job, a cancel or shutdown comes first)."""
        with self._lock:
            if self._jobs.pop(outer, None) is None:
                return
            self._in_flight -= 1
        outer.set_result(outcome)

    def _cancel_inner(self, inner: Future[Outcome]) -> None:
        executor = self._executor
        if isinstance(executor, SupervisedPool):
            executor.cancel(inner)
        else:
            inner.cancel()

    def cancel(self, future: Future[Outcome]) -> bool:
        """Cancel a job this service queued (a client gave up, a newer goal replaced it): it is answered
        "cancelled" and its slot is freed now; the pool stops the job (queued: never runs; running: stopped
        between search chunks, or its worker replaced). False if it had already ended."""
        with self._lock:
            inner = self._jobs.get(future)
        if inner is None:
            return False
        self._cancel_inner(inner)
        self._resolve(future, outcome_of_exception(PlannerCancelled("the job was cancelled")))
        return True

    # ---------------------------------------------------------------- capabilities

    def resolve_map(self, name: str) -> Path:
        """The file of map ``name`` in the maps folder, or :class:`NotFound`."""
        index = map_files(self.maps_dir)
        path = index.get(name)
        if path is None:
            shown = ", ".join(sorted(index)) or "none"
            raise NotFound("map", f"no map named {name!r} in the maps folder (available: {shown})")
        return path

    def robot_profile(self, name: str | None) -> RobotProfile:
        """The built-in profile ``name`` (None: the default), loaded once per request and handed down as is."""
        self.resolve_robot(name)
        return load_robot(name)

    def resolve_robot(self, name: str | None) -> None:
        """Raise :class:`NotFound` unless ``name`` is None or a built-in profile (no file paths)."""
        if name is not None and name not in builtin_robots():
            raise NotFound("robot", f"unknown robot {name!r}; built-in: {', '.join(builtin_robots())}")

    def submit_plan(self, request: PlanRequest) -> Future[Outcome]:
        """Check ``request`` against this service (robot, options, limits, map) and queue the plan.

        Raises :class:`NotFound`/:class:`InvalidInput` for a bad request and :class:`ServiceBusy`.
        """
        robot = self.robot_profile(request.robot)
        limit = self.settings.max_time_limit_s
        if request.time_limit_s is not None and request.time_limit_s > limit:
            raise InvalidInput("time_limit_s", f"must be ≤ {limit:g} s on this server")
        termination = Termination() if request.time_limit_s is None else Termination(request.time_limit_s)
        query = PlanQuery(request.start.as_pose(), request.goal.as_pose(),
                          PlannerOptions.from_dict(request.options or {}), termination)
        source = self._map_source(request.map)
        self._check_plan_size(query, source)
        return self._submit(plan_job, query, robot, source,
                            deadline_s=termination.time_limit_s + MAP_LOAD_ALLOWANCE_S)

    def _check_plan_size(self, query: PlanQuery, source: Path | InlineGrid) -> None:
        """What a plan request may make a worker hold, bounded before a job is queued: the states of the result
        (start–goal distance / ``options.state_spacing_m``; the worker checks again with the map's size) and, for an
        inline grid, its extent (cells × resolution) and that start and goal are no farther apart than it."""
        distance = math.dist(query.start[:2], query.goal[:2])
        if isinstance(source, InlineGrid):
            rows, cols = len(source.data), len(source.data[0])
            extent = math.hypot(rows, cols) * source.resolution_m
            cells = distance / source.resolution_m
            if extent > MAX_INLINE_EXTENT_M:
                raise InvalidInput("map.resolution_m", f"the grid spans {extent:.3g} m; this server plans on "
                                                       f"inline grids at most {MAX_INLINE_EXTENT_M:g} m across")
            if cells > math.hypot(rows, cols) * 1.01:
                raise InvalidInput("goal", f"start and goal are {distance:.3g} m apart, farther than the inline "
                                           f"grid ({extent:.3g} m across)")
        states = distance / query.options.state_spacing_m
        if states > MAX_RESULT_STATES:
            raise InvalidInput("options.state_spacing_m",
                               f"{query.options.state_spacing_m:g} m would return more than {states:.3g} states; "
                               f"this server returns at most {MAX_RESULT_STATES}")

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
        from planner.closed_loop.simulate import SimulationOptions, check_plan_fits
        from planner.closed_loop.tracker import MPCParams

        robot = self._plan_robot(request.robot, request.path, DEFAULT_ROBOT)
        source = self._map_source(request.map)
        check_plan_fits(request.path.model_dump(mode="json"), request.map if isinstance(request.map, str) else None,
                        robot,
                        allow_other_map=request.allow_other_map, allow_other_robot=request.allow_other_robot,
                        map_field="map", robot_field="robot", map_flag='"allow_other_map": true',
                        robot_flag='"allow_other_robot": true')
        options = SimulationOptions(control_rate_hz=request.rate_hz, tracker=request.tracker,
                                    mpc=MPCParams(horizon=request.horizon), time_limit_s=request.time_limit_s)
        termination, deadline = self._job_termination()
        return self._submit(simulate_job, request.path.model_dump(mode="json"), source, robot,
                            request.seed, request.noise, options, termination, deadline_s=deadline)

    def _job_termination(self) -> tuple[Termination, float]:
        """The wall-clock termination of a job without a time limit of its own (``max_job_s``; the job stops
        itself at it) and the pool's deadline, ``JOB_STOP_ALLOWANCE_S`` later (only a job that cannot stop is
        killed there)."""
        return Termination(self.settings.max_job_s), self.settings.max_job_s + JOB_STOP_ALLOWANCE_S

    def submit_reconfigure(self, request: ReconfigureIn) -> Future[Outcome]:
        """Queue a Spherobot reconfiguration (optionally checked against a map). The request itself bounds the
        radius and the goal's distance (``planner.spherobot.request.MAX_RADII`` sphere radii from the start: the
        rolled result is sampled along the way, so its size and cost grow with distance / radius)."""
        problem = ReconfigureRequest.from_dict(request.model_dump(exclude={"map"}))
        termination, deadline = self._job_termination()
        return self._submit(reconfigure_job, problem, None if request.map is None else self._map_source(request.map),
                            termination, deadline_s=deadline)

    def submit_vpip_rods(self, request: VpipRodsRequest) -> Future[Outcome]:
        """Queue one eq. 18 rod-length evaluation."""
        self.resolve_robot(request.robot)
        angles = (request.phi_vpip, request.theta_vpip, request.roll, request.pitch_phase)
        return self._submit(vpip_rods_job, *(_radians(a, request.degrees) for a in angles), request.robot)

    def submit_vpip_schedule(self, request: VpipScheduleRequest) -> Future[Outcome]:
        """Queue a 100 Hz VPIP schedule along ``request.path`` (robot: the request's, the plan's, daedalus)."""
        robot = self._plan_robot(request.robot, request.path, "daedalus")
        termination, deadline = self._job_termination()
        return self._submit(vpip_schedule_job, request.path.model_dump(mode="json"), robot, request.driver,
                            termination, deadline_s=deadline)

    def submit_tensegrity_static(self, request: TensegrityStaticRequest) -> Future[Outcome]:
        """Queue the TeXploR static-state computation."""
        self.resolve_robot(request.robot)
        return self._submit(tensegrity_static_job, _radians(request.theta1, request.degrees),
                            _radians(request.theta2, request.degrees), request.robot, request.verify)

    def submit_perceive(self, request: PerceiveRequest) -> Future[Outcome]:
        """Decode and check a stereo pair (images, calibrations, sizes, angles) and queue its perception."""
        import base64
        import binascii

        from planner.perception.camera_info import camera_info_from_dict
        from planner.perception.image_io import decode_image
        from planner.perception.mount import check_angle
        from planner.perception.obstacle_filter import ObstacleFilter
        from planner.perception.stereo import check_pair

        self.resolve_robot(request.robot)
        images = []
        for field, text in zip(PERCEIVE_FIELDS[:2], (request.left_image, request.right_image), strict=True):
            try:
                data = base64.b64decode(text, validate=True)
            except (binascii.Error, ValueError):
                raise InvalidInput(field, "is not base64 text") from None
            images.append(decode_image(data, field))
        left_info = camera_info_from_dict(request.left_info, "left_info")
        right_info = camera_info_from_dict(request.right_info, "right_info")
        check_pair(images[0], images[1], left_info, right_info, PERCEIVE_FIELDS)
        pose = request.pose.as_pose()  # yaw (rad) or yaw_deg, as every pose on the wire; degrees is roll/pitch's
        roll = check_angle(_radians(request.roll, request.degrees), "roll")
        pitch = check_angle(_radians(request.pitch, request.degrees), "pitch")
        obstacles = ObstacleFilter(min_height_m=request.min_height_m, max_height_m=request.max_height_m,
                                   max_range_m=request.max_range_m, min_blob_px=request.min_blob_px)
        return self._submit(perceive_job, images[0], images[1], left_info, right_info, pose, roll, pitch,
                            request.robot, obstacles)

    def plan(self, request: PlanRequest, timeout_s: float | None = None) -> Outcome:
        """Blocking plan: the :class:`Outcome`, with request errors and busy mapped to outcomes too. A plan
        not answered within ``timeout_s`` is cancelled (its slot freed) and answered busy."""
        try:
            future = self.submit_plan(request)
        except (ServiceBusy, SpherePlanError) as exc:
            return outcome_of_exception(exc)
        try:
            return future.result(timeout=timeout_s)
        except FuturesTimeout:
            self.cancel(future)
            return error_outcome(ServiceBusy, f"no answer within {timeout_s} s; the plan was cancelled")

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
        executor = self._executor
        workers_ready = executor.ready_workers if isinstance(executor, SupervisedPool) else self.settings.workers
        status = ("ok" if self.ready else "stopping" if self._closing else
                  "starting" if not self._ready else "degraded")
        return {"status": status, "workers_ready": workers_ready, "workers": self.settings.workers,
                "in_flight": self._in_flight, "max_in_flight": self.settings.in_flight_cap,
                "warm_up_s": round(self.warm_up_s, 3), "uptime_s": round(time.time() - self.started_at, 3)}
