"""Arc reconfiguration (paper 004 §4): straight rolls (action a) and circles of radius R·tan θ (action b).

Action (a) rolls the sphere along P's azimuth α, changing θ; the point F where θ would be 0 stays fixed.
Action (b) holds θ and rolls the centre on a circle of radius R·tan θ (eq. 11) about C, which lies on the
ray from the centre opposite to P's azimuth; F (at distance R·(tan θ − θ) from C) turns rigidly about C
with the centre, so α changes by exactly the angle turned.

Partial reconfiguration (§4.2) to (O, P on top, final roll direction α_f): (1) roll P to the top, reaching
F; (2) roll along α' by R·θ'; (3) circle about C' until F reaches O; (4) roll P back to the top, arriving
at O. C' lies on the line through O with direction α_f, C' = O − ρ·(cos α_f, sin α_f) with
ρ = R·(tan θ' − θ') = |F − O|² / (−2 (F − O)·u_f) (eq. 12–15); α' is the direction from C' to F (eq. 16).
The circle can be travelled the short way (direct, |Δα| ≤ π, eq. 22) or the long way (complementary,
eq. 23); Δα = α_f − α'.

Complete reconfiguration (§4.3): steps 2–4 change the heading by Δq = Δα·(1 − 1/cos θ') (eq. 20, checked
against SO(3) rolling in the tests), and the chord gives 2·(tan θ' − θ')·|sin(Δα/2)| = r = |F − O|/R
(eq. 21). For a required heading change the planner scans θ' on the four branches (direct/complementary ×
counter-clockwise/clockwise) and solves Δq(θ') ≡ required (mod 2π) with Brent's method.

Assumption beyond the paper: when F coincides with O (r = 0) no heading change is possible, so step 1 may
add one full revolution (2π·R, orientation unchanged) to move F away; rolling P to the top forwards
(2π − θ0) is offered as another alternative.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import brentq

from planner.errors import InvalidInput
from planner.kinematics import wrap
from planner.spherobot.manoeuvre import Manoeuvre
from planner.spherobot.rolling import GroundSegment, Quat, roll_segment, tilt_from_quat

TWO_PI = 2.0 * math.pi
HALF_PI = 0.5 * math.pi
MAX_TAN_THETA = 200.0  # largest circle used: radius 200·R (θ' ≈ 89.7°)
_THETA_MAX = math.atan(MAX_TAN_THETA)
_GRID = 256  # θ' samples per branch when searching
_INFO_KEYS = (
    "theta_prime_rad",
    "alpha_prime_rad",
    "alpha_final_rad",
    "delta_alpha_rad",
    "delta_q_rad",
    "circle",
    "turn",
    "fixed_point_F",
    "circle_radius_m",
    "circle_center",
)
_BRANCHES = (("direct", 1), ("direct", -1), ("complementary", 1), ("complementary", -1))


def offset_of(theta: float) -> float:
    """tan θ − θ: distance from C to F on the unit sphere (eq. 15)."""
    return math.tan(theta) - theta


def theta_for_offset(offset: float) -> float:
    """Solve tan θ − θ = ``offset`` (≥ 0) for θ ∈ [0, π/2) (eq. 15)."""
    if offset <= 0.0:
        return 0.0
    hi = math.atan(offset + HALF_PI)  # tan(hi) − hi ≥ offset
    return float(
        brentq(lambda t: math.tan(t) - t - offset, 0.0, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    )


def paper_circle_center(
    x0: float, y0: float, theta0: float, alpha0: float, alpha_f: float
) -> tuple[float, float]:
    """C' = (a, b) by eq. 12 and 14 (unit sphere, goal at the origin). Singular where tan α_f is."""
    ta = math.tan(alpha_f)
    num = x0 * x0 + y0 * y0 + theta0 * theta0 - 2 * theta0 * (x0 * math.cos(alpha0) + y0 * math.sin(alpha0))
    den = 2 * (x0 + y0 * ta - theta0 * (math.cos(alpha0) + math.sin(alpha0) * ta))
    a = num / den
    return a, a * ta


