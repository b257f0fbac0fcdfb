"""How every door answers: one table from an error's type to its kind, CLI exit code, HTTP status and Zenoh reply.

The CLI, the HTTP app and the Zenoh node look an error up in :data:`ANSWERS` (along the error's class
hierarchy, so the most specific row wins) and answer as its row says; nothing else maps errors to
statuses. A start or goal outside the map or occupied (:class:`~planner.errors.BadEndpoint`) is bad input
by its type: exit 2 like any other bad input, though its body is still the failed-result JSON with the
Nav2 code. Every service answer is an :class:`Outcome`: the JSON body (bytes, exactly what the CLI
prints) and the row it is answered by. Kept free of pydantic and the web stack so that the CLI's cold
start stays short.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, Literal

from planner.errors import BadEndpoint, NotFound, PlannerTimedOut, PlanningError, SpherePlanError

#: Nav2 ComputePathToPose UNKNOWN: the code of every error that is not a planning failure
UNKNOWN_ERROR_CODE = 200

EXIT_OK = 0
#: not the input's fault: a bug (Python exits 1 on the traceback the CLI lets through) or a busy service
EXIT_FAULT = 1
EXIT_BAD_INPUT = 2
EXIT_NO_SOLUTION = 3
EXIT_TIMEOUT = 4

Kind = Literal["ok", "bad_input", "not_found", "failed", "busy", "unavailable", "unauthorized", "internal"]


class ServiceBusy(Exception):
    """Too many jobs in flight; retry after ``retry_after_s`` seconds."""

    def __init__(self, in_flight: int, retry_after_s: int) -> None:
        super().__init__(f"the planner is busy ({in_flight} jobs in flight); retry in {retry_after_s} s")
        self.retry_after_s = retry_after_s


class WorkerLost(Exception):
    """A server fault, not the request's: the worker process running the job died, or hung and was killed
    (answered 503 with ``Retry-After``; the request may be sent again)."""


class Unauthorized(Exception):
    """No or wrong credentials (the bearer token on HTTP, the token attachment on Zenoh)."""

    field = "authorization"


class RateLimited(ServiceBusy):
    """One client sent updates (a robot session's observations) faster than allowed; retry after
    ``retry_after_s`` seconds."""

    def __init__(self, msg: str, retry_after_s: int = 1) -> None:
        Exception.__init__(self, msg)
        self.retry_after_s = retry_after_s


@dataclass(frozen=True)
class Answer:
    """One row of the table: what kind of answer an error is and how each door gives it.

    ``cli_label`` starts the CLI's stderr line (``sphereplan VERB: LABEL: message``).
    """

    kind: Kind
    exit_code: int
    cli_label: str
    http_status: int
    zenoh_reply: Literal["reply", "reply_err"]


OK = Answer("ok", EXIT_OK, "", 200, "reply")

#: error type → answer; :func:`answer_for` walks an error's class hierarchy, so the most specific row wins
ANSWERS: dict[type[BaseException], Answer] = {
    BadEndpoint: Answer("bad_input", EXIT_BAD_INPUT, "error", 422, "reply_err"),
    PlannerTimedOut: Answer("failed", EXIT_TIMEOUT, "timeout", 422, "reply_err"),
    PlanningError: Answer("failed", EXIT_NO_SOLUTION, "no path", 422, "reply_err"),
    NotFound: Answer("not_found", EXIT_BAD_INPUT, "error", 404, "reply_err"),
    SpherePlanError: Answer("bad_input", EXIT_BAD_INPUT, "error", 422, "reply_err"),
    RateLimited: Answer("busy", EXIT_FAULT, "busy", 429, "reply_err"),
    ServiceBusy: Answer("busy", EXIT_FAULT, "busy", 503, "reply_err"),
    WorkerLost: Answer("unavailable", EXIT_FAULT, "unavailable", 503, "reply_err"),
    Unauthorized: Answer("unauthorized", EXIT_BAD_INPUT, "error", 401, "reply_err"),
    BaseException: Answer("internal", EXIT_FAULT, "internal error", 500, "reply_err"),
}


def answer_for(error: BaseException | type[BaseException]) -> Answer:
    """The row of ``error`` (an exception or its type)."""
    cls = error if isinstance(error, type) else type(error)
    return next(ANSWERS[base] for base in cls.__mro__ if base in ANSWERS)


@dataclass(frozen=True)
class Outcome:
    """The answer to one request: ``body`` is the JSON (UTF-8 bytes) every transport sends unchanged,
    ``answer`` the table row it is given by, ``error_code`` the Nav2 code of a failure (0 on success)."""

    answer: Answer
    body: bytes
    error_code: int = 0

    @property
    def kind(self) -> Kind:
        return self.answer.kind

    @property
    def ok(self) -> bool:
        return self.answer.kind == "ok"

    def json(self) -> Any:
        return json.loads(self.body)


def dumps(data: Any) -> bytes:
    """Compact JSON bytes (NaN and infinities refused)."""
    return json.dumps(data, allow_nan=False, separators=(",", ":")).encode()


def ok_outcome(data: Any) -> Outcome:
    """A success: ``data`` as the JSON body."""
    return Outcome(OK, dumps(data))


def error_body(msg: str, field: str | None = None, code: int = UNKNOWN_ERROR_CODE) -> dict[str, Any]:
    """The body of every error that is not a planning failure: ``{error_code, error_msg, field}``."""
    return {"error_code": code, "error_msg": msg, "field": field}


def error_outcome(error: type[BaseException], msg: str, field: str | None = None,
                  code: int = UNKNOWN_ERROR_CODE) -> Outcome:
    """An :func:`error_body` answered as the row of ``error`` says."""
    return Outcome(answer_for(error), dumps(error_body(msg, field, code)), code)


def outcome_of_exception(exc: BaseException, plan_robot: Any = None) -> Outcome:
    """``exc`` as an :class:`Outcome`, answered by its row. A planning failure is the failed plan-result
    JSON of docs/contracts.md when ``plan_robot`` (the robot JSON of a plan) is given, else
    ``{status: failed, error_code, error_msg, field: null}``. A bug's message names only its type."""
    answer = answer_for(exc)
    if isinstance(exc, PlanningError):
        if plan_robot is not None:
            from planner.result import failure_json

            body = failure_json(exc.code, exc.msg, None, exc.planning_time_s, exc.expansions)
            body["robot"] = plan_robot
        else:
            body = {"status": "failed", "error_code": exc.code, "error_msg": exc.msg, "field": None}
        return Outcome(answer, dumps(body), exc.code)
    if answer.kind == "internal":
        return error_outcome(type(exc), f"internal error: {type(exc).__name__}")
    return error_outcome(type(exc), str(exc), getattr(exc, "field", None))
