"""Camera models read from ROS ``camera_info`` YAML files (the ``camera_calibration_parsers`` layout).

A file holds ``image_width``, ``image_height``, ``camera_matrix`` (K, 3 × 3), ``distortion_model``
(``plumb_bob`` or ``rational_polynomial``: paper 001 eq. 8's k1, k2, p1, p2, k3 [, k4, k5, k6]),
``distortion_coefficients`` (D), ``rectification_matrix`` (R, 3 × 3) and ``projection_matrix`` (P, 3 × 4), each
matrix as ``{rows, cols, data}``. As in ROS, the right camera of a stereo pair holds P[0, 3] = −fx'·B (B the
baseline in metres), the left camera P[0, 3] = 0. Anything missing, malformed or non-finite is
:class:`~planner.errors.InvalidInput` naming the option the file came from.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from planner.errors import InvalidInput

#: distortion models OpenCV applies with the coefficients in ROS's order → the coefficient counts they take
DISTORTION_MODELS = {"plumb_bob": (4, 5), "rational_polynomial": (5, 8, 12, 14)}


@dataclass(frozen=True)
class CameraInfo:
    """One calibrated camera (ROS ``sensor_msgs/CameraInfo``): image size in pixels, intrinsic ``k`` (3, 3),
    distortion ``d`` (n,) in ROS's order for ``distortion_model``, rectification ``r`` (3, 3) and projection ``p``
    (3, 4) of the rectified image (pixels)."""

    width: int
    height: int
    k: np.ndarray
    d: np.ndarray
    distortion_model: str
    r: np.ndarray
    p: np.ndarray
    name: str = ""

    @property
    def is_rectified(self) -> bool:
        """True when the raw image already is the rectified one (no distortion, R = I, P's 3 × 3 = K)."""
        return (not np.any(self.d) and np.allclose(self.r, np.eye(3)) and np.allclose(self.p[:, :3], self.k))

    @property
    def rectified_k(self) -> np.ndarray:
        """The rectified camera's intrinsic matrix (P's left 3 × 3), pixels."""
        return np.array(self.p[:, :3], dtype=float)


def _matrix(doc: dict[str, Any], key: str, shape: tuple[int, int] | None, field: str) -> np.ndarray:
    entry = doc.get(key)
    if not isinstance(entry, dict) or "data" not in entry:
        raise InvalidInput(field, f"'{key}' is missing or not a {{rows, cols, data}} mapping")
    try:
        data = np.asarray(entry["data"], dtype=float).ravel()
    except (TypeError, ValueError, OverflowError):
        raise InvalidInput(field, f"'{key}.data' is not a list of numbers") from None
    if not np.all(np.isfinite(data)):
        raise InvalidInput(field, f"'{key}.data' holds a non-finite number")
    if shape is None:
        return data
    if data.size != shape[0] * shape[1]:
        raise InvalidInput(field, f"'{key}' needs {shape[0] * shape[1]} numbers, has {data.size}")
    return data.reshape(shape)


def camera_info_from_dict(doc: Any, field: str = "camera_info") -> CameraInfo:
    """A :class:`CameraInfo` from a parsed camera_info document; errors name ``field``."""
    if not isinstance(doc, dict):
        raise InvalidInput(field, "is not a camera_info mapping (image_width, image_height, camera_matrix, ...)")
    size = []
    for key in ("image_width", "image_height"):
        value = doc.get(key)
        if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
            raise InvalidInput(field, f"'{key}' must be a positive integer, got {value!r}")
        size.append(value)
    k = _matrix(doc, "camera_matrix", (3, 3), field)
    if k[0, 0] <= 0 or k[1, 1] <= 0 or k[2, 2] != 1 or k[2, 0] != 0 or k[2, 1] != 0:
        raise InvalidInput(field, "'camera_matrix' must be [fx 0 cx; 0 fy cy; 0 0 1] with fx, fy > 0")
    model = doc.get("distortion_model", "plumb_bob")
    if not isinstance(model, str) or model not in DISTORTION_MODELS:
        raise InvalidInput(field, f"'distortion_model' {model!r} is not one of {', '.join(DISTORTION_MODELS)}")
    d = _matrix(doc, "distortion_coefficients", None, field) if "distortion_coefficients" in doc else np.zeros(5)
    if d.size and d.size not in DISTORTION_MODELS[model]:
        counts = " or ".join(map(str, DISTORTION_MODELS[model]))
        raise InvalidInput(field, f"'distortion_coefficients' has {d.size} numbers; {model} takes {counts}")
    r = _matrix(doc, "rectification_matrix", (3, 3), field) if "rectification_matrix" in doc else np.eye(3)
    if not np.allclose(r @ r.T, np.eye(3), atol=1e-4) or np.linalg.det(r) <= 0:
        raise InvalidInput(field, "'rectification_matrix' is not a rotation")
    if "projection_matrix" in doc:
        p = _matrix(doc, "projection_matrix", (3, 4), field)
    else:
        p = np.hstack([k, np.zeros((3, 1))])
    if p[0, 0] <= 0 or p[1, 1] <= 0 or p[2, 2] != 1:
        raise InvalidInput(field, "'projection_matrix' must be [fx' 0 cx' Tx; 0 fy' cy' Ty; 0 0 1 0] with fx', fy' > 0")
    name = doc.get("camera_name", "")
    return CameraInfo(size[0], size[1], k, d, model, r, p, name if isinstance(name, str) else "")


def read_camera_info(path: str | Path, field: str = "--camera-info") -> CameraInfo:
    """Read a camera_info YAML file; an unreadable or malformed file is :class:`InvalidInput` naming ``field``."""
    import yaml

    p = Path(path)
    if not p.is_file():
        raise InvalidInput(field, f"file {p} does not exist")
    try:
        doc = yaml.safe_load(p.read_text())
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        raise InvalidInput(field, f"{p} is not readable YAML: {str(exc).splitlines()[0]}") from None
    except OSError as exc:
        raise InvalidInput(field, f"cannot read {p}: {exc.strerror or exc}") from None
    return camera_info_from_dict(doc, field)


def stereo_baseline_m(left: CameraInfo, right: CameraInfo, field: str = "--right-info") -> float:
    """The baseline B (m) of a rectified pair from the right camera's P[0, 3] = −fx'·B (ROS's convention).

    The left camera must have P[0, 3] = 0 and both the same rectified fx', fy' and cy' (a row-aligned pair)."""
    if abs(left.p[0, 3]) > 1e-9 * max(1.0, abs(left.p[0, 0])):
        raise InvalidInput(field.replace("right", "left"), "the left camera's projection_matrix must have Tx = 0")
    if not (np.isclose(left.p[0, 0], right.p[0, 0]) and np.isclose(left.p[1, 1], right.p[1, 1])
            and np.isclose(left.p[1, 2], right.p[1, 2])):
        raise InvalidInput(field, "the rectified pair must share fx', fy' and cy' (projection_matrix)")
    baseline = -right.p[0, 3] / right.p[0, 0]
    if not math.isfinite(baseline) or baseline <= 0:
        raise InvalidInput(field, f"projection_matrix Tx = {right.p[0, 3]:g} must be −fx'·baseline < 0 for the "
                                  "right camera of a pair")
    return float(baseline)
