"""``sphereplan controllers``: paper 001's motion-control experiments on the pendulum sphere's dynamic model.

sphereplan controllers step --controller lmpc|pid --speed V [--floor tiled|rubber] --out F.json [--plot F.png]
sphereplan controllers roll --controller rslqr|pid --speed V --roll PHI --out F.json [--plot F.png]
sphereplan controllers figures [--out-dir DIR] [--out F.json]     every case of Figs. 11–13, both controllers
sphereplan controllers patrol [--map maps/garage.yaml] [--goal X Y YAW ...] --out F.json [--plot F.png]
sphereplan controllers tune --loop speed|roll                      how the PID baselines were tuned
sphereplan controllers bench                                       controller step times (table)
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from planner.errors import InvalidInput
from service.cli._io import (
    add_degrees_flag,
    angle,
    emit_json,
    finite_float,
    make_folder,
    map_path,
    positive_float,
    say,
    seed_int,
)
from service.outcome import EXIT_NO_SOLUTION

VERB = "controllers"
HELP = "pendulum-sphere motion control (paper 001 §5–6): LMPC/RSLQR vs PID steps, Figs. 10–13, tuning, timing"


def _summary(result: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in result.items() if k not in ("series", "trajectory", "estimate", "odometry", "gnss",
                                                          "commands", "plan")}


def _emit(result: dict[str, Any], out: str | None) -> None:
    """The full result to ``out`` (and its figures without time series on stdout), or all of it on stdout; a
    one-line summary on stderr."""
    emit_json(result, out)
    if out:
        emit_json(_summary(result), None)
    rise = result.get("rise_time_s")
    rise_text = "none" if rise is None else f"{rise:.3f} s"
    say("controllers", f"{result.get('experiment', 'step')} with {result.get('controller')}: rise {rise_text}, "
                       f"overshoot {100 * result.get('overshoot', 0):.1f} %")


def _step(args: argparse.Namespace) -> int:
    from planner.pendulum.steps import speed_step

    result = speed_step(args.robot, args.controller, args.speed, args.floor, args.duration)
    if args.plot:
        from planner.pendulum.plot import plot_step

        plot_step(result, args.plot)
    _emit(result, args.out)
    return 0


def _roll(args: argparse.Namespace) -> int:
    from planner.pendulum.steps import roll_step

    roll = angle(args, args.roll, "--roll")
    result = roll_step(args.robot, args.controller, args.speed, roll, args.duration)
    if args.plot:
        from planner.pendulum.plot import plot_step

        plot_step(result, args.plot)
    _emit(result, args.out)
    return 0


def _figures(args: argparse.Namespace) -> int:
    from lab.pendulum.figures import format_summary, run_figures, summary_rows
    from planner.pendulum.plot import plot_fig11, plot_fig12, plot_fig13

    folder = Path(args.out_dir) if args.out_dir else None
    if folder is not None:
        make_folder(folder, "--out-dir")
    figs = run_figures(args.robot)
    if folder is not None:
        stem = f"pendulum-{figs['robot']}"
        plot_fig11(figs, folder / f"{stem}-fig11.png")
        plot_fig12(figs, folder / f"{stem}-fig12.png")
        plot_fig13(figs, folder / f"{stem}-fig13.png")
    if args.out:
        emit_json(figs, args.out)
    sys.stdout.write(format_summary(figs) + "\n")
    limits = ", ".join(f"{v} m/s: {r:.3f} rad" for v, r in figs["max_steady_roll_rad"].items())
    sys.stdout.write(f"largest roll the auxiliary motor can hold in a steady turn: {limits}\n")
    if args.json:
        emit_json(summary_rows(figs), None)
    return 0


def _tune(args: argparse.Namespace) -> int:
    from lab.pendulum.tuning import tune_pid, tune_rslqr

    if args.controller == "rslqr":
        if args.loop != "roll":
            raise InvalidInput("loop", "the RSLQR is the roll controller: use --loop roll")
        from planner.pendulum.rslqr import RSLQRSettings

        st = tune_rslqr(args.robot, base=RSLQRSettings(scheduled=args.scheduled))
        sys.stdout.write(
            f"# RSLQRSettings.q (on ∫e, β, β̇, φ − φ_d, φ̇; r = {st.settings.r}, "
            f"scheduled = {st.settings.scheduled}): objective {st.objective:.3f} s "
            f"after {st.evaluations} evaluations\nq = {st.settings.q}\n"
        )
        emit_json(st.cases, None)
        return 0
    res = tune_pid(args.robot, args.loop)
    g = res.gains
    band = "" if g.integral_band is None else f", integral_band = {g.integral_band}"
    sys.stdout.write(
        f"[dynamics.pid.{args.loop}]  # sphereplan controllers tune --loop {args.loop}: objective "
        f"{res.objective:.3f} s after {res.evaluations} evaluations\n"
        f"kp = {g.kp}, ki = {g.ki}, kd = {g.kd}, inner_kp = {g.inner_kp}, inner_ki = {g.inner_ki}, "
        f"inner_kd = {g.inner_kd}{band}\n"
    )
    emit_json(res.cases, None)
    return 0


def _bench(args: argparse.Namespace) -> int:
    from lab.pendulum.timing import bench_controllers, format_bench

    sys.stdout.write(format_bench(bench_controllers(args.robot, args.steps)) + "\n")
    return 0


def _pose(values: list[float], field: str) -> tuple[float, float, float]:
    if len(values) != 3:
        raise InvalidInput(field, "needs three numbers X Y YAW")
    return values[0], values[1], values[2]


def _patrol(args: argparse.Namespace) -> int:
    from planner.closed_loop.patrol import GARAGE_PATROL, patrol
    from planner.maps.nav2 import load_map
    from planner.robot import load_robot

    goals = [_pose(g, f"goal[{i}]") for i, g in enumerate(args.goal)] if args.goal else list(GARAGE_PATROL)
    if len(goals) < 2:
        raise InvalidInput("goal", "give a start and at least one goal (--goal X Y YAW, repeated)")
    grid = load_map(map_path(args.map))
    robot = load_robot(args.robot)
    result = patrol(grid, robot, goals, model=args.model, seed=args.seed, noise=args.noise)
    if args.plot:
        from planner.closed_loop.plot import plot_simulation

        plot_simulation(grid, result["plan"], result, args.plot)
    _emit(result, args.out)
    worst = result["patrol"]["true_error_max_m"]
    if result["status"] != "reached":  # written for a look; the exit code says it failed (as simulate's)
        say("controllers", f"patrol FAILED: {result['error_msg']}; worst true goal error {worst:.2f} m")
        return EXIT_NO_SOLUTION
    say("controllers", f"patrol reached its last goal; worst true goal error {worst:.2f} m (GNSS denied)")
    return 0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="controllers_command", required=True, parser_class=type(parser))

    def common(p: argparse.ArgumentParser) -> None:
        p.add_argument("--robot", default="zju-60", help="pendulum-sphere profile with [dynamics] (default zju-60)")

    step = sub.add_parser("step", help="Figs. 11-12: from rest to --speed under LMPC or PID")
    step.add_argument("--controller", choices=("lmpc", "pid"), required=True)
    step.add_argument("--speed", type=finite_float, required=True, metavar="V", help="desired speed (m/s)")
    step.add_argument("--floor", default=None, help="floor of the profile's rolling_resistance (tiled, rubber)")
    step.add_argument("--duration", type=positive_float, default=8.0, metavar="S", help="run length (8 s)")
    step.add_argument("--out", metavar="F.json", help="write the result here (default: stdout)")
    step.add_argument("--plot", metavar="F.png", help="draw speed, pendulum pitch and torque")
    common(step)
    step.set_defaults(func=_step)

    roll = sub.add_parser("roll", help="Fig. 13: a roll step to --roll while rolling at --speed, RSLQR or PID")
    roll.add_argument("--controller", choices=("rslqr", "pid"), required=True)
    roll.add_argument("--speed", type=finite_float, required=True, metavar="V", help="rolling speed (m/s)")
    roll.add_argument("--roll", type=finite_float, required=True, metavar="PHI", help="desired roll (rad)")
    add_degrees_flag(roll)
    roll.add_argument("--duration", type=positive_float, default=4.0, metavar="S", help="run after the step (4 s)")
    roll.add_argument("--out", metavar="F.json", help="write the result here (default: stdout)")
    roll.add_argument("--plot", metavar="F.png", help="draw roll, pendulum roll and torque")
    common(roll)
    roll.set_defaults(func=_roll)

    figs = sub.add_parser("figures", help="every case of Figs. 11-13 with both controllers: table (+ PNGs)")
    figs.add_argument("--out-dir", metavar="DIR", help="write pendulum-<robot>-fig11/12/13.png here")
    figs.add_argument("--out", metavar="F.json", help="write every run with its time series here")
    figs.add_argument("--json", action="store_true", help="also print the table rows as JSON")
    common(figs)
    figs.set_defaults(func=_figures)

    pat = sub.add_parser("patrol", help="Fig. 10: a patrol over several goals without GNSS")
    pat.add_argument("--map", default="maps/garage.yaml", metavar="M.yaml", help="map (default maps/garage.yaml)")
    pat.add_argument(
        "--goal", nargs=3, type=finite_float, action="append", metavar=("X", "Y", "YAW"),
        help="start, then goals (repeat; default: a garage patrol)",
    )
    pat.add_argument("--model", choices=("dynamic", "kinematic"), default="dynamic", help="plant (dynamic)")
    pat.add_argument("--seed", type=seed_int, default=0, help="seed of every disturbance (default 0)")
    pat.add_argument("--noise", choices=("none", "default"), default="default", help="disturbances")
    pat.add_argument("--out", metavar="F.json", help="write the SIM.json with the patrol report here")
    pat.add_argument("--plot", metavar="F.png", help="draw the patrol")
    common(pat)
    pat.set_defaults(func=_patrol)

    tune = sub.add_parser("tune", help="tune a PID baseline (or the RSLQR) as docs/pendulum.md describes (minutes)")
    tune.add_argument("--loop", choices=("speed", "roll"), required=True)
    tune.add_argument("--controller", choices=("pid", "rslqr"), default="pid", help="what to tune (pid)")
    tune.add_argument(
        "--scheduled", action="store_true", help="RSLQR: design the gains about rolling at the measured speed"
    )
    common(tune)
    tune.set_defaults(func=_tune)

    bench = sub.add_parser("bench", help="print the controllers' step times")
    bench.add_argument("--steps", type=int, default=300, help="control periods per controller (300)")
    common(bench)
    bench.set_defaults(func=_bench)
