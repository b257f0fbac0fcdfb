"""Static equilibria of TeXploR in its four hybrid states (paper 002 §II-D/E, §III).

In each state the robot pivots on one end of one link and rests on the other link's arc:

=====  =========  ============  ===================================
state  pivot      rolling link  contact angles
=====  =========  ============  ===================================
1      A2         L1            φ1 ∈ [0, π], φ2 = 0
2      B2         L1            φ1 ∈ [0, π], φ2 = π
3      A1         L2            φ1 = 0,      φ2 ∈ [0, π]
4      B1         L2            φ1 = π,      φ2 ∈ [0, π]
=====  =========  ============  ===================================

The up vector in {b} is z_b = −(1/√2)[cφ1, sφ1, cφ2] (eq. 8, rolling on L1) or
z_b = (1/√2)[−cφ1, sφ2, −cφ2] (eq. 9, rolling on L2); O_b is then r/√2 above the ground. Along each
state the height of O_b is constant, so the equilibrium puts the centre of mass c in the vertical plane
through the two contacts: φ1 = atan2(c_y, c_x) on L1 and φ2 = atan2(−c_y, c_z) on L2. With equal
sliders and equal links this is the paper's tan φ1 = (sθ1 − sθ2)/cθ1 and tan φ2 = (sθ2 − sθ1)/cθ2.
The reaction forces follow from the lever rule along the contact segment (the paper's §III balance).
R_sb is eq. 16 (Rodrigues), T_sb puts O_b at [0, 0, r/√2].

Checked against physics (``energy.py``), with these corrections to the printed paper:

* eq. 13 (state 2) prints state 1's z_b; the correct one is eq. 8 with φ2 = π, −(1/√2)[cφ1, sφ1, −1].
* eq. 15 (state 4) prints (1/√2)[−1, −sφ2, cφ2] and "pivot on A2"; the pivot is B1 and z_b is eq. 9
  with φ1 = π, (1/√2)[1, sφ2, −cφ2] (the printed one puts B1 above the ground).
* eq. 12–15 (reaction forces) as printed sum to −(M1+M2+m1+m2)g and their bracket is twice the lever
  rule's; ``F_r1``/``F_r2`` here are the physical (upward, ≥ 0) forces, the printed values are kept as
  ``F_r_paper`` for comparison.
* the height of O_b is r/√2 (§III-B prints √r/2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.robot import RobotProfile
from planner.tensegrity.energy import all_minima, angle_deg, local_minimum
from planner.tensegrity.geometry import (
    G,
    TexplorParams,
    centre_of_mass,
    check_mass_angle,
    link_point,
    mass_points,
    params_from_profile,
    rodrigues_up,
)

#: Tolerance (rad) on a contact angle leaving [0, π], and (N) on a negative reaction force.
ANGLE_TOL = 1e-9
FORCE_TOL = 1e-9
#: A contact angle this close (rad) to 0 or π puts the body on a corner (two link ends).
CORNER_TOL = 1e-7
#: Below this (× r) the centre of mass has no direction in the rolling link's plane: neutral balance.
NEUTRAL_TOL = 1e-9
#: Closed form and energy minimum must agree to this many degrees for ``verified``.
VERIFY_TOL_DEG = 0.05


@dataclass(frozen=True)
class StateSpec:
    """Which link end is the pivot and which link rolls in a hybrid state."""

    state: int
    rolling_link: int
    pivot_link: int
    pivot_angle_rad: float
    pivot_name: str


STATES: dict[int, StateSpec] = {
    1: StateSpec(1, 1, 2, 0.0, "A2"),
    2: StateSpec(2, 1, 2, math.pi, "B2"),
    3: StateSpec(3, 2, 1, 0.0, "A1"),
    4: StateSpec(4, 2, 1, math.pi, "B1"),
}


def contact_angles(state: int, rolling_angle_rad: float) -> tuple[float, float]:
    """(φ1, φ2) of ``state`` with the rolling link's contact at ``rolling_angle_rad``."""
    spec = STATES[state]
    if spec.rolling_link == 1:
        return rolling_angle_rad, spec.pivot_angle_rad
    return spec.pivot_angle_rad, rolling_angle_rad


