"""``sphereplan stabilise``: one frame and a folder of frames with an IMU CSV, against the level render; bad input
exits 2 naming the option."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import yaml
from PIL import Image

from lab.perception_render import camera_info, camera_with_attitude, horizon_scene, render
from service.cli import main

W, H = 270, 206
ATTITUDES = ((6.0, -3.0), (-8.0, 4.0), (0.0, 0.0))  # degrees


def ncc(a, b, mask):
    x, y = a[mask].astype(float), b[mask].astype(float)
    x -= x.mean()
    y -= y.mean()
    return float((x * y).sum() / math.sqrt((x * x).sum() * (y * y).sum()))


@pytest.fixture(scope="module")
def scene_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("eis")
    scene = horizon_scene()
    level_cam = camera_with_attitude(W, H, 70, (0, 0, 0.3), 0, 0)
    level = render(level_cam, scene, supersample=1).image
    (folder / "camera.yaml").write_text(yaml.safe_dump(camera_info("camera", level_cam)))
    frames = folder / "frames"
    frames.mkdir()
    rows = ["time,roll,pitch"]
    for i, (roll, pitch) in enumerate(ATTITUDES):
        cam = camera_with_attitude(W, H, 70, (0, 0, 0.3), math.radians(roll), math.radians(pitch))
        Image.fromarray(render(cam, scene, supersample=1).image).save(frames / f"f{i}.png")
        rows.append(f"{0.1 * i},{roll},{pitch}")
    (folder / "imu.csv").write_text("\n".join(rows) + "\n")
    return folder, level


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_one_frame_is_levelled(scene_files, capsys) -> None:
    folder, level = scene_files
    out = folder / "one.png"
    code, stdout, err = run(capsys, "stabilise", "--image", folder / "frames" / "f0.png", "--roll", 6, "--pitch", -3,
                            "--degrees", "--camera-info", folder / "camera.yaml", "--out", out)
    assert code == 0, err
    summary = json.loads(stdout)
    assert summary["roll"] == pytest.approx(math.radians(6)) and summary["valid_fraction"] > 0.8
    result = np.asarray(Image.open(out))
    mask = result > 0
    raw = np.asarray(Image.open(folder / "frames" / "f0.png"))
    assert ncc(result, level, mask) > 0.9 > ncc(raw, level, mask)


def test_a_folder_with_an_imu_csv(scene_files, capsys) -> None:
    folder, level = scene_files
    out = folder / "stable"
    code, stdout, err = run(capsys, "stabilise", "--frames", folder / "frames", "--imu", folder / "imu.csv",
                            "--degrees", "--camera-info", folder / "camera.yaml", "--out-dir", out, "-q")
    assert code == 0, err
    assert json.loads(stdout)["frames"] == len(ATTITUDES)
    for i in range(len(ATTITUDES)):
        result = np.asarray(Image.open(out / f"f{i}.png"))
        assert ncc(result, level, result > 0) > 0.9
    # with --fps the frames are taken at 0, 0.05, 0.1 s: the middle one halfway between rows 0 and 1
    code, stdout, err = run(capsys, "stabilise", "--frames", folder / "frames", "--imu", folder / "imu.csv",
                            "--fps", 20, "--degrees", "--camera-info", folder / "camera.yaml", "--out-dir", out, "-q")
    assert code == 0, err
    middle = json.loads(stdout)["stabilised"][1]
    assert middle["roll"] == pytest.approx(math.radians(-1.0), abs=1e-6)


@pytest.mark.parametrize("extra, field", [
    (["--roll", "nan", "--pitch", 0], "--roll"),
    (["--roll", 0, "--pitch", "nan"], "--pitch"),
    (["--roll", 10, "--pitch", 0], "--roll"),  # 10 rad: degrees given as radians
    (["--pitch", 0], "--roll"),
    (["--roll", 0, "--pitch", 0, "--imu", "x.csv"], "--imu"),
    (["--roll", 0, "--pitch", 0, "--out-dir", "x"], "--out-dir"),
])
def test_bad_angles_exit_2_naming_the_field(scene_files, capsys, extra, field) -> None:
    folder, _ = scene_files
    code, _, err = run(capsys, "stabilise", "--image", folder / "frames" / "f0.png", *extra, "--camera-info",
                       folder / "camera.yaml", "--out", folder / "x.png")
    assert code == 2 and field in err and "Traceback" not in err, err


def test_bad_files_exit_2_naming_the_field(scene_files, capsys, tmp_path) -> None:
    folder, _ = scene_files
    frame = folder / "frames" / "f0.png"
    (tmp_path / "broken.yaml").write_text("camera_matrix: {rows: 3, cols: 3, data: [1, 2]}\nimage_width: 270\n"
                                          "image_height: 206\n")
    code, _, err = run(capsys, "stabilise", "--image", frame, "--roll", 0, "--pitch", 0, "--camera-info",
                       tmp_path / "broken.yaml", "--out", tmp_path / "x.png")
    assert code == 2 and "--camera-info" in err and "needs 9 numbers" in err
    small = tmp_path / "small.png"
    Image.open(frame).crop((0, 0, 100, 100)).save(small)
    code, _, err = run(capsys, "stabilise", "--image", small, "--roll", 0, "--pitch", 0, "--camera-info",
                       folder / "camera.yaml", "--out", tmp_path / "x.png")
    assert code == 2 and "--image" in err and "100 × 100" in err
    (tmp_path / "nan.csv").write_text("0,0,0\n0.1,nan,0\n0.2,0,0\n")
    code, _, err = run(capsys, "stabilise", "--frames", folder / "frames", "--imu", tmp_path / "nan.csv",
                       "--camera-info", folder / "camera.yaml", "--out-dir", tmp_path / "o")
    assert code == 2 and "--imu" in err and "row 2: roll" in err
    code, _, err = run(capsys, "stabilise", "--frames", tmp_path / "none", "--imu", folder / "imu.csv",
                       "--camera-info", folder / "camera.yaml", "--out-dir", tmp_path / "o")
    assert code == 2 and "--frames" in err
