"""The HTTP API: a thin FastAPI adapter over :class:`service.core.PlanningService`.

``create_app(settings)`` builds the app; its lifespan opens the warmed process pool and the Zenoh node
and closes both on shutdown. One router per resource (health, plan, simulate, reconfigure, vpip,
tensegrity, maps, robots); every job route answers through :func:`answer`. An error raised by the
service is answered as the outcome table says (:mod:`service.outcome`); the HTTP-level ones (400, 413,
415, unknown routes) here. Every error is JSON ``{error_code, error_msg, field}`` with a Nav2 code
(200 = not a planning failure):

=====  ==================================================================================
400    malformed JSON, unreadable or empty body
401    no or wrong bearer token (when the server has ``--token-file``)
404    unknown map or robot, unknown route
413    body larger than ``settings.max_body_bytes``
415    a body that is not ``application/json`` (or no ``Content-Type``)
422    wrong types, unknown fields, NaN/inf, negative or too long time limits, bad options;
       a plan that failed (start/goal outside or occupied 203–206, timeout 207, no path 208):
       the body is then the failed-result JSON (``status: failed``) the CLI prints
503    the pool is full (``Retry-After`` header), too many large bodies waiting to be parsed, the service is
       not ready or shutting down, or the worker under the job died or hung (``Retry-After``)
=====  ==================================================================================

Nothing a client sends produces a 5xx; a server fault is a 503, a 500 means a bug and is logged with its
traceback. Bodies are read by :func:`json_body`: a large one is parsed in a parse process (:mod:`service.limits`).
"""

from __future__ import annotations

import asyncio
import hmac
import logging
from collections.abc import AsyncIterator, Callable
from concurrent.futures import Future
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Annotated, Any, TypeVar

from fastapi import APIRouter, Depends, FastAPI, Request
from fastapi import Path as PathParam
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response
from pydantic import BaseModel
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from service.core import PlanningService
from service.limits import SMALL_BODY_BYTES, MalformedBody, ParseGate, parse_json_model
from service.outcome import ANSWERS, Outcome, error_body, outcome_of_exception
from service.settings import ServiceSettings
from service.wire import (
    NAME_PATTERN,
    ErrorBody,
    Health,
    MapInfo,
    PerceiveRequest,
    PlanRequest,
    PlanResultOut,
    ReconfigureIn,
    RobotInfo,
    SimulateRequest,
    TensegrityStaticRequest,
    VpipRodsRequest,
    VpipScheduleRequest,
    invalid_input,
)

log = logging.getLogger(__name__)

JSON = "application/json"
M = TypeVar("M", bound=BaseModel)


def _error(status: int, msg: str, field: str | None = None, headers: dict[str, str] | None = None) -> JSONResponse:
    """An HTTP-level error (malformed body, unknown route, ...) with the service's error body."""
    return JSONResponse(error_body(msg, field), status, headers)


def outcome_response(outcome: Outcome, retry_after_s: int = 1) -> Response:
    """An :class:`Outcome` as an HTTP response with its row's status; the body bytes are sent as they are."""
    headers = {"Retry-After": str(retry_after_s)} if outcome.kind in ("busy", "unavailable") else None
    return Response(outcome.body, outcome.answer.http_status, headers, media_type=JSON)


#: how often a route waiting for its job checks whether the client is still there (s)
DISCONNECT_POLL_S = 0.2


async def answer(request: Request, service: PlanningService, submit: Callable[[M], Future[Outcome]],
                 body: M) -> Response:
    """What every job route does: queue ``body`` with ``submit`` (off the event loop: it checks the request
    and may list the maps folder), wait for the job without blocking the loop, answer its outcome.

    A client that disconnects while waiting cancels its job (its slot is freed at once); so does the
    server cancelling the request task."""
    future = await asyncio.to_thread(submit, body)
    waiter = asyncio.shield(asyncio.wrap_future(future))
    try:
        while True:
            done, _ = await asyncio.wait({waiter}, timeout=DISCONNECT_POLL_S)
            if done:
                break
            if await request.is_disconnected():
                log.info("client gone: cancelling its %s job", request.url.path)
                service.cancel(future)
                break
    except asyncio.CancelledError:
        service.cancel(future)
        raise
    return outcome_response(await waiter, service.settings.retry_after_s)


class BodyRefused(Exception):
    """An HTTP-level refusal of a body (415 not JSON, 400 empty or malformed), answered with the error JSON."""

    def __init__(self, status: int, msg: str, field: str) -> None:
        super().__init__(msg)
        self.status, self.msg, self.field = status, msg, field


