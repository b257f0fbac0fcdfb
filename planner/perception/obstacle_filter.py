"""Which measured points are obstacles: the thresholds of paper 001 §3.2.

"Objects 5 cm above the ground that are not suspended and within 10 m of a spherical robot may cause
collisions ... We set a certain threshold to filter out suspended, too far obstacles, and false obstacles with
negative height values due to ground reflection, leaving only obstacles that may cause collisions." Per map-frame
point (z up, the ground at z = 0):

* ``ground`` — lower than ``min_height_m`` (5 cm) above the ground, the ground itself;
* ``below_ground`` — lower than −``ground_tolerance_m``: reflections and mismatches (a point pushed further
  along a ray that meets the ground ends up under it); they are counted apart from the ground;
* ``suspended`` — higher than ``max_height_m`` (default: the top of the shell, 2r, plus ``headroom_m``): the
  robot passes beneath it;
* ``too_far`` — farther than ``max_range_m`` (10 m) from the sphere's centre, measured on the ground.

Each point is dropped by the first test it fails, in that order. One test is not the paper's: what remains must
also form, in the left image, a patch of at least ``min_blob_px`` touching pixels (``small_blob``). Ground seen at a
grazing angle near an obstacle's foot, 8–10 m away, is now and then mismatched by several pixels of disparity,
enough to lift a few of its points over 5 cm; those come as specks of a handful of pixels. The price: at 541 × 413
with a 70° lens, 20 pixels are about 10 × 10 cm of surface at 9 m (6 × 6 cm at 5 m), and a real obstacle showing
less than that above the 5 cm line is dropped too (``min_blob_px`` = 1 keeps everything).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planner.errors import InvalidInput
from planner.perception.opencv import opencv

REASONS = ("below_ground", "ground", "suspended", "too_far")
#: the reason :meth:`ObstacleFilter.specks` drops a point for, counted after :data:`REASONS`
SMALL_BLOB = "small_blob"


@dataclass(frozen=True)
class ObstacleFilter:
    """The paper's thresholds (metres). ``max_height_m`` None = 2·radius + ``headroom_m``. ``min_blob_px``: the
    smallest patch of kept pixels (8-connected, in the left image) that counts; 1 keeps every point."""

    min_height_m: float = 0.05
    max_height_m: float | None = None
    headroom_m: float = 0.10
    max_range_m: float = 10.0
    ground_tolerance_m: float = 0.05
    min_blob_px: int = 20

    def __post_init__(self) -> None:
        for name in ("min_height_m", "headroom_m", "max_range_m", "ground_tolerance_m"):
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0:
                raise InvalidInput(name, f"must be a finite number ≥ 0, got {value!r}")
        if self.max_range_m <= 0:
            raise InvalidInput("max_range_m", "must be > 0")
        if isinstance(self.min_blob_px, bool) or not isinstance(self.min_blob_px, int) or self.min_blob_px < 1:
            raise InvalidInput("min_blob_px", f"must be an integer ≥ 1, got {self.min_blob_px!r}")
        if self.max_height_m is not None and not (math.isfinite(self.max_height_m)
                                                  and self.max_height_m > self.min_height_m):
            raise InvalidInput("max_height_m", f"must be a finite height above min_height_m ({self.min_height_m} m)")

    def ceiling_m(self, radius_m: float) -> float:
        """The height above which a point is suspended (m)."""
        return self.max_height_m if self.max_height_m is not None else 2 * radius_m + self.headroom_m

    def apply(self, points_map: np.ndarray, centre_xy: tuple[float, float],
              radius_m: float) -> tuple[np.ndarray, dict[str, int]]:
        """(keep mask (N,), dropped count per reason) for map points (N, 3) seen by a sphere at ``centre_xy``."""
        z = points_map[:, 2]
        rng = np.hypot(points_map[:, 0] - centre_xy[0], points_map[:, 1] - centre_xy[1])
        tests = {
            "below_ground": z < -self.ground_tolerance_m,
            "ground": z < self.min_height_m,
            "suspended": z > self.ceiling_m(radius_m),
            "too_far": rng > self.max_range_m,
        }
        keep = np.ones(len(points_map), dtype=bool)
        dropped = {}
        for reason in REASONS:
            hit = keep & tests[reason]
            dropped[reason] = int(hit.sum())
            keep &= ~hit
        return keep, dropped

    def specks(self, pixels: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
        """Mask (N,) of the points whose pixels ((N, 2) row, column of an image of ``shape``) lie in a patch of
        fewer than ``min_blob_px`` touching pixels (8-connected)."""
        if self.min_blob_px <= 1 or len(pixels) == 0:
            return np.zeros(len(pixels), dtype=bool)
        cv2 = opencv()

        image = np.zeros(shape, dtype=np.uint8)
        image[pixels[:, 0], pixels[:, 1]] = 1
        _, labels, stats, _ = cv2.connectedComponentsWithStats(image, connectivity=8)
        area = stats[:, cv2.CC_STAT_AREA]
        return np.asarray(area[labels[pixels[:, 0], pixels[:, 1]]] < self.min_blob_px)
