"""Where the cameras sit on the pendulum sphere, and the extrinsic matrix T of paper 001 eq. 4 and eq. 9.

The camera model on the sphere, in the paper's words (§2.1, §3.2–3.3): "a camera rigidly connected to main axis
is installed in spherical shells on both sides, which forms a stereo camera system with a baseline larger than
50 cm"; the side shells "are rigidly connected to main axis ... sharing the same pose as the main axis, and do
not roll as the middle part"; "IMU and cameras share the same Euler angles since they are rigidly connected to
main axis". So the cameras turn with the main axis, not with the rolling middle shell:

* both optical centres lie on the main axis through the sphere's centre, ``radius_m`` above the ground; the left
  one ``baseline/2`` toward the robot's left (+y of the robot frame), the right one ``baseline/2`` to its right;
* both look forward (optical z = the robot's x, optical x = −y, optical y = −z: ROS's optical frame);
* they yaw with the heading and roll with the sphere's roll φ; the middle shell's forward rolling (the shell
  turning about the main axis) does not pitch them. A pitch of the axis itself (the frame's reaction to the
  pendulum, which the IMU reports) can be given and defaults to 0.

Sign of the roll. sphereplan's roll φ > 0 leans the sphere left and turns it left (docs/contracts.md). Eq. 1's
sideways term ẏ = r·φ̇ (robot frame) is the shell rolling without slip to its left as φ grows, a rotation about
the forward axis by −φ; the main axis tips with it. The main axis's attitude is therefore the REP-103 Euler
attitude (yaw θ, pitch ψ, roll −φ): ``R_map_body = Rz(θ)·Ry(ψ)·Rx(−φ)``; the left camera is lowered by
(B/2)·sin φ. The tests render the tipped pair independently and check the points land where the scene is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planner import angles

#: the optical axes (x right, y down, z forward) as columns in the robot frame (x forward, y left, z up)
OPTICAL_IN_BODY = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])

#: the largest magnitude an angle in radians may have (docs/contracts.md: beyond it, degrees given as radians)


def check_angle(value: float, field: str) -> float:
    """``value`` (rad) by the one angle rule of every door (:func:`planner.angles.check_angle`)."""
    return float(angles.check_angle(field, float(value), "--degrees (CLI) or \"degrees\": true (HTTP, Zenoh)"))


def rot_x(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def attitude_rep103(roll_rad: float, pitch_rad: float, yaw_rad: float = 0.0) -> np.ndarray:
    """The rotation (3, 3) of a body with REP-103 Euler angles: ``Rz(yaw)·Ry(pitch)·Rx(roll)`` (body → world)."""
    return rot_z(yaw_rad) @ rot_y(pitch_rad) @ rot_x(roll_rad)


@dataclass(frozen=True)
class CameraPose:
    """A camera's pose in the map: ``rotation`` (3, 3) has the optical axes as columns in the map frame,
    ``position`` (3,) is the optical centre (m). Map points ``P_g`` (N, 3) → camera points ``R^T (P_g − t)``."""

    rotation: np.ndarray
    position: np.ndarray

    def extrinsic(self) -> np.ndarray:
        """Paper 001's T (4, 4) of eq. 4 / eq. 9: homogeneous map point → homogeneous camera point."""
        t = np.eye(4)
        t[:3, :3] = self.rotation.T
        t[:3, 3] = -self.rotation.T @ self.position
        return t

    def to_map(self, points_cam: np.ndarray) -> np.ndarray:
        """Camera-frame points (N, 3) → map points (N, 3): ``T⁻¹`` of eq. 4 applied to ``P̃_c``."""
        return rotate(points_cam, self.rotation, self.position)


def rotate(points: np.ndarray, rotation: np.ndarray, offset: np.ndarray | None = None) -> np.ndarray:
    """``points @ rotation.T + offset`` for (N, 3) points, written out per column: a (N, 3) × (3, 3) product
    through BLAS wakes its thread pool, which on a loaded machine costs more than the arithmetic."""
    p = np.asarray(points, dtype=float)
    out = np.empty_like(p)
    for i in range(3):
        out[:, i] = p[:, 0] * rotation[i, 0] + p[:, 1] * rotation[i, 1] + p[:, 2] * rotation[i, 2]
        if offset is not None:
            out[:, i] += offset[i]
    return out


def camera_pose(x: float, y: float, yaw_rad: float, roll_rad: float, radius_m: float, offset_left_m: float,
                pitch_rad: float = 0.0) -> CameraPose:
    """The pose of a camera on the main axis (see the module text): sphere at (x, y) with heading ``yaw_rad``,
    roll ``roll_rad`` (sphereplan's, > 0 leans left), optional axis pitch ``pitch_rad`` (REP-103, > 0 nose
    down), centre ``radius_m`` above the ground, optical centre ``offset_left_m`` along the axis to the left."""
    body = attitude_rep103(-roll_rad, pitch_rad, yaw_rad)
    centre = np.array([x, y, radius_m], dtype=float)
    return CameraPose(body @ OPTICAL_IN_BODY, centre + body @ np.array([0.0, offset_left_m, 0.0]))
