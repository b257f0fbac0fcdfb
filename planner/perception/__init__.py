"""Paper 001 §3.2–3.3: stereo obstacle perception and electronic image stabilisation (EIS) for the pendulum sphere.

Public surface (one concept per module):

* :func:`obstacle_points` — one stereo pair → ``(points_map (N, 3), origin_map (3,))``, the live map's input:
  obstacle points in the map frame (m) and the left camera's optical centre every ray starts from;
  :func:`perceive` returns the whole :class:`ObstacleScan` (disparity, counts per filter, timings).
* :class:`CameraInfo`, :func:`read_camera_info` — ROS camera_info YAML (``camera_info.py``).
* :class:`StereoOptions` (SGBM, ``disparity.py``), :class:`ObstacleFilter` (the paper's thresholds,
  ``obstacle_filter.py``), :func:`camera_pose` (the cameras on the main axis, eq. 4 / 9, ``mount.py``).
* :func:`stabilise`, :func:`correction_rotation`, :func:`stabilising_homography` — EIS (eq. 5–13, ``eis.py``);
  :func:`read_imu_csv` the IMU log of a batch (``imu_log.py``).

Everything uses OpenCV (``opencv-python-headless``), imported on first use.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from planner.perception.camera_info import CameraInfo, read_camera_info
    from planner.perception.disparity import StereoOptions
    from planner.perception.eis import correction_rotation, stabilise, stabilising_homography
    from planner.perception.imu_log import read_imu_csv
    from planner.perception.mount import camera_pose
    from planner.perception.obstacle_filter import ObstacleFilter
    from planner.perception.stereo import ObstacleScan, obstacle_points, perceive

#: public name → its module, imported on first use
_EXPORTS = {
    "CameraInfo": "planner.perception.camera_info",
    "read_camera_info": "planner.perception.camera_info",
    "StereoOptions": "planner.perception.disparity",
    "ObstacleFilter": "planner.perception.obstacle_filter",
    "camera_pose": "planner.perception.mount",
    "ObstacleScan": "planner.perception.stereo",
    "perceive": "planner.perception.stereo",
    "obstacle_points": "planner.perception.stereo",
    "stabilise": "planner.perception.eis",
    "correction_rotation": "planner.perception.eis",
    "stabilising_homography": "planner.perception.eis",
    "read_imu_csv": "planner.perception.imu_log",
}

__all__ = ["CameraInfo", "ObstacleFilter", "ObstacleScan", "StereoOptions", "camera_pose", "correction_rotation",
           "obstacle_points", "perceive", "read_camera_info", "read_imu_csv", "stabilise", "stabilising_homography"]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'planner.perception' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value
