"""What a running service is configured with: :class:`ServiceSettings`, validated once, and the hard limits.

``sphereplan serve`` builds the settings from its options; the planning service, the HTTP app and the
Zenoh node read them. The module imports nothing heavy, so the CLI can read the limits for its help text.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

from planner.errors import InvalidInput

#: largest grid a request may carry (cells): a 100 m × 100 m map at 5 cm (2000 × 2000). A server may set a lower
#: one; the body limit caps the JSON list forms further (~1.5 M cells in 4 MB), the compressed form
#: (``data_gzip_b64`` of a nav_msgs/OccupancyGrid) carries the largest in well under 1 MB
MAX_INLINE_CELLS = 4_000_000
#: largest time limit a request may ask for (s); a server may set a lower one
MAX_TIME_LIMIT_S = 60.0
#: one Zenoh key chunk naming robot ids (``*``, ``r1``, ``east-$*``); never ``**`` or a ``/``
ROBOT_PATTERN = re.compile(r"\*|(?:[A-Za-z0-9_.-]|\$\*)+")


@dataclass(frozen=True)
class ServiceSettings:
    """Everything the service, the HTTP app and the Zenoh node are configured with, validated once.

    ``maps_dir`` None means the shipped maps (:func:`planner.maps.catalogue.default_maps_dir`).
    ``max_in_flight`` 0 means 4 jobs per worker. ``zenoh_listen`` is the default peer's only endpoint
    (ignored when ``zenoh_config`` names a Zenoh config file). ``max_body_bytes`` bounds HTTP bodies and
    Zenoh payloads. ``worker_memory_mb`` is each worker process's address-space ceiling (0: none): a job
    that reaches it is answered as bad input instead of growing until the machine kills something.
    ``max_job_s`` is the wall-clock deadline of a job without a time limit of its own (everything but a
    plan, whose deadline is its time limit). ``http_token``, when set, is the token every door requires
    (:mod:`service.auth`): the bearer token of every HTTP route but the health probes, and the attachment of
    every Zenoh query and pose/goal put.
    """

    maps_dir: Path | None = None
    workers: int = 2
    max_in_flight: int = 0
    max_time_limit_s: float = MAX_TIME_LIMIT_S
    max_inline_cells: int = MAX_INLINE_CELLS
    max_body_bytes: int = 4_000_000
    retry_after_s: int = 1
    worker_memory_mb: int = 2048
    max_job_s: float = 300.0
    http_token: str | None = None
    warm_up: bool = True
    zenoh: bool = True
    zenoh_config: Path | None = None
    zenoh_listen: str = "tcp/127.0.0.1:7447"
    #: robot ids whose pose/goal topics this instance plans, as Zenoh key chunks (``*`` every robot, ``r1``, or
    #: ``east-$*`` the ids starting ``east-``): instances serving one fleet take disjoint sets
    zenoh_robots: tuple[str, ...] = ("*",)
    #: ROS 2 over Zenoh in rmw_zenoh's format (service/ros2_zenoh.py): on/off, domain, namespace of the
    #: topics, the map goals are planned on until a nav_msgs/OccupancyGrid arrives on <ns>/map, the robot
    ros2: bool = False
    ros2_domain_id: int = 0
    ros2_namespace: str = "/"
    ros2_map: str | None = None
    ros2_robot: str | None = None

    def __post_init__(self) -> None:
        def need(ok: bool, name: str, msg: str) -> None:
            if not ok:
                raise InvalidInput(name, msg)

        need(1 <= self.workers <= 64, "workers", f"must be in [1, 64], got {self.workers}")
        need(self.max_in_flight >= 0, "max_in_flight", f"must be ≥ 0 (0 = 4 per worker), got {self.max_in_flight}")
        need(math.isfinite(self.max_time_limit_s) and 0 < self.max_time_limit_s <= MAX_TIME_LIMIT_S,
             "max_time_limit_s", f"must be in (0, {MAX_TIME_LIMIT_S:g}], got {self.max_time_limit_s}")
        need(1 <= self.max_inline_cells <= MAX_INLINE_CELLS, "max_inline_cells",
             f"must be in [1, {MAX_INLINE_CELLS}], got {self.max_inline_cells}")
        need(self.max_body_bytes >= 1024, "max_body_bytes", f"must be ≥ 1024, got {self.max_body_bytes}")
        need(self.worker_memory_mb == 0 or self.worker_memory_mb >= 512, "worker_memory_mb",
             f"must be 0 (no ceiling) or ≥ 512, got {self.worker_memory_mb}")
        need(math.isfinite(self.max_job_s) and self.max_job_s >= 1, "max_job_s", f"must be ≥ 1 s, got {self.max_job_s}")
        need(self.retry_after_s >= 1, "retry_after_s", f"must be ≥ 1, got {self.retry_after_s}")
        need(0 <= self.ros2_domain_id <= 232, "ros2_domain_id", f"must be in [0, 232], got {self.ros2_domain_id}")
        need(not self.ros2 or self.zenoh, "ros2", "needs the Zenoh node (drop --no-zenoh)")
        need(bool(self.zenoh_robots) and all(ROBOT_PATTERN.fullmatch(p) for p in self.zenoh_robots), "zenoh_robots",
             f"each must be one Zenoh key chunk (letters, digits, _ - . * $*), got {self.zenoh_robots}")
        if self.zenoh_config is not None:
            need(Path(self.zenoh_config).is_file(), "zenoh_config", f"{self.zenoh_config} is not a file")

    @property
    def in_flight_cap(self) -> int:
        return self.max_in_flight or 4 * self.workers
