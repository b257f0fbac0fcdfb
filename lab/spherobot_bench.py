"""Plan-time benchmark of paper 004's two reconfiguration methods (``sphereplan bench --suite reconfigure``).

Random problems (R 0.1–2 m, start and goal within 10·R, any tilt, spin and heading) are planned with the
§3 spherical-triangle and the §4 straight-roll + circle methods, partial and complete; the table gives
the end-to-end :func:`~planner.spherobot.reconfigure.plan_reconfiguration` time (candidates, rolling
through SO(3), samples, result dict) and the planner's candidate generation alone.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from planner.spherobot.reconfigure import candidates, plan_reconfiguration
from planner.spherobot.request import METHODS, ReconfigureRequest


def random_request(rng: np.random.Generator, method: str, complete: bool) -> ReconfigureRequest:
    """A random problem: R in [0.1, 2] m, start/goal within 10·R, any tilt, spin and heading."""
    R = float(rng.uniform(0.1, 2.0))
    return ReconfigureRequest(
        method=method,
        start=(float(rng.uniform(-10, 10)) * R, float(rng.uniform(-10, 10)) * R),
        goal=(float(rng.uniform(-10, 10)) * R, float(rng.uniform(-10, 10)) * R),
        start_tilt=(float(rng.uniform(0, math.pi)), float(rng.uniform(-math.pi, math.pi))),
        start_spin=float(rng.uniform(-math.pi, math.pi)),
        goal_heading=float(rng.uniform(-math.pi, math.pi)) if complete else None,
        radius_m=R,
        roll_rate_rad_s=1.0,
    )


def benchmark(n: int = 200, seed: int = 0) -> list[dict[str, Any]]:
    """Plan ``n`` random problems per method and mode; rows of median / p95 / max times (ms).

    ``plan`` is :func:`plan_reconfiguration` end to end (candidates, rolling, samples, result dict);
    ``geometry`` is the planner's candidate generation alone.
    """
    rows = []
    for method in METHODS:
        for complete in (False, True):
            rng = np.random.default_rng(seed)
            reqs = [random_request(rng, method, complete) for _ in range(n)]
            plan_ms, geo_ms, lengths = [], [], []
            for req in reqs:
                t0 = time.perf_counter()
                candidates(req)
                t1 = time.perf_counter()
                res = plan_reconfiguration(req)
                t2 = time.perf_counter()
                geo_ms.append((t1 - t0) * 1e3)
                plan_ms.append((t2 - t1) * 1e3)
                lengths.append(res["length_m"] / res["radius_m"])
            rows.append(
                {
                    "method": method,
                    "mode": "complete" if complete else "partial",
                    "n": n,
                    "plan_median_ms": float(np.median(plan_ms)),
                    "plan_p95_ms": float(np.percentile(plan_ms, 95)),
                    "plan_max_ms": float(np.max(plan_ms)),
                    "geometry_median_ms": float(np.median(geo_ms)),
                    "median_length_radii": float(np.median(lengths)),
                }
            )
    return rows


def format_benchmark(rows: Sequence[Mapping[str, Any]]) -> str:
    """The benchmark rows as a fixed-width table."""
    head = (
        f"{'method':<9}{'mode':<10}{'n':>5}{'plan med ms':>13}{'p95 ms':>9}{'max ms':>9}"
        f"{'geom med ms':>13}{'len/R med':>11}"
    )
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(
            f"{r['method']:<9}{r['mode']:<10}{r['n']:>5}{r['plan_median_ms']:>13.2f}{r['plan_p95_ms']:>9.2f}"
            f"{r['plan_max_ms']:>9.2f}{r['geometry_median_ms']:>13.2f}{r['median_length_radii']:>11.1f}"
        )
    return "\n".join(lines)
