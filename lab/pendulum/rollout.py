"""Roll a plan for every shipped solvable problem on the dynamic pendulum sphere and report collisions.

Run from the repository root (≈ 10–20 min on a shared 2-core machine, so it is a script, not a CI test)::

    python -m lab.pendulum.rollout                       # zju-60, eq. 15 MPC → LMPC + RSLQR → plant
    python -m lab.pendulum.rollout --only garage --csv out.csv

For each solvable problem of ``maps/problems/*.json`` (:func:`planner.maps.problems.list_problems`) it
plans with the Hybrid A* (``plan_path``, the problem's time limit) and rolls the plan with
``simulate_plan(..., SimulationOptions(model="dynamic"), noise="none", seed=0)`` — the same closed loop
as ``tests/planner/closed_loop/test_simulate_shipped.py`` but through paper 001's motion controllers and
pendulum plant instead of the kinematic simulator. It prints one row per problem (collided, clearance,
reached goal, final error, cross-track, pendulum angles, run time) and exits 1 if any run collided.
docs/pendulum.md reports the last run.
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from planner.closed_loop.simulate import SimulationOptions, simulate_plan
from planner.hybrid_astar.plan import plan_path
from planner.maps.nav2 import load_map
from planner.maps.problems import list_problems
from planner.occupancy import OccupancyGrid
from planner.robot import load_robot
from planner.termination import Termination

COLUMNS = (
    "problem", "collided", "min_clearance_m", "reached_goal", "final_position_error_m", "cross_track_max_m",
    "pendulum_pitch_max_deg", "pendulum_roll_max_deg", "duration_s", "wall_s",
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--robot", default="zju-60")
    parser.add_argument("--only", help="only problems whose map or name contains this text")
    parser.add_argument("--tracker", choices=("mpc", "pursuit"), default="mpc")
    parser.add_argument("--csv", help="also write the rows here")
    args = parser.parse_args(argv)
    robot = load_robot(args.robot)
    problems = [p for p in list_problems() if p.solvable]
    if args.only:
        problems = [p for p in problems if args.only in p.map or args.only in p.name]
    grids: dict[str, OccupancyGrid] = {}
    rows = []
    print(" | ".join(COLUMNS))
    for p in problems:
        if str(p.map_path) not in grids:
            grids[str(p.map_path)] = load_map(p.map_path)
        grid = grids[str(p.map_path)]
        plan = plan_path(grid, robot, p.start, p.goal, termination=Termination(p.time_limit_s)).to_json()
        t0 = time.perf_counter()
        sim = simulate_plan(
            grid,
            plan,
            robot,
            seed=0,
            noise="none",
            options=SimulationOptions(model="dynamic", tracker=args.tracker),
        )
        m = sim["metrics"]
        row = {
            "problem": f"{p.map[:-5]}:{p.name}",
            "collided": m["collided"],
            "min_clearance_m": round(m["min_clearance_m"], 3),
            "reached_goal": m["reached_goal"],
            "final_position_error_m": round(m["final_position_error_m"], 3),
            "cross_track_max_m": round(m["cross_track_max_m"], 3),
            "pendulum_pitch_max_deg": round(math.degrees(m["pendulum_pitch_max_rad"]), 1),
            "pendulum_roll_max_deg": round(math.degrees(m["pendulum_roll_max_rad"]), 1),
            "duration_s": round(m["duration_s"], 1),
            "wall_s": round(time.perf_counter() - t0, 1),
        }
        rows.append(row)
        print(" | ".join(str(row[c]) for c in COLUMNS), flush=True)
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=COLUMNS)
            writer.writeheader()
            writer.writerows(rows)
    collided = [r["problem"] for r in rows if r["collided"]]
    print(f"{len(rows)} problems, {len(collided)} collided" + (f": {', '.join(collided)}" if collided else ""))
    return 1 if collided else 0


if __name__ == "__main__":
    raise SystemExit(main())