def json_body(model: type[M]) -> Callable[[Request], Any]:
    """A dependency that reads the request body as ``model`` (documented in OpenAPI by :func:`body_doc`).

    The body is bounded by :class:`BodyLimit`; a small one is parsed on the event loop, a large one (an inline
    map) in the parse pool of :mod:`service.limits` (at most ``PARSE_CONCURRENCY`` at once, further ones wait,
    beyond ``MAX_PENDING_PARSES`` 503), so health probes and small requests never wait behind big bodies."""

    async def read(request: Request) -> Any:
        content_type = request.headers.get("content-type", "").split(";")[0].strip().lower()
        if not (content_type == JSON or content_type.endswith("+json")):
            got = repr(content_type) if content_type else "none"
            raise BodyRefused(415, f"Content-Type must be {JSON}, got {got}", "content-type")
        raw = await request.body()
        limit = get_service(request).settings.max_body_bytes
        try:
            if len(raw) <= SMALL_BODY_BYTES:
                return parse_json_model(model, raw, limit)
            gate: ParseGate = request.app.state.parse_gate
            return await asyncio.wrap_future(gate.submit(model, raw, limit))
        except MalformedBody as exc:
            raise BodyRefused(400, exc.msg, exc.field) from None

    read.__name__ = f"{model.__name__}_body"
    return read


#: the request models documented through :func:`body_doc` (added to the OpenAPI components by create_app)
_BODY_MODELS: list[type[BaseModel]] = []


def body_doc(model: type[BaseModel]) -> dict[str, Any]:
    """The OpenAPI ``requestBody`` of a route that reads ``model`` with :func:`json_body`."""
    _BODY_MODELS.append(model)
    return {"requestBody": {"required": True, "content": {JSON: {"schema": {
        "$ref": f"#/components/schemas/{model.__name__}"}}}}}


def _openapi_with_bodies(app: FastAPI) -> Callable[[], dict[str, Any]]:
    from pydantic.json_schema import models_json_schema

    build = app.openapi

    def openapi() -> dict[str, Any]:
        if app.openapi_schema is None:
            schema = build()
            _, defs = models_json_schema([(m, "validation") for m in dict.fromkeys(_BODY_MODELS)],
                                         ref_template="#/components/schemas/{model}")
            components = schema.setdefault("components", {}).setdefault("schemas", {})
            for name, definition in defs.get("$defs", {}).items():
                components.setdefault(name, definition)
            app.openapi_schema = schema
        return app.openapi_schema

    return openapi


class BodyLimit:
    """ASGI middleware: answer 413 when a request body exceeds ``limit`` bytes (declared or streamed)."""

    def __init__(self, app: ASGIApp, limit: int) -> None:
        self.app = app
        self.limit = limit

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = dict(scope.get("headers") or [])
        declared = headers.get(b"content-length")
        if declared is not None:
            if not declared.isdigit():
                await _error(400, "Content-Length is not a number", "content-length")(scope, receive, send)
                return
            if int(declared) > self.limit:
                await self._too_large(scope, receive, send)
                return
        received = 0
        started = False

        async def limited_receive() -> Message:
            nonlocal received
            message = await receive()
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > self.limit:
                    raise _TooLarge(self.limit)
            return message

        async def tracking_send(message: Message) -> None:
            nonlocal started
            started = started or message["type"] == "http.response.start"
            await send(message)

        try:
            await self.app(scope, limited_receive, tracking_send)
        except _TooLarge:
            if not started:
                await self._too_large(scope, receive, send)

    async def _too_large(self, scope: Scope, receive: Receive, send: Send) -> None:
        await _error(413, f"request body larger than {self.limit} bytes", "body")(scope, receive, send)


class BearerToken:
    """ASGI middleware: every route but the health probes needs ``Authorization: Bearer <token>`` (401)."""

    OPEN = frozenset({"/healthz", "/readyz"})

    def __init__(self, app: ASGIApp, token: str) -> None:
        self.app = app
        self.expected = f"Bearer {token}".encode()

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope.get("path") in self.OPEN:
            await self.app(scope, receive, send)
            return
        given = dict(scope.get("headers") or []).get(b"authorization", b"")
        if not hmac.compare_digest(given, self.expected):
            await _error(401, "a valid 'Authorization: Bearer <token>' header is required", "authorization",
                         {"WWW-Authenticate": "Bearer"})(scope, receive, send)
            return
        await self.app(scope, receive, send)


