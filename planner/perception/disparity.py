"""Disparity of a rectified stereo pair by Semi-Global Block Matching (paper 001 §3.2, OpenCV's StereoSGBM).

The paper: "The Semi-Global Matching algorithm is a classic high-precision stereo matching algorithm [17], which
is implemented in the form of Semi-Global Block Matching (SGBM) algorithm in OpenCV. Based on this algorithm, we
can conveniently and accurately obtain the disparity map of images from two cameras". Images that are not yet
rectified are undistorted (eq. 8's plumb-bob model) and rectified with their camera_info's R and P first, as
ROS's ``image_proc`` does.

The disparity search range follows from the nearest depth of interest: ``d_max = fx'·B / min_depth_m``, rounded
up to a multiple of 16 (OpenCV's requirement). Pixels nearer than that are not measured; the paper's
below-ground filter removes what SGBM mismatches there on the ground (a ray that meets the ground, extended
further, runs under it).
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.errors import InvalidInput
from planner.perception.camera_info import CameraInfo
from planner.perception.opencv import opencv

#: StereoSGBM modes by name (OpenCV constants): 5 directions single pass, 8 directions (two passes), 3-way
MODES = {"sgbm": 0, "hh": 1, "3way": 2, "hh4": 3}


@dataclass(frozen=True)
class StereoOptions:
    """StereoSGBM's parameters (OpenCV names). ``num_disparities`` None = from ``min_depth_m`` (m, the nearest
    depth searched); ``p1``/``p2`` None = OpenCV's usual 8·block² and 32·block² smoothness penalties. The 3 × 3
    block is OpenCV's own SGBM example's; 5 × 5 and larger smear the disparity of the grazing ground near an
    obstacle's foot far enough (3–4 px at 10 m) to lift ground points over the 5 cm threshold.

    OpenCV matches no pixel of the left image's first ``num_disparities`` columns (the search would leave the
    right image): at 541 × 413 with 144 disparities the left 27 % of the view is blind. ``full_width`` pads both
    images on the left with that many black columns so those pixels are matched too (near points there, whose
    match would lie outside the right image, meet black and mostly find none); it costs about a quarter more
    SGBM time."""

    min_depth_m: float = 1.5
    num_disparities: int | None = None
    block_size: int = 3
    p1: int | None = None
    p2: int | None = None
    uniqueness_ratio: int = 10
    speckle_window_size: int = 100
    speckle_range: int = 2
    disp12_max_diff: int = 1
    pre_filter_cap: int = 31
    mode: str = "sgbm"
    full_width: bool = False

    def __post_init__(self) -> None:
        if not (math.isfinite(self.min_depth_m) and self.min_depth_m > 0):
            raise InvalidInput("min_depth_m", "must be a positive number of metres")
        if self.num_disparities is not None and (self.num_disparities < 16 or self.num_disparities % 16):
            raise InvalidInput("num_disparities", "must be a positive multiple of 16")
        if self.block_size < 1 or self.block_size % 2 == 0:
            raise InvalidInput("block_size", "must be an odd number ≥ 1")
        if self.mode not in MODES:
            raise InvalidInput("mode", f"must be one of {', '.join(MODES)}")

    def disparities_for(self, fx_px: float, baseline_m: float) -> int:
        """The number of disparities searched: given, or ⌈fx'·B / min_depth / 16⌉·16."""
        if self.num_disparities is not None:
            return self.num_disparities
        return max(16, 16 * math.ceil(fx_px * baseline_m / self.min_depth_m / 16))


def to_grey(image: np.ndarray, field: str) -> np.ndarray:
    """An 8-bit single-channel copy of ``image`` ((H, W) or (H, W, 3|4) uint8/uint16/float in [0, 255])."""
    cv2 = opencv()

    a = np.asarray(image)
    if a.ndim == 3 and a.shape[2] in (3, 4):
        a = cv2.cvtColor(np.ascontiguousarray(a[:, :, :3]), cv2.COLOR_BGR2GRAY)
    if a.ndim != 2 or a.size == 0:
        raise InvalidInput(field, f"is not an image (shape {a.shape})")
    if a.dtype == np.uint16:
        a = (a >> 8).astype(np.uint8)
    elif a.dtype != np.uint8:
        if not np.all(np.isfinite(a)):
            raise InvalidInput(field, "holds non-finite pixel values")
        a = np.clip(np.rint(a), 0, 255).astype(np.uint8)
    return np.ascontiguousarray(a)


def rectify(image: np.ndarray, info: CameraInfo) -> np.ndarray:
    """The rectified image of ``info``'s camera (unchanged when it already is: no distortion, R = I, P = K)."""
    cv2 = opencv()

    if info.is_rectified:
        return image
    maps = cv2.initUndistortRectifyMap(info.k, info.d, info.r, info.rectified_k, (info.width, info.height),
                                       cv2.CV_32FC1)
    return np.asarray(cv2.remap(image, maps[0], maps[1], cv2.INTER_LINEAR))


_matchers = threading.local()  # one matcher per thread and settings: it keeps its work buffers between frames


def _matcher(num_disparities: int, options: StereoOptions) -> Any:
    cv2 = opencv()

    cache = _matchers.__dict__.setdefault("cache", {})
    key = (num_disparities, options)
    if key not in cache:
        bs = options.block_size
        cache.clear()
        cache[key] = cv2.StereoSGBM.create(
            minDisparity=0, numDisparities=num_disparities, blockSize=bs,
            P1=options.p1 if options.p1 is not None else 8 * bs * bs,
            P2=options.p2 if options.p2 is not None else 32 * bs * bs,
            disp12MaxDiff=options.disp12_max_diff, preFilterCap=options.pre_filter_cap,
            uniquenessRatio=options.uniqueness_ratio, speckleWindowSize=options.speckle_window_size,
            speckleRange=options.speckle_range, mode=MODES[options.mode])
    return cache[key]


def sgbm_disparity(left: np.ndarray, right: np.ndarray, num_disparities: int, options: StereoOptions) -> np.ndarray:
    """Disparity (H, W) float32 in pixels of the rectified grey pair (left as reference); NaN where SGBM found
    no match. OpenCV's fixed-point output (1/16 px) is divided out."""
    if options.full_width:
        cv2 = opencv()

        pad = num_disparities
        left = cv2.copyMakeBorder(left, 0, 0, pad, 0, cv2.BORDER_CONSTANT, value=0)
        right = cv2.copyMakeBorder(right, 0, 0, pad, 0, cv2.BORDER_CONSTANT, value=0)
        raw = _matcher(num_disparities, options).compute(left, right)[:, pad:]
    else:
        raw = _matcher(num_disparities, options).compute(left, right)
    disparity = raw.astype(np.float32) / 16.0
    disparity[raw <= 0] = np.nan  # invalid (minDisparity − 1) and zero disparity (a point at infinity)
    return disparity
