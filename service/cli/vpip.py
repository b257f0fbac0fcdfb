"""``sphereplan vpip``: rod lengths, roll↔radius, calibration, 100 Hz rod schedules and circle runs (paper 000)."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

from planner.errors import InvalidInput
from planner.vpip.choices import CONTACTS, DRIVERS, GAIN_SETS, PLANTS
from service.cli._io import (
    Stages,
    add_degrees_flag,
    angle,
    angle_deg,
    emit_json,
    finite_float,
    is_mcap_out,
    positive_float,
    read_json_file,
    say,
)
from service.outcome import EXIT_NO_SOLUTION

VERB = "vpip"
HELP = "VPIP rod driver for rod-driven spheres (daedalus): rods, radius, roll, calibrate, schedule, circle"


def _rods(args: argparse.Namespace) -> int:
    from planner.vpip import api

    report = api.rods_report(
        angle(args, args.phi_vpip, "--phi-vpip"),
        angle(args, args.theta_vpip, "--theta-vpip"),
        angle(args, args.roll, "--roll"),
        angle(args, args.pitch_phase, "--pitch-phase"),
        args.robot,
    )
    emit_json(report, None)
    active = [r for r in report["rods"] if r["active"]]
    longest = max((r["length_m"] for r in active), default=0.0)
    say("vpip rods", f"{len(active)} of {len(report['rods'])} rods active, the longest {longest:.3f} m")
    return 0


def _radius(args: argparse.Namespace) -> int:
    from planner.vpip import api

    report = api.radius_report(angle(args, args.roll, "--roll"), args.robot)
    emit_json(report, None)
    radius = report["radius_m"]
    turn = "rolls straight" if radius is None else f"turns on a {radius:.3f} m radius"
    say("vpip radius", f"roll {report['roll_rad']:.4g} rad {turn} "
                       f"({report['model']}{', beyond the table' if report['beyond_table'] else ''})")
    return 0


def _roll(args: argparse.Namespace) -> int:
    from planner.vpip import api

    report = api.roll_report(args.radius, args.robot, left=not args.right)
    emit_json(report, None)
    if report["roll_rad"] is None:
        say("vpip roll", f"a {report['radius_m']:.3f} m radius is not achievable")
    else:
        say("vpip roll", f"a {report['radius_m']:.3f} m radius needs roll {report['roll_rad']:.4g} rad "
                         f"({report['roll_deg']:.2f}°){'' if report['achievable'] else ', not achievable'}")
    return 0


def _read(path: str, field: str) -> str:
    p = Path(path)
    if not p.is_file():
        raise InvalidInput(field, f"file {path} does not exist")
    return p.read_text()


def _rolls(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise InvalidInput("rolls", f"must be comma-separated numbers in degrees, got {text!r}") from None
    if not values or not all(math.isfinite(v) and 0 < v < 90 for v in values):
        raise InvalidInput("rolls", f"must be comma-separated rolls in (0, 90) degrees, got {text!r}")
    return [math.radians(v) for v in values]


def _calibrate(args: argparse.Namespace) -> int:
    from planner.robot import load_robot
    from planner.vpip import api

    profile = load_robot(args.robot)
    sources = sum(x is not None for x in (args.runs, args.circles, args.rolls))
    if sources != 1:
        raise InvalidInput("runs", "give exactly one of --runs (CSV), --circles (circle JSONs), --rolls (simulate)")
    if args.runs is not None:
        result = api.calibrate_report(_read(args.runs, "runs"), profile)
    elif args.circles is not None:
        circles = [read_json_file(path, f"circles[{i}]") for i, path in enumerate(args.circles)]
        result = api.calibrate_from_circles(circles, profile)
    else:
        result = api.calibrate_by_simulation(
            _rolls(args.rolls), profile, args.plant, args.duration, contact=args.contact, gains=args.gains
        )
    if args.out:
        Path(args.out).write_text(api.profile_toml(profile, result["roll_model"]))
        load_robot(args.out)  # the written profile must load
        result["profile_written"] = str(args.out)
    emit_json(result, None)
    return 0


def _circle(args: argparse.Namespace) -> int:
    from planner.vpip import api

    if not 0 < args.duration <= 600:
        raise InvalidInput("duration", f"must be in (0, 600] s, got {args.duration}")
    theta = None if args.theta_deg is None else math.radians(angle_deg(args.theta_deg, "--theta-deg"))
    result = api.circle_report(
        math.radians(angle_deg(args.roll_deg, "--roll-deg")),
        args.robot,
        args.plant,
        args.duration,
        args.driver,
        args.omega,
        theta,
        heading_rad=math.radians(angle_deg(args.heading_deg, "--heading-deg")),
        contact=args.contact,
        gains=args.gains,
    )
    emit_json(result, args.out)
    if args.plot:
        from planner.vpip.plot import plot_circle

        plot_circle(result, args.plot)
    emit_json({"out": str(args.out), "plot": args.plot, **result["summary"]}, None)
    return 0


def _schedule(args: argparse.Namespace) -> int:
    from planner.vpip import api

    plan: Any = read_json_file(args.path, "path")
    with Stages("vpip schedule", ["schedule", *(["plot"] if args.plot else [])]) as stages:
        stages.start("schedule")
        result = api.schedule_report(plan, args.robot, args.driver, args.plant, args.contact, args.gains)
        if is_mcap_out(args.out):
            from service.ros import write_schedule_mcap

            write_schedule_mcap(args.out, plan, result)
        else:
            emit_json(result, args.out)
        if args.plot:
            stages.start("plot")
            from planner.vpip.plot import plot_schedule

            plot_schedule(result, args.plot, plan)
    summary = result["summary"]
    emit_json({"out": str(args.out), "plot": args.plot, "driver": result["driver"], **summary}, None)
    if not summary["reached_end"]:  # the files are written for a look; the exit code says it failed
        sys.stderr.write(
            f"sphereplan vpip schedule: {result['robot']} did not reach the end of the path: stopped after "
            f"{summary['duration_s']:.1f} s (the plan takes {summary['plan_duration_s']:.1f} s), "
            f"{summary['final_position_error_m']:.2f} m from its end\n"
        )
        return EXIT_NO_SOLUTION
    return 0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="vpip_command", required=True, parser_class=type(parser))

    def common(p: argparse.ArgumentParser, robot_default: str | None = "daedalus") -> None:
        p.add_argument("--robot", default=robot_default, help="profile name or TOML path (default: daedalus)")

    def settings(p: argparse.ArgumentParser) -> None:
        p.add_argument(
            "--contact",
            choices=CONTACTS,
            help="MuJoCo contact setting from the profile: regolith (its default) or paper (the paper's Gazebo "
            "defaults: Table 1 friction, no spin or rolling friction); docs/vpip.md",
        )
        p.add_argument(
            "--gains",
            choices=GAIN_SETS,
            help="controller gains from the profile: rod-rate (its default, chosen for 0.1 m/s rods) or table1 "
            "(paper 000 Table 1); docs/vpip.md",
        )

    rods = sub.add_parser("rods", help="eq. 18 length of every rod for one plane, roll and pitch phase")
    rods.add_argument(
        "--phi-vpip", type=finite_float, required=True, help="plane roll, > 0 lowers the left side"
    )
    rods.add_argument(
        "--theta-vpip", type=finite_float, required=True, help="plane pitch, > 0 drives forward"
    )
    rods.add_argument("--roll", type=finite_float, default=0.0, help="robot roll, > 0 leans left (default 0)")
    rods.add_argument("--pitch-phase", type=finite_float, default=0.0, help="how far the sphere has rolled")
    add_degrees_flag(rods)
    common(rods)
    rods.set_defaults(func=_rods)

    radius = sub.add_parser("radius", help="turning radius held at a roll angle (profile roll model)")
    radius.add_argument("--roll", type=finite_float, required=True, help="roll (rad; --degrees for degrees)")
    add_degrees_flag(radius)
    common(radius)
    radius.set_defaults(func=_radius)

    roll = sub.add_parser("roll", help="roll angle that holds a turning radius (profile roll model)")
    roll.add_argument("--radius", type=positive_float, required=True, help="turning radius (m)")
    roll.add_argument("--right", action="store_true", help="right turn (negative roll)")
    common(roll)
    roll.set_defaults(func=_roll)

    cal = sub.add_parser(
        "calibrate", help="fit a calibrated roll model from measured runs, circle JSONs or simulated circles"
    )
    cal.add_argument("--runs", help="CSV with header roll_deg,diameter_m (one row per run)")
    cal.add_argument("--circles", nargs="+", help="circle result JSONs written by 'vpip circle --out'")
    cal.add_argument("--rolls", help="simulate one circle per roll, comma-separated degrees (e.g. 5,10,15)")
    cal.add_argument("--plant", choices=PLANTS, default="mujoco", help="plant for --rolls (default mujoco)")
    cal.add_argument("--duration", type=positive_float, default=30.0, help="seconds per simulated circle")
    cal.add_argument("--out", help="write the profile with the fitted table to this TOML file")
    common(cal)
    settings(cal)
    cal.set_defaults(func=_calibrate)

    sched = sub.add_parser("schedule", help="100 Hz VPIP angles and rod lengths along a planned path")
    sched.add_argument(
        "--path", required=True, help="planner result JSON (states x, y, yaw, roll, v, t, s, curvature)"
    )
    sched.add_argument("--out", required=True, help="write the time series JSON here; a name ending in .mcap "
                       "writes ROS 2 messages (rod lengths and plane angles as JointState, the plan)")
    sched.add_argument("--plot", help="write a PNG: rod-length heat map, roll and plane angles, path")
    sched.add_argument(
        "--driver", choices=DRIVERS, default="vpip", help="rod driver (default vpip)"
    )
    sched.add_argument(
        "--plant", choices=PLANTS, default="surrogate", help="surrogate (fast, default) or mujoco (rod physics)"
    )
    common(sched)
    settings(sched)
    sched.set_defaults(func=_schedule)

    circ = sub.add_parser("circle", help="hold a roll (and omega) on a plant and fit the circle rolled (paper §5)")
    circ.add_argument("--roll-deg", type=finite_float, required=True, help="desired roll (deg), > 0 turns left")
    circ.add_argument(
        "--plant", choices=PLANTS, default="mujoco", help="mujoco (rod physics, default) or surrogate (table)"
    )
    circ.add_argument("--duration", type=positive_float, default=30.0, help="simulated seconds (default 30)")
    circ.add_argument("--out", required=True, help="write the result with its time series (JSON) here")
    circ.add_argument("--plot", help="write a PNG: track with fitted circle, roll, omega, rods")
    circ.add_argument("--driver", choices=DRIVERS, default="vpip", help="rod driver (default vpip)")
    circ.add_argument("--omega", type=positive_float, default=1.0, help="desired rolling rate (rad/s, default 1)")
    circ.add_argument(
        "--theta-deg",
        type=finite_float,
        help="hold theta_vpip fixed (deg, open loop as in Fig. 7) instead of the pitch PI",
    )
    circ.add_argument(
        "--heading-deg",
        type=finite_float,
        default=0.0,
        help="start heading (deg, default 0); repeat a MuJoCo run at other headings to see its spread",
    )
    add_degrees_flag(circ)  # accepted on every angle-taking command; the --...-deg options are degrees anyway
    common(circ)
    settings(circ)
    circ.set_defaults(func=_circle)
    parser.set_defaults(func=lambda args: args.func(args))
