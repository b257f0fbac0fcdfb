"""The transport-free planning service: one object that the HTTP app and the Zenoh node both call.

:class:`PlanningService` owns a process pool (planning is CPU-bound), warmed at start-up so the first
request does not pay for imports and compiled-code loading. Each job carries its own deadline (the
planner's time limit); at most ``max_in_flight`` jobs are queued or running, beyond that a submit
raises :class:`ServiceBusy` (HTTP 503 + Retry-After). Each capability is one method here that returns
a :class:`concurrent.futures.Future` of an :class:`Outcome`: the result JSON (bytes, exactly what the
CLI prints) and what kind of answer it is, which each transport maps onto its own status.

Bad requests are rejected in the calling process before a job is queued: unknown map or robot
(:class:`~planner.errors.NotFound`), bad planner options (:class:`~planner.errors.InvalidInput`).
Map names are looked up in a listing of the maps folder, never joined onto a path, so a request can
only reach a map file that is in that folder.

Worker processes cache loaded maps and (through :func:`planner.hybrid_astar.plan.plan_path`) Hybrid A*
planners per (map, robot, options), so repeated queries on a map skip the distance transform.
"""

from __future__ import annotations

import hashlib
import io
import logging
import math
import multiprocessing
import os
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from concurrent.futures import TimeoutError as FuturesTimeout
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from planner.errors import InvalidInput, NotFound, PlanningError, SpherePlanError
from planner.hybrid_astar.search import PlannerOptions
from planner.maps.catalogue import default_maps_dir, list_maps
from planner.maps.catalogue import map_files as map_index
from planner.maps.nav2 import MESH_SUFFIXES
from planner.occupancy import OccupancyGrid
from planner.robot import DEFAULT_ROBOT, builtin_robots, load_robot
from service.outcome import Outcome, ServiceBusy, error_outcome, ok_outcome, outcome_of_exception
from service.pipeline import execute_plan
from service.wire import (
    MAX_INLINE_CELLS,
    MAX_TIME_LIMIT_S,
    PlanIn,
    PlanRequest,
    ReconfigureRequest,
    SimulateRequest,
    TensegrityStaticRequest,
    VpipRodsRequest,
    VpipScheduleRequest,
)

log = logging.getLogger(__name__)

#: farthest reconfiguration goal, in sphere radii from the start (paper 004's examples are a few radii)
MAX_RECONFIGURE_RADII = 200


@dataclass(frozen=True)
class ServiceSettings:
    """Everything the service, the HTTP app and the Zenoh node are configured with, validated once.

    ``maps_dir`` None means the shipped maps (:func:`planner.maps.catalogue.default_maps_dir`).
    ``max_in_flight`` 0 means 4 jobs per worker. ``zenoh_listen`` is the default peer's only endpoint
    (ignored when ``zenoh_config`` names a Zenoh config file). ``max_body_bytes`` bounds HTTP bodies.
    """

    maps_dir: Path | None = None
    workers: int = 2
    max_in_flight: int = 0
    max_time_limit_s: float = MAX_TIME_LIMIT_S
    max_inline_cells: int = MAX_INLINE_CELLS
    max_body_bytes: int = 4_000_000
    retry_after_s: int = 1
    warm_up: bool = True
    zenoh: bool = True
    zenoh_config: Path | None = None
    zenoh_listen: str = "tcp/127.0.0.1:7447"

    def __post_init__(self) -> None:
        def need(ok: bool, name: str, msg: str) -> None:
            if not ok:
                raise InvalidInput(name, msg)

        need(1 <= self.workers <= 64, "workers", f"must be in [1, 64], got {self.workers}")
        need(self.max_in_flight >= 0, "max_in_flight", f"must be ≥ 0 (0 = 4 per worker), got {self.max_in_flight}")
        need(math.isfinite(self.max_time_limit_s) and 0 < self.max_time_limit_s <= MAX_TIME_LIMIT_S,
             "max_time_limit_s", f"must be in (0, {MAX_TIME_LIMIT_S:g}], got {self.max_time_limit_s}")
        need(1 <= self.max_inline_cells <= MAX_INLINE_CELLS, "max_inline_cells",
             f"must be in [1, {MAX_INLINE_CELLS}], got {self.max_inline_cells}")
        need(self.max_body_bytes >= 1024, "max_body_bytes", f"must be ≥ 1024, got {self.max_body_bytes}")
        need(self.retry_after_s >= 1, "retry_after_s", f"must be ≥ 1, got {self.retry_after_s}")
        if self.zenoh_config is not None:
            need(Path(self.zenoh_config).is_file(), "zenoh_config", f"{self.zenoh_config} is not a file")

    @property
    def in_flight_cap(self) -> int:
        return self.max_in_flight or 4 * self.workers


