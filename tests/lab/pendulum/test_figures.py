"""Paper 001 Figs. 11–13 on the dynamic plant: the step metrics, and the comparisons issue 15 asks for.

docs/pendulum.md tabulates these runs; the assertions below are what it claims: on zju-60 the LMPC rises
faster than its tuned PID in every Fig. 11 case (by 8–27 ms: both accelerate along the same 15°
pendulum bound; the rise is interpolated between samples, so sub-period margins are real), settles
sooner and swings the pendulum less; the RSLQR rises faster than its tuned PID in every Fig. 13 case
within the 10 % overshoot limit and settles sooner. On zju-80, with its own tuned PIDs, the LMPC rises
faster in every case; the RSLQR (zju-60's weights, not tuned for zju-80) settles sooner within the
overshoot limit in every case, and its tuned PID rises faster only by overshooting the limit or by less
than 5 ms. Both sides are computed here, not pasted.
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np
import pytest

from lab.pendulum.figures import run_figures
from planner.pendulum.dynamics import params_from_profile
from planner.pendulum.steps import (
    FIG11_CASES,
    FIG13_CASES,
    MAX_OVERSHOOT,
    crossing_time,
    max_steady_roll,
    roll_step,
    speed_step,
    step_metrics,
)
from planner.robot import load_robot

ROBOT = load_robot("zju-60")


@pytest.fixture(scope="module")
def figs() -> dict[str, Any]:
    return run_figures(ROBOT)


def test_step_metrics_of_known_responses() -> None:
    t = np.arange(0.0, 10.0, 0.001)
    first = 2.0 * (1.0 - np.exp(-t / 0.5))  # first order, τ = 0.5 s, step 0 → 2
    m = step_metrics(t, first, 0.0, 2.0)
    assert m["rise_time_s"] == pytest.approx(0.5 * math.log(9.0), abs=2e-3)
    assert m["overshoot"] == 0.0
    assert m["settling_time_s"] == pytest.approx(0.5 * math.log(20.0), abs=2e-3)
    assert m["steady_state_error"] < 1e-6
    zeta, wn = 0.3, 4.0  # second order: overshoot exp(−πζ/√(1−ζ²))
    wd = wn * math.sqrt(1 - zeta**2)
    second = 1.0 - np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t))
    m2 = step_metrics(t, second, 0.0, 1.0)
    assert m2["overshoot"] == pytest.approx(math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2)), abs=1e-3)
    never = step_metrics(t, 0.5 * first, 0.0, 2.0)  # stalls at half the step
    assert never["rise_time_s"] is None and never["settling_time_s"] is None
    assert never["steady_state_error"] == pytest.approx(1.0, abs=1e-3)
    down = step_metrics(t, 2.0 - first, 2.0, 0.0)  # a step down is measured the same way
    assert down["rise_time_s"] == pytest.approx(m["rise_time_s"])


def test_rise_time_is_not_quantised_by_the_sampling() -> None:
    """Sampled at the 50 Hz control rate, the rise is still the continuous one: the crossings are
    interpolated (the first sample past 10 % / 90 % would be up to one period off each)."""
    exact = 0.5 * math.log(9.0)
    for shift in (0.0, 0.007, 0.013):  # where the samples fall relative to the crossings
        t = np.arange(0.0, 4.0, 0.02)
        y = np.where(t >= shift, 1.0 - np.exp(-(t - shift) / 0.5), 0.0)
        assert step_metrics(t, y, 0.0, 1.0)["rise_time_s"] == pytest.approx(exact, abs=1e-3)
    t = np.arange(0.0, 4.0, 0.02)
    assert crossing_time(t, np.clip(t / 2.0, 0.0, 1.0), 0.45) == pytest.approx(0.9)
    assert crossing_time(t, t, 10.0) is None


def _dip_below_steady_pitch(res: dict[str, Any]) -> float:
    """How far (rad, ≤ 0) the pitch swings below its final value once the speed has reached 90 %."""
    v = np.array([r["v"] for r in res["series"]])
    pitch = np.array([r["pitch"] for r in res["series"]])
    after = int(np.argmax(v >= 0.9 * res["speed_m_s"]))
    return float((pitch[after:] - pitch[-1]).min())


def test_fig11_lmpc_rises_faster_than_pid(figs: dict[str, Any]) -> None:
    params = params_from_profile(ROBOT)
    assert len(figs["fig11"]) == len(FIG11_CASES) == 4
    faster = 0
    for case in figs["fig11"]:
        lmpc, pid = case["lmpc"], case["pid"]
        assert lmpc["rise_time_s"] < pid["rise_time_s"], (lmpc["speed_m_s"], lmpc["floor"])
        faster += 1
        assert lmpc["overshoot"] < 0.01 and lmpc["steady_state_error"] < 1e-3 * lmpc["speed_m_s"]
        assert lmpc["overshoot"] < pid["overshoot"] and lmpc["settling_time_s"] < pid["settling_time_s"]
        assert lmpc["max_pitch_rad"] < params.max_pendulum_angle_rad + math.radians(0.15)
        # Fig. 12: once up to speed the LMPC sets the pendulum down on its steady pitch without swinging
        # below it; on tiles the PID's pendulum swings past it (on rubber it does not, since the re-tuning)
        lmpc_dip, pid_dip = _dip_below_steady_pitch(lmpc), _dip_below_steady_pitch(pid)
        assert lmpc_dip > -math.radians(0.1)
        if lmpc["floor"] == "tiled":
            assert pid_dip < lmpc_dip - math.radians(0.5)
    assert faster == 4


def test_fig13_rslqr_rises_faster_than_pid(figs: dict[str, Any]) -> None:
    assert len(figs["fig13"]) == len(FIG13_CASES) == 3
    for case in figs["fig13"]:
        lqr, pid = case["rslqr"], case["pid"]
        assert lqr["rise_time_s"] < pid["rise_time_s"], (lqr["speed_m_s"], lqr["roll_rad"])
        assert lqr["overshoot"] <= MAX_OVERSHOOT and lqr["settling_time_s"] < pid["settling_time_s"]


@pytest.mark.parametrize("robot", ["zju-80"])
def test_model_based_controllers_against_their_pids_on_another_robot(robot: str) -> None:
    """Every case of Figs. 11 and 13 on another robot with its own tuned PIDs (zju-60: the tests above).
    The LMPC rises faster in every case. The RSLQR keeps zju-60's weights: it stays within the overshoot
    limit and settles sooner in every case, but its PID (tuned on zju-80) rises faster where it overshoots
    the limit, and ties it within 5 ms elsewhere (docs/pendulum.md)."""
    rob = load_robot(robot)
    for speed, floor in FIG11_CASES:
        runs = {c: speed_step(rob, c, speed, floor, duration_s=1.0 + 2.7 * speed) for c in ("lmpc", "pid")}
        assert runs["lmpc"]["rise_time_s"] < runs["pid"]["rise_time_s"], (speed, floor)
    for speed, roll in FIG13_CASES:
        lqr, pid = (roll_step(rob, c, speed, roll, duration_s=4.0) for c in ("rslqr", "pid"))
        assert lqr["overshoot"] <= MAX_OVERSHOOT and lqr["settling_time_s"] < pid["settling_time_s"], (speed, roll)
        assert (lqr["rise_time_s"] < pid["rise_time_s"] + 0.005 or pid["overshoot"] > MAX_OVERSHOOT), (speed, roll)


def test_larger_roll_is_harder_at_higher_speed(figs: dict[str, Any]) -> None:
    """Fig. 13's remark: the torque a turn needs grows with v² tan φ, the roll that can be held shrinks."""
    params = params_from_profile(ROBOT)
    limits = [max_steady_roll(params, v) for v in (0.5, 1.0, 1.5, 2.0)]
    assert all(a > b for a, b in itertools.pairwise(limits))
    assert limits[1] > 0.19 > limits[2]  # 0.19 rad can be held at 1.0 m/s, not at 1.5 m/s
    torque = {
        (c["rslqr"]["speed_m_s"], c["rslqr"]["roll_rad"]): np.mean([r["torque"] for r in c["rslqr"]["series"][-25:]])
        for c in figs["fig13"]
    }
    assert torque[(0.5, 0.12)] < torque[(1.0, 0.12)] < torque[(1.0, 0.19)]
    assert figs["max_steady_roll_rad"]["1.0"] == pytest.approx(limits[1])
