"""Regenerate the MuJoCo numbers and figures of docs/vpip.md (paper 000 §5, Figs. 7 and 10; the cave run).

Run from the repository root (a few minutes on one core)::

    python -m lab.vpip_mujoco_figures --out docs/img            # all figures and docs/img/vpip-mujoco.json

For each contact setting of the daedalus profile (``paper``: the paper's Gazebo defaults; ``regolith``):

1. Held-roll circles at 5°, 10°, 15° (ω = 1 rad/s, 30 s, the default ``rod-rate`` gains) on the MuJoCo
   plant, each repeated from six start headings (physically the same run on a flat floor; the spread is
   the runs' chaotic detail), with the spin/lean split of every turn; the same from four headings with
   Table 1's gains (``--gains table1``) for contrast → ``vpip-mujoco-diameters.png`` (diameter against
   the roll actually held, both contacts).
2. `calibrate` from the heading-0 circles (what ``vpip calibrate --rolls 5,10,15 --contact C`` does) →
   a daedalus profile whose roll table is that ground's physics.
3. A daedalus plan on maps/cave.yaml (problem ``cave_first_bend``) made with that table, rolled by the VPIP
   cascade in MuJoCo on the same contact; cross-track error reported.

Then Fig. 7 (fixed θ_VPIP, roll held at 0, and the simple driver) on the paper contact.
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
from planner.termination import Termination
from planner.vpip.api import calibrate_from_circles, profile_toml
from planner.vpip.cascade import run_schedule
from planner.vpip.choices import CONTACTS
from planner.vpip.circle import PAPER_DIAMETERS_M, run_circle
from planner.vpip.plot import plot_circle, plot_schedule

log = logging.getLogger("vpip_mujoco_figures")

ROLLS = (5.0, 10.0, 15.0)
"""Desired rolls (deg) of paper 000 §5."""

def _fig7(profile: RobotProfile, out: Path, duration: float, contact: str) -> dict[str, Any]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs: dict[str, Any] = {}
    fig, ax = plt.subplots(figsize=(9, 4.5), constrained_layout=True)
    for theta in (10, 20, 30, 40):
        r = run_circle(
            profile, 0.0, duration, "mujoco", "vpip", theta_vpip_rad=math.radians(theta), contact=contact
        )
        runs[f"theta_{theta}"] = r["summary"]
        ax.plot(r["series"]["t"], _smooth(r["series"]["omega_rad_s"]), lw=1.2, label=f"VPIP θ = {theta}°")
    r = run_circle(profile, 0.0, duration, "mujoco", "simple", contact=contact)
    runs["simple"] = r["summary"]
    ax.plot(r["series"]["t"], _smooth(r["series"]["omega_rad_s"]), "k", lw=1.4, label="simple (§2)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("ω (rad/s, 0.5 s moving average)")
    ax.set_title(f"Fig. 7 on the MuJoCo plant ({contact} contact): fixed θ_VPIP (open loop, roll held at 0) vs simple")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=5, loc="upper left")
    fig.savefig(out / "vpip-mujoco-fig7.png", dpi=90)
    plt.close(fig)
    return runs


HEADINGS = (0.0, 0.4, 0.8, 1.2, 1.6, 2.0)
"""Start headings (rad) of the repeated circle runs."""

STAT_KEYS = (
    "diameter_m",
    "diameter_from_heading_m",
    "no_spin_diameter_m",
    "spin_lean_diameter_m",
    "held_roll_deg",
    "std_roll_deg",
    "mean_omega_rad_s",
    "mean_spin_rad_s",
    "mean_no_spin_yaw_rate_rad_s",
    "mean_yaw_rate_rad_s",
    "turned_deg",
)
"""Summary numbers the docs quote, as median (range) over the start headings."""


def _stats(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Median, min and max over repeated runs of :data:`STAT_KEYS` (null fits left out), rod-rate extremes."""
    out: dict[str, Any] = {"runs": len(runs)}
    for key in STAT_KEYS:
        v = np.array([r[key] for r in runs if r.get(key) is not None], dtype=float)
        out[key] = (
            {"median": float(np.median(v)), "min": float(v.min()), "max": float(v.max()), "n": int(v.size)}
            if v.size
            else None
        )
    out["max_measured_rod_rate_m_s"] = max(r["measured_rod_rate"]["max_m_s"] for r in runs)
    out["max_p95_measured_rod_rate_m_s"] = max(r["measured_rod_rate"]["p95_m_s"] for r in runs)
    out["max_commanded_rod_rate_m_s"] = max(r["commanded_rod_rate"]["max_m_s"] for r in runs)
    out["max_roll_pid_saturated_fraction"] = max(r.get("roll_pid", {}).get("output_saturated_fraction", 0.0)
                                                 for r in runs)
    return out


def _ensemble(
    profile: RobotProfile, duration: float, headings: tuple[float, ...], contact: str, gains: str
) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for roll in ROLLS:
        runs = [
            run_circle(
                profile, math.radians(roll), duration, "mujoco", "vpip", heading_rad=h, contact=contact, gains=gains
            )["summary"]
            for h in headings
        ]
        out[f"{roll:g}"] = _stats(runs)
        out[f"{roll:g}"]["rod_feet_first_heading"] = runs[0].get("rod_feet")
        out[f"{roll:g}"]["roll_pid_first_heading"] = runs[0].get("roll_pid")
        log.info("%s/%s roll %g: %s", contact, gains, roll, out[f"{roll:g}"]["diameter_m"])
    return out


