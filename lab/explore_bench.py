"""The exploration sweep (``sphereplan bench --suite explore``): every seeded world of
:mod:`lab.explore_worlds` explored in closed loop, then one table.

Per world: whether the true world has a path (planned with full knowledge), the outcome (``reached`` /
``no_path`` / ``collided`` / ``timeout``) and whether it is the right one (reached where a path exists,
``no_path`` and no collision where none does), replans and their latency percentiles, the live-map update
time per 10 m sensor sweep, the driven length over the length planned with full knowledge, and why it replanned
(``blocked``, ``request``: a timed-out search retried while stopped, ``map_changed``: a failed plan retried after
the map changed, ``timer``) with the number of replans that found no path in brackets. The summary
line pools the replan latencies and sweep times of all worlds (and of the 100 m field and the garage apart,
the issue's two targets). Wall times depend on the machine's load: compare within a run.
"""

from __future__ import annotations

import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from lab.explore_worlds import WorldSpec, build_world, sweep_specs
from planner.closed_loop.explore import ExploreOptions, explore, explore_json
from planner.robot import RobotProfile


@dataclass
class SweepRow:
    spec: WorldSpec
    has_path: bool
    outcome: str
    metrics: dict[str, Any]
    latencies_s: list[float]
    wall_s: float

    @property
    def correct(self) -> bool:
        if self.metrics["collided"]:
            return False
        return self.outcome == ("reached" if self.has_path else "no_path")


def run_world(spec: WorldSpec, robot: RobotProfile, options: ExploreOptions) -> SweepRow:
    """Explore one world."""
    t0 = time.perf_counter()
    world = build_world(spec, robot)
    result = explore_json(explore(world.known, world.true, robot, spec.start, spec.goal, options, seed=spec.seed))
    m = result["metrics"]
    latencies = [e["latency_s"] for e in result["replans"] if e["reason"] != "goal"]
    return SweepRow(spec, bool(m["true_world_has_path"]), result["outcome"], m, latencies, time.perf_counter() - t0)


def sweep_update_times(map_path: str, robot: RobotProfile, sweeps: int = 40, seed: int = 0) -> list[float]:
    """Wall time (s) of applying one 10 m, 720-beam sweep to a live map of ``map_path``, at ``sweeps`` random free
    poses (seeded): the live-map update alone, without the planner's refresh."""
    from planner.live import LiveMap, ObstacleLayerParams, RangeSensor
    from planner.maps.clearance import ClearanceMap
    from planner.maps.load import load_any

    grid = load_any(map_path)
    live = LiveMap(grid, ObstacleLayerParams.for_robot(robot))
    rng = np.random.default_rng(seed)
    free = np.argwhere(ClearanceMap(grid).clearance > 0.5)
    sensor = RangeSensor()
    live.apply(sensor.scan(grid, (1.0, 1.0, 0.0), rng))  # compile
    out = []
    for iy, ix in free[rng.integers(len(free), size=sweeps)]:
        pose = (grid.origin[0] + (ix + 0.5) * grid.resolution_m, grid.origin[1] + (iy + 0.5) * grid.resolution_m,
                float(rng.uniform(-np.pi, np.pi)))
        scan = sensor.scan(grid, pose, rng)
        out.append(live.apply(scan).time_s)
    return out


def _ms(v: float | None) -> str:
    return "—" if v is None else f"{1e3 * v:.0f}"


def _ms1(v: float | None) -> str:
    return "—" if v is None else f"{1e3 * v:.1f}"


def _why(m: dict[str, Any]) -> str:
    """The replans' reasons with their counts (``blocked 3, request 1``) and how many of them failed."""
    reasons = m.get("replan_reasons") or {}
    text = ", ".join(f"{k} {v}" for k, v in sorted(reasons.items())) or "—"
    failed = m.get("replans_failed") or 0
    return f"{text} ({failed})" if failed else text


def _pct(values: list[float], q: float) -> float | None:
    return float(np.percentile(values, q)) if values else None