# ---------------------------------------------------------------------------------------- map catalogue


_GRIDS: OrderedDict[tuple[Any, ...], OccupancyGrid] = OrderedDict()
_GRID_CACHE_SIZE = 8
_GRID_LOCK = threading.Lock()


def _cached(key: tuple[Any, ...], make: Callable[[], OccupancyGrid]) -> OccupancyGrid:
    with _GRID_LOCK:
        grid = _GRIDS.get(key)
        if grid is not None:
            _GRIDS.move_to_end(key)
            return grid
    grid = make()
    with _GRID_LOCK:
        _GRIDS[key] = grid
        while len(_GRIDS) > _GRID_CACHE_SIZE:
            _GRIDS.popitem(last=False)
    return grid


def load_map_file(path: Path, robot_name: str | None) -> OccupancyGrid:
    """A map file as a grid, cached per (file, modification time[, robot for meshes])."""
    from planner.maps.load import load_any

    stat = path.stat()
    mesh = path.suffix.lower() in MESH_SUFFIXES
    key = ("file", str(path), stat.st_mtime_ns, stat.st_size, robot_name if mesh else None)
    return _cached(key, lambda: load_any(path, load_robot(robot_name) if mesh else None))


def inline_grid(spec: dict[str, Any]) -> OccupancyGrid:
    """An :class:`OccupancyGrid` from the inline-grid JSON of :class:`service.wire.InlineGrid` (cached
    by content, so repeated inline requests reuse the planner built for it)."""
    data = np.asarray(spec["data"], dtype=np.int8)
    origin = tuple(float(v) for v in spec["origin"])
    digest = hashlib.sha1(data.tobytes()).hexdigest()
    key = ("inline", digest, data.shape, float(spec["resolution_m"]), origin, spec["name"])
    return _cached(key, lambda: OccupancyGrid(data=data, resolution_m=float(spec["resolution_m"]),
                                              origin=origin, name=str(spec["name"])))  # type: ignore[arg-type]


