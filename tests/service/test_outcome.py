"""The outcome table: every error type answers with its documented exit code, HTTP status and Zenoh reply."""

from __future__ import annotations

import inspect

import pytest

import planner.errors as errors
from planner.errors import BadEndpoint, PlanningError, StartOccupied
from service.http import outcome_response
from service.outcome import (
    RateLimited,
    ServiceBusy,
    Unauthorized,
    WorkerLost,
    answer_for,
    ok_outcome,
    outcome_of_exception,
)

# error type → (kind, CLI exit code, HTTP status, Zenoh reply) as docs/contracts.md and docs/service.md say
DOCUMENTED: dict[type[BaseException], tuple[str, int, int, str]] = {
    errors.SpherePlanError: ("bad_input", 2, 422, "reply_err"),
    errors.InvalidInput: ("bad_input", 2, 422, "reply_err"),
    errors.MapError: ("bad_input", 2, 422, "reply_err"),
    errors.RobotProfileError: ("bad_input", 2, 422, "reply_err"),
    errors.NotFound: ("not_found", 2, 404, "reply_err"),
    errors.BadEndpoint: ("bad_input", 2, 422, "reply_err"),
    errors.StartOutsideMap: ("bad_input", 2, 422, "reply_err"),
    errors.GoalOutsideMap: ("bad_input", 2, 422, "reply_err"),
    errors.StartOccupied: ("bad_input", 2, 422, "reply_err"),
    errors.GoalOccupied: ("bad_input", 2, 422, "reply_err"),
    errors.PlanningError: ("failed", 3, 422, "reply_err"),
    errors.NoValidPathFound: ("failed", 3, 422, "reply_err"),
    errors.PlannerCancelled: ("failed", 3, 422, "reply_err"),
    errors.PlannerTimedOut: ("failed", 4, 422, "reply_err"),
    ServiceBusy: ("busy", 1, 503, "reply_err"),
    WorkerLost: ("unavailable", 1, 503, "reply_err"),  # a worker died or hung under the job: a server fault
    Unauthorized: ("unauthorized", 2, 401, "reply_err"),
    RateLimited: ("busy", 1, 429, "reply_err"),
    RuntimeError: ("internal", 1, 500, "reply_err"),
}


def test_every_planner_error_type_is_in_the_documented_table() -> None:
    defined = {obj for _, obj in inspect.getmembers(errors, inspect.isclass) if obj.__module__ == errors.__name__}
    assert defined <= set(DOCUMENTED), defined - set(DOCUMENTED)


@pytest.mark.parametrize("error", list(DOCUMENTED), ids=[e.__name__ for e in DOCUMENTED])
def test_each_error_type_answers_as_documented(error: type[BaseException]) -> None:
    answer = answer_for(error)
    assert (answer.kind, answer.exit_code, answer.http_status, answer.zenoh_reply) == DOCUMENTED[error]


def test_an_occupied_start_is_bad_input_by_its_type_not_its_code() -> None:
    occupied = outcome_of_exception(StartOccupied("the start is in a wall"), {"name": "zju-60"})
    assert occupied.kind == "bad_input" and occupied.answer.exit_code == 2 and occupied.error_code == 205
    body = occupied.json()  # still the failed-result JSON every door sends for a failed plan
    assert body["status"] == "failed" and body["error_code"] == 205 and body["robot"] == {"name": "zju-60"}

    class SameCode(PlanningError):  # a Nav2 code in 203-206 does not make an error bad input
        code = 205

    class Walled(BadEndpoint):  # the type does, whatever its code
        code = 208

    assert answer_for(SameCode).exit_code == 3
    assert answer_for(Walled).exit_code == 2


def _instance(error: type[BaseException]) -> BaseException:
    if issubclass(error, errors.InvalidInput | errors.NotFound):
        return error("field", "message")
    if error is ServiceBusy:
        return ServiceBusy(3, 1)
    if error is RateLimited:
        return RateLimited("too fast", 1)
    return error("message")


def test_http_and_zenoh_answer_by_the_row() -> None:
    for error, (_, _, status, reply) in DOCUMENTED.items():
        outcome = outcome_of_exception(_instance(error))
        response = outcome_response(outcome, retry_after_s=2)
        assert response.status_code == status, error
        assert response.headers.get("retry-after") == ("2" if error in (ServiceBusy, WorkerLost, RateLimited) else None)
        assert outcome.answer.zenoh_reply == reply
    assert outcome_response(ok_outcome({})).status_code == 200 and ok_outcome({}).answer.zenoh_reply == "reply"