def format_table(rows: list[SweepRow], sweep_s: dict[str, list[float]]) -> str:
    head = (f"{'world':<26} {'path?':>5} {'outcome':>8} {'ok':>3} {'replans':>7} {'p50 ms':>7} {'p95 ms':>7} "
            f"{'upd ms':>6} {'driven m':>8} {'known m':>8} {'ratio':>6} {'clear m':>7} {'wall s':>6}  why (failed)")
    lines = [head, "-" * len(head)]
    for r in rows:
        m = r.metrics
        ratio = f"{m['length_ratio']:.2f}" if m["length_ratio"] else "—"
        lines.append(
            f"{r.spec.name:<26} {'yes' if r.has_path else 'no':>5} {r.outcome:>8} {'✓' if r.correct else '✗':>3} "
            f"{m['replans']:>7} {_ms(m['replan_latency_p50_s']):>7} {_ms(m['replan_latency_p95_s']):>7} "
            f"{_ms(m['map_update_p50_s']):>6} {m['length_m']:>8.1f} "
            f"{(m['length_known_world_m'] or 0):>8.1f} "
            f"{ratio:>6} {m['min_clearance_m']:>7.2f} "
            f"{r.wall_s:>6.0f}  {_why(m)}")
    lines.append("-" * len(head))
    reached = sum(r.outcome == "reached" for r in rows)
    collided = sum(bool(r.metrics["collided"]) for r in rows)
    no_path = sum(r.outcome == "no_path" for r in rows)
    ratios = [r.metrics["length_ratio"] for r in rows if r.metrics["length_ratio"]]
    lines.append(f"{len(rows)} worlds ({sum(r.has_path for r in rows)} with a path): {reached} reached, "
                 f"{no_path} no path, {collided} collided, "
                 f"{sum(r.outcome == 'timeout' for r in rows)} timed out; right outcome in "
                 f"{sum(r.correct for r in rows)}/{len(rows)}")
    if ratios:
        lines.append(f"driven length ÷ full-knowledge length: median {statistics.median(ratios):.2f}, "
                     f"max {max(ratios):.2f}")

    def pooled(label: str, keep: Callable[[SweepRow], bool]) -> None:
        lat = [x for r in rows if keep(r) for x in r.latencies_s]
        lines.append(f"replan latency {label}: p50 {_ms(_pct(lat, 50))} ms, p95 {_ms(_pct(lat, 95))} ms "
                     f"({len(lat)} replans)")

    pooled("(all worlds)", lambda r: True)
    pooled("(100 m field)", lambda r: "100by100" in r.spec.map)
    pooled("(garage)", lambda r: "garage" in r.spec.map)
    for name, times in sweep_s.items():
        lines.append(f"live-map update, one 10 m sweep (720 beams) on {name}: p50 {_ms1(_pct(times, 50))} ms, "
                     f"p95 {_ms1(_pct(times, 95))} ms ({len(times)} sweeps)")
    return "\n".join(lines)


def run_sweep(robot: RobotProfile, tracker: str = "mpc", only: str = "",
              progress: Callable[[str], None] | None = None) -> tuple[list[SweepRow], dict[str, list[float]]]:
    """Every world of the sweep whose name contains ``only``; then the sweep-update timings."""
    specs = [s for s in sweep_specs() if only in s.name]
    options = ExploreOptions(tracker=tracker)
    rows = []
    for spec in specs:
        rows.append(run_world(spec, robot, options))
        if progress is not None:
            progress(spec.name)
    from lab.explore_worlds import maps_dir

    sweep_s = {name: sweep_update_times(str(maps_dir() / path), robot)
               for name, path in (("the 100 m field", "real/100by100_20.yaml"), ("the garage", "garage.yaml"))}
    return rows, sweep_s


def main(robot_name: str | None = None, tracker: str = "mpc", only: str = "", quiet: bool = False) -> int:
    """Run the sweep and print the table (progress on stderr)."""
    from planner.robot import load_robot

    robot = load_robot(robot_name)

    def progress(name: str) -> None:
        if not quiet:
            print(f"explored {name}", file=sys.stderr, flush=True)

    rows, sweep_s = run_sweep(robot, tracker, only, progress)
    print(f"sphereplan bench --suite explore: {robot.name}, tracker {tracker}, 10 m range sensor at 5 Hz, "
          f"{len(rows)} seeded worlds")
    print(format_table(rows, sweep_s))
    return 0 if all(r.correct for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
