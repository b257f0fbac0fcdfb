"""Visual obstacle perception of paper 001 §3.2: a stereo pair on the main axis → obstacle points in the map.

The steps, as in the paper:

1. rectify the pair (eq. 8's distortion model and the calibration's R, P; a rectified pair passes through);
2. Semi-Global Block Matching gives the disparity map (:mod:`planner.perception.disparity`);
3. the pinhole model inverted gives camera coordinates ``P̃_c`` (:mod:`planner.perception.triangulate`);
4. the extrinsic matrix T of the camera on the sphere, from the fused pose (eq. 4: ``P̃_c = T·P_g``), takes
   them to the map (:mod:`planner.perception.mount`);
5. the thresholds drop the ground, reflections under it, suspended and too-distant points, and specks of a
   few pixels (:mod:`planner.perception.obstacle_filter`).

For the live map (marking and ray-traced clearing as Nav2's obstacle layer does), :func:`obstacle_points`
returns just ``(points_map, origin_map)``: the kept points (N, 3) and the point every ray was seen from, the
left camera's optical centre (3,), both in the map frame in metres. A ray from the origin to each point
crossed free space; cells holding a point are obstacles.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from planner.errors import InvalidInput
from planner.perception.camera_info import CameraInfo, stereo_baseline_m
from planner.perception.disparity import StereoOptions, rectify, sgbm_disparity, to_grey
from planner.perception.mount import CameraPose, camera_pose, check_angle, rotate
from planner.perception.obstacle_filter import SMALL_BLOB, ObstacleFilter
from planner.perception.triangulate import points_from_disparity

#: the names a pair's inputs are reported by in errors (the CLI passes its own option names)
DEFAULT_FIELDS = ("left", "right", "left_info", "right_info")


@dataclass(frozen=True)
class ObstacleScan:
    """What one stereo pair showed.

    ``points_map`` (N, 3): the kept obstacle points, map frame, m. ``origin_map`` (3,): the left camera's optical
    centre, where every ray starts. ``pixels`` (N, 2): each kept point's (row, column) in the left rectified
    image. ``disparity`` (H, W) float32 px, NaN where unmatched (None unless asked for). ``measured``: points
    SGBM gave in front of the cameras; ``dropped``: how many each filter removed. ``timings_s``: seconds per
    step (``rectify``, ``sgbm``, ``points``, ``filter``, ``total``)."""

    points_map: np.ndarray
    origin_map: np.ndarray
    pixels: np.ndarray
    measured: int
    dropped: dict[str, int]
    baseline_m: float
    num_disparities: int
    timings_s: dict[str, float]
    camera: CameraPose = field(repr=False)
    pose: tuple[float, float, float] = (0.0, 0.0, 0.0)
    roll_rad: float = 0.0
    pitch_rad: float = 0.0
    filters: dict[str, float] = field(default_factory=dict)
    disparity: np.ndarray | None = field(default=None, repr=False)

    def to_json(self) -> dict[str, Any]:
        """The JSON of ``sphereplan perceive`` and ``POST /v1/perceive`` (without the disparity image)."""
        x, y, yaw = self.pose
        return {
            "frame_id": "map",
            "pose": {"x": x, "y": y, "yaw": yaw},
            "roll": self.roll_rad,
            "pitch": self.pitch_rad,
            "origin_map": [round(float(v), 6) for v in self.origin_map],
            "count": len(self.points_map),
            "measured": self.measured,
            "dropped": dict(self.dropped),
            "filters": dict(self.filters),
            "baseline_m": self.baseline_m,
            "num_disparities": self.num_disparities,
            "timings_s": {k: round(v, 6) for k, v in self.timings_s.items()},
            "points_map": np.round(self.points_map, 4).tolist(),
        }


def check_pair(left: np.ndarray, right: np.ndarray, left_info: CameraInfo, right_info: CameraInfo,
               fields: Sequence[str] = DEFAULT_FIELDS) -> float:
    """Check the pair's sizes against each other and their calibrations; returns the baseline (m). Errors are
    :class:`InvalidInput` naming the input (``fields``: names of left, right, left_info, right_info)."""
    lf, rf, lif, rif = fields
    lh, lw = np.shape(left)[:2]
    rh, rw = np.shape(right)[:2]
    if (lh, lw) != (rh, rw):
        raise InvalidInput(rf, f"is {rw} × {rh} px but the left image is {lw} × {lh} px (mismatched image sizes)")
    for name, info in ((lif, left_info), (rif, right_info)):
        if (info.width, info.height) != (lw, lh):
            raise InvalidInput(name, f"calibrates a {info.width} × {info.height} image, the images are {lw} × {lh}")
    return stereo_baseline_m(left_info, right_info, rif)


def perceive(left: np.ndarray, right: np.ndarray, left_info: CameraInfo, right_info: CameraInfo,
             pose: tuple[float, float, float], roll_rad: float = 0.0, pitch_rad: float = 0.0,
             radius_m: float = 0.30, stereo: StereoOptions | None = None, obstacles: ObstacleFilter | None = None,
             keep_disparity: bool = False, fields: Sequence[str] = DEFAULT_FIELDS) -> ObstacleScan:
    """Obstacle points in the map from one stereo pair (paper 001 §3.2; steps in the module text).

    ``left``/``right``: the raw images (H, W) or (H, W, 3), 8-bit. ``pose``: the sphere's (x, y, yaw) in the map
    (m, m, rad), from the fused positioning. ``roll_rad``: sphereplan's roll (> 0 leans left), ``pitch_rad``: the
    main axis's REP-103 pitch; ``radius_m``: the shell radius (the axis's height). Raises :class:`InvalidInput`
    for mismatched sizes, a calibration that does not fit the images, or a non-finite pose."""
    t_start = time.perf_counter()
    stereo = stereo or StereoOptions()
    obstacles = obstacles or ObstacleFilter()
    x, y, yaw = (float(v) for v in pose)
    for name, value in (("x", x), ("y", y)):
        if not np.isfinite(value):
            raise InvalidInput("pose", f"{name} = {value!r} is not finite")
    check_angle(yaw, "pose yaw")
    check_angle(roll_rad, "roll")
    check_angle(pitch_rad, "pitch")
    if not (np.isfinite(radius_m) and radius_m > 0):
        raise InvalidInput("radius_m", "must be a positive number of metres")
    baseline = check_pair(left, right, left_info, right_info, fields)
    timings: dict[str, float] = {}

    t = time.perf_counter()
    grey_l = rectify(to_grey(left, fields[0]), left_info)
    grey_r = rectify(to_grey(right, fields[1]), right_info)
    timings["rectify"] = time.perf_counter() - t

    p = left_info.p
    n_disp = stereo.disparities_for(float(p[0, 0]), baseline)
    width, need = grey_l.shape[1], stereo.block_size // 2 + (0 if stereo.full_width else n_disp)
    if width <= need:  # OpenCV's own condition, width − numDisparities > blockSize / 2, on the padded width
        raise InvalidInput(fields[0], f"is {width} px wide: SGBM with {n_disp} disparities needs more than {need} "
                                      "columns (raise the nearest depth, lower the number of disparities, or match "
                                      "the full width)")
    t = time.perf_counter()
    disparity = sgbm_disparity(grey_l, grey_r, n_disp, stereo)
    timings["sgbm"] = time.perf_counter() - t

    t = time.perf_counter()
    pts_rect, pixels = points_from_disparity(disparity, float(p[0, 0]), float(p[1, 1]), float(p[0, 2]),
                                             float(p[1, 2]), baseline, float(right_info.p[0, 2]))
    cam = camera_pose(x, y, yaw, roll_rad, radius_m, baseline / 2, pitch_rad)
    pts_map = cam.to_map(rotate(pts_rect, left_info.r.T))  # rectified frame → the camera's own: X_cam = Rᵀ·X_rect
    timings["points"] = time.perf_counter() - t

    t = time.perf_counter()
    keep, dropped = obstacles.apply(pts_map, (x, y), radius_m)
    specks = obstacles.specks(pixels[keep], disparity.shape)
    dropped[SMALL_BLOB] = int(specks.sum())
    keep[np.flatnonzero(keep)[specks]] = False
    timings["filter"] = time.perf_counter() - t
    timings["total"] = time.perf_counter() - t_start
    filters = {"min_height_m": obstacles.min_height_m, "max_height_m": obstacles.ceiling_m(radius_m),
               "max_range_m": obstacles.max_range_m, "min_blob_px": obstacles.min_blob_px}
    return ObstacleScan(pts_map[keep], cam.position.copy(), pixels[keep], len(pts_map), dropped, baseline, n_disp,
                        timings, cam, (x, y, yaw), float(roll_rad), float(pitch_rad), filters,
                        disparity if keep_disparity else None)


def obstacle_points(left: np.ndarray, right: np.ndarray, left_info: CameraInfo, right_info: CameraInfo,
                    pose: tuple[float, float, float], roll_rad: float = 0.0, pitch_rad: float = 0.0,
                    radius_m: float = 0.30, stereo: StereoOptions | None = None,
                    obstacles: ObstacleFilter | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The live map's input from one stereo pair: ``(points_map, origin_map)``.

    ``points_map`` (N, 3) float64: obstacle points in the map frame (m) that passed the paper's filters (at least
    5 cm above the ground, not above the shell, within 10 m); ``origin_map`` (3,) float64: the left camera's
    optical centre in the map frame (m), the start of every ray (ray-trace from it to each point to clear free
    space, then mark the point). Arguments as :func:`perceive`."""
    scan = perceive(left, right, left_info, right_info, pose, roll_rad, pitch_rad, radius_m, stereo, obstacles)
    return scan.points_map, scan.origin_map