class _TooLarge(StarletteHTTPException):
    def __init__(self, limit: int) -> None:
        super().__init__(413, f"request body larger than {limit} bytes")


# -------------------------------------------------------------------------------------------- routers


def get_service(request: Request) -> PlanningService:
    service: PlanningService = request.app.state.service
    return service


Service = Annotated[PlanningService, Depends(get_service)]


# request bodies, read by json_body (off the event loop when large)
PlanBody = Annotated[PlanRequest, Depends(json_body(PlanRequest))]
SimulateBody = Annotated[SimulateRequest, Depends(json_body(SimulateRequest))]
ReconfigureBody = Annotated[ReconfigureIn, Depends(json_body(ReconfigureIn))]
VpipRodsBody = Annotated[VpipRodsRequest, Depends(json_body(VpipRodsRequest))]
VpipScheduleBody = Annotated[VpipScheduleRequest, Depends(json_body(VpipScheduleRequest))]
TensegrityStaticBody = Annotated[TensegrityStaticRequest, Depends(json_body(TensegrityStaticRequest))]
PerceiveBody = Annotated[PerceiveRequest, Depends(json_body(PerceiveRequest))]
MapName = Annotated[str, PathParam(pattern=NAME_PATTERN, description="a map in the maps folder")]
ERRORS: dict[int | str, dict[str, Any]] = {
    code: {"model": ErrorBody, "description": text} for code, text in
    ((400, "malformed request"), (401, "bearer token missing or wrong (servers with --token-file)"),
     (404, "unknown map or robot"), (413, "body too large"),
     (415, "body is not JSON"),
     (422, "invalid request or failed plan"), (503, "busy: retry after Retry-After seconds"))
}

health = APIRouter(tags=["health"])


@health.get("/healthz", response_model=Health)
async def healthz(service: Service) -> dict[str, Any]:
    """Liveness: answers as long as the event loop runs (planning happens in other processes)."""
    return service.health()


@health.get("/readyz", response_model=Health, responses={503: {"model": ErrorBody}})
async def readyz(service: Service) -> Any:
    """Readiness: 200 once the worker pool is warmed, 503 before and during shutdown."""
    if not service.ready:
        return _error(503, "the planner is starting or stopping", headers={"Retry-After": "1"})
    return service.health()


plan = APIRouter(prefix="/v1", tags=["plan"])


@plan.post("/plan", response_model=PlanResultOut, responses=ERRORS, openapi_extra=body_doc(PlanRequest))
async def post_plan(request: Request, body: PlanBody, service: Service) -> Response:
    """Plan a rollable path from ``start`` to ``goal`` on a named map (or an inline grid, at most
    ``max_inline_cells`` cells). Answers the plan result JSON — the same object ``sphereplan plan``
    prints. A failed plan answers 422 with the failed-result JSON and its Nav2 code."""
    return await answer(request, service, service.submit_plan, body)


simulate = APIRouter(prefix="/v1", tags=["simulate"])


@simulate.post("/simulate", responses=ERRORS, openapi_extra=body_doc(SimulateRequest))
async def post_simulate(request: Request, body: SimulateBody, service: Service) -> Response:
    """Roll a plan (the result of ``/v1/plan``) in closed loop on a map: simulator, odometry/GNSS fusion
    and the MPC tracker of paper 001. Answers the SIM.json object ``sphereplan simulate`` writes
    (``trajectory``, ``estimate``, ``odometry``, ``gnss``, ``commands``, ``metrics``)."""
    return await answer(request, service, service.submit_simulate, body)


reconfigure = APIRouter(prefix="/v1", tags=["reconfigure"])


@reconfigure.post("/reconfigure", responses=ERRORS, openapi_extra=body_doc(ReconfigureIn))
async def post_reconfigure(request: Request, body: ReconfigureBody, service: Service) -> Response:
    """Spherobot reconfiguration (paper 004): reach ``goal`` with the camera point P on top (and, with
    ``goal_heading``, a heading), proved by rolling the sphere through SO(3). What ``sphereplan
    reconfigure`` prints; with ``map`` the swept sphere is checked against it (failures 203–206, 208)."""
    return await answer(request, service, service.submit_reconfigure, body)


vpip = APIRouter(prefix="/v1/vpip", tags=["vpip"])


