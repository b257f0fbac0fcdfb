"""Electronic image stabilisation (EIS) of paper 001 §3.3: level the picture of a camera that rolls with the sphere.

The paper: "IMU and cameras share the same Euler angles since they are rigidly connected to main axis. For roll
and pitch angles of cameras, the expected value after EIS is 0°" (eq. 5); the adjustment becomes a rotation R0
(eq. 6–7); the raw image is undistorted (eq. 8) and reprojected through ``T_p = K·R0·K⁻¹`` (eq. 9–13), a
perspective transformation, exact for a rotation about the optical centre.

Angles are the camera's attitude as the IMU measures it, REP-103: roll about x (forward), pitch about y (left),
right-handed, so the body's attitude is ``A = Ry(pitch)·Rx(roll)`` (yaw is kept: this module levels, it does not
steer; eq. 5's sliding-window yaw is not applied). A world ray d reaches the camera as ``Mᵀ·Aᵀ·d`` in its optical
frame (M: optical axes in the body, :data:`~planner.perception.mount.OPTICAL_IN_BODY`), and as ``Mᵀ·d`` in the
level camera's, so the pixel map from the raw to the level image is ``K·R0·K⁻¹`` with

    R0 = Mᵀ·Ry(pitch)·Rx(roll)·M = Rx_opt(−pitch)·Rz_opt(roll)

(rotations about the optical axes). Eq. 6 as printed is ``Ry(θ_adj)·Rx(ψ_adj)·Rz(φ_adj)`` about the optical axes
(y down, x right, z forward) with eq. 5's ``adj = exp − now = −now``: the same matrix when ψ_now is the REP-103
pitch and φ_now = −roll, i.e. when the paper's roll is positive leaning left (sphereplan's φ). Fed the REP-103 roll
unchanged, eq. 6 turns the picture the wrong way (a 10° roll ends 20° off); tests/planner/perception/test_eis.py
renders a rolled and pitched camera and checks both.
"""

from __future__ import annotations

import math

import numpy as np

from planner.errors import InvalidInput
from planner.perception.camera_info import CameraInfo
from planner.perception.mount import OPTICAL_IN_BODY, attitude_rep103, check_angle
from planner.perception.opencv import opencv


def eq6_matrix(roll_adj_rad: float, pitch_adj_rad: float, yaw_adj_rad: float) -> np.ndarray:
    """Paper 001 eq. 6–7 as printed: R0 (3, 3) from the adjustments φ_adj, ψ_adj, θ_adj (rad)."""
    sr, cr = math.sin(roll_adj_rad), math.cos(roll_adj_rad)
    sp, cp = math.sin(pitch_adj_rad), math.cos(pitch_adj_rad)
    sy, cy = math.sin(yaw_adj_rad), math.cos(yaw_adj_rad)
    return np.array([[cy * cr + sy * sp * sr, -cy * sr + sy * sp * cr, sy * cp],
                     [cp * sr, cp * cr, -sp],
                     [-sy * cr + cy * sp * sr, sy * sr + cy * sp * cr, cy * cp]])


def correction_rotation(roll_rad: float, pitch_rad: float) -> np.ndarray:
    """R0 (3, 3): the rotation, in the camera's optical frame, that takes the rolled camera's view to the level
    one, for the IMU's REP-103 ``roll_rad`` and ``pitch_rad`` (see the module text; = eq. 6 with φ_adj = roll,
    ψ_adj = −pitch, θ_adj = 0)."""
    return OPTICAL_IN_BODY.T @ attitude_rep103(roll_rad, pitch_rad) @ OPTICAL_IN_BODY


def stabilising_homography(k: np.ndarray, roll_rad: float, pitch_rad: float) -> np.ndarray:
    """Eq. 13's perspective transformation ``T_p = K·R0·K⁻¹`` (3, 3): raw (undistorted) pixel → level pixel."""
    return np.asarray(k, float) @ correction_rotation(roll_rad, pitch_rad) @ np.linalg.inv(k)


def stabilise(image: np.ndarray, info: CameraInfo, roll_rad: float, pitch_rad: float,
              field: str = "image") -> tuple[np.ndarray, np.ndarray]:
    """The level picture of one frame: ``(stabilised, valid)``.

    ``image`` (H, W) or (H, W, C), the raw frame of ``info``'s camera; ``roll_rad``/``pitch_rad`` the IMU's REP-103
    attitude (rad). Undistortion (eq. 8, ``info``'s model and coefficients) and the reprojection ``K·R0·K⁻¹``
    run as one remap with the same K; ``stabilised`` has the image's shape and dtype, black where no raw pixel
    maps; ``valid`` (H, W) bool marks the pixels that came from inside the raw frame."""
    cv2 = opencv()

    check_angle(roll_rad, "roll")
    check_angle(pitch_rad, "pitch")
    a = np.asarray(image)
    if a.ndim not in (2, 3) or a.shape[0] == 0 or a.shape[1] == 0:
        raise InvalidInput(field, f"is not an image (shape {a.shape})")
    h, w = a.shape[:2]
    if (info.width, info.height) != (w, h):
        raise InvalidInput(field, f"is {w} × {h} px, its camera_info calibrates {info.width} × {info.height}")
    r0 = correction_rotation(roll_rad, pitch_rad)
    map_x, map_y = cv2.initUndistortRectifyMap(info.k, info.d, r0, info.k, (w, h), cv2.CV_32FC1)
    out = cv2.remap(a, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    valid = (map_x >= 0) & (map_x <= w - 1) & (map_y >= 0) & (map_y <= h - 1)
    return np.asarray(out), valid
