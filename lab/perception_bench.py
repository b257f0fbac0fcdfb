"""Perception timings (``sphereplan bench --suite perception``): paper 001 §6.3's three resolutions, our times
beside the paper's.

The paper: "When frame resolution is 1624*1240, the processing time for a single group of frames from stereo
camera is 2 s ... reduced to 812*620, the average single-frame processing time is shortened to 0.3 s ... 541*413
... 0.1 s" (Intel i7-8559U), and EIS at about 10 ms a frame with GPU acceleration (§6.4). Each resolution renders
the obstacle course (:func:`lab.perception_render.obstacle_course`, 0.5 m baseline, 70° field of view) once, runs
one warm-up and then ``runs`` timed calls of :func:`planner.perception.perceive` (rectify, SGBM, points, filters)
and of :func:`planner.perception.stabilise` on the left frame, on ``threads`` OpenCV threads (1 = one core).
Wall-clock seconds depend on what else the machine runs; the CPU column is the calling thread's CPU time per pair
(OpenCV runs in that thread when ``threads`` = 1), which a shared machine disturbs much less. The box 9 m ahead is
measured too (median distance error of its points against the rendered truth).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

#: (width, height, the paper's seconds per frame pair)
RESOLUTIONS: tuple[tuple[int, int, float], ...] = ((1624, 1240, 2.0), (812, 620, 0.3), (541, 413, 0.1))


def bench_perception(runs: int = 5, resolutions: tuple[tuple[int, int, float], ...] = RESOLUTIONS,
                     threads: int = 1, mode: str = "sgbm") -> list[dict[str, Any]]:
    """One row per resolution: median and max seconds of a stereo pair (total and SGBM alone), the disparity
    range, kept points, the box's median relative distance error, and the median EIS time per frame (s)."""
    import cv2

    from lab.perception_render import BOX_AHEAD, obstacle_course, render_pair
    from planner.perception.camera_info import camera_info_from_dict
    from planner.perception.disparity import StereoOptions
    from planner.perception.eis import stabilise
    from planner.perception.stereo import perceive

    scene = obstacle_course()
    box = scene.objects.index(BOX_AHEAD)
    before = cv2.getNumThreads()
    cv2.setNumThreads(threads)
    rows = []
    try:
        for width, height, paper_s in resolutions:
            pair = render_pair(scene, width, height, supersample=1)
            li, ri = camera_info_from_dict(pair.left_info), camera_info_from_dict(pair.right_info)
            options = StereoOptions(mode=mode)

            def once(li: Any = li, ri: Any = ri, pair: Any = pair, options: StereoOptions = options) -> Any:
                return perceive(pair.left.image, pair.right.image, li, ri, (0.0, 0.0, 0.0), stereo=options)

            scan = once()
            totals, sgbm, cpu = [], [], []
            for _ in range(runs):
                c0 = time.thread_time()
                scan = once()
                cpu.append(time.thread_time() - c0)
                totals.append(scan.timings_s["total"])
                sgbm.append(scan.timings_s["sgbm"])
            on_box = pair.left.hit[scan.pixels[:, 0], scan.pixels[:, 1]] == box
            truth = pair.left.points[scan.pixels[on_box, 0], scan.pixels[on_box, 1]]
            measured = np.linalg.norm(scan.points_map[on_box] - scan.origin_map, axis=1)
            true = np.linalg.norm(truth - scan.origin_map, axis=1)
            error = float(abs(np.median(measured) - np.median(true)) / np.median(true)) if on_box.any() else np.nan
            stabilise(pair.left.image, li, 0.17, 0.09)
            eis = []
            for _ in range(runs):
                t = time.perf_counter()
                stabilise(pair.left.image, li, 0.17, 0.09)
                eis.append(time.perf_counter() - t)
            rows.append({"width": width, "height": height, "paper_s": paper_s,
                         "median_s": float(np.median(totals)), "max_s": float(np.max(totals)),
                         "cpu_median_s": float(np.median(cpu)),
                         "sgbm_median_s": float(np.median(sgbm)), "num_disparities": scan.num_disparities,
                         "kept": len(scan.points_map), "box_points": int(on_box.sum()), "box_error": error,
                         "eis_median_s": float(np.median(eis)), "runs": runs, "threads": threads, "mode": mode})
    finally:
        cv2.setNumThreads(before)
    return rows


def format_perception_bench(rows: list[dict[str, Any]]) -> str:
    """The rows of :func:`bench_perception` as a table, the paper's time in its own column."""
    lines = [f"{'resolution':>11} {'paper s':>8} {'median s':>9} {'max s':>7} {'CPU s':>7} {'SGBM s':>7} "
             f"{'disp':>5} {'kept':>6} {'box err':>8} {'EIS ms':>7}"]
    for r in rows:
        paper = f"{r['paper_s']:>8.1f}" if np.isfinite(r["paper_s"]) else f"{'—':>8}"
        lines.append(f"{r['width']:>5} × {r['height']:<4} {paper} {r['median_s']:>9.3f} "
                     f"{r['max_s']:>7.3f} {r['cpu_median_s']:>7.3f} {r['sgbm_median_s']:>7.3f} "
                     f"{r['num_disparities']:>5} {r['kept']:>6} "
                     f"{100 * r['box_error']:>7.2f}% {1000 * r['eis_median_s']:>7.1f}")
    return "\n".join(lines)