@vpip.post("/rods", responses=ERRORS, openapi_extra=body_doc(VpipRodsRequest))
async def post_vpip_rods(request: Request, body: VpipRodsBody, service: Service) -> Response:
    """Eq. 18 length of every rod of a rod-driven sphere (paper 000) for one VPIP plane, roll and pitch
    phase: what ``sphereplan vpip rods`` prints."""
    return await answer(request, service, service.submit_vpip_rods, body)


@vpip.post("/schedule", responses=ERRORS, openapi_extra=body_doc(VpipScheduleRequest))
async def post_vpip_schedule(request: Request, body: VpipScheduleBody, service: Service) -> Response:
    """The 100 Hz VPIP cascade along a plan: plane angles and rod lengths per tick, the series
    ``sphereplan vpip schedule --out`` writes."""
    return await answer(request, service, service.submit_vpip_schedule, body)


tensegrity = APIRouter(prefix="/v1/tensegrity", tags=["tensegrity"])


@tensegrity.post("/static", responses=ERRORS, openapi_extra=body_doc(TensegrityStaticRequest))
async def post_tensegrity_static(request: Request, body: TensegrityStaticBody, service: Service) -> Response:
    """The four hybrid static states of the TeXploR two-arc robot (paper 002) for slider angles θ1, θ2:
    what ``sphereplan tensegrity static`` prints."""
    return await answer(request, service, service.submit_tensegrity_static, body)


perception = APIRouter(prefix="/v1", tags=["perception"])


@perception.post("/perceive", responses=ERRORS, openapi_extra=body_doc(PerceiveRequest))
async def post_perceive(request: Request, body: PerceiveBody, service: Service) -> Response:
    """Stereo obstacle perception (paper 001 §3.2): base64 images and camera_info documents of a pair, the
    sphere's pose and roll → the kept obstacle points in the map frame (``points_map``, N × 3, m) and the sensor
    origin (``origin_map``): what ``sphereplan perceive`` prints."""
    return await answer(request, service, service.submit_perceive, body)


maps = APIRouter(prefix="/v1", tags=["maps"])


@maps.get("/maps", response_model=list[MapInfo])
async def get_maps(service: Service) -> list[dict[str, Any]]:
    """The maps in the maps folder (the names ``map`` may take)."""
    return await asyncio.to_thread(service.maps)


@maps.get("/maps/{name}.png", response_class=Response, responses={200: {"content": {"image/png": {}}}, **ERRORS})
async def get_map_png(name: MapName, service: Service) -> Response:
    """The map as a greyscale PNG (free white, occupied black, unknown grey; north up)."""
    png = await asyncio.to_thread(service.map_png, name)
    return Response(png, media_type="image/png")


@maps.get("/maps/{name}", response_model=MapInfo, responses=ERRORS)
async def get_map(name: MapName, service: Service) -> dict[str, Any]:
    """Metadata of one map: size in cells and metres, resolution, origin, blocked fraction."""
    return await asyncio.to_thread(service.map_info, name)


robots = APIRouter(prefix="/v1", tags=["robots"])


@robots.get("/robots", response_model=list[RobotInfo])
async def get_robots(service: Service) -> list[dict[str, Any]]:
    """The built-in robot profiles (the names ``robot`` may take)."""
    return service.robots()


viewer = APIRouter(tags=["viewer"])
VIEWER_DIR = Path(__file__).with_name("viewer")
#: the viewer's files and their media types: everything the page loads comes from here (no CDN)
VIEWER_FILES = {"index.html": "text/html; charset=utf-8", "viewer.js": "text/javascript; charset=utf-8",
                "viewer.css": "text/css; charset=utf-8"}


def _viewer_file(name: str) -> Response:
    media_type = VIEWER_FILES.get(name)
    if media_type is None:
        return _error(404, f"no viewer file {name!r}", "path")
    return Response((VIEWER_DIR / name).read_bytes(), media_type=media_type, headers={"Cache-Control": "no-cache"})


@viewer.get("/", response_class=Response, include_in_schema=False)
async def get_viewer() -> Response:
    """The browser viewer (docs/ros2.md): pick a map and robot, set start and goal, plan, simulate, reconfigure."""
    return _viewer_file("index.html")


@viewer.get("/viewer/{name}", response_class=Response, include_in_schema=False)
async def get_viewer_file(name: str) -> Response:
    return _viewer_file(name)


# ----------------------------------------------------------------------------------------------- app


