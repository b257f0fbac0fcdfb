"""The test renderer's geometry is exact: the truth the perception tests measure against.

Checked against closed forms that do not use the renderer's own code paths: the ground seen by a level camera at
height h lies at depth Z = fy·h / (v − cy); every landing point projects back into its own pixel; a stereo pair's
right camera sees each left landing point at u − fx·B / Z on the same row; the box's front face lies at x = 9 m.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lab.perception_render import (
    BOX_AHEAD,
    Box,
    Scene,
    camera_on_sphere,
    camera_with_attitude,
    obstacle_course,
    render,
    render_pair,
    value_noise,
)

W, H = 160, 120


@pytest.fixture(scope="module")
def pair():
    return render_pair(obstacle_course(), W, H, supersample=1)


def test_level_ground_depth_is_the_closed_form(pair) -> None:
    cam, left = pair.left_camera, pair.left
    rows = np.arange(H)
    for v in rows[rows > cam.cy + 3]:
        ground = left.hit[v] == 0
        expected = cam.fy * 0.30 / (v - cam.cy)
        np.testing.assert_allclose(left.depth[v, ground], expected, rtol=1e-12)
        np.testing.assert_allclose(left.points[v, ground, 2], 0.0, atol=1e-12)


def test_every_landing_point_projects_back_into_its_pixel(pair) -> None:
    for cam, rend in ((pair.left_camera, pair.left), (pair.right_camera, pair.right)):
        seen = rend.hit >= 0
        uv = cam.project(rend.points[seen])
        v, u = np.nonzero(seen)
        np.testing.assert_allclose(uv[:, 0], u, atol=1e-9)
        np.testing.assert_allclose(uv[:, 1], v, atol=1e-9)


def test_the_pair_is_rectified_with_the_baseline_in_the_right_projection(pair) -> None:
    seen = pair.left.hit >= 0
    points = pair.left.points[seen]
    v, u = np.nonzero(seen)
    z = pair.left.depth[seen]
    uv_right = pair.right_camera.project(points)
    fx = pair.left_camera.fx
    np.testing.assert_allclose(uv_right[:, 1], v, atol=1e-9)  # same row
    np.testing.assert_allclose(u - uv_right[:, 0], fx * 0.5 / z, rtol=1e-9)  # disparity = fx·B / Z
    assert pair.right_info["projection_matrix"]["data"][3] == pytest.approx(-fx * 0.5)
    np.testing.assert_allclose(pair.right_camera.position - pair.left_camera.position, [0, -0.5, 0], atol=1e-12)


def test_the_box_face_is_where_the_scene_says(pair) -> None:
    box = obstacle_course().objects.index(BOX_AHEAD)
    on_box = pair.left.hit == box
    assert on_box.sum() > 20
    np.testing.assert_allclose(pair.left.points[on_box][:, 0], 9.0, atol=1e-9)
    assert np.all(np.abs(pair.left.points[on_box][:, 1]) <= 0.8 + 1e-9)


def test_a_leaning_sphere_lowers_its_left_camera() -> None:
    lean = math.radians(10)
    left = camera_on_sphere(W, H, 70, 0, 0, 0, 0.3, 0.25, lean_left_rad=lean)
    np.testing.assert_allclose(left.position, [0, 0.25 * math.cos(lean), 0.3 - 0.25 * math.sin(lean)], atol=1e-12)
    # the camera's "up" (−optical y) tips toward the robot's left (+y)
    assert -left.rotation[1, 1] > 0


def test_rep103_roll_turns_the_right_side_down() -> None:
    cam = camera_with_attitude(W, H, 70, (0, 0, 1), math.radians(10), 0.0)
    right_axis = cam.rotation[:, 0]  # optical x = the camera's right
    assert right_axis[2] < 0


def test_texture_is_solid_and_deterministic() -> None:
    p = np.random.default_rng(0).uniform(-5, 5, (500, 3))
    a, b = value_noise(p, 0.1, 3), value_noise(p, 0.1, 3)
    np.testing.assert_array_equal(a, b)
    assert 0 <= a.min() and a.max() <= 1 and a.std() > 0.05
    assert not np.array_equal(a, value_noise(p, 0.1, 4))  # another seed, another pattern


def test_nothing_hit_is_sky() -> None:
    scene = Scene((Box("far", (100, -1, -1), (101, 1, 1)),))
    cam = camera_with_attitude(W, H, 70, (0, 0, 0), 0, 0, math.pi)  # looking away from the box
    rend = render(cam, scene, supersample=1)
    assert np.all(rend.hit == -1) and np.all(np.isinf(rend.depth)) and np.all(rend.image == 235)