def _diameter_figure(report: dict[str, Any], out: Path) -> None:
    """Diameter against the roll actually held, both contact settings, with the no-spin curve and the paper."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 5.5), constrained_layout=True)
    fine = np.linspace(3.0, 16.0, 100)
    ax.plot(fine, 2 * 0.232 / np.tan(np.radians(fine)), "k-", lw=0.8, label="no spin: 2r / tan(held roll)")
    paper = np.array([PAPER_DIAMETERS_M[r] for r in ROLLS])
    ax.plot(ROLLS, paper, "C3s", ms=8, label="paper §5 (Gazebo), at the roll asked for")
    for contact, colour in zip(CONTACTS, ("C0", "C2"), strict=False):
        for gains, mark in (("rod-rate", "o"), ("table1", "x")):
            ens = report["contacts"][contact].get(f"ensemble_{gains}")
            if ens is None:
                continue
            for i, roll in enumerate(ROLLS):
                st, held = ens[f"{roll:g}"]["diameter_m"], ens[f"{roll:g}"]["held_roll_deg"]
                if st is None:
                    continue
                ax.errorbar(
                    held["median"], st["median"],
                    xerr=[[held["median"] - held["min"]], [held["max"] - held["median"]]],
                    yerr=[[st["median"] - st["min"]], [st["max"] - st["median"]]],
                    fmt=colour + mark, capsize=3, mfc="none" if gains == "table1" else colour,
                    label=f"{contact} contact, {gains} gains: fit, median (range)" if i == 0 else None,
                )
    ax.set_xlabel("held roll (deg, mean measured after settling)")
    ax.set_ylabel("circle diameter (m)")
    ax.set_ylim(0, 11)
    ax.set_title("Held-roll circles on the MuJoCo plant (30 s, ω = 1 rad/s asked), 5°/10°/15° asked")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")
    fig.savefig(out / "vpip-mujoco-diameters.png", dpi=90)
    plt.close(fig)


def _smooth(values: list[float], n: int = 50) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    return np.convolve(v, np.ones(n) / n, mode="same")


def _cave(profile: RobotProfile, problem_name: str, contact: str) -> tuple[dict[str, Any], dict[str, Any]]:
    problems = {p.name: p for p in load_problem_set("maps/problems/cave.json")}
    prob = problems[problem_name]
    grid = load_map(prob.map_path)
    plan = plan_path(grid, profile, prob.start, prob.goal, termination=Termination(60.0)).to_json()
    duration = float(plan["states"][-1]["t"])
    result = run_schedule(plan, profile, plant="mujoco", max_duration_s=3.0 * duration + 20.0, contact=contact)
    return plan, result


def _contact_report(daedalus: RobotProfile, contact: str, out: Path, args: argparse.Namespace) -> dict[str, Any]:
    """Circles, ensembles, calibration and the cave run for one contact setting."""
    rep: dict[str, Any] = {}
    circles = []
    for roll in ROLLS:
        r = run_circle(daedalus, math.radians(roll), args.duration, "mujoco", "vpip", contact=contact)
        plot_circle(r, out / f"vpip-mujoco-{contact}-circle{int(roll)}.png")
        circles.append(r["summary"])
        log.info("%s roll %g: diameter %s", contact, roll, r["summary"]["diameter_m"])
    rep["circles"] = circles
    rep["ensemble_rod-rate"] = _ensemble(daedalus, args.duration, HEADINGS, contact, "rod-rate")
    rep["ensemble_table1"] = _ensemble(daedalus, args.duration, HEADINGS[:4], contact, "table1")
    cal = calibrate_from_circles(circles, daedalus)
    rep["calibration"] = {k: cal[k] for k in ("roll_model", "table", "source")}
    import tomllib

    table_profile = profile_from_dict(tomllib.loads(profile_toml(daedalus, cal["roll_model"])), "daedalus")
    for name, prof in (("own_table", table_profile), ("paper_table", daedalus)):
        try:
            plan, result = _cave(prof, args.problem, contact)
        except Exception as exc:  # a planning failure is a result too
            rep[f"cave_{name}"] = {"error": f"{type(exc).__name__}: {exc}"}
            continue
        plot_schedule(result, out / f"vpip-mujoco-{contact}-cave-{name.replace('_', '-')}.png", plan)
        rep[f"cave_{name}"] = {
            "problem": args.problem,
            "plan_length_m": plan["length_m"],
            "plan_min_turning_radius_m": prof.min_turning_radius_m,
            **result["summary"],
        }
        log.info("%s cave %s: %s", contact, name, result["summary"])
    return rep


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
    report: dict[str, Any] = {"contacts": {c: _contact_report(daedalus, c, out, args) for c in CONTACTS}}
    _diameter_figure(report, out)
    simple = run_circle(daedalus, math.radians(10.0), args.duration, "mujoco", "simple", contact="paper")
    plot_circle(simple, out / "vpip-mujoco-simple10.png")
    report["simple_circle_10_paper_contact"] = simple["summary"]
    report["fig7_paper_contact"] = _fig7(daedalus, out, 20.0, "paper")
    (out / "vpip-mujoco.json").write_text(json.dumps(report, indent=2, allow_nan=False) + "\n")


if __name__ == "__main__":
    main()
