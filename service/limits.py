"""Bounded parsing of request bodies and payloads, shared by the HTTP app and the Zenoh node.

A body is refused by its length before it is read further (``max_body_bytes``). A small one (at most
``SMALL_BODY_BYTES``) is parsed where it arrives: it costs less than a health probe. A large one (an inline
map of a few MB becomes hundreds of MB of Python lists while it is parsed) is parsed off the event loop or the
Zenoh callback thread, at most ``PARSE_CONCURRENCY`` at a time, and at most ``MAX_PENDING_PARSES`` wait for
their turn; beyond that the request is answered busy (503 / ``reply_err``) instead of queued. So a burst of
large bodies bounds the memory it can take and never holds a health probe or a small query behind it.

:class:`KeyedSerialExecutor` runs the Zenoh topics' work off the callback thread in order per robot (a pose
published just before a goal is applied first) while different robots go in parallel.
"""

from __future__ import annotations

import json
import threading
from collections import deque
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError

from planner.errors import InvalidInput
from service.outcome import ServiceBusy
from service.wire import invalid_input

M = TypeVar("M", bound=BaseModel)

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


class ParseGate:
    """At most ``PARSE_CONCURRENCY`` large parses at once in a small thread pool, at most
    ``MAX_PENDING_PARSES`` admitted (running or waiting); :meth:`admit` raises :class:`ServiceBusy` beyond."""

    def __init__(self, concurrency: int = PARSE_CONCURRENCY, pending: int = MAX_PENDING_PARSES,
                 retry_after_s: int = 1) -> None:
        self.executor = ThreadPoolExecutor(concurrency, thread_name_prefix="sphereplan-parse")
        self._slots = threading.BoundedSemaphore(pending)
        self._pending = pending
        self._retry_after_s = retry_after_s

    def admit(self) -> None:
        """Take a pending slot or raise :class:`ServiceBusy`; give it back with :meth:`release`."""
        if not self._slots.acquire(blocking=False):
            raise ServiceBusy(self._pending, self._retry_after_s)

    def release(self) -> None:
        self._slots.release()

    def submit(self, fn: Callable[[], Any]) -> Any:
        """Admit and run ``fn`` in the parse pool (the slot is released when it ends); a future."""
        self.admit()
        try:
            future = self.executor.submit(fn)
        except RuntimeError:
            self.release()
            raise ServiceBusy(self._pending, self._retry_after_s) from None
        future.add_done_callback(lambda _: self.release())
        return future

    def close(self) -> None:
        self.executor.shutdown(wait=False, cancel_futures=True)


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
            fn()  # the callable handles its own errors

    def close(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)
