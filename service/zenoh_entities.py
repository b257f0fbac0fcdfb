"""What the Zenoh node and its rmw_zenoh face share about the entities they declare on a session."""

from __future__ import annotations

import logging
from typing import Any

import zenoh

log = logging.getLogger(__name__)


def undeclare_all(entities: list[Any]) -> None:
    """Undeclare ``entities`` (subscribers, queryables, tokens ...) newest first and empty the list; an
    entity the closing session already dropped is skipped."""
    for entity in reversed(entities):
        try:
            entity.undeclare()
        except zenoh.ZError as exc:
            log.debug("undeclare: %s", exc)
    entities.clear()
