"""Bounded parsing of request bodies and payloads, shared by the HTTP app and the Zenoh node.

A body is refused by its length before it is read further (``max_body_bytes``). A small one (at most
``SMALL_BODY_BYTES``) is parsed where it arrives: it costs less than a health probe. A large one (an inline
map of a few MB becomes hundreds of MB of Python lists while it is parsed) is parsed in a separate process,
off the event loop and the Zenoh callback threads and off the GIL they need, at most ``PARSE_CONCURRENCY``
at a time; at most ``MAX_PENDING_PARSES`` are admitted, beyond that the request is answered busy (503 /
``reply_err``) instead of queued. So a burst of large bodies bounds the memory it can take and never holds
a health probe or a small query behind it.

:class:`KeyedSerialExecutor` runs the Zenoh topics' work off the callback thread in order per robot (a pose
published just before a goal is applied first) while different robots go in parallel.
"""

from __future__ import annotations

import json
import logging
import threading
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError

from planner.errors import InvalidInput
from service.outcome import ServiceBusy
from service.wire import invalid_input

M = TypeVar("M", bound=BaseModel)
log = logging.getLogger(__name__)

#: bodies up to this size are parsed where they arrive (B)
SMALL_BODY_BYTES = 64 * 1024
#: large bodies parsed at the same time, per process
PARSE_CONCURRENCY = 2
#: large bodies waiting for a parse slot before further ones are answered busy
MAX_PENDING_PARSES = 16


class MalformedBody(InvalidInput):
    """The body is empty or not JSON (HTTP answers it 400; it is bad input like any other elsewhere)."""

    def __init__(self, msg: str) -> None:
        super().__init__("body", msg)


def parse_json_model(model: type[M], raw: bytes, limit: int) -> M:
    """Validate a JSON body against a wire model; :class:`InvalidInput` naming the field (``body`` when it is
    too long or nested too deeply; :class:`MalformedBody` when it is empty or not JSON)."""
    if not raw:
        raise MalformedBody("a JSON body is required")
    if len(raw) > limit:
        raise InvalidInput("body", f"payload of {len(raw)} bytes; this server accepts at most {limit}")
    try:
        data = json.loads(raw)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise MalformedBody(f"malformed JSON: {exc}") from None
    except RecursionError:
        raise MalformedBody("malformed JSON: nested too deeply") from None
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        raise invalid_input(exc.errors()) from None
    except RecursionError:
        raise InvalidInput("body", "nested too deeply") from None


def _parse_in_child(model: type[M], raw: bytes, limit: int) -> tuple[str, Any, str, str]:
    """:func:`parse_json_model` in a parse process: ("ok", model, "", "") or ("malformed" | "invalid", None,
    field, message) (exceptions with their own constructors are not sent across processes)."""
    try:
        return "ok", parse_json_model(model, raw, limit), "", ""
    except MalformedBody as exc:
        return "malformed", None, exc.field, exc.msg
    except InvalidInput as exc:
        return "invalid", None, exc.field, exc.msg


def _ready() -> bool:
    return True


class ParseGate:
    """Large bodies parsed in ``PARSE_CONCURRENCY`` separate processes (spawned): JSON decoding and pydantic
    validation hold the GIL for the whole call (≈ 0.5 s for a 3 MB grid on a busy machine), so a thread would
    still stop the event loop and the Zenoh callbacks. At most ``MAX_PENDING_PARSES`` are admitted (running or
    waiting); :meth:`submit` raises :class:`ServiceBusy` beyond."""

    def __init__(self, concurrency: int = PARSE_CONCURRENCY, pending: int = MAX_PENDING_PARSES,
                 retry_after_s: int = 1) -> None:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        self._executor = ProcessPoolExecutor(concurrency, mp_context=multiprocessing.get_context("spawn"))
        self._slots = threading.BoundedSemaphore(pending)
        self._pending = pending
        self._retry_after_s = retry_after_s

    def warm(self) -> None:
        """Start the parse processes now (blocking), so the first large body does not wait for them."""
        self._executor.submit(_ready).result(timeout=300)

    def submit(self, model: type[M], raw: bytes, limit: int) -> Future[M]:
        """Parse ``raw`` as ``model`` in a parse process: a future of the model, or of the :class:`InvalidInput`
        (:class:`MalformedBody`) it amounts to. Raises :class:`ServiceBusy` when too many are admitted."""
        if not self._slots.acquire(blocking=False):
            raise ServiceBusy(self._pending, self._retry_after_s)
        try:
            inner = self._executor.submit(_parse_in_child, model, raw, limit)
        except RuntimeError:  # shut down
            self._slots.release()
            raise ServiceBusy(self._pending, self._retry_after_s) from None
        outer: Future[M] = Future()

        def done(job: Future[tuple[str, Any, str, str]]) -> None:
            self._slots.release()
            try:
                kind, value, field, msg = job.result()
            except BaseException as exc:  # the parse process died (its memory), or the pool shut down
                outer.set_exception(ServiceBusy(self._pending, self._retry_after_s) if not
                                    isinstance(exc, InvalidInput) else exc)
                return
            if kind == "ok":
                outer.set_result(value)
            else:
                outer.set_exception(MalformedBody(msg) if kind == "malformed" else InvalidInput(field, msg))

        inner.add_done_callback(done)
        return outer

    def close(self) -> None:
        self._executor.shutdown(wait=False, cancel_futures=True)


class KeyedSerialExecutor:
    """Runs callables in order per key on a shared thread pool (keys in parallel). At most ``max_pending``
    callables wait in all; :meth:`submit` returns False (and drops the callable) beyond that."""

    def __init__(self, workers: int = 4, max_pending: int = 256) -> None:
        self._pool = ThreadPoolExecutor(workers, thread_name_prefix="sphereplan-topic")
        self._lock = threading.Lock()
        self._queues: dict[str, deque[Callable[[], None]]] = {}
        self._pending = 0
        self._max_pending = max_pending

    def submit(self, key: str, fn: Callable[[], None]) -> bool:
        with self._lock:
            if self._pending >= self._max_pending:
                return False
            self._pending += 1
            queue = self._queues.get(key)
            if queue is not None:  # a runner for this key is active: it will take it in order
                queue.append(fn)
                return True
            self._queues[key] = deque([fn])
        try:
            self._pool.submit(self._drain, key)
        except RuntimeError:  # shut down
            with self._lock:
                self._queues.pop(key, None)
                self._pending = 0
            return False
        return True

    def _drain(self, key: str) -> None:
        while True:
            with self._lock:
                queue = self._queues[key]
                if not queue:
                    del self._queues[key]
                    return
                fn = queue.popleft()
                self._pending -= 1
            try:
                fn()
            except Exception:  # a bug in the callable: logged, and this key's queue keeps draining
                log.exception("handling a message for %s failed", key)

    def close(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)