def grid_png(grid: OccupancyGrid) -> bytes:
    """The grid as a greyscale PNG the way map_server images look: free white, occupied black,
    unknown grey, image row 0 at the top."""
    from PIL import Image

    data = grid.data
    pixels = np.where(data < 0, 205, 254 - (np.clip(data, 0, 100).astype(np.int32) * 254) // 100).astype(np.uint8)
    buf = io.BytesIO()
    Image.fromarray(pixels[::-1], mode="L").save(buf, format="PNG")
    return buf.getvalue()


# ------------------------------------------------------------------------------------- worker side


def _worker_init() -> None:
    """Runs once in each worker process: import the planner (and its compiled code) up front."""
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s worker %(process)d %(message)s")
    import planner.hybrid_astar.plan  # noqa: F401


def warm_up_job() -> int:
    """Plan once on a small synthetic map so that compiled code is loaded before the first request."""
    from planner.hybrid_astar.plan import plan_path

    occupied = np.zeros((50, 80), dtype=bool)
    occupied[[0, -1], :] = True
    occupied[:, [0, -1]] = True
    occupied[:15, 40] = True
    grid = OccupancyGrid.from_occupied(occupied, 0.1, name="warm-up")
    robot = load_robot(None)
    try:
        plan_path(grid, robot, (1.5, 1.0, 0.0), (6.5, 1.0, 0.0), time_limit_s=MAX_TIME_LIMIT_S)
    except PlanningError as exc:  # still warm: the compiled code ran
        log.warning("warm-up plan failed: %s", exc)
    return os.getpid()


def plan_job(request: dict[str, Any], map_path: str | None) -> Outcome:
    """Run one plan request (the JSON of a validated :class:`PlanRequest`) in a worker process.

    The same pipeline as ``sphereplan plan``: load the robot and the map, then
    :func:`service.pipeline.execute_plan`.
    """
    robot_json = None
    try:
        robot = load_robot(request.get("robot"))
        robot_json = robot.to_json()
        grid = load_map_file(Path(map_path), request.get("robot")) if map_path is not None else inline_grid(
            request["map"])
        result = execute_plan(request, grid, robot)
        return ok_outcome(result.to_json())
    except SpherePlanError as exc:
        return outcome_of_exception(exc, robot_json)
    except (ValueError, ArithmeticError) as exc:  # see _job
        log.warning("plan: computation failed for a request", exc_info=True)
        return error_outcome(InvalidInput, f"the plan computation failed for this input: {type(exc).__name__}: {exc}")
    except Exception as exc:  # a bug, not the client's fault: log it and answer 500
        log.exception("plan job failed")
        return outcome_of_exception(exc)


def simulate_job(request: dict[str, Any], map_path: str | None, robot_name: str) -> Outcome:
    """Run one simulate request in a worker: ``simulate_plan`` with the options of ``sphereplan simulate``."""
    from planner.closed_loop.simulate import SimulationOptions, simulate_plan
    from planner.closed_loop.tracker import MPCParams

    def compute() -> dict[str, Any]:
        grid = load_map_file(Path(map_path), None) if map_path is not None else inline_grid(request["map"])
        options = SimulationOptions(control_rate_hz=request["rate_hz"], tracker=request["tracker"],
                                    mpc=MPCParams(horizon=request["horizon"]), time_limit_s=request["time_limit_s"])
        return simulate_plan(grid, request["path"], load_robot(robot_name), seed=request["seed"],
                             noise=request["noise"], options=options)

    return _job("simulate", compute)


def _job(name: str, compute: Callable[[], Any]) -> Outcome:
    """Run one capability's computation: its JSON, or the error outcome.

    A ``ValueError``/``ArithmeticError`` that is not a sphereplan error means the request's numbers took
    the computation outside its domain (or produced NaN): answered as bad input (422), logged with the
    traceback so the unchecked case can be turned into a named error in ``planner/``.
    """
    try:
        return ok_outcome(compute())
    except SpherePlanError as exc:
        return outcome_of_exception(exc, plan=False)
    except (ValueError, ArithmeticError) as exc:
        log.warning("%s: computation failed for a request", name, exc_info=True)
        return error_outcome(InvalidInput, f"the {name} computation failed for this input: {type(exc).__name__}: {exc}")
    except Exception as exc:
        log.exception("%s job failed", name)
        return outcome_of_exception(exc)


def _radians(request: dict[str, Any], key: str) -> float:
    return math.radians(request[key]) if request["degrees"] else float(request[key])


def tensegrity_static_job(request: dict[str, Any]) -> Outcome:
    """``static_equilibria`` in a worker (what ``sphereplan tensegrity static`` prints)."""
    from planner.tensegrity import static_equilibria

    return _job("tensegrity", lambda: static_equilibria(
        _radians(request, "theta1"), _radians(request, "theta2"), load_robot(request["robot"]), request["verify"]))


def reconfigure_job(request: dict[str, Any], map_path: str | None) -> Outcome:
    """``plan_reconfiguration`` in a worker (what ``sphereplan reconfigure`` prints)."""
    from planner.spherobot.reconfigure import plan_reconfiguration

    def compute() -> dict[str, Any]:
        grid = None
        if map_path is not None:
            grid = load_map_file(Path(map_path), None)
        elif request["map"] is not None:
            grid = inline_grid(request["map"])
        return plan_reconfiguration({k: v for k, v in request.items() if k != "map"}, grid=grid)

    return _job("reconfigure", compute)


def vpip_rods_job(request: dict[str, Any]) -> Outcome:
    """``rods_report`` in a worker (what ``sphereplan vpip rods`` prints)."""
    from planner.vpip.api import rods_report

    return _job("vpip rods", lambda: rods_report(
        _radians(request, "phi_vpip"), _radians(request, "theta_vpip"), _radians(request, "roll"),
        _radians(request, "pitch_phase"), request["robot"]))


def vpip_schedule_job(request: dict[str, Any], robot_name: str) -> Outcome:
    """``schedule_report`` in a worker (the series ``sphereplan vpip schedule --out`` writes)."""
    from planner.vpip.api import schedule_report

    return _job("vpip schedule", lambda: schedule_report(request["path"], robot_name, request["driver"]))


# ------------------------------------------------------------------------------------------ service


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
                                   initializer=_worker_init)

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
        index = map_index(self.maps_dir)
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
        """Validate ``request`` against this service (map, robot, options, limits) and queue the plan.

        Raises :class:`NotFound`/:class:`InvalidInput` for a bad request and :class:`ServiceBusy`.
        """
        self.resolve_robot(request.robot)
        PlannerOptions.from_dict(dict(request.options or {}))
        if request.time_limit_s is not None and request.time_limit_s > self.settings.max_time_limit_s:
            raise InvalidInput("time_limit_s", f"must be ≤ {self.settings.max_time_limit_s:g} s on this server")
        options_limit = (request.options or {}).get("time_limit_s")
        if isinstance(options_limit, int | float) and options_limit > self.settings.max_time_limit_s:
            raise InvalidInput("options.time_limit_s", f"must be ≤ {self.settings.max_time_limit_s:g} s on this server")
        return self._submit(plan_job, request.request_json(), self._map_argument(request.map))

    def _map_argument(self, map_spec: str | Any) -> str | None:
        """The file of a named map (checked now), or None for an inline grid (size checked now)."""
        if isinstance(map_spec, str):
            return str(self.resolve_map(map_spec))
        cells = len(map_spec.data) * len(map_spec.data[0])
        if cells > self.settings.max_inline_cells:
            limit = self.settings.max_inline_cells
            raise InvalidInput("map.data", f"{cells} cells; this server accepts at most {limit}")
        return None

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
        robot = self._plan_robot(request.robot, request.path, DEFAULT_ROBOT)
        return self._submit(simulate_job, request.request_json(), self._map_argument(request.map), robot)

    def submit_reconfigure(self, request: ReconfigureRequest) -> Future[Outcome]:
        """Queue a Spherobot reconfiguration (optionally checked against a map). The goal may be at most
        ``MAX_RECONFIGURE_RADII`` sphere radii from the start: the rolled result is sampled along the way,
        so its size and cost grow with distance / radius."""
        from planner.spherobot.reconfigure import ROBOT

        radius = request.radius_m if request.radius_m is not None else load_robot(ROBOT).radius_m
        distance = math.dist(request.start, request.goal)
        if distance > MAX_RECONFIGURE_RADII * radius:
            raise InvalidInput("goal", f"is {distance:.3g} m from the start; this server rolls at most "
                                       f"{MAX_RECONFIGURE_RADII} sphere radii ({MAX_RECONFIGURE_RADII * radius:.3g} m)")
        map_path = None if request.map is None else self._map_argument(request.map)
        return self._submit(reconfigure_job, request.request_json(), map_path)

    def submit_vpip_rods(self, request: VpipRodsRequest) -> Future[Outcome]:
        """Queue one eq. 18 rod-length evaluation."""
        self.resolve_robot(request.robot)
        return self._submit(vpip_rods_job, request.request_json())

    def submit_vpip_schedule(self, request: VpipScheduleRequest) -> Future[Outcome]:
        """Queue a 100 Hz VPIP schedule along ``request.path`` (robot: the request's, the plan's, daedalus)."""
        robot = self._plan_robot(request.robot, request.path, "daedalus")
        return self._submit(vpip_schedule_job, request.request_json(), robot)

    def submit_tensegrity_static(self, request: TensegrityStaticRequest) -> Future[Outcome]:
        """Queue the TeXploR static-state computation."""
        self.resolve_robot(request.robot)
        return self._submit(tensegrity_static_job, request.request_json())

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
        index = map_index(self.maps_dir)
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
