"""``sphereplan stabilise``: electronic image stabilisation (paper 001 §3.3) of one frame or a folder of frames.

One frame: ``--image IN.png --roll R --pitch P --camera-info C.yaml --out OUT.png``. A batch: ``--frames DIR --imu
IMU.csv [--fps F] --camera-info C.yaml --out-dir OUT_DIR`` (the CSV's rows are ``time, roll, pitch``; see
:mod:`planner.perception.imu_log`). Angles are the camera's attitude as its IMU measures it, REP-103 (roll about x
forward, pitch about y left, right-handed), radians unless ``--degrees``. Prints a JSON summary.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from planner.errors import InvalidInput
from service.cli._io import Stages, add_degrees_flag, angle, check_output, emit_json, finite_float, positive_float

VERB = "stabilise"
HELP = "electronic image stabilisation (paper 001 §3.3): level a frame from the IMU's roll and pitch"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--image", help="one raw frame (PNG, JPEG, ...)")
    source.add_argument("--frames", help="a folder of raw frames, taken in file-name order")
    parser.add_argument("--roll", type=finite_float, help="with --image: the camera's roll (REP-103, about x forward)")
    parser.add_argument("--pitch", type=finite_float,
                        help="with --image: the camera's pitch (REP-103, about y left, > 0 nose down)")
    parser.add_argument("--imu", help="with --frames: CSV of time (s), roll, pitch rows")
    parser.add_argument("--fps", type=positive_float, default=None,
                        help="with --frames: frame rate; frame i is at the log's first time + i / fps, angles "
                             "interpolated (default: one CSV row per frame)")
    add_degrees_flag(parser)
    parser.add_argument("--camera-info", required=True, help="the camera's camera_info YAML (K and distortion)")
    parser.add_argument("--out", help="with --image: the stabilised image")
    parser.add_argument("--out-dir", help="with --frames: the folder the stabilised frames go to (made if missing)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from planner.perception.camera_info import read_camera_info

    if args.image is not None:
        for name in ("roll", "pitch"):
            if getattr(args, name) is None:
                raise InvalidInput(f"--{name}", "is required with --image")
        for name in ("imu", "fps", "out_dir"):
            if getattr(args, name) is not None:
                raise InvalidInput(f"--{name.replace('_', '-')}", "only applies to --frames")
        if args.out is None:
            raise InvalidInput("--out", "is required with --image")
        check_output(args.out, "--out", {"png", "jpg", "jpeg", "bmp", "tif", "tiff"})
        info = read_camera_info(args.camera_info, "--camera-info")
        emit_json(_one(args, info), None)
        return 0
    for name in ("roll", "pitch"):
        if getattr(args, name) is not None:
            raise InvalidInput(f"--{name}", "only applies to --image; --frames takes its angles from --imu")
    if args.imu is None:
        raise InvalidInput("--imu", "is required with --frames")
    if args.out is not None:
        raise InvalidInput("--out", "only applies to --image; give --out-dir with --frames")
    if args.out_dir is None:
        raise InvalidInput("--out-dir", "is required with --frames")
    info = read_camera_info(args.camera_info, "--camera-info")
    emit_json(_batch(args, info), None)
    return 0


def _one(args: argparse.Namespace, info: Any) -> dict[str, Any]:
    from planner.perception.eis import stabilise
    from planner.perception.image_io import read_image, write_image
    from planner.perception.mount import check_angle

    roll = check_angle(angle(args, args.roll, "--roll"), "--roll")
    pitch = check_angle(angle(args, args.pitch, "--pitch"), "--pitch")
    image = read_image(args.image, "--image")
    out, valid = stabilise(image, info, roll, pitch, "--image")
    write_image(args.out, out, "--out")
    return {"image": str(args.image), "out": str(args.out), "roll": roll, "pitch": pitch,
            "valid_fraction": round(float(valid.mean()), 4)}


def _batch(args: argparse.Namespace, info: Any) -> dict[str, Any]:
    from planner.perception.eis import stabilise
    from planner.perception.image_io import read_image, write_image
    from planner.perception.imu_log import list_frames, read_imu_csv

    out_dir = Path(args.out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise InvalidInput("--out-dir", f"{out_dir} is a file; give a folder")
    if not out_dir.parent.is_dir():
        raise InvalidInput("--out-dir", f"folder {out_dir.parent} does not exist")
    frames = list_frames(args.frames, "--frames")
    log = read_imu_csv(args.imu, args.degrees, "--imu")
    rolls, pitches = log.at_frames(len(frames), args.fps, "--imu")
    out_dir.mkdir(exist_ok=True)
    written = []
    with Stages("stabilise", [f"{len(frames)} frames"]) as stages:
        stages.start(f"{len(frames)} frames")
        for frame, roll, pitch in zip(frames, rolls, pitches, strict=True):
            image = read_image(frame, f"--frames ({frame.name})")
            out, _ = stabilise(image, info, float(roll), float(pitch), f"--frames ({frame.name})")
            target = out_dir / frame.name
            write_image(target, out, "--out-dir")
            written.append({"frame": frame.name, "out": str(target), "roll": round(float(roll), 6),
                            "pitch": round(float(pitch), 6)})
    return {"frames": len(written), "out": str(out_dir), "stabilised": written}
