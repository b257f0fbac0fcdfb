"""Regenerate the MuJoCo numbers and figures of docs/vpip.md (paper 000 §5, Figs. 7 and 10; the cave run).

Run from the repository root (a few minutes on one core)::

    python tools/vpip_mujoco_figures.py --out docs/img            # all figures and docs/img/vpip-mujoco.json

1. Held-roll circles at 5°, 10°, 15° (ω = 1 rad/s, 30 s) on the MuJoCo plant → diameters, Fig. 10 style.
2. Fig. 7: ω(t) for fixed θ_VPIP 10/20/30/40° (roll held at 0) and the simple driver, MuJoCo plant.
3. `calibrate` from those circles → a daedalus profile whose roll table is the physics'.
4. A daedalus plan on maps/cave.yaml (problem ``cave_first_bend``) made with that profile, rolled by the
   VPIP cascade in MuJoCo; cross-track error reported (and the same with the paper's table, for contrast).
"""

from __future__ import annotations

import argparse
import json
import logging
import math
from pathlib import Path
from typing import Any

import numpy as np

from planner import load_map, plan_path
from planner.maps.problems import load_problem_set
from planner.robot import RobotProfile, load_robot, profile_from_dict
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


def _smooth(values: list[float], n: int = 50) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    return np.convolve(v, np.ones(n) / n, mode="same")


def _cave(profile: RobotProfile, problem_name: str) -> tuple[dict[str, Any], dict[str, Any]]:
    problems = {p.name: p for p in load_problem_set("maps/problems/cave.json")}
    prob = problems[problem_name]
    grid = load_map(prob.map_path)
    plan = plan_path(grid, profile, prob.start, prob.goal, time_limit_s=60.0).to_json()
    duration = float(plan["states"][-1]["t"])
    result = run_schedule(plan, profile, plant="mujoco", max_duration_s=3.0 * duration + 20.0)
    return plan, result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="docs/img")
    ap.add_argument("--duration", type=float, default=30.0, help="seconds per circle (paper: 30)")
    ap.add_argument("--problem", default="cave_first_bend")
    args = ap.parse_args()
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
