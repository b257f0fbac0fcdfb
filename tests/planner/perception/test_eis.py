"""Electronic image stabilisation (paper 001 §3.3) checked by rendering, not by reading the equations.

A camera rolled 10° and pitched 5° (REP-103, as its IMU reports) renders the horizon scene; stabilised, its frame
must match the level camera's render: normalised cross-correlation ≥ 0.9 over the shared field of view and a
horizon tilted by at most 0.5°. The printed eq. 6 fed the REP-103 roll unchanged must fail the same check (so the
check can tell the signs apart), and equal ours with the paper's roll taken positive leaning left.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lab.perception_render import camera_info, camera_with_attitude, horizon_scene, render
from planner.errors import InvalidInput
from planner.perception.camera_info import camera_info_from_dict
from planner.perception.eis import correction_rotation, eq6_matrix, stabilise, stabilising_homography
from planner.perception.imu_log import read_imu_csv

W, H, FOV = 541, 413, 70.0
ROLL, PITCH = math.radians(10.0), math.radians(5.0)
POSITION = (0.0, 0.0, 0.3)


@pytest.fixture(scope="module")
def frames():
    scene = horizon_scene()
    level_cam = camera_with_attitude(W, H, FOV, POSITION, 0.0, 0.0)
    level = render(level_cam, scene)
    rolled = render(camera_with_attitude(W, H, FOV, POSITION, ROLL, PITCH), scene)
    return level, rolled, camera_info_from_dict(camera_info("camera", level_cam))


def ncc(a: np.ndarray, b: np.ndarray, mask: np.ndarray) -> float:
    x, y = a[mask].astype(float), b[mask].astype(float)
    x -= x.mean()
    y -= y.mean()
    return float((x * y).sum() / math.sqrt((x * x).sum() * (y * y).sum()))


def shared_view(valid: np.ndarray) -> np.ndarray:
    """The stabilised frame's pixels that came from inside the raw one, 2 px in from the edge of that region."""
    import cv2

    return cv2.erode(valid.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)


def horizon_tilt_deg(image: np.ndarray, valid: np.ndarray) -> float:
    """The horizon's angle to the image rows (deg): per column, the first row from the top where the plain sky
    (grey 235) gives way to the ground, found to a sub-pixel by the crossing of grey 200; the straight line most
    columns agree on within 1 px (RANSAC over pairs of columns, seeded: boxes standing over the horizon hide it in
    their columns) is then fitted to those columns by least squares."""
    img = image.astype(float)
    us, vs = [], []
    for u in range(0, image.shape[1], 2):
        col, ok = img[:, u], valid[:, u]
        top = np.argmax(ok)
        if not ok.any() or abs(col[top] - 235) > 1:  # the column must start in the sky
            continue
        below = np.nonzero(ok & (np.arange(len(col)) > top) & (col < 200))[0]
        if len(below) == 0:
            continue
        v = below[0]
        frac = (col[v - 1] - 200) / (col[v - 1] - col[v])
        us.append(u)
        vs.append(v - 1 + frac)
    u, v = np.array(us, float), np.array(vs)
    rng = np.random.default_rng(0)
    best = np.zeros(len(u), bool)
    for _ in range(300):
        i, j = rng.choice(len(u), 2, replace=False)
        if u[i] == u[j]:
            continue
        slope = (v[j] - v[i]) / (u[j] - u[i])
        inliers = np.abs(v - (v[i] + slope * (u - u[i]))) < 1.0
        if inliers.sum() > best.sum():
            best = inliers
    assert best.sum() > 60, "the horizon must be visible across much of the frame"
    slope, _ = np.polyfit(u[best], v[best], 1)
    return math.degrees(math.atan(slope))


def test_the_level_render_has_a_level_horizon_at_cy(frames) -> None:
    level, _, info = frames
    assert abs(horizon_tilt_deg(level.image, np.ones_like(level.image, bool))) < 0.05


def test_rolled_and_pitched_frame_stabilises_to_the_level_render(frames) -> None:
    level, rolled, info = frames
    raw_tilt = horizon_tilt_deg(rolled.image, np.ones_like(rolled.image, bool))
    assert abs(raw_tilt) > 7  # the raw frame is visibly rolled (10° about the optical axis, seen pitched 5°)
    out, valid = stabilise(rolled.image, info, ROLL, PITCH)
    shared = shared_view(valid)
    assert shared.mean() > 0.7
    assert ncc(out, level.image, shared) >= 0.9
    assert abs(horizon_tilt_deg(out, shared)) <= 0.5


