"""From disparity to 3-D points in the left camera's frame: the pinhole model of paper 001 eq. 9 inverted.

For a rectified pair with the left camera's projection ``[fx 0 cx 0; 0 fy cy 0; 0 0 1 0]`` and the right's
``[fx 0 cx' −fx·B; …]``, a pixel (u, v) of the left image with disparity d (px) sees the point

    Z = fx·B / (d − (cx − cx')),   X = (u − cx)·Z / fx,   Y = (v − cy)·Z / fy

in the left rectified optical frame (x right, y down, z forward, metres): the paper's ``P̃_c``. Only points with
Z > 0 exist: a disparity that would put a point behind the cameras (d ≤ cx − cx') gives none.
"""

from __future__ import annotations

import numpy as np


def points_from_disparity(disparity: np.ndarray, fx: float, fy: float, cx: float, cy: float, baseline_m: float,
                          cx_right: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Camera-frame points (N, 3) float64 of the valid pixels of ``disparity`` (H, W) px (NaN = no match), and
    their pixel indices (N, 2) as (row, column), in row-major order. ``cx_right`` None = the left camera's cx."""
    d = np.asarray(disparity, dtype=np.float32)
    shift = 0.0 if cx_right is None else cx - cx_right
    with np.errstate(invalid="ignore"):
        valid = d > shift  # NaN compares False
    flat = np.flatnonzero(valid)
    rows, cols = np.divmod(flat, d.shape[1])
    z = (fx * baseline_m) / (d.ravel()[flat].astype(np.float64) - shift)
    out = np.empty((len(flat), 3))
    out[:, 0] = (cols - cx) * (z / fx)
    out[:, 1] = (rows - cy) * (z / fy)
    out[:, 2] = z
    return out, np.stack([rows, cols], axis=1)
