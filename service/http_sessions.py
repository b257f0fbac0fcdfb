"""HTTP door of robot sessions: the ``/v1/sessions`` resource over :class:`service.sessions.SessionStore`.

=========================================  ====================================================================
``POST /v1/sessions``                      create (map or unknown area, start, optional goal) → 201 session
``GET /v1/sessions/{id}``                  status: pose, goal, path length, last replan, known fraction
``DELETE /v1/sessions/{id}``               end it (204)
``POST /v1/sessions/{id}/pose``            the robot's pose (odometry) → status, and a replan on the timer
``POST /v1/sessions/{id}/goal``            a new goal → the replan and the path
``POST /v1/sessions/{id}/observations``    points, a scan or a region → the map update, and the replan if the
                                           path was blocked
``GET /v1/sessions/{id}/path``             the current path (plan-result JSON); 422 with the failure when none
``GET /v1/sessions/{id}/map``              the live map as ``nav_msgs/OccupancyGrid`` JSON (``.png``: a picture)
``GET /v1/sessions/{id}/events``           Server-Sent Events: ``replan`` (with the new path), ``map`` (the
                                           changed rectangle), ``closed``; ``?max_events=N`` ends after N
=========================================  ====================================================================

Planning happens in a thread of the server process (a session's planner stays warm between replans), never on
the event loop. Errors are answered through the outcome table like every other route.
"""

from __future__ import annotations

import asyncio
import json
import math
import queue
from collections.abc import AsyncIterator
from typing import Annotated, Any

import numpy as np
from fastapi import APIRouter, Depends, Query, Request
from fastapi import Path as PathParam
from fastapi.responses import JSONResponse, Response, StreamingResponse

from planner.errors import InvalidInput, NoValidPathFound
from planner.live import ObstacleLayerParams, ReplanEvent, live_options
from planner.occupancy import UNKNOWN, OccupancyGrid
from service.core import PlanningService
from service.outcome import outcome_of_exception
from service.sessions import Entry, SessionStore, map_json, path_json
from service.wire import NAME_PATTERN, ErrorBody, InlineGrid, PoseIn, RosOccupancyGrid
from service.wire_live import ObservationIn, SessionCreate

#: the error statuses of the session routes (as service.http documents its own; not imported: http imports this)
SESSION_ERRORS: dict[int | str, dict[str, Any]] = {
    code: {"model": ErrorBody, "description": text} for code, text in
    ((400, "malformed request"), (401, "bearer token missing or wrong (servers with --token-file)"),
     (404, "unknown session, map or robot"), (413, "body too large"), (415, "body is not JSON"),
     (422, "invalid request, or no path"), (429, "updates too fast for the session: retry after Retry-After s"),
     (503, "too many sessions: retry after Retry-After seconds"))
}
router = APIRouter(prefix="/v1/sessions", tags=["sessions"], responses=SESSION_ERRORS)

SessionId = Annotated[str, PathParam(pattern=NAME_PATTERN, description="the session's id")]
SSE_POLL_S = 0.1
SSE_HEARTBEAT_S = 15.0


def get_store(request: Request) -> SessionStore:
    store: SessionStore = request.app.state.sessions
    return store


def get_service(request: Request) -> PlanningService:
    service: PlanningService = request.app.state.service
    return service


Store = Annotated[SessionStore, Depends(get_store)]
Service = Annotated[PlanningService, Depends(get_service)]


def client_of(request: Request) -> str:
    """Who a request comes from, for the per-client session limit."""
    return request.client.host if request.client is not None else "unknown"


def session_grid(service: PlanningService, body: SessionCreate, robot: Any,
                 max_cells: int) -> tuple[OccupancyGrid, str]:
    """The grid a new session starts from: a named map, an inline grid, a ROS grid, or an unknown area."""
    from service.grids import inline_grid, load_map_file

    spec = body.map
    if isinstance(spec, str):
        return load_map_file(service.resolve_map(spec), robot), spec
    if isinstance(spec, RosOccupancyGrid):
        spec = spec.as_inline()
    if isinstance(spec, InlineGrid):
        return inline_grid(spec), spec.name
    area = body.unknown
    assert area is not None
    w, h = math.ceil(area.width_m / area.resolution_m), math.ceil(area.height_m / area.resolution_m)
    if w * h > max_cells:
        raise InvalidInput("unknown.resolution_m", f"{w}×{h} cells; a session's map may have at most {max_cells}")
    x, y, yaw = area.origin
    data = np.full((h, w), UNKNOWN, dtype=np.int8)
    return OccupancyGrid(data, area.resolution_m, (x, y, yaw), name="unknown"), "unknown"


def session_body(entry: Entry, event: ReplanEvent | None = None, **extra: Any) -> dict[str, Any]:
    body: dict[str, Any] = {"id": entry.id, "map": entry.name, "robot": entry.session.robot.name,
                            "status": entry.session.status(), **extra}
    body["replan"] = None if event is None else event.to_json()
    if event is not None:
        body["path"] = path_json(entry)
    return body


