"""What the Zenoh doors publish (a goal's status and path, a live session's status) is sent with congestion
control BLOCK: Zenoh's default for a put, DROP, lets a full queue (a busy router, a slow subscriber) lose a
"succeeded" for good; CI once waited 300 s for one such status among 100 robots."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import zenoh

from service.core import PlanningService
from service.settings import ServiceSettings
from service.zenoh_live import LiveZenohNode
from service.zenoh_node import ZenohNode
from tests.service.service_harness import make_maps


class _Recorder:
    """A session stand-in that records each put's key and keyword options."""

    def __init__(self) -> None:
        self.puts: list[tuple[str, dict[str, Any]]] = []

    def put(self, key: str, payload: Any, **options: Any) -> None:
        self.puts.append((key, options))


def test_goal_statuses_and_paths_are_published_reliably(tmp_path: Path) -> None:
    service = PlanningService(ServiceSettings(maps_dir=make_maps(tmp_path / "maps"), workers=1, zenoh=False,
                                              warm_up=False))
    node = ZenohNode(service)
    recorder = _Recorder()
    node.session = recorder  # type: ignore[assignment]
    node._status("r1", 1, "succeeded")
    node._publish("r1", "path", b"{}")
    assert [key for key, _ in recorder.puts] == ["sphereplan/r1/status", "sphereplan/r1/path"]
    assert all(options.get("congestion_control") == zenoh.CongestionControl.BLOCK for _, options in recorder.puts)


def test_live_session_statuses_are_published_reliably(tmp_path: Path) -> None:
    service = PlanningService(ServiceSettings(maps_dir=make_maps(tmp_path / "maps"), workers=1, zenoh=False,
                                              warm_up=False))
    recorder = _Recorder()
    node = LiveZenohNode(service, store=None, session=recorder, max_body_bytes=1 << 16)  # type: ignore[arg-type]
    node._status("r1", {"state": "failed"})
    ((key, options),) = recorder.puts
    assert key == "sphereplan/r1/live/status"
    assert options.get("congestion_control") == zenoh.CongestionControl.BLOCK
