"""A patrol over several goals without GNSS: paper 001 §6.5, Fig. 10 (the underground garage).

The robot plans a path through a list of goal poses (Hybrid A*, one leg per pair of consecutive goals,
joined into one plan so it rolls through each goal without stopping — the paper's pre-set target-point
script), then rolls it in closed loop with the GNSS denied, so its estimate is wheel odometry alone
(eq. 2). With ``model="dynamic"`` the eq. 15 commands go through the LMPC and RSLQR motion controllers
to the pendulum plant (paper 001 §5), which is where the lateral shaking after big turns the paper
reports comes from.

The result is the SIM.json of :func:`~planner.closed_loop.simulate.simulate_plan` plus ``patrol``: per
goal, the moment the robot *believed* it was closest to the goal, with the true distance to the goal
then (``true_error_m``: what an observer would measure) and the estimate's own error then
(``estimate_error_m``: odometry drift) reported separately, and the shaking after each big turn
(:func:`turn_overshoots`: how far the roll swings past zero, to the other side, as it returns from a
turn — paper 001 §6.5: "prone to shaking after a significant turn as a result of the roll angle
returning to zero").
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from planner.closed_loop.simulate import SimulationOptions, simulate_plan
from planner.closed_loop.simulator import Disturbances
from planner.errors import InvalidInput
from planner.occupancy import OccupancyGrid
from planner.robot import RobotProfile
from planner.termination import Termination

GARAGE_PATROL: tuple[tuple[float, float, float], ...] = (
    (35.0, 8.05, math.pi),
    (21.0, 15.5, math.pi / 2),
    (30.0, 23.55, 0.0),
    (37.0, 23.55, 0.0),
)
"""Default patrol on ``maps/garage.yaml``: lane 1 westward, up the middle aisle, east along lane 2."""


def _join(legs: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """One plan from consecutive legs (each leg's first state is the previous leg's last)."""
    states: list[dict[str, Any]] = []
    s_off = t_off = 0.0
    for leg in legs:
        rows = leg["states"] if not states else leg["states"][1:]
        for row in rows:
            r = dict(row)
            if "s" in r:
                r["s"] = float(r["s"]) + s_off
            if "t" in r:
                r["t"] = float(r["t"]) + t_off
            states.append(r)
        last = leg["states"][-1]
        s_off += float(last.get("s", 0.0))
        t_off += float(last.get("t", 0.0))
    plan = dict(legs[0])
    plan["states"] = states
    plan["length_m"] = float(sum(float(leg.get("length_m", 0.0)) for leg in legs))
    return plan


def turn_overshoots(
    t: np.ndarray, roll: np.ndarray, turn_rad: float = 0.15, hold_s: float = 1.0, window_s: float = 3.0
) -> list[dict[str, float]]:
    """For every turn (|roll| ≥ ``turn_rad`` for at least ``hold_s``), the roll's largest swing to the
    other side within ``window_s`` after it first crosses zero again (rad, ≥ 0) and when that happened."""
    out = []
    i, n = 0, len(t)
    while i < n:
        if abs(roll[i]) < turn_rad:
            i += 1
            continue
        sign = math.copysign(1.0, roll[i])
        j = i
        while j < n and sign * roll[j] >= turn_rad:
            j += 1
        if t[min(j, n - 1)] - t[i] < hold_s:
            i = j + 1
            continue
        k = j
        while k < n and sign * roll[k] > 0.0:
            k += 1
        if k >= n:
            break
        end = int(np.searchsorted(t, t[k] + window_s))
        swing = float(max(0.0, -sign * roll[k:end].min())) if sign > 0 else float(max(0.0, roll[k:end].max()))
        out.append({"turn_end_t": float(t[k]), "turn_roll_rad": float(sign * np.abs(roll[i:j]).max()),
                    "overshoot_rad": swing})
        i = k
    return out


def patrol(
    grid: OccupancyGrid,
    robot: RobotProfile,
    goals: Sequence[tuple[float, float, float]],
    model: str = "dynamic",
    seed: int = 0,
    noise: str = "default",
    time_limit_s: float = 5.0,
    options: SimulationOptions | None = None,
) -> dict[str, Any]:
    """Plan through ``goals`` (the first is the start) and roll the patrol with GNSS denied."""
    from planner.hybrid_astar.plan import plan_path

    if len(goals) < 2:
        raise InvalidInput("goals", "a patrol needs a start and at least one goal")
    legs = []
    for i, (a, b) in enumerate(itertools.pairwise(goals)):
        try:
            legs.append(plan_path(grid, robot, a, b, termination=Termination(time_limit_s)).to_json())
        except InvalidInput as exc:
            raise InvalidInput(f"goals[{i + 1}]", str(exc)) from exc
    plan = _join(legs)
    base = Disturbances.named(noise)
    denied = Disturbances(**{**base.__dict__, "gnss_available": False})
    opts = options or SimulationOptions()
    opts = SimulationOptions(**{**opts.__dict__, "model": model})
    sim = simulate_plan(grid, plan, robot, seed=seed, noise=denied, options=opts)
    tr = np.array([[r["t"], r["x"], r["y"], r["yaw"], r["roll"]] for r in sim["trajectory"]])
    es = np.array([[r["x"], r["y"]] for r in sim["estimate"]])
    report: list[dict[str, Any]] = []
    for k, goal in enumerate(goals[1:], start=1):
        gxy = np.array(goal[:2])
        i = int(np.argmin(np.hypot(*(es - gxy).T)))
        report.append({
            "goal": list(goal),
            "t": float(tr[i, 0]),
            "believed_distance_m": float(np.hypot(*(es[i] - gxy))),
            "true_error_m": float(np.hypot(*(tr[i, 1:3] - gxy))),
            "estimate_error_m": float(np.hypot(*(tr[i, 1:3] - es[i]))),
            "leg": k,
        })
    roll_rate = np.gradient(tr[:, 4], tr[:, 0]) if len(tr) > 2 else np.zeros(len(tr))
    shakes = turn_overshoots(tr[:, 0], tr[:, 4])
    sim["noise"] = f"{noise}, GNSS denied"
    sim["patrol"] = {
        "goals": [list(g) for g in goals],
        "gnss": "denied",
        "reached": report,
        "true_error_max_m": max(float(r["true_error_m"]) for r in report),
        "estimate_error_final_m": sim["metrics"]["estimate_error_final_m"],
        "roll_rate_max_rad_s": float(np.abs(roll_rate).max()),
        "turns": shakes,
        "turn_overshoot_max_rad": max((s["overshoot_rad"] for s in shakes), default=0.0),
    }
    sim["plan"] = {"length_m": plan["length_m"], "legs": len(legs), "states": plan["states"]}
    return sim


__all__ = ["GARAGE_PATROL", "patrol", "turn_overshoots"]
