"""``sphereplan tensegrity``: statics, rolling gaits and form finding of the TeXploR robot (paper 002)."""

from __future__ import annotations

import argparse
import math

from planner.errors import InvalidInput
from service.cli._io import Stages, add_degrees_flag, angle, emit_json, finite_float, say

VERB = "tensegrity"
HELP = "two-arc tensegrity robot (TeXploR): static states, rolling gaits, form finding"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="tensegrity_command", required=True)

    static = sub.add_parser("static", help="the four hybrid static states for slider angles θ1, θ2")
    static.add_argument(
        "--theta1", type=finite_float, required=True, help="slider 1 angle (rad, or deg with --degrees)"
    )
    static.add_argument(
        "--theta2", type=finite_float, required=True, help="slider 2 angle (rad, or deg with --degrees)"
    )
    add_degrees_flag(static)
    static.add_argument("--no-verify", action="store_true", help="skip the potential-energy cross-check")
    static.add_argument("--robot", default="texplor", help="profile name or TOML path (default texplor)")
    static.add_argument("--out", help="write the JSON here instead of stdout")

    gait = sub.add_parser("gait", help="slider trajectories that roll the robot a distance")
    gait.add_argument("--distance", type=finite_float, required=True, help="metres; negative = reverse gait")
    gait.add_argument("--steps", type=int, default=32, help="samples per state leg (default 32)")
    gait.add_argument("--start-state", type=int, default=1, help="hybrid state at the start (1-4, default 1)")
    gait.add_argument(
        "--corner", type=finite_float, help="slider path corner θ1 (rad, or deg with --degrees; default 45°)"
    )
    add_degrees_flag(gait)
    gait.add_argument(
        "--measure",
        choices=("net", "rolled"),
        default="net",
        help="distance = net advance of the centre (default) or rolled contact length Σ r|Δφ|",
    )
    gait.add_argument("--robot", default="texplor", help="profile name or TOML path (default texplor)")
    gait.add_argument("--out", help="write the JSON here instead of stdout")
    gait.add_argument("--plot", help="write a Fig. 9-style PNG here")

    formfind = sub.add_parser("formfind", help="cable-energy form finding (eq. 18): T12 and cable lengths")
    formfind.add_argument(
        "--fix-centre", action="store_true", help="keep the arc centres coincident (o12 = 0)"
    )
    formfind.add_argument("--starts", type=int, default=16, help="optimiser starts (default 16)")
    formfind.add_argument("--seed", type=int, default=0, help="seed of the random starts")
    formfind.add_argument("--robot", default="texplor", help="profile name or TOML path (default texplor)")
    formfind.add_argument("--out", help="write the JSON here instead of stdout")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Dispatch ``sphereplan tensegrity static|gait|formfind``; returns the exit code."""
    commands = {"static": _run_static, "gait": _run_gait, "formfind": _run_formfind}
    return commands[args.tensegrity_command](args)


def _run_static(args: argparse.Namespace) -> int:
    from planner.robot import load_robot
    from planner.tensegrity import static_equilibria

    result = static_equilibria(
        angle(args, args.theta1, "--theta1"), angle(args, args.theta2, "--theta2"), load_robot(args.robot),
        not args.no_verify,
    )
    emit_json(result, args.out)
    feasible = [str(s["state"]) for s in result["states"] if s["feasible"]]
    checked = "" if args.no_verify else f", checked by energy minimisation: {result['verified']}"
    states = ", ".join(feasible) or "none"
    say("tensegrity static", f"feasible rest states {states} of {len(result['states'])}{checked}")
    return 0


def _run_gait(args: argparse.Namespace) -> int:
    from planner.robot import load_robot
    from planner.tensegrity import plan_gait
    from planner.tensegrity.geometry import params_from_profile
    from planner.tensegrity.plot import plot_gait

    if not args.out:
        raise InvalidInput("out", "the gait JSON is long; give --out FILE.json")
    corner_deg = None if args.corner is None else math.degrees(angle(args, args.corner, "--corner"))
    with Stages("tensegrity gait", ["plan the gait", *(["plot"] if args.plot else [])]) as stages:
        stages.start("plan the gait")
        profile = load_robot(args.robot)
        result = plan_gait(args.distance, profile, args.steps, args.start_state, corner_deg, args.measure)
        if args.plot:
            stages.start("plot")
            plot_gait(result, params_from_profile(profile), args.plot)
    emit_json(result, args.out)
    say("tensegrity gait", f"{result['net_displacement_m']:.3f} m net in {result['duration_s']:.1f} s through states "
                           f"{result['state_sequence']}, wrote {args.out}{' and ' + args.plot if args.plot else ''}")
    return 0


def _run_formfind(args: argparse.Namespace) -> int:
    from planner.robot import load_robot
    from planner.tensegrity import form_find

    result = form_find(load_robot(args.robot), args.fix_centre, args.starts, args.seed)
    emit_json(result, args.out)
    say("tensegrity formfind", f"cable energy {result['energy_j']:.4g} J, "
                               f"{result['rotation_error_deg_vs_eq3']:.3g}° from eq. 3's rotation")
    return 0