def surface_normal(state: int, phi1: float, phi2: float) -> np.ndarray:
    """Up vector z_b = R_sb^T z_s in {b} (unit, shape (3,)): eq. 8 (rolling on L1) or eq. 9 (on L2)."""
    if STATES[state].rolling_link == 1:
        return -np.array([math.cos(phi1), math.sin(phi1), math.cos(phi2)]) / math.sqrt(2.0)
    return np.array([-math.cos(phi1), math.sin(phi2), -math.cos(phi2)]) / math.sqrt(2.0)


def closed_form_angle(state: int, theta1: float, theta2: float, params: TexplorParams) -> float:
    """Unclipped closed-form contact angle (rad, in (−π + 1e-7, π + 1e-7]) of the rolling link.

    φ1 = atan2(c_y, c_x) on L1 (states 1, 2), φ2 = atan2(−c_y, c_z) on L2 (states 3, 4), c the centre of
    mass in {b}. The state exists only when the result lies in [0, π].
    """
    com = centre_of_mass(theta1, theta2, params)
    if STATES[state].rolling_link == 1:
        angle = math.atan2(com[1], com[0])
    else:
        angle = math.atan2(-com[1], com[2])
    return angle + 2.0 * math.pi if angle < -math.pi + CORNER_TOL else angle


def paper_contact_angle(state: int, theta1: float, theta2: float) -> float:
    """The paper's printed tan formula (eq. 12–15, equal masses), as an angle in [0, π)."""
    s1, s2, c1, c2 = math.sin(theta1), math.sin(theta2), math.cos(theta1), math.cos(theta2)
    if STATES[state].rolling_link == 1:
        angle = math.atan2(s1 - s2, c1)
    else:
        angle = math.atan2(s2 - s1, c2)
    return angle % math.pi


def reaction_forces(
    state: int, phi1: float, phi2: float, theta1: float, theta2: float, params: TexplorParams
) -> tuple[float, float]:
    """Upward ground forces (N) at the contacts Q1 (on L1) and Q2 (on L2).

    Lever rule along the horizontal contact segment Q2→Q1: F_r1 = W g (c − q2)·(q1 − q2)/|q1 − q2|²,
    F_r2 = W g − F_r1 (the paper's F_r1 + F_r2 = W g and moment balance about the segment).
    """
    r = params.radius_m
    q1, q2 = link_point(1, phi1, r), link_point(2, phi2, r)
    com = centre_of_mass(theta1, theta2, params)
    weight = params.total_mass_kg * G
    seg = q1 - q2
    f1 = weight * float((com - q2) @ seg) / float(seg @ seg)
    return f1, weight - f1


def paper_reaction_forces(
    state: int, phi: float, theta1: float, theta2: float, params: TexplorParams
) -> tuple[float, float]:
    """F_r1, F_r2 (N) exactly as printed in eq. 12–15 (M, m = mean slider and link mass)."""
    big = sum(params.slider_mass_kg) / 2.0 * G
    small = sum(params.link_mass_kg) / 2.0 * G
    c = math.cos
    if state in (1, 2):
        sign = -1.0 if state == 1 else 1.0
        bracket = c(phi + theta2) / 2 + sign * c(theta2) + c(phi - theta1) - c(phi - theta2) / 2
    else:
        bracket = -c(phi + theta1) / 2 + c(theta1) - c(phi - theta2) + c(phi - theta1) / 2
    return big * (-1.0 + bracket) - small, big * (-1.0 - bracket) - small


def resting_states(up_b: np.ndarray, radius_m: float, tol: float = 1e-6) -> set[int]:
    """The hybrid states an orientation (up vector in {b}) physically belongs to, from its lowest points.

    Each link's lowest point is an interior arc point or an end (support function, ``lowest_depth``);
    links within ``tol``·r of the lowest depth touch the ground. An interior contact on one link with an
    end of the other is one state; two ends (a corner) belong to both neighbouring states.
    """
    w = -np.asarray(up_b, dtype=float)
    touches = {}
    for link, (x, y) in ((1, (w[0], w[1])), (2, (w[2], -w[1]))):
        angle = math.atan2(y, x) if y >= 0 else (0.0 if x >= 0 else math.pi)
        touches[link] = (float(np.hypot(x, y)) if y >= 0 else abs(x), angle)
    deepest = max(d for d, _ in touches.values())
    contacts = {link: a for link, (d, a) in touches.items() if d >= deepest - tol}
    if len(contacts) < 2:
        return set()
    out = set()
    for spec in STATES.values():
        pivot = contacts[spec.pivot_link]
        rolling = contacts[spec.rolling_link]
        if abs(pivot - spec.pivot_angle_rad) <= tol and -tol <= rolling <= math.pi + tol:
            out.add(spec.state)
    return out