@dataclass(frozen=True)
class ArcSolution:
    """Steps 2–4 of §4.2 on the unit sphere, goal at the origin.

    ``delta_alpha`` > 0 turns counter-clockwise about C'. ``center`` is C' (unit sphere coordinates).
    """

    theta_prime: float
    alpha_prime: float
    delta_alpha: float
    circle: str

    @property
    def alpha_final(self) -> float:
        return wrap(self.alpha_prime + self.delta_alpha)

    @property
    def delta_q(self) -> float:
        """Heading change of steps 2–4 (eq. 20)."""
        return self.delta_alpha * (1.0 - 1.0 / math.cos(self.theta_prime))

    @property
    def length(self) -> float:
        """Steps 2–4 path length on the unit sphere."""
        return 2.0 * self.theta_prime + math.tan(self.theta_prime) * abs(self.delta_alpha)


def _rotate_center(fx: float, fy: float, delta_alpha: float) -> tuple[float, float]:
    """Centre C of the rotation by ``delta_alpha`` that carries F = (fx, fy) to the origin."""
    c, s = math.cos(delta_alpha), math.sin(delta_alpha)
    # (I − Rot) C = −Rot·F
    bx, by = -(c * fx - s * fy), -(s * fx + c * fy)
    m00, m01, m10, m11 = 1 - c, s, -s, 1 - c
    det = m00 * m11 - m01 * m10
    return (m11 * bx - m01 * by) / det, (-m10 * bx + m00 * by) / det


def _solution(fx: float, fy: float, theta_p: float, delta_alpha: float, circle: str) -> ArcSolution:
    cx, cy = _rotate_center(fx, fy, delta_alpha)
    return ArcSolution(theta_p, math.atan2(fy - cy, fx - cx), delta_alpha, circle)


def solve_partial_alpha(fx: float, fy: float, alpha_f: float) -> list[ArcSolution]:
    """Direct and complementary circles for a given final direction α_f (eq. 12–16), unit sphere.

    Empty when F is at the goal, when α_f points towards F ((F − O)·u_f ≥ 0: C' would have to lie beyond O),
    or when the circle would be larger than ``MAX_TAN_THETA``·R.
    """
    ux, uy = math.cos(alpha_f), math.sin(alpha_f)
    dot = fx * ux + fy * uy
    r2 = fx * fx + fy * fy
    if r2 == 0.0:
        return []
    if dot >= 0.0:
        return []  # the last roll would have to point towards F: no circle with θ' < π/2
    rho = r2 / (-2.0 * dot)
    if rho > offset_of(_THETA_MAX):
        return []  # α_f nearly perpendicular to F − O: the circle would exceed MAX_TAN_THETA·R
    theta_p = theta_for_offset(rho)
    cx, cy = -rho * ux, -rho * uy
    alpha_p = math.atan2(fy - cy, fx - cx)
    direct = wrap(alpha_f - alpha_p)
    comp = direct - math.copysign(TWO_PI, direct)
    return [
        ArcSolution(theta_p, alpha_p, direct, "direct"),
        ArcSolution(theta_p, alpha_p, comp, "complementary"),
    ]


def _branch_grid(r: float) -> tuple[np.ndarray, np.ndarray]:
    """θ' grid from the smallest feasible circle to ``MAX_TAN_THETA``, and the half chord angle asin(x)."""
    theta_min = theta_for_offset(r / 2.0)
    t = np.exp(np.linspace(math.log(math.tan(theta_min)), math.log(MAX_TAN_THETA), _GRID))
    theta = np.arctan(t)
    theta[0] = theta_min
    half = np.arcsin(np.clip(r / (2.0 * (np.tan(theta) - theta)), 0.0, 1.0))
    return theta, half


def _delta_alpha(half: Any, circle: str, sign: int) -> Any:
    """Signed Δα of a branch from the half chord angle (array or float); eq. 22 direct, eq. 23 complement."""
    return sign * (2.0 * half if circle == "direct" else TWO_PI - 2.0 * half)


