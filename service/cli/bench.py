"""``sphereplan bench``: the planner against OMPL BIT*/RRT* on the shipped problems; prints a table."""

from __future__ import annotations

import argparse
import sys

from planner.errors import InvalidInput
from planner.hybrid_astar.bench import cold_start_s, format_table, plot_bench, run_bench, write_csv
from planner.maps.problems import list_problems
from planner.robot import load_robot
from service.cli._io import finite_float

VERB = "bench"
HELP = "benchmark the Hybrid A* against OMPL BIT* and RRT* on the shipped problem sets"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--maps", default=None, help="maps folder (default: the shipped maps)")
    parser.add_argument("--problems", default="", help="only problems whose map or name contains this text")
    parser.add_argument("--robot", default=None)
    parser.add_argument("--runs", type=int, default=5, help="timed runs per problem (after one warm-up)")
    parser.add_argument("--ompl-time", type=finite_float, default=10.0, help="BIT* budget, s (0 = skip)")
    parser.add_argument("--rrt-time", type=finite_float, default=2.0, help="RRT* budget, s (0 = skip)")
    parser.add_argument("--csv", default="bench.csv")
    parser.add_argument("--png", default="bench.png")
    parser.add_argument("--suite", choices=("planning", "reconfigure", "mpc", "all"), default="planning",
                        help="planning: Hybrid A* vs OMPL (default); reconfigure: Spherobot plan times; "
                             "mpc: MPC step times of the tracker; all: every table")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if args.runs < 1:
        raise InvalidInput("--runs", "must be ≥ 1")
    if args.suite in ("reconfigure", "all"):
        from planner.spherobot.bench import benchmark, format_benchmark

        print("reconfiguration plan times (200 random problems per method and mode)")
        print(format_benchmark(benchmark(200, 0)) + "\n")
    if args.suite in ("mpc", "all"):
        from planner.closed_loop.simulate import bench_mpc, format_mpc_bench

        print("MPC tracker step times (zju-60, 50 Hz)")
        print(format_mpc_bench(bench_mpc()) + "\n")
    if args.suite not in ("planning", "all"):
        return 0
    robot = load_robot(args.robot)
    problems = [p for p in list_problems(args.maps) if args.problems in p.name or args.problems in p.map]
    if not problems:
        raise InvalidInput("--problems", f"no shipped problem matches {args.problems!r}")
    from tqdm import tqdm

    planners = 1 + (args.ompl_time > 0) + (args.rrt_time > 0)
    with tqdm(total=len(problems) * planners, file=sys.stderr, desc="bench") as bar:

        def progress(msg: str) -> None:
            bar.set_postfix_str(msg[:40])
            bar.update(1)

        rows = run_bench(problems, robot, args.runs, args.ompl_time, args.rrt_time, progress=progress)
    print(format_table(rows))
    garage = next((p for p in problems if p.map.startswith("garage") and p.solvable), None)
    if garage is not None:
        print(f"\ncold start `sphereplan plan` on garage ({garage.name}): "
              f"{cold_start_s(garage.map_path, garage.start, garage.goal):.2f} s")
    write_csv(rows, args.csv)
    plot_bench(rows, args.png)
    print(f"wrote {args.csv} and {args.png}")
    return 0
