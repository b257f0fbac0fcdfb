"""Rolling gaits: allowed hybrid transitions, requested distance, no slip, fixed pivots."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from planner.errors import InvalidInput
from planner.robot import load_robot
from planner.tensegrity import ALLOWED_TRANSITIONS, plan_gait
from planner.tensegrity.geometry import link_point

PROFILE = load_robot("texplor")
R = PROFILE.radius_m


def _pairs(result: dict) -> list[tuple[int, int]]:
    seq = result["state_sequence"]
    return list(itertools.pairwise(seq))


@pytest.mark.parametrize("distance", [0.05, 0.7, 2.3, -0.7, -2.3])
@pytest.mark.parametrize("measure", ["net", "rolled"])
def test_gait_reaches_distance_with_allowed_transitions(distance: float, measure: str) -> None:
    result = plan_gait(distance, PROFILE, steps=16, measure=measure)
    assert all(pair in ALLOWED_TRANSITIONS for pair in _pairs(result))
    assert not any({a, b} in ({1, 2}, {3, 4}) for a, b in _pairs(result))
    ring = (1, 3, 2, 4) if distance > 0 else (1, 4, 2, 3)
    for a, b in _pairs(result):
        assert ring[(ring.index(a) + 1) % 4] == b
    got = result["net_displacement_m"] if measure == "net" else result["rolled_distance_m"]
    assert got == pytest.approx(abs(distance), abs=1e-9)
    steps = result["steps"]
    # accumulated per-step ground displacement: the centre's advance along the heading, and the contact's
    # travel r·|Δφ| of the rolling link
    heading = np.array([math.cos(result["heading_rad"]), math.sin(result["heading_rad"]), 0.0])
    centre = np.array([s["centre_m"] for s in steps])
    advance = float(np.sum(np.diff(centre, axis=0) @ heading))
    assert advance == pytest.approx(result["net_displacement_m"], abs=1e-9)
    rolled = 0.0
    for prev, cur in itertools.pairwise(steps):
        if prev["state"] == cur["state"]:
            key = "phi1_rad" if cur["state"] in (1, 2) else "phi2_rad"
            rolled += R * abs(cur[key] - prev[key])
    assert rolled == pytest.approx(result["rolled_distance_m"], abs=1e-9)


def test_contacts_stay_on_ground_pivot_fixed_and_no_slip() -> None:
    result = plan_gait(1.5, PROFILE, steps=200)
    steps = result["steps"]
    for s in steps:
        assert s["q1_ground_m"][2] == pytest.approx(0.0, abs=1e-12)
        assert s["q2_ground_m"][2] == pytest.approx(0.0, abs=1e-12)
        assert s["centre_m"][2] == pytest.approx(R / math.sqrt(2), abs=1e-12)
        assert s["F_r1"] >= 0 and s["F_r2"] >= 0
    worst_slip = 0.0
    for prev, cur in itertools.pairwise(steps):
        if prev["state"] != cur["state"]:
            assert np.allclose(prev["T_sb"], cur["T_sb"], atol=1e-12)  # transitions do not jump
            continue
        pivot = "q2_ground_m" if cur["state"] in (1, 2) else "q1_ground_m"
        assert np.allclose(prev[pivot], cur[pivot], atol=1e-12)
        rolling_link = 1 if cur["state"] in (1, 2) else 2
        key = f"phi{rolling_link}_rad"
        dphi = abs(cur[key] - prev[key])
        if dphi < 1e-6:
            continue
        # the body point touching the ground at `prev` moves only to second order (no slip)
        body_point = link_point(rolling_link, prev[key], R)
        t_prev, t_cur = np.array(prev["T_sb"]), np.array(cur["T_sb"])
        moved = (t_cur[:3, :3] - t_prev[:3, :3]) @ body_point + t_cur[:3, 3] - t_prev[:3, 3]
        worst_slip = max(worst_slip, float(np.linalg.norm(moved)) / (R * dphi))
        # the contact's ground trace: arc of radius r*sqrt(2) about the pivot, length r*|dphi|
        qa, qb = (np.array(s[f"q{rolling_link}_ground_m"]) - np.array(cur[pivot]) for s in (prev, cur))
        assert np.linalg.norm(qa) == pytest.approx(R * math.sqrt(2))
        swept = math.acos(min(1.0, float(qa @ qb / (np.linalg.norm(qa) * np.linalg.norm(qb)))))
        assert R * math.sqrt(2) * swept == pytest.approx(R * dphi, rel=1e-6)
    assert worst_slip < 0.02


def test_forward_then_reverse_full_cycles_move_along_a_line() -> None:
    result = plan_gait(2.0, PROFILE, steps=8)
    per_cycle = result["per_cycle"]["net_m"]
    assert per_cycle == pytest.approx(4 * math.sqrt(2) * R * math.sin(math.pi / (2 * math.sqrt(2))), rel=1e-9)
    assert result["per_cycle"]["rolled_m"] == pytest.approx(4 * math.pi * R)


def test_slider_path_is_monotone_in_contact_angle() -> None:
    steps = plan_gait(1.1, PROFILE, steps=50)["steps"]
    for prev, cur in itertools.pairwise(steps):
        if prev["state"] == cur["state"]:
            assert cur["net_m"] >= prev["net_m"] - 1e-12
            assert cur["rolled_m"] >= prev["rolled_m"] - 1e-12


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"distance_m": 0.0}, "distance"),
        ({"distance_m": 1.0, "steps": 1}, "steps"),
        ({"distance_m": 1.0, "start_state": 5}, "start_state"),
        ({"distance_m": 1.0, "corner_deg": 95.0}, "corner"),
        ({"distance_m": 1.0, "measure": "x"}, "measure"),
    ],
)
def test_bad_gait_input_names_the_field(kwargs: dict, field: str) -> None:
    with pytest.raises(InvalidInput, match=field):
        plan_gait(profile=PROFILE, **kwargs)


@pytest.mark.parametrize("start_state", [1, 2, 3, 4])
@pytest.mark.parametrize("distance", [1.0, -1.0, 0.4])
def test_positive_distance_rolls_towards_plus_x(distance: float, start_state: int) -> None:
    """Forward (distance > 0) advances O_b along +x, the reverse gait along −x (issue #13: it went −x)."""
    result = plan_gait(distance, PROFILE, steps=8, start_state=start_state)
    first, last = result["steps"][0]["centre_m"], result["steps"][-1]["centre_m"]
    assert last[0] - first[0] == pytest.approx(distance, abs=1e-6)
    assert result["heading_rad"] == pytest.approx(0.0 if distance > 0 else math.pi, abs=1e-9)