def solve_partial_free(fx: float, fy: float, per_branch: int = 4) -> list[ArcSolution]:
    """Partial reconfiguration with α_f free: the shortest circle on each branch plus a few longer ones."""
    r = math.hypot(fx, fy)
    if r == 0.0:
        return []
    theta, half = _branch_grid(r)
    out: list[ArcSolution] = []
    for circle, sign in _BRANCHES:
        da = _delta_alpha(half, circle, sign)
        length = 2 * theta + np.tan(theta) * np.abs(da)
        order = np.argsort(length)
        picks = [int(order[0]), *(int(i) for i in order[1 :: max(1, _GRID // per_branch)][: per_branch - 1])]
        for i in picks:
            out.append(_solution(fx, fy, float(theta[i]), float(da[i]), circle))
    return out


def solve_complete(fx: float, fy: float, delta_q: float, max_solutions: int = 8) -> list[ArcSolution]:
    """All circles (up to ``max_solutions``, shortest first) whose steps 2–4 turn the heading by ``delta_q``.

    Solves Δα(θ')·(1 − 1/cos θ') ≡ delta_q (mod 2π) on the four branches (eq. 20–23), unit sphere.
    """
    r = math.hypot(fx, fy)
    if r == 0.0:
        return []
    theta, half = _branch_grid(r)
    brackets: list[tuple[float, str, int, int, int]] = []
    for circle, sign in _BRANCHES:
        da = _delta_alpha(half, circle, sign)
        f = (da * (1.0 - 1.0 / np.cos(theta)) - delta_q) / TWO_PI
        length = 2 * theta + np.tan(theta) * np.abs(da)
        kmin = np.floor(np.minimum(f[:-1], f[1:])) + 1
        kmax = np.floor(np.maximum(f[:-1], f[1:]))
        idx = np.flatnonzero(kmax >= kmin)
        seg_len = np.minimum(length[:-1], length[1:])[idx]
        for i in idx[np.argsort(seg_len)[:max_solutions]]:
            for k in range(int(kmin[i]), int(kmax[i]) + 1):
                brackets.append((float(min(length[i], length[i + 1])), circle, sign, int(i), k))
    brackets.sort(key=lambda item: item[0])
    out: list[ArcSolution] = []
    for _, circle, sign, i, k in brackets[:max_solutions]:
        target = delta_q + TWO_PI * k

        def residual(tp: float, circle: str = circle, sign: int = sign, target: float = target) -> float:
            h = math.asin(min(1.0, r / (2.0 * offset_of(tp))))
            return float(_delta_alpha(h, circle, sign)) * (1.0 - 1.0 / math.cos(tp)) - target

        a, b_ = float(theta[i]), float(theta[i + 1])
        if residual(a) == 0.0:
            tp = a
        elif residual(b_) == 0.0:
            tp = b_
        else:
            tp = float(brentq(residual, a, b_, xtol=1e-15, rtol=4 * np.finfo(float).eps))
        h = math.asin(min(1.0, r / (2.0 * offset_of(tp))))
        out.append(_solution(fx, fy, tp, float(_delta_alpha(h, circle, sign)), circle))
    out.sort(key=lambda s: s.length)
    return out


def arc_segments(sol: ArcSolution, fx: float, fy: float, radius_m: float) -> list[GroundSegment]:
    """Steps 2–4 as ground segments (m) starting at the fixed point F = (fx, fy) m, world frame."""
    R = radius_m
    tp, ap = sol.theta_prime, sol.alpha_prime
    step2 = GroundSegment(fx, fy, ap, R * tp, 0.0, "a")
    qx, qy = step2.end
    rho = R * math.tan(tp)
    sign = 1.0 if sol.delta_alpha > 0 else -1.0
    step3 = GroundSegment(
        qx, qy, wrap(ap + sign * HALF_PI), rho * abs(sol.delta_alpha), sign / rho, "b"
    )
    ex, ey = step3.end
    step4 = GroundSegment(ex, ey, wrap(sol.alpha_final + math.pi), R * tp, 0.0, "a")
    return [step2, step3, step4]


def arc_candidates(
    start_xy: tuple[float, float],
    q0: Quat,
    goal_xy: tuple[float, float],
    goal_heading: float | None,
    alpha_final: float | None,
    radius_m: float,
) -> list[Manoeuvre]:
    """Candidate arc manoeuvres (shortest first) from (start_xy, q0) to goal_xy with P on top.

    ``goal_heading`` (rad) makes it a complete reconfiguration (§4.3); otherwise partial (§4.2), with the
    final roll direction ``alpha_final`` (rad) when given, else the shortest choices.
    """
    R = radius_m
    sx, sy = start_xy
    gx, gy = goal_xy
    theta0, alpha0, _ = tilt_from_quat(q0)
    preludes: list[tuple[str, list[GroundSegment]]] = []
    if theta0 > 0.0:
        preludes.append(
            ("step 1 backwards", [GroundSegment(sx, sy, wrap(alpha0 + math.pi), R * theta0, 0.0, "a")])
        )
        preludes.append(("step 1 forwards", [GroundSegment(sx, sy, alpha0, R * (TWO_PI - theta0), 0.0, "a")]))
    else:
        preludes.append(("P already on top", []))
    fx0, fy0 = preludes[0][1][-1].end if preludes[0][1] else (sx, sy)
    r0 = math.hypot(fx0 - gx, fy0 - gy) / R
    if goal_heading is not None and r0 < 1.0:
        away = math.atan2(fy0 - gy, fx0 - gx) if r0 > 0 else 0.0
        extra = R * (theta0 + TWO_PI)
        if theta0 > 0.0:
            dist_dir = wrap(alpha0 + math.pi)
            preludes.append(
                (
                    "step 1 backwards with one extra revolution",
                    [GroundSegment(sx, sy, dist_dir, extra, 0.0, "a")],
                )
            )
        else:
            preludes.append(("one full revolution first", [GroundSegment(sx, sy, away, extra, 0.0, "a")]))

    out: list[Manoeuvre] = []
    for pname, psegs in preludes:
        q = q0
        for seg in psegs:
            q = roll_segment(q, seg, R)
        fx, fy = psegs[-1].end if psegs else (sx, sy)
        ux, uy = (fx - gx) / R, (fy - gy) / R
        psteps = ("step 1: P to the top",) * len(psegs)
        if math.hypot(ux, uy) < 1e-12 and goal_heading is None:
            none = dict.fromkeys(_INFO_KEYS)
            out.append(
                Manoeuvre("arc", f"{pname}; F is the goal, no circle needed", tuple(psegs), psteps, none)
            )
            continue
        if goal_heading is not None:
            need = wrap(goal_heading - tilt_from_quat(q)[2])
            sols = solve_complete(ux, uy, need)
        elif alpha_final is not None:
            sols = solve_partial_alpha(ux, uy, alpha_final)
        else:
            sols = solve_partial_free(ux, uy)
        for sol in sols:
            segs = arc_segments(sol, fx, fy, R)
            turn = "counter-clockwise" if sol.delta_alpha > 0 else "clockwise"
            info = {
                "theta_prime_rad": sol.theta_prime,
                "alpha_prime_rad": sol.alpha_prime,
                "alpha_final_rad": sol.alpha_final,
                "delta_alpha_rad": sol.delta_alpha,
                "delta_q_rad": sol.delta_q,
                "circle": sol.circle,
                "turn": turn,
                "fixed_point_F": [fx, fy],
                "circle_radius_m": R * math.tan(sol.theta_prime),
                "circle_center": list(segs[1].center or (math.nan, math.nan)),
            }
            steps = (*psteps, "step 2: roll along alpha'", "step 3: circle", "step 4: P to the top")
            out.append(
                Manoeuvre(
                    "arc", f"{pname}; {sol.circle} circle, {turn}", tuple(psegs) + tuple(segs), steps, info
                )
            )
    if not out and alpha_final is not None:
        bad = math.degrees(math.atan2(gy - fy0, gx - fx0))
        raise InvalidInput(
            "alpha_final",
            f"no circle ends rolling along {math.degrees(alpha_final):.1f}°: the last roll must point away "
            "from "
            f"F (where P first comes on top), i.e. within 90° of {bad:.1f}°",
        )
    out.sort(key=lambda m: m.length_m)
    return out