def _corner_problem(state: int, phi: float, theta1: float, theta2: float, params: TexplorParams) -> str:
    """Why a state whose contact sits on an end of its rolling link is not at rest ("" if it is).

    At an end (φ = 0 or π) the body stands on two link ends, a corner shared with the state that pivots
    on that end. It stays there only when that neighbour's closed-form angle also points at the corner
    (the quasi-static transition boundary of Fig. 9); otherwise it rolls on through the neighbour.
    """
    at_start, at_end = phi <= CORNER_TOL, phi >= math.pi - CORNER_TOL
    if not (at_start or at_end):
        return ""
    spec = STATES[state]
    end_angle = 0.0 if at_start else math.pi
    neighbour = next(
        s for s in STATES.values() if s.pivot_link == spec.rolling_link and s.pivot_angle_rad == end_angle
    )
    other = closed_form_angle(neighbour.state, theta1, theta2, params)
    if abs(other - spec.pivot_angle_rad) <= CORNER_TOL:
        return ""
    return (
        f"the contact is at the end of link {spec.rolling_link}, and from that corner the body rolls on "
        f"into state {neighbour.state} (its contact angle is {math.degrees(other):.2f} deg)"
    )


@dataclass(frozen=True)
class StateEquilibrium:
    """One hybrid state's static solution for given slider angles (SI units, radians)."""

    state: int
    feasible: bool
    reason: str
    phi1_rad: float
    phi2_rad: float
    z_b: np.ndarray
    forces_n: tuple[float, float]
    paper_forces_n: tuple[float, float]
    r_sb: np.ndarray
    o_sb_m: np.ndarray
    paper_phi_rad: float
    energy_min_deg_error: float
    verified: bool

    def to_json(self) -> dict[str, Any]:
        t_sb = np.eye(4)
        t_sb[:3, :3] = self.r_sb
        t_sb[:3, 3] = self.o_sb_m
        return {
            "state": self.state,
            "feasible": self.feasible,
            "reason": self.reason,
            "pivot": STATES[self.state].pivot_name,
            "rolling_link": STATES[self.state].rolling_link,
            "phi1_rad": self.phi1_rad,
            "phi2_rad": self.phi2_rad,
            "phi_paper_rad": self.paper_phi_rad,
            "z_b": self.z_b.tolist(),
            "F_r1": self.forces_n[0],
            "F_r2": self.forces_n[1],
            "F_r_paper": list(self.paper_forces_n),
            "R_sb": self.r_sb.tolist(),
            "T_sb": t_sb.tolist(),
            "energy_min_deg_error": None
            if math.isnan(self.energy_min_deg_error)
            else self.energy_min_deg_error,
            "verified": self.verified,
        }