def install_error_handlers(app: FastAPI) -> None:
    @app.exception_handler(RequestValidationError)
    async def invalid(request: Request, exc: RequestValidationError) -> JSONResponse:
        errors = list(exc.errors())
        content_type = request.headers.get("content-type", "").split(";")[0].strip().lower()
        about_body = any(tuple(e.get("loc", ()))[:1] == ("body",) for e in errors)
        if about_body and not (content_type == JSON or content_type.endswith("+json")):
            got = repr(content_type) if content_type else "none"
            return _error(415, f"Content-Type must be {JSON}, got {got}", "content-type")
        error = invalid_input(errors)
        # an unparsable body, or none at all where a JSON object is required
        malformed = any(e.get("type") == "json_invalid" or (e.get("type") == "missing" and tuple(e.get("loc", ())) ==
                                                            ("body",)) for e in errors)
        return _error(400 if malformed else 422, str(error), error.field)

    @app.exception_handler(BodyRefused)
    async def body_refused(request: Request, exc: BodyRefused) -> JSONResponse:
        return _error(exc.status, exc.msg, exc.field)

    @app.exception_handler(StarletteHTTPException)
    async def http_error(request: Request, exc: StarletteHTTPException) -> JSONResponse:
        return _error(exc.status_code, str(exc.detail), headers=getattr(exc, "headers", None))

    async def refused(request: Request, exc: Exception) -> Response:
        outcome = outcome_of_exception(exc)
        if outcome.kind == "internal":
            log.error("unhandled error on %s %s", request.method, request.url.path, exc_info=exc)
        return outcome_response(outcome, get_service(request).settings.retry_after_s)

    # one handler for every row of the outcome table; the catch-all row is Starlette's last resort (Exception)
    for error in ANSWERS:
        app.add_exception_handler(error if issubclass(error, Exception) else Exception, refused)


def create_app(settings: ServiceSettings | None = None, service: PlanningService | None = None) -> FastAPI:
    """The HTTP app. Its lifespan starts ``service`` (default: a new :class:`PlanningService` on
    ``settings``) and, if ``settings.zenoh``, the Zenoh node; both are closed on shutdown."""
    settings = settings or (service.settings if service else ServiceSettings())
    svc = service or PlanningService(settings)

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        node = None
        await asyncio.to_thread(app.state.parse_gate.warm)
        live = None
        await asyncio.to_thread(svc.start)
        try:
            if settings.zenoh:
                from service.zenoh_live import start_live_doors
                from service.zenoh_node import ZenohNode

                node = ZenohNode(svc, settings, parse_gate=app.state.parse_gate)
                await asyncio.to_thread(node.start)
                live = await asyncio.to_thread(start_live_doors, svc, app.state.sessions, node, settings)
            log.info("sphereplan service ready (%d workers, warm-up %.1f s)", settings.workers, svc.warm_up_s)
            yield
        finally:
            app.state.sessions.close()
            for door in live or []:
                await asyncio.to_thread(door.close)
            if node is not None:
                await asyncio.to_thread(node.close)
            await asyncio.to_thread(svc.close)
            app.state.parse_gate.close()

    app = FastAPI(
        title="sphereplan",
        version="0.1.0",
        summary="Motion planning for spherical rolling robots",
        description="Plans paths a spherical robot can roll (spherical Hybrid A*). The same request and "
                    "result JSON as the `sphereplan` CLI and the Zenoh node.",
        lifespan=lifespan,
        redirect_slashes=False,  # /v1/plan/ is an unknown route (404), not a redirect built from the Host header
    )
    app.state.service = svc
    app.state.parse_gate = ParseGate(retry_after_s=settings.retry_after_s)
    from service.http_sessions import router as sessions
    from service.sessions import SessionStore

    app.state.sessions = SessionStore()
    app.include_router(health)
    app.include_router(plan)
    app.include_router(simulate)
    app.include_router(reconfigure)
    app.include_router(vpip)
    app.include_router(tensegrity)
    app.include_router(perception)
    app.include_router(maps)
    app.include_router(robots)
    app.include_router(viewer)
    app.include_router(sessions)
    install_error_handlers(app)
    app.openapi = _openapi_with_bodies(app)  # type: ignore[method-assign]
    app.add_middleware(BodyLimit, limit=settings.max_body_bytes)
    if settings.http_token is not None:
        app.add_middleware(BearerToken, token=settings.http_token)  # outermost: checked before the body is read
    return app
