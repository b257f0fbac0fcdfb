"""Fixtures the service tests share: the session's one real ``sphereplan serve`` and an HTTP client of it."""

from __future__ import annotations

from collections.abc import Iterator

import httpx
import pytest

from tests.service import service_harness as harness
from tests.service.service_harness import Server


@pytest.fixture(scope="session")
def server() -> Iterator[Server]:
    yield harness.acquire()
    harness.release()


@pytest.fixture()
def client(server: Server) -> Iterator[httpx.Client]:
    with httpx.Client(base_url=server.url, timeout=60) as c:
        yield c
