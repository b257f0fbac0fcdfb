"""``sphereplan bench``: the planner against OMPL BIT*/RRT* on the shipped problems; prints a table.

``--suite real`` instead draws seeded random problems on Nav2's maps (``maps/real``) the way Nav2's planner
benchmark does and compares sphereplan with OMPL BIT* on Dubins and Reeds–Shepp spaces
(:mod:`lab.planning.real`, docs/planning.md "The real-map benchmark"). ``--suite perception`` times stereo
obstacle perception and EIS at paper 001's three resolutions next to the paper's figures (:mod:`lab.perception_bench`,
docs/perception.md). ``--suite load`` runs the service under load (:func:`lab.loadtest.fleet_main`: one instance
vs two behind HAProxy, health probes under big bodies, failover).
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import TYPE_CHECKING, Any

from planner.errors import InvalidInput
from service.cli._io import finite_float, positive_float, quiet

if TYPE_CHECKING:  # the benchmark's modules load numba, scipy and OMPL: only when the verb runs (fast --help)
    from planner.hybrid_astar.search import PlannerOptions

VERB = "bench"
HELP = "benchmark the Hybrid A* against OMPL BIT* and RRT* on the shipped problem sets or on Nav2's maps"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--maps", default=None, help="maps folder (default: the shipped maps)")
    parser.add_argument("--problems", default="", help="only problems whose map or name contains this text")
    parser.add_argument("--robot", default=None)
    parser.add_argument("--runs", type=int, default=5, help="timed runs per problem (after one warm-up)")
    parser.add_argument("--ompl-time", type=finite_float, default=10.0, help="BIT* budget, s (0 = skip)")
    parser.add_argument("--rrt-time", type=finite_float, default=2.0, help="RRT* budget, s (0 = skip)")
    parser.add_argument("--csv", default=None,
                        help="CSV output (default bench.csv; bench_real.csv for --suite real); only the planning, "
                             "all and real suites write one")
    parser.add_argument("--png", default=None,
                        help="PNG output (default bench.png; bench_real.png for --suite real); only the planning, "
                             "all and real suites write one")
    parser.add_argument("--suite",
                        choices=("planning", "reconfigure", "mpc", "all", "real", "perception", "load", "explore"),
                        default="planning",
                        help="planning: Hybrid A* vs OMPL on the shipped problems (default); reconfigure: Spherobot "
                             "plan times; mpc: MPC step times of the tracker; all: those three; real: random "
                             "problems on Nav2's maps against BIT* (minutes); perception: stereo and EIS times at "
                             "paper 001's three resolutions; load: the service under load, one instance vs two "
                             "behind HAProxy, and failover (needs haproxy; minutes); explore: live-map exploration "
                             "of seeded worlds with hidden obstacles (tens of minutes; --problems filters by world "
                             "name)")
    real = parser.add_argument_group("--suite real")
    real.add_argument("--real-maps", default=None,
                      help="comma-separated map names in maps/real or YAML paths (default: every map in maps/real)")
    real.add_argument("--per-map", type=int, default=10,
                      help="problems drawn per map (default 10: 60 problems on the 6 shipped maps; fewer is quicker)")
    real.add_argument("--seed", type=int, default=0, help="seed of the problem draw (default 0)")
    real.add_argument("--time-limit", type=positive_float, default=None,
                      help="time limit per planner and problem, s (default: 10 s on maps of ≥ 1 M cells, else 5 s)")
    real.add_argument("--options", default=None,
                      help="JSON object of sphereplan planner options (default: the defaults), e.g. "
                           "'{\"allow_reverse\": true}'")
    real.add_argument("--reference-time", type=finite_float, default=None,
                      help="BIT*'s budget per space and problem, s: the first solution (within --time-limit), then "
                           "optimising until this much in all; its final path is the reference's best (default 3; "
                           "0 = optimise until the time limit)")
    real.add_argument("--no-reference", action="store_true", help="skip OMPL BIT* (no solvability reference)")
    real.add_argument("--room-reference", action="store_true",
                      help="also time BIT* asked to keep the room sphereplan's path keeps (its footprint grown by "
                           "that clearance, up to the robot's preferred_clearance_m) to its first solution, on every "
                           "problem sphereplan solved: the table's 'x room' columns (a convex footprint only)")
    real.add_argument("--repeat", type=int, default=1,
                      help="time each solved problem this many times, sphereplan and BIT*'s first solution alike, "
                           "and keep the median (default 1; 3 steadies the per-problem time ratios)")
    perception = parser.add_argument_group("--suite perception")
    perception.add_argument("--threads", type=int, default=1, help="OpenCV threads (default 1: one core)")
    perception.add_argument("--resolutions", default=None,
                            help="comma-separated WxH (default: the paper's 1624x1240,812x620,541x413)")
    load = parser.add_argument_group("--suite load")
    load.add_argument("--duration", type=positive_float, default=10.0, help="seconds per row (default 10)")
    load.add_argument("--workers", type=int, default=1, help="worker processes per instance (default 1)")
    parser.set_defaults(func=run)


def _options(text: str | None) -> PlannerOptions:
    from planner.hybrid_astar.search import PlannerOptions

    if not text:
        return PlannerOptions()
    try:
        data: Any = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InvalidInput("--options", f"is not valid JSON: {exc}") from None
    if not isinstance(data, dict):
        raise InvalidInput("--options", "must be a JSON object")
    return PlannerOptions.from_dict(data)


def run_real(args: argparse.Namespace) -> int:
    """``--suite real``: table on stdout, progress on stderr, CSV and PNG written."""
    from lab.planning.real.bench import DEFAULT_REFERENCE_S, run_real_bench
    from lab.planning.real.figure import plot_real
    from lab.planning.real.problems import real_map_names, resolve_map
    from lab.planning.real.summary import format_real_table, write_real_csv
    from planner.robot import load_robot

    if args.per_map < 1:
        raise InvalidInput("--per-map", "must be ≥ 1")
    if args.repeat < 1:
        raise InvalidInput("--repeat", "must be ≥ 1")
    reference_s = DEFAULT_REFERENCE_S if args.reference_time is None else args.reference_time
    if reference_s < 0:
        raise InvalidInput("--reference-time", "must be ≥ 0 (0 = until the time limit)")
    robot = load_robot(args.robot)
    if args.room_reference:
        from lab.planning.real.bench import check_room_reference

        try:
            check_room_reference(robot, not args.no_reference)
        except ValueError as exc:
            raise InvalidInput("--room-reference", str(exc)) from None
    options = _options(args.options)
    given = args.real_maps if args.real_maps is not None else ",".join(real_map_names())
    specs = [m.strip() for m in given.split(",") if m.strip()]
    if not specs:
        raise InvalidInput("--real-maps", "names no map")
    paths = [resolve_map(m) for m in specs]
    from tqdm import tqdm

    per_problem = 1 if args.no_reference else 4 if args.room_reference else 3
    with tqdm(total=len(paths) * args.per_map * per_problem, file=sys.stderr, desc="bench real",
              disable=quiet() or not sys.stderr.isatty()) as bar:

        def progress(msg: str) -> None:
            bar.set_postfix_str(msg[:40])
            bar.update(1)

        result = run_real_bench(paths, robot, args.per_map, args.seed, time_limit_s=args.time_limit,
                                options=options, reference=not args.no_reference,
                                reference_s=reference_s or None,
                                progress=progress, repeat=args.repeat, room_reference=args.room_reference)
    limit = "default limits (10 s ≥ 1 M cells, else 5 s)" if args.time_limit is None else f"{args.time_limit:g} s"
    ref = ("no BIT*" if args.no_reference else f"BIT* {reference_s:g} s per space" if reference_s
           else "BIT* optimising until the limit") + (", BIT* keeping sphereplan's room" if args.room_reference else "")
    title = (f"sphereplan bench --suite real: {robot.name}, {len(paths)} maps × {args.per_map} problems, seed "
             f"{args.seed}, {limit}, {ref}, {'reversing' if result.reverse_allowed else 'forward-only'} sphereplan"
             + (f", times the median of {args.repeat} runs" if args.repeat > 1 else ""))
    print(title)
    print(format_real_table(result.summaries))
    csv_path = args.csv or "bench_real.csv"
    png_path = args.png or "bench_real.png"
    write_real_csv(result.records, csv_path)
    plot_real(result.records, result.summaries, png_path, title)
    print(f"wrote {csv_path} and {png_path}")
    return 0


def run_perception(args: argparse.Namespace) -> int:
    """``--suite perception``: the timing table on stdout."""
    from lab.perception_bench import RESOLUTIONS, bench_perception, format_perception_bench

    if args.threads < 1:
        raise InvalidInput("--threads", "must be ≥ 1")
    resolutions = RESOLUTIONS
    if args.resolutions:
        paper = {(w, h): s for w, h, s in RESOLUTIONS}
        resolutions = tuple((w, h, paper.get((w, h), float("nan"))) for w, h in _sizes(args.resolutions))
    print(f"stereo perception and EIS per frame (obstacle course, 0.5 m baseline, {args.threads} OpenCV "
          f"thread{'s' if args.threads > 1 else ''}, median of {args.runs} runs; paper: i7-8559U)")
    print(format_perception_bench(bench_perception(args.runs, resolutions, args.threads)))
    return 0


def _sizes(text: str) -> list[tuple[int, int]]:
    sizes = []
    for item in text.split(","):
        w, _, h = item.strip().lower().partition("x")
        if not (w.isdigit() and h.isdigit() and int(w) >= 64 and int(h) >= 48):
            raise InvalidInput("--resolutions", f"{item.strip()!r} is not WIDTHxHEIGHT (at least 64x48)")
        sizes.append((int(w), int(h)))
    return sizes


def run(args: argparse.Namespace) -> int:
    if args.suite not in ("planning", "all", "real"):
        for flag, value in (("--csv", args.csv), ("--png", args.png)):
            if value is not None:  # only the planning and real suites write files: never drop what was asked
                raise InvalidInput(flag, f"--suite {args.suite} writes no {flag[2:].upper()} (its table goes to "
                                         "stdout); --csv and --png are for --suite planning, all and real")
    if args.suite == "real":
        return run_real(args)
    if args.suite == "load":
        from lab.loadtest import fleet_main  # starts servers and HAProxy: only when asked

        if not 1 <= args.workers <= 64:
            raise InvalidInput("--workers", "must be in [1, 64]")
        return fleet_main(args.duration, args.workers)
    if args.suite == "explore":
        from lab.explore_bench import main as explore_main
        from lab.explore_worlds import sweep_specs

        if not any(args.problems in spec.name for spec in sweep_specs()):
            raise InvalidInput("--problems", f"no explore world matches {args.problems!r}")
        return explore_main(args.robot, only=args.problems, quiet=quiet())  # 1 when a world's outcome is wrong
    if args.runs < 1:
        raise InvalidInput("--runs", "must be ≥ 1")
    if args.suite == "perception":
        return run_perception(args)
    if args.suite in ("reconfigure", "all"):
        from lab.spherobot_bench import benchmark, format_benchmark

        print("reconfiguration plan times (200 random problems per method and mode)")
        print(format_benchmark(benchmark(200, 0)) + "\n")
    if args.suite in ("mpc", "all"):
        from lab.mpc_bench import bench_mpc, format_mpc_bench

        print("MPC tracker step times (zju-60, 50 Hz)")
        print(format_mpc_bench(bench_mpc()) + "\n")
    if args.suite not in ("planning", "all"):
        return 0
    from lab.planning.shipped import cold_start_s, format_table, plot_bench, run_bench, write_csv
    from planner.maps.problems import list_problems
    from planner.robot import load_robot

    robot = load_robot(args.robot)
    problems = [p for p in list_problems(args.maps) if args.problems in p.name or args.problems in p.map]
    if not problems:
        raise InvalidInput("--problems", f"no shipped problem matches {args.problems!r}")
    from tqdm import tqdm

    planners = 1 + (args.ompl_time > 0) + (args.rrt_time > 0)
    with tqdm(total=len(problems) * planners, file=sys.stderr, desc="bench",
              disable=quiet() or not sys.stderr.isatty()) as bar:

        def progress(msg: str) -> None:
            bar.set_postfix_str(msg[:40])
            bar.update(1)

        rows = run_bench(problems, robot, args.runs, args.ompl_time, args.rrt_time, progress=progress)
    print(format_table(rows))
    garage = next((p for p in problems if p.map.startswith("garage") and p.solvable), None)
    if garage is not None:
        print(f"\ncold start `sphereplan plan` on garage ({garage.name}): "
              f"{cold_start_s(garage.map_path, garage.start, garage.goal):.2f} s")
    csv_path, png_path = args.csv or "bench.csv", args.png or "bench.png"
    write_csv(rows, csv_path)
    budgets = {"ompl-BIT*": args.ompl_time, "ompl-RRT*": args.rrt_time}
    title = (f"sphereplan bench: {robot.name}, {len(problems)} shipped problems "
             f"({sum(not p.solvable for p in problems)} unsolvable), Hybrid A* median of {args.runs} runs"
             + (f", BIT* {args.ompl_time:g} s" if args.ompl_time > 0 else "")
             + (f", RRT* {args.rrt_time:g} s" if args.rrt_time > 0 else ""))
    plot_bench(rows, png_path, title, args.runs, budgets)
    print(f"wrote {csv_path} and {png_path}")
    return 0
