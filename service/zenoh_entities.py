"""What the Zenoh node and its rmw_zenoh face share about the entities they declare on a session."""

from __future__ import annotations

import logging
from typing import Any

import zenoh

log = logging.getLogger(__name__)

# What sphereplan publishes (statuses, paths) is an outcome a robot waits for, like a ROS action result over
# reliable QoS: Zenoh's default for a put is DROP when a queue is full (a busy router, a slow subscriber), which
# loses a "succeeded" for good. BLOCK makes the publishing thread wait instead; it is one of ours, never the
# subscriber callback.
RELIABLE = zenoh.CongestionControl.BLOCK


def undeclare_all(entities: list[Any]) -> None:
    """Undeclare ``entities`` (subscribers, queryables, tokens ...) newest first and empty the list; an
    entity the closing session already dropped is skipped."""
    for entity in reversed(entities):
        try:
            entity.undeclare()
        except zenoh.ZError as exc:
            log.debug("undeclare: %s", exc)
    entities.clear()
