"""Regenerate the MuJoCo numbers and figures of docs/vpip.md (paper 000 §5, Figs. 7 and 10; the cave run).

Run from the repository root (a few minutes on one core)::

    python -m lab.vpip_mujoco_figures --out docs/img            # all figures and docs/img/vpip-mujoco.json

1. Held-roll circles at 5°, 10°, 15° (ω = 1 rad/s, 30 s) on the MuJoCo plant → diameters, Fig. 10 style;
   each repeated from six start headings (physically the same run on a flat floor; the spread is the
   runs' chaotic detail) and, from four headings, for the contact and roll-controller variants of
   docs/vpip.md ("Why the circles are wider") → ``vpip-mujoco-diameters.png``.
2. Fig. 7: ω(t) for fixed θ_VPIP 10/20/30/40° (roll held at 0) and the simple driver, MuJoCo plant.
3. `calibrate` from those circles → a daedalus profile whose roll table is the physics'.
4. A daedalus plan on maps/cave.yaml (problem ``cave_first_bend``) made with that profile, rolled by the
   VPIP cascade in MuJoCo; cross-track error reported (and the same with the paper's table, for contrast).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import math
from pathlib import Path
from typing import Any

import numpy as np

from planner import load_map, plan_path
from planner.maps.problems import load_problem_set
from planner.robot import RobotProfile, load_robot, profile_from_dict
from planner.termination import Termination
from planner.vpip.api import calibrate_from_circles, profile_toml
from planner.vpip.cascade import run_schedule
from planner.vpip.circle import run_circle
from planner.vpip.plot import plot_circle, plot_schedule

log = logging.getLogger("vpip_mujoco_figures")


def _fig7(profile: RobotProfile, out: Path, duration: float) -> dict[str, Any]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs: dict[str, Any] = {}
    fig, ax = plt.subplots(figsize=(9, 4.5), constrained_layout=True)
    for theta in (10, 20, 30, 40):
        r = run_circle(profile, 0.0, duration, "mujoco", "vpip", theta_vpip_rad=math.radians(theta))
        runs[f"theta_{theta}"] = r["summary"]
        ax.plot(r["series"]["t"], _smooth(r["series"]["omega_rad_s"]), lw=1.2, label=f"VPIP θ = {theta}°")
    r = run_circle(profile, 0.0, duration, "mujoco", "simple")
    runs["simple"] = r["summary"]
    ax.plot(r["series"]["t"], _smooth(r["series"]["omega_rad_s"]), "k", lw=1.4, label="simple (§2)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("ω (rad/s, 0.5 s moving average)")
    ax.set_title("Fig. 7 on the MuJoCo plant: fixed θ_VPIP (open loop, roll held at 0) vs the simple driver")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=5, loc="upper left")
    fig.savefig(out / "vpip-mujoco-fig7.png", dpi=90)
    plt.close(fig)
    return runs


HEADINGS = (0.0, 0.4, 0.8, 1.2, 1.6, 2.0)
"""Start headings (rad) of the repeated circle runs."""

VARIANTS: dict[str, dict[str, float]] = {
    "no-slip contact (Table 1 friction 100), no spin friction (Gazebo/ODE point contact)": {
        "ground_friction": 100.0,
        "rod_tip_friction": 100.0,
        "ground_torsional_friction_m": 0.0,
    },
    "no-slip contact (friction 100), spin friction 0.03 m": {"ground_friction": 100.0, "rod_tip_friction": 100.0},
    "rod feet no-slip (friction 100), shell unchanged": {"rod_tip_friction": 100.0},
    "roll k_d 0.5 (D part below the 20 deg limit at rod-driven roll rates)": {"roll_kd": 0.5},
    "roll anti-windup 10 deg (= k_i x 5 deg, the other reading of Table 1)": {"roll_integral_limit_deg": 10.0},
    "roll k_d 0.5 and anti-windup 10 deg (roll held closer)": {"roll_kd": 0.5, "roll_integral_limit_deg": 10.0},
}
"""Variants of the ``[vpip]`` section measured beside the default (keys override the profile's)."""

SHORT = {
    "ground_friction": "μ shell",
    "rod_tip_friction": "μ feet",
    "ground_torsional_friction_m": "spin fr.",
    "roll_kd": "roll k_d",
    "roll_integral_limit_deg": "roll AW°",
}
"""Legend abbreviations of the override keys."""


def _with_vpip(profile: RobotProfile, overrides: dict[str, float]) -> RobotProfile:
    extra = dict(profile.extra)
    extra["vpip"] = {**dict(extra["vpip"]), **overrides}
    return dataclasses.replace(profile, extra=extra)


def _stats(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Median, min and max over repeated runs of the numbers the docs quote (null fits left out)."""
    out: dict[str, Any] = {"runs": len(runs)}
    for key in (
        "diameter_m",
        "diameter_from_heading_m",
        "no_spin_diameter_m",
        "mean_roll_deg",
        "mean_omega_rad_s",
        "mean_spin_rad_s",
        "mean_no_spin_yaw_rate_rad_s",
        "mean_yaw_rate_rad_s",
        "turned_deg",
    ):
        v = np.array([r[key] for r in runs if r.get(key) is not None], dtype=float)
        out[key] = (
            {"median": float(np.median(v)), "min": float(v.min()), "max": float(v.max()), "n": int(v.size)}
            if v.size
            else None
        )
    return out


def _ensemble(profile: RobotProfile, duration: float, headings: tuple[float, ...]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for roll in (5.0, 10.0, 15.0):
        runs = [
            run_circle(profile, math.radians(roll), duration, "mujoco", "vpip", heading_rad=h)["summary"]
            for h in headings
        ]
        out[f"{roll:g}"] = _stats(runs)
        out[f"{roll:g}"]["rod_feet_first_heading"] = runs[0].get("rod_feet")
        out[f"{roll:g}"]["roll_pid_first_heading"] = runs[0].get("roll_pid")
        log.info("ensemble roll %g: %s", roll, out[f"{roll:g}"]["diameter_m"])
    return out


def _diameter_figure(report: dict[str, Any], out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rolls = np.array([5.0, 10.0, 15.0])
    fig, ax = plt.subplots(figsize=(9, 5.5), constrained_layout=True)
    fine = np.linspace(4.0, 16.0, 100)
    ax.plot(fine, 2 * 0.232 / np.tan(np.radians(fine)), "k-", lw=0.8, label="no spin, roll held: 2r / tan(roll)")
    ax.fill_between(rolls, 0.7 * np.array([2.6, 2.0, 1.7]), 1.3 * np.array([2.6, 2.0, 1.7]), color="C3", alpha=0.12,
                    label="paper ± 30 %")
    ax.plot(rolls, [2.6, 2.0, 1.7], "C3s", ms=8, label="paper §5 (Gazebo)")
    ens = report["circle_ensemble"]
    for dx, key, mark, label in (
        (-0.25, "diameter_m", "C0o", "default: circle fit"),
        (0.0, "diameter_from_heading_m", "C0^", "default: 2·path / turned"),
    ):
        for i, roll in enumerate(rolls):
            st = ens[f"{roll:g}"][key]
            if st is None:
                continue
            ax.errorbar(roll + dx, st["median"], yerr=[[st["median"] - st["min"]], [st["max"] - st["median"]]],
                        fmt=mark, capsize=3, label=label if i == 0 else None)
    held = [ens[f"{r:g}"]["no_spin_diameter_m"]["median"] for r in rolls]
    ax.plot(rolls, held, "kD", mfc="none", ms=7, label="default: 2r / tan(roll actually held), median")
    for j, (name, res) in enumerate(report["variants"].items()):
        med = [res[f"{r:g}"]["diameter_m"]["median"] if res[f"{r:g}"]["diameter_m"] else np.nan for r in rolls]
        over = report["variant_overrides"][name]
        short = ", ".join(f"{SHORT.get(k, k)} {v:g}" for k, v in over.items())
        ax.plot(rolls + 0.25 + 0.1 * j, med, "x", color=f"C{j + 4}", ms=7, label=f"variant {short}: fit, median")
    ax.set_xlabel("desired roll (deg)")
    ax.set_ylabel("circle diameter (m)")
    ax.set_ylim(0, 11)
    ax.set_title("Held-roll circles on the MuJoCo plant (30 s, ω = 1 rad/s asked): median, range over start headings")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")
    fig.savefig(out / "vpip-mujoco-diameters.png", dpi=90)
    plt.close(fig)


def _smooth(values: list[float], n: int = 50) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    return np.convolve(v, np.ones(n) / n, mode="same")


def _cave(profile: RobotProfile, problem_name: str) -> tuple[dict[str, Any], dict[str, Any]]:
    problems = {p.name: p for p in load_problem_set("maps/problems/cave.json")}
    prob = problems[problem_name]
    grid = load_map(prob.map_path)
    plan = plan_path(grid, profile, prob.start, prob.goal, termination=Termination(60.0)).to_json()
    duration = float(plan["states"][-1]["t"])
    result = run_schedule(plan, profile, plant="mujoco", max_duration_s=3.0 * duration + 20.0)
    return plan, result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="docs/img")
    ap.add_argument("--duration", type=float, default=30.0, help="seconds per circle (paper: 30)")
    ap.add_argument("--problem", default="cave_first_bend")
    ap.add_argument("--replot", action="store_true", help="only redraw vpip-mujoco-diameters.png from the JSON")
    args = ap.parse_args()
    if args.replot:
        _diameter_figure(json.loads((Path(args.out) / "vpip-mujoco.json").read_text()), Path(args.out))
        return
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    daedalus = load_robot("daedalus")
    report: dict[str, Any] = {}

    circles = []
    for roll in (5.0, 10.0, 15.0):
        r = run_circle(daedalus, math.radians(roll), args.duration, "mujoco", "vpip")
        plot_circle(r, out / f"vpip-mujoco-circle{int(roll)}.png")
        circles.append(r["summary"])
        log.info("roll %g: diameter %s", roll, r["summary"]["diameter_m"])
    report["circles"] = circles
    report["circle_ensemble"] = _ensemble(daedalus, args.duration, HEADINGS)
    report["variants"] = {
        name: _ensemble(_with_vpip(daedalus, over), args.duration, HEADINGS[:4]) for name, over in VARIANTS.items()
    }
    report["variant_overrides"] = VARIANTS
    _diameter_figure(report, out)
    simple = run_circle(daedalus, math.radians(10.0), args.duration, "mujoco", "simple")
    plot_circle(simple, out / "vpip-mujoco-simple10.png")
    report["simple_circle_10"] = simple["summary"]

    report["fig7"] = _fig7(daedalus, out, 20.0)

    cal = calibrate_from_circles(circles, daedalus)
    report["calibration"] = {k: cal[k] for k in ("roll_model", "table", "source")}
    import tomllib

    physics_profile = profile_from_dict(tomllib.loads(profile_toml(daedalus, cal["roll_model"])), "daedalus")
    for name, prof in (("mujoco_table", physics_profile), ("paper_table", daedalus)):
        try:
            plan, result = _cave(prof, args.problem)
        except Exception as exc:  # a planning failure is a result too
            report[f"cave_{name}"] = {"error": f"{type(exc).__name__}: {exc}"}
            continue
        plot_schedule(result, out / f"vpip-mujoco-cave-{name.replace('_', '-')}.png", plan)
        report[f"cave_{name}"] = {
            "problem": args.problem,
            "plan_length_m": plan["length_m"],
            "plan_min_turning_radius_m": prof.min_turning_radius_m,
            **result["summary"],
        }
        log.info("cave %s: %s", name, result["summary"])
    (out / "vpip-mujoco.json").write_text(json.dumps(report, indent=2, allow_nan=False) + "\n")


if __name__ == "__main__":
    main()
