"""``sphereplan perceive``: a stereo pair and its camera_info files → obstacle points in the map (paper 001 §3.2).

Prints (or writes to ``--out``) the JSON of :class:`planner.perception.ObstacleScan` plus the pose it was seen
from; ``--out X.mcap`` writes the points as ``sensor_msgs/PointCloud2`` (frame ``map``) instead, with the JSON on
stdout. ``--disparity`` saves the disparity image (``.png``: 16-bit, disparity × 16 as OpenCV computes it, 0 =
unmatched; ``.npy``: float32 pixels, NaN = unmatched), ``--plot`` a picture of what was seen and kept.
"""

from __future__ import annotations

import argparse

from planner.errors import InvalidInput
from service.cli._io import (
    Stages,
    add_degrees_flag,
    angle,
    check_output,
    emit_result,
    finite_float,
    positive_float,
    say,
    write_file,
)

VERB = "perceive"
HELP = "stereo obstacle perception (paper 001 §3.2): a stereo pair → obstacle points in the map frame"
#: StereoSGBM modes (the planner's planner.perception.disparity.MODES, repeated for a fast --help)
MODES = ("sgbm", "3way", "hh", "hh4")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--left", required=True, help="left camera image (PNG, JPEG, ...)")
    parser.add_argument("--right", required=True, help="right camera image, the same size")
    parser.add_argument("--left-info", required=True, help="left camera_info YAML (ROS camera_calibration_parsers)")
    parser.add_argument("--right-info", required=True,
                        help="right camera_info YAML; its projection_matrix holds −fx·baseline as ROS's does")
    parser.add_argument("--pose", nargs=3, type=finite_float, required=True, metavar=("X", "Y", "YAW"),
                        help="the sphere's pose in the map (m, m, rad or deg with --degrees)")
    parser.add_argument("--roll", type=finite_float, default=0.0,
                        help="the sphere's roll (> 0 leans and turns left, as in a plan's states; default 0)")
    parser.add_argument("--pitch", type=finite_float, default=0.0,
                        help="the main axis's pitch (REP-103, > 0 nose down; default 0: the cameras do not pitch "
                             "with the rolling shell)")
    add_degrees_flag(parser)
    parser.add_argument("--robot", default=None, help="profile name or TOML path (its radius is the axis height; "
                                                      "default zju-60)")
    parser.add_argument("--out", default=None, help="write the JSON here (.mcap: ROS 2 PointCloud2, JSON on stdout)")
    parser.add_argument("--plot", default=None, help="a picture of the disparity and the kept points (PNG)")
    parser.add_argument("--disparity", default=None, help="save the disparity image (.png 16-bit ×16, or .npy)")
    filters = parser.add_argument_group("the paper's filters (metres)")
    filters.add_argument("--min-height", type=finite_float, default=0.05,
                         help="drop points lower than this above the ground (default 0.05)")
    filters.add_argument("--max-height", type=positive_float, default=None,
                         help="drop points higher than this: suspended (default: the shell's top 2r + 0.10)")
    filters.add_argument("--max-range", type=positive_float, default=10.0,
                         help="drop points farther than this from the sphere, on the ground (default 10)")
    filters.add_argument("--min-blob", type=int, default=20,
                         help="drop patches of fewer kept pixels than this in the left image (default 20; 1 = off)")
    sgbm = parser.add_argument_group("semi-global block matching (OpenCV StereoSGBM)")
    sgbm.add_argument("--min-depth", type=positive_float, default=1.5,
                      help="nearest depth searched, m; sets the disparity range fx·B / min-depth (default 1.5)")
    sgbm.add_argument("--num-disparities", type=int, default=None,
                      help="disparity range, a multiple of 16 (default: from --min-depth)")
    sgbm.add_argument("--block-size", type=int, default=3, help="matched block size, odd (default 3)")
    sgbm.add_argument("--mode", choices=MODES, default="sgbm", help="SGBM variant (default sgbm)")
    sgbm.add_argument("--full-width", action="store_true",
                      help="also match the left image's first num-disparities columns, which OpenCV leaves blind "
                           "(pads the pair; about a quarter slower)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from planner.perception.camera_info import read_camera_info
    from planner.perception.disparity import StereoOptions
    from planner.perception.image_io import read_image
    from planner.perception.mount import check_angle
    from planner.perception.obstacle_filter import ObstacleFilter
    from planner.perception.stereo import check_pair, perceive
    from planner.robot import load_robot

    check_output(args.out, "--out")
    check_output(args.plot, "--plot", {"png", "pdf", "svg"})
    check_output(args.disparity, "--disparity", {"png", "npy"})
    x, y = args.pose[0], args.pose[1]
    yaw = check_angle(angle(args, args.pose[2], "--pose YAW"), "--pose YAW")
    roll = check_angle(angle(args, args.roll, "--roll"), "--roll")
    pitch = check_angle(angle(args, args.pitch, "--pitch"), "--pitch")
    if args.min_height < 0:
        raise InvalidInput("--min-height", "must be ≥ 0")
    try:
        stereo = StereoOptions(min_depth_m=args.min_depth, num_disparities=args.num_disparities,
                               block_size=args.block_size, mode=args.mode, full_width=args.full_width)
        obstacles = ObstacleFilter(min_height_m=args.min_height, max_height_m=args.max_height,
                                   max_range_m=args.max_range, min_blob_px=args.min_blob)
    except InvalidInput as exc:
        field = {"min_blob_px": "min_blob"}.get(exc.field, exc.field)
        raise InvalidInput("--" + field.removesuffix("_m").replace("_", "-"), exc.msg) from None
    robot = load_robot(args.robot)
    fields = ("--left", "--right", "--left-info", "--right-info")
    left, right = read_image(args.left, "--left"), read_image(args.right, "--right")
    left_info, right_info = read_camera_info(args.left_info, "--left-info"), read_camera_info(args.right_info,
                                                                                                "--right-info")
    check_pair(left, right, left_info, right_info, fields)

    with Stages("perceive", ["match and triangulate", *(["plot"] if args.plot else [])]) as stages:
        stages.start("match and triangulate")
        scan = perceive(left, right, left_info, right_info, (x, y, yaw), roll, pitch, robot.radius_m, stereo,
                        obstacles, keep_disparity=bool(args.plot or args.disparity), fields=fields)
        if args.plot:
            stages.start("plot")
            from planner.perception.plot import plot_scan

            write_file(args.plot, "--plot",
                       lambda: plot_scan(scan, left, (x, y, yaw), obstacles.max_range_m, args.plot))
    if args.disparity:
        _write_disparity(args.disparity, scan.disparity)
    result = {**scan.to_json(), "robot": {"name": robot.name, "radius_m": robot.radius_m}}
    if args.disparity:
        result["disparity"] = str(args.disparity)
    if args.plot:
        result["plot"] = str(args.plot)
    result["points_map"] = result.pop("points_map")  # the long list last

    def write_mcap(out: str) -> None:
        from service.ros import write_perception_mcap

        write_perception_mcap(out, result)

    emit_result(result, args.out, write_mcap)
    say("perceive", f"{len(scan.points_map)} obstacle points kept of {scan.measured} measured "
                    f"in {scan.timings_s['total']:.3f} s")
    return 0


def _write_disparity(path: str, disparity: object) -> None:
    import numpy as np

    from planner.perception.image_io import write_image

    d = np.asarray(disparity, dtype=np.float32)
    if path.lower().endswith(".npy"):
        write_file(path, "--disparity", lambda: np.save(path, d))
    else:
        write_image(path, np.where(np.isfinite(d), np.clip(np.rint(d * 16), 0, 65535), 0).astype(np.uint16),
                    "--disparity")