def solve_state(
    state: int, theta1: float, theta2: float, params: TexplorParams, verify: bool = True
) -> StateEquilibrium:
    """Closed-form equilibrium of ``state`` at slider angles θ1, θ2 (rad), checked against the energy.

    ``feasible``: the closed-form contact angle lies on the rolling link (0 ≤ φ ≤ π) and both reaction
    forces are ≥ 0. ``energy_min_deg_error`` is the angle between the closed-form z_b and the potential-
    energy minimum reached by descending from it; ``verified`` says that the physics agrees with the
    closed form's verdict (feasible and a minimum, or infeasible and the body rolls away).
    """
    spec = STATES[state]
    com = centre_of_mass(theta1, theta2, params)
    neutral = (
        float(np.hypot(com[1], com[0] if spec.rolling_link == 1 else com[2])) < NEUTRAL_TOL * params.radius_m
    )
    raw = math.pi / 2 if neutral else closed_form_angle(state, theta1, theta2, params)
    on_arc = -ANGLE_TOL <= raw <= math.pi + ANGLE_TOL
    phi = min(max(raw, 0.0), math.pi)
    phi1, phi2 = contact_angles(state, phi if on_arc else raw)
    z_b = surface_normal(state, phi1, phi2)
    forces = reaction_forces(state, phi1, phi2, theta1, theta2, params)
    paper_forces = paper_reaction_forces(
        state, phi1 if spec.rolling_link == 1 else phi2, theta1, theta2, params
    )
    reason = ""
    corner = _corner_problem(state, phi, theta1, theta2, params) if on_arc and not neutral else ""
    if not on_arc:
        end = "A" if raw < 0 and abs(raw) < math.pi / 2 else "B"
        reason = (
            f"the centre of mass lies beyond end {end}{spec.rolling_link} of the rolling link "
            f"(closed-form angle {math.degrees(raw):.2f} deg is off the arc)"
        )
    elif corner:
        reason = corner
    elif min(forces) < -FORCE_TOL:
        reason = "the centre of mass lies outside the contact segment (a reaction force is negative)"
    feasible = not reason
    if neutral:
        reason = (
            "neutral: the centre of mass lies on the normal of the rolling link's plane through O_b, "
            "so every contact angle balances; 90 deg reported"
        )
    error = math.nan
    verified = False
    if verify:
        u = local_minimum(z_b, theta1, theta2, params)
        error = angle_deg(u, z_b)
        verified = error <= VERIFY_TOL_DEG if feasible else state not in resting_states(u, params.radius_m)
    r = params.radius_m
    return StateEquilibrium(
        state=state,
        feasible=feasible,
        reason=reason,
        phi1_rad=phi1,
        phi2_rad=phi2,
        z_b=z_b,
        forces_n=forces,
        paper_forces_n=paper_forces,
        r_sb=rodrigues_up(z_b),
        o_sb_m=np.array([0.0, 0.0, r / math.sqrt(2.0)]),
        paper_phi_rad=paper_contact_angle(state, theta1, theta2),
        energy_min_deg_error=error,
        verified=verified,
    )


def equilibria(
    theta1: float, theta2: float, params: TexplorParams, verify: bool = True
) -> list[StateEquilibrium]:
    """The four states' solutions at slider angles θ1, θ2 (rad)."""
    theta1 = check_mass_angle("theta1", theta1)
    theta2 = check_mass_angle("theta2", theta2)
    return [solve_state(s, theta1, theta2, params, verify) for s in STATES]


def static_equilibria(
    theta1: float, theta2: float, profile: RobotProfile, verify: bool = True
) -> dict[str, Any]:
    """What ``sphereplan tensegrity static`` prints: the four states at slider angles θ1, θ2 (rad).

    Besides the per-state closed form it scans the potential energy for all its minima
    (``energy_minima``) and says whether each is a feasible closed-form state.
    """
    params = params_from_profile(profile)
    states = equilibria(theta1, theta2, params, verify)
    result: dict[str, Any] = {
        "robot": profile.name,
        "radius_m": params.radius_m,
        "masses": params.masses_json(),
        "theta1_rad": theta1,
        "theta2_rad": theta2,
        "centre_of_mass_b": centre_of_mass(theta1, theta2, params).tolist(),
        "states": [s.to_json() for s in states],
    }
    if verify:
        minima = []
        for u in all_minima(theta1, theta2, params):
            match = [s.state for s in states if s.feasible and angle_deg(u, s.z_b) <= VERIFY_TOL_DEG]
            minima.append({"z_b": u.tolist(), "state": match[0] if match else None})
        result["energy_minima"] = minima
        result["verified"] = all(s.verified for s in states) and all(m["state"] is not None for m in minima)
    return result


__all__ = [
    "STATES",
    "StateEquilibrium",
    "StateSpec",
    "closed_form_angle",
    "contact_angles",
    "equilibria",
    "mass_points",
    "paper_contact_angle",
    "paper_reaction_forces",
    "reaction_forces",
    "solve_state",
    "static_equilibria",
    "surface_normal",
]
