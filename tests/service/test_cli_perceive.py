"""``sphereplan perceive``: files in, map-frame obstacle points out (JSON and ROS 2 PointCloud2 in MCAP); bad input
exits 2 naming the option."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from PIL import Image
from rosbags.typesys import Stores, get_typestore

from lab.perception_render import obstacle_course, render_pair, write_pair
from planner.perception import perceive
from planner.perception.camera_info import camera_info_from_dict
from service.cli import main

TS = get_typestore(Stores.ROS2_HUMBLE)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("pair")
    pair = render_pair(obstacle_course(), 270, 206, supersample=1)
    return pair, write_pair(pair, folder), folder


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def args(paths, *extra):
    return ["perceive", "--left", paths["left_png"], "--right", paths["right_png"], "--left-info",
            paths["left_yaml"], "--right-info", paths["right_yaml"], *extra]


def test_prints_the_points_the_library_finds(files, capsys) -> None:
    pair, paths, _ = files
    code, out, err = run(capsys, *args(paths, "--pose", 1.0, 2.0, 0.0, "-q"))
    assert code == 0, err
    result = json.loads(out)
    scan = perceive(pair.left.image, pair.right.image, camera_info_from_dict(pair.left_info),
                    camera_info_from_dict(pair.right_info), (1.0, 2.0, 0.0))
    points = np.array(result["points_map"])
    assert points.shape == (len(scan.points_map), 3) and len(points) > 50
    np.testing.assert_allclose(points, scan.points_map, atol=1e-4)
    np.testing.assert_allclose(result["origin_map"], [1.0, 2.25, 0.3], atol=1e-6)
    assert result["baseline_m"] == pytest.approx(0.5)
    assert set(result["dropped"]) == {"below_ground", "ground", "suspended", "too_far", "small_blob"}
    assert result["timings_s"]["total"] > 0 and result["pose"] == {"x": 1.0, "y": 2.0, "yaw": 0.0}


def test_degrees_and_filters(files, capsys) -> None:
    _, paths, _ = files
    code, out, err = run(capsys, *args(paths, "--pose", 0, 0, 90, "--degrees", "--roll", 2, "-q"))
    assert code == 0, err
    result = json.loads(out)
    assert result["pose"]["yaw"] == pytest.approx(math.pi / 2) and result["roll"] == pytest.approx(math.radians(2))
    code, out, err = run(capsys, *args(paths, "--pose", 0, 0, 0, "--max-range", 5, "-q"))
    assert code == 0, err
    result = json.loads(out)
    assert result["filters"]["max_range_m"] == 5.0
    assert result["count"] == 0 and result["dropped"]["too_far"] > 0  # the box is 9 m ahead: beyond 5 m


def test_mcap_holds_a_pointcloud2_of_the_same_points(files, capsys, tmp_path) -> None:
    _, paths, _ = files
    mcap = tmp_path / "points.mcap"
    code, out, err = run(capsys, *args(paths, "--pose", 0, 0, 0, "--out", mcap, "-q"))
    assert code == 0, err
    points = np.array(json.loads(out)["points_map"])
    topics = {}
    with open(mcap, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            topics[channel.topic] = (schema.name, TS.deserialize_cdr(message.data, schema.name))
    name, cloud = topics["/perception/obstacles"]
    assert name == "sensor_msgs/msg/PointCloud2" and cloud.header.frame_id == "map"
    assert cloud.width == len(points) and cloud.height == 1 and cloud.point_step == 12
    assert [(f.name, f.offset, f.datatype) for f in cloud.fields] == [("x", 0, 7), ("y", 4, 7), ("z", 8, 7)]
    decoded = np.frombuffer(cloud.data.tobytes(), dtype="<f4").reshape(-1, 3)
    np.testing.assert_allclose(decoded, points, atol=1e-4)
    name, origin = topics["/perception/origin"]
    assert name == "geometry_msgs/msg/PointStamped"
    assert (origin.point.x, origin.point.y, origin.point.z) == pytest.approx((0.0, 0.25, 0.3))


def test_plot_and_disparity_files(files, capsys, tmp_path) -> None:
    _, paths, _ = files
    code, out, err = run(capsys, *args(paths, "--pose", 0, 0, 0, "--plot", tmp_path / "p.png", "--disparity",
                                       tmp_path / "d.png", "-q"))
    assert code == 0, err
    assert Image.open(tmp_path / "p.png").size[0] > 500
    d16 = np.asarray(Image.open(tmp_path / "d.png"))
    assert d16.shape == (206, 270) and d16.max() > 16  # 1/16 px fixed point, as OpenCV computes it
    code, _, err = run(capsys, *args(paths, "--pose", 0, 0, 0, "--disparity", tmp_path / "d.npy", "-q"))
    assert code == 0, err
    d = np.load(tmp_path / "d.npy")
    valid = d16 > 0
    np.testing.assert_allclose(d[valid], d16[valid] / 16.0, atol=1 / 32)
    assert np.all(np.isnan(d[~valid]))


def test_mismatched_image_sizes_exit_2_naming_the_field(files, capsys, tmp_path) -> None:
    _, paths, _ = files
    small = tmp_path / "small.png"
    Image.open(paths["right_png"]).crop((0, 0, 200, 206)).save(small)
    code, _, err = run(capsys, *args({**paths, "right_png": small}, "--pose", 0, 0, 0))
    assert code == 2 and "--right" in err and "mismatched image sizes" in err and "Traceback" not in err


@pytest.mark.parametrize("content, message", [
    ("image_width: [not, a, number\n", "not readable YAML"),
    ("image_width: 270\nimage_height: 206\n", "'camera_matrix' is missing"),
    (None, "does not exist"),
])
def test_an_unreadable_calibration_exits_2_naming_the_field(files, capsys, tmp_path, content, message) -> None:
    _, paths, _ = files
    bad = tmp_path / "bad.yaml"
    if content is not None:
        bad.write_text(content)
    code, _, err = run(capsys, *args({**paths, "left_yaml": bad}, "--pose", 0, 0, 0))
    assert code == 2 and "--left-info" in err and message in err, err


def test_a_calibration_with_a_nan_exits_2(files, capsys, tmp_path) -> None:
    _, paths, _ = files
    doc = yaml.safe_load(paths["right_yaml"].read_text())
    doc["projection_matrix"]["data"][3] = float("nan")
    bad = tmp_path / "nan.yaml"
    bad.write_text(yaml.safe_dump(doc))
    code, _, err = run(capsys, *args({**paths, "right_yaml": bad}, "--pose", 0, 0, 0))
    assert code == 2 and "--right-info" in err and "non-finite" in err


@pytest.mark.parametrize("extra, field", [
    (["--pose", 0, 0, "nan"], "--pose"),
    (["--pose", 0, 0, 0, "--roll", "nan"], "--roll"),
    (["--pose", 0, 0, 7.0], "--pose YAW"),
    (["--pose", 0, 0, 0, "--pitch", -7.0], "--pitch"),
    (["--pose", 0, 0, 0, "--num-disparities", 40], "--num-disparities"),
    (["--pose", 0, 0, 0, "--block-size", 4], "--block-size"),
    (["--pose", 0, 0, 0, "--min-blob", 0], "--min-blob"),
    (["--pose", 0, 0, 0, "--out", "."], "--out"),  # a folder, not a file
])
def test_bad_numbers_exit_2_naming_the_field(files, capsys, extra, field) -> None:
    _, paths, _ = files
    code, _, err = run(capsys, *args(paths, *extra))
    assert code == 2 and field in err and "Traceback" not in err, err


def test_an_unreadable_image_exits_2(files, capsys, tmp_path) -> None:
    _, paths, _ = files
    junk = tmp_path / "junk.png"
    junk.write_bytes(b"not a png")
    code, _, err = run(capsys, *args({**paths, "left_png": junk}, "--pose", 0, 0, 0))
    assert code == 2 and "--left" in err and "not a readable image" in err