def test_the_printed_eq6_with_rep103_roll_turns_the_wrong_way(frames) -> None:
    import cv2

    level, rolled, info = frames
    r0 = eq6_matrix(-ROLL, -PITCH, 0.0)  # eq. 5: adj = exp − now = −now, with REP-103 angles as they come
    h = info.k @ r0 @ np.linalg.inv(info.k)
    out = cv2.warpPerspective(rolled.image, h, (W, H))
    valid = cv2.warpPerspective(np.ones((H, W), np.uint8), h, (W, H)).astype(bool)
    shared = shared_view(valid)
    assert ncc(out, level.image, shared) < 0.8
    assert abs(horizon_tilt_deg(out, shared)) > 15  # 10° roll made 20°


def test_r0_is_eq6_with_the_papers_roll_positive_leaning_left() -> None:
    rng = np.random.default_rng(2)
    for roll, pitch in rng.uniform(-0.5, 0.5, (20, 2)):
        # eq. 5 with now = (φ = −roll, ψ = pitch): adj = (roll, −pitch)
        np.testing.assert_allclose(correction_rotation(roll, pitch), eq6_matrix(roll, -pitch, 0.0), atol=1e-12)
        r0 = correction_rotation(roll, pitch)
        np.testing.assert_allclose(r0 @ r0.T, np.eye(3), atol=1e-12)


def test_homography_is_eq13(frames) -> None:
    _, _, info = frames
    h = stabilising_homography(info.k, ROLL, PITCH)
    np.testing.assert_allclose(h, info.k @ correction_rotation(ROLL, PITCH) @ np.linalg.inv(info.k))


def test_zero_attitude_only_undistorts(frames) -> None:
    """With roll = pitch = 0 the remap is eq. 8's undistortion alone: OpenCV's undistort of the same frame."""
    import cv2

    level, _, info = frames
    from dataclasses import replace

    distorted = replace(info, d=np.array([-0.2, 0.05, 0.001, -0.001, 0.0]))
    out, valid = stabilise(level.image, distorted, 0.0, 0.0)
    expected = cv2.undistort(level.image, distorted.k, distorted.d)
    inner = shared_view(valid)
    diff = np.abs(out[inner].astype(int) - expected[inner].astype(int))  # OpenCV's undistort interpolates in
    assert diff.max() <= 4 and (diff <= 1).mean() > 0.995  # fixed point (1/32 px), the remap in floats
    same, _ = stabilise(level.image, info, 0.0, 0.0)
    np.testing.assert_array_equal(same, level.image)


def test_bad_frames_and_angles_name_the_field(frames) -> None:
    level, _, info = frames
    with pytest.raises(InvalidInput, match="roll"):
        stabilise(level.image, info, float("nan"), 0.0)
    with pytest.raises(InvalidInput, match=r"pitch.*degrees"):
        stabilise(level.image, info, 0.0, 10.0)
    with pytest.raises(InvalidInput, match=r"image.*540 × 413"):
        stabilise(level.image[:, :-1], info, 0.0, 0.0)


def test_imu_log(tmp_path) -> None:
    path = tmp_path / "imu.csv"
    path.write_text("time,roll,pitch\n0.0,0.0,0.0\n1.0,10,-4\n2.0,20,-8\n")
    log = read_imu_csv(path, degrees=True)
    roll, pitch = log.at_frames(3, fps=2.0)  # frames at 0, 0.5, 1.0 s
    np.testing.assert_allclose(np.degrees(roll), [0, 5, 10])
    np.testing.assert_allclose(np.degrees(pitch), [0, -2, -4])
    roll, _ = log.at_frames(3, fps=None)  # one row per frame
    np.testing.assert_allclose(np.degrees(roll), [0, 10, 20])
    with pytest.raises(InvalidInput, match="3 rows for 2 frames"):
        log.at_frames(2, fps=None)
    with pytest.raises(InvalidInput, match="ends at 2 s"):
        log.at_frames(6, fps=2.0)
    for text, message in (("0,nan,0\n", "row 1: roll"), ("0,0\n", "row 1 has 2 columns"),
                          ("0,0,0\n0,0,0\n", "time must increase"), ("0,0,x\n", "pitch 'x' is not a number"),
                          ("0,7,0\n", "row 1 roll.*degrees")):
        path.write_text(text)
        with pytest.raises(InvalidInput, match=message):
            read_imu_csv(path)