@router.post("", status_code=201)
async def create_session(request: Request, body: SessionCreate, service: Service, store: Store) -> JSONResponse:
    """Create a robot session; with a goal it plans at once (the response carries the path)."""

    def work() -> dict[str, Any]:
        robot = service.robot_profile(body.robot)
        grid, name = session_grid(service, body, robot, store.limits.max_cells)
        options = live_options(body.options)
        policy = body.policy()
        base = ObstacleLayerParams.for_robot(robot)
        layer = body.layer.params(base) if body.layer is not None else base
        entry, event = store.create(client_of(request), grid, robot, body.start.as_pose(),
                                    None if body.goal is None else body.goal.as_pose(), options, policy, layer,
                                    name, body.id)
        return session_body(entry, event)

    return JSONResponse(await asyncio.to_thread(work), 201)


@router.get("/{sid}")
async def get_session(sid: SessionId, store: Store) -> dict[str, Any]:
    """The session's status."""
    return session_body(store.get(sid))


@router.delete("/{sid}", status_code=204)
async def delete_session(sid: SessionId, store: Store) -> Response:
    """End the session."""
    store.delete(sid)
    return Response(status_code=204)


@router.post("/{sid}/pose")
async def post_pose(sid: SessionId, body: PoseIn, store: Store) -> dict[str, Any]:
    """The robot's current pose (map frame); replans when the session's timer says so."""
    event = await asyncio.to_thread(store.pose, sid, body.as_pose())
    return session_body(store.get(sid), event)


@router.post("/{sid}/goal")
async def post_goal(sid: SessionId, body: PoseIn, store: Store) -> dict[str, Any]:
    """A new goal: planned from the current pose at once."""
    event = await asyncio.to_thread(store.goal, sid, body.as_pose())
    return session_body(store.get(sid), event)


@router.post("/{sid}/observations")
async def post_observation(sid: SessionId, body: ObservationIn, store: Store) -> dict[str, Any]:
    """Points, a laser scan or a map region; the path is replanned when the update blocks it."""
    observation = body.value()
    update, event = await asyncio.to_thread(store.observe, sid, observation)
    return session_body(store.get(sid), event, update=update)


@router.get("/{sid}/path")
async def get_path(sid: SessionId, store: Store) -> Response:
    """The current path (plan-result JSON); 422 with the last failure when there is none."""
    entry = store.get(sid)
    path = path_json(entry)
    if path is None:
        failure = entry.session.last_failure
        msg = failure.error_msg if failure is not None else "the session has no goal yet"
        exc = NoValidPathFound(msg)
        if failure is not None:
            exc.code = failure.error_code
        outcome = outcome_of_exception(exc, entry.session.robot.to_json())
        return Response(outcome.body, outcome.answer.http_status, media_type="application/json")
    return Response(json.dumps(path, allow_nan=False).encode(), media_type="application/json")


@router.get("/{sid}/map")
async def get_session_map(sid: SessionId, store: Store) -> Response:
    """The live map as ``nav_msgs/OccupancyGrid`` JSON."""
    entry = store.get(sid)
    body = await asyncio.to_thread(lambda: json.dumps(map_json(entry)).encode())
    return Response(body, media_type="application/json")


@router.get("/{sid}/map.png", response_class=Response, responses={200: {"content": {"image/png": {}}}})
async def get_session_map_png(sid: SessionId, store: Store) -> Response:
    """The live map as a PNG (free white, occupied black, unknown grey, north up)."""
    from service.grids import grid_png

    entry = store.get(sid)
    png = await asyncio.to_thread(grid_png, entry.session.map.snapshot())
    return Response(png, media_type="image/png")


# not in the OpenAPI schema: an event stream has no response schema, and it runs until the session ends
@router.get("/{sid}/events", include_in_schema=False)
async def get_events(request: Request, sid: SessionId, store: Store,
                     max_events: Annotated[int | None, Query(ge=1, le=100_000)] = None) -> StreamingResponse:
    """Server-Sent Events of the session: ``replan`` (the event, the new path, the status), ``map`` (an update's
    changed rectangle) and ``closed``; a comment every 15 s keeps the connection open."""
    q = store.subscribe(sid)

    async def stream() -> AsyncIterator[bytes]:
        sent = 0
        idle = 0.0
        try:
            yield b": sphereplan session events\n\n"
            while max_events is None or sent < max_events:
                try:
                    item = q.get_nowait()
                except queue.Empty:
                    if await request.is_disconnected():
                        return
                    await asyncio.sleep(SSE_POLL_S)
                    idle += SSE_POLL_S
                    if idle >= SSE_HEARTBEAT_S:
                        idle = 0.0
                        yield b": keep-alive\n\n"
                    continue
                idle = 0.0
                sent += 1
                data = json.dumps(item["data"], allow_nan=False, separators=(",", ":"))
                yield f"event: {item['event']}\ndata: {data}\n\n".encode()
                if item["event"] == "closed":
                    return
        finally:
            store.unsubscribe(sid, q)

    return StreamingResponse(stream(), media_type="text/event-stream",
                             headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"})
