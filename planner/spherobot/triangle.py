"""Spherical-triangle reconfiguration (paper 004 §3): reach a position with P on top and any heading.

Rolling the sphere along a ground polyline whose trace on the sphere is a closed spherical triangle brings
the contact point (and so P, its antipode) back to where it was, displaces the centre and turns the sphere
about the vertical by the triangle's spherical excess E = A + B + C − π (eq. 9/10: −E for a left-handed
path, +E for a right-handed one; verified against SO(3) rolling in the tests).

Paper 004 eq. 5 is misprinted. The displacement is that of the planar polyline with legs a, b, c at headings
0, π − C, 2π − A − C from the first leg (left-handed; mirrored for right-handed), i.e.
``d² = a² + b² + c² − 2ab cos C + 2ac cos(A + C) − 2bc cos A``; eq. 6 (its direction φ) is consistent with it.

Strategy (§3.2): (1) roll straight to the goal O, (2) roll P to the top along P's azimuth (away from O by
θ_O·R ≤ π·R), (3) return to O with at most two triangles whose excesses give the missing heading change.
As a shorter alternative the planner also tries rolling P to the top straight away and then using the
triangles over the whole distance. Triangles are taken from the right-isosceles family a = b = s, C = π/2,
where everything is closed form (Napier: tan A = 1 / cos s): E(s) = 2·atan2(1, cos s) − π/2 ∈ (0, π),
c = arccos(cos² s), left-handed displacement (s − c sin A, s − c cos A) (unit sphere). Two such triangles
with displacements d1, d2 reach any d with |d1 − d2| ≤ d ≤ d1 + d2 by choosing their first-leg directions,
and any heading change with the four hand combinations; the paper's Fig. 5 region argument says the same.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from planner.kinematics import wrap
from planner.spherobot.manoeuvre import Manoeuvre
from planner.spherobot.rolling import GroundSegment, Quat, roll_segment, tilt_from_quat

TWO_PI = 2.0 * math.pi
HALF_PI = 0.5 * math.pi
_E1_GRID = np.linspace(0.0, math.pi, 182)[1:-1]  # excesses of the first triangle searched over


@dataclass(frozen=True)
class SphericalTriangle:
    """A spherical triangle on the unit sphere: sides a, b, c (rad) opposite angles A, B, C (rad).

    The rolling order is Q → R (side a) → P (side b) → Q (side c); C is the angle at R, A the angle at P.
    """

    a: float
    b: float
    c: float
    A: float
    B: float
    C: float

    @property
    def excess(self) -> float:
        """Spherical excess E = A + B + C − π (the triangle's area on the unit sphere)."""
        return self.A + self.B + self.C - math.pi

    def leg_headings(self, hand: int) -> tuple[float, float, float]:
        """Ground headings of legs a, b, c relative to the first (hand −1 left turns, +1 right turns)."""
        turn = -float(hand)
        return 0.0, turn * (math.pi - self.C), turn * (TWO_PI - self.A - self.C)

    def displacement(self, hand: int) -> tuple[float, float]:
        """Net centre displacement on the unit sphere in the first leg's frame (x along the first leg).

        The planar polyline of the three legs (corrected eq. 5, docs/references.md; its angle is eq. 6).
        """
        h = self.leg_headings(hand)
        legs = (self.a, self.b, self.c)
        return (
            sum(ln * math.cos(hd) for ln, hd in zip(legs, h, strict=True)),
            sum(ln * math.sin(hd) for ln, hd in zip(legs, h, strict=True)),
        )

    def yaw(self, hand: int) -> float:
        """Net rotation about the vertical (rad): −E left-handed (eq. 9), +E right-handed (eq. 10)."""
        return hand * self.excess


def spherical_triangle(a: float, b: float, C: float) -> SphericalTriangle:
    """Solve the triangle with sides a, b (rad, in (0, π)) and included angle C (rad, in (0, π)).

    Spherical law of cosines for c, then the sine/cosine rules for A and B.
    """
    cc = math.cos(a) * math.cos(b) + math.sin(a) * math.sin(b) * math.cos(C)
    c = math.acos(max(-1.0, min(1.0, cc)))
    if math.sin(c) <= 0.0:
        raise ValueError("degenerate spherical triangle")
    A = math.atan2(math.sin(a) * math.sin(C) * math.sin(b), math.cos(a) - math.cos(b) * cc)
    B = math.atan2(math.sin(b) * math.sin(C) * math.sin(a), math.cos(b) - math.cos(a) * cc)
    return SphericalTriangle(a, b, c, A, B, C)


def right_isosceles(excess: float) -> SphericalTriangle:
    """The triangle a = b = s, C = π/2 with spherical excess ``excess`` ∈ (0, π) (closed form)."""
    A = 0.5 * (excess + HALF_PI)
    s = math.acos(max(-1.0, min(1.0, math.cos(A) / math.sin(A))))
    c = math.acos(math.cos(s) ** 2)
    return SphericalTriangle(s, s, c, A, A, HALF_PI)


def _family_arrays(excess: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Right-isosceles family, vectorised: (d, φ (left-handed), length, s) on the unit sphere."""
    A = 0.5 * (excess + HALF_PI)
    s = np.arccos(np.clip(np.cos(A) / np.sin(A), -1.0, 1.0))
    c = np.arccos(np.cos(s) ** 2)
    x = s - c * np.sin(A)
    y = s - c * np.cos(A)
    return np.hypot(x, y), np.arctan2(y, x), 2.0 * s + c, s


def _family_distance(excess: float) -> float:
    d, _, _, _ = _family_arrays(np.array([excess]))
    return float(d[0])


MAX_FAMILY_DISTANCE = _family_distance(math.pi - 1e-9)  # ≈ 4.37 (unit sphere)


@dataclass(frozen=True)
class TriangleLeg:
    """One triangle of a plan: the triangle, its hand (+1 right, −1 left) and first-leg heading (rad)."""

    triangle: SphericalTriangle
    hand: int
    heading_rad: float


def _excess_for_distance(d: float) -> float:
    """Excess of the right-isosceles triangle whose displacement is ``d`` (unit sphere, 0 < d < 4.37)."""
    return float(brentq(lambda e: _family_distance(e) - d, 1e-9, math.pi - 1e-9, xtol=1e-14))


def _place(tri: SphericalTriangle, hand: int, direction: float) -> TriangleLeg:
    """Orient ``tri`` so that its displacement points along ``direction`` (rad)."""
    dx, dy = tri.displacement(hand)
    return TriangleLeg(tri, hand, direction - math.atan2(dy, dx))


def solve_triangles(dx: float, dy: float, yaw: float | None) -> list[tuple[str, list[TriangleLeg]]]:
    """Triangle sets (at most two) that displace the centre by (dx, dy) and turn the sphere by ``yaw``.

    Unit sphere. ``yaw`` is the required rotation about the vertical (rad, mod 2π) or None when any
    heading will do (partial reconfiguration). Returns labelled alternatives, shortest first.
    """
    d = math.hypot(dx, dy)
    gamma = math.atan2(dy, dx)
    out: list[tuple[float, str, list[TriangleLeg]]] = []
    if yaw is None:
        if d < 1e-12:
            return [("no triangle needed", [])]
        if d < MAX_FAMILY_DISTANCE:
            tri = right_isosceles(_excess_for_distance(d))
            for hand, name in ((-1, "left"), (1, "right")):
                out.append((tri.a + tri.b + tri.c, f"one {name}-handed triangle", [_place(tri, hand, gamma)]))
        if d / 2 < MAX_FAMILY_DISTANCE:
            tri = right_isosceles(_excess_for_distance(d / 2))
            for hand, name in ((-1, "left"), (1, "right")):
                legs = [_place(tri, hand, gamma), _place(tri, -hand, gamma)]
                out.append((2 * (tri.a + tri.b + tri.c), f"{name}- then opposite-handed triangles", legs))
        out.sort(key=lambda item: item[0])
        return [(name, legs) for _, name, legs in out]

    target = wrap(yaw)
    for h1 in (1, -1):
        for h2 in (1, -1):
            for k in (-1, 0, 1):
                total = target + TWO_PI * k
                e1 = _E1_GRID
                if h1 == h2:
                    e1 = np.append(e1, h1 * total / 2.0)  # the symmetric pair, exact for d = 0
                e2 = h2 * (total - h1 * e1)
                ok = (e1 > 0) & (e1 < math.pi) & (e2 > 0) & (e2 < math.pi)
                if not ok.any():
                    continue
                e1, e2 = e1[ok], e2[ok]
                d1, _, l1, _ = _family_arrays(e1)
                d2, _, l2, _ = _family_arrays(e2)
                feasible = (np.abs(d1 - d2) <= d + 1e-10) & (d <= d1 + d2 + 1e-10)
                if not feasible.any():
                    continue
                idx = np.flatnonzero(feasible)
                best = idx[np.argmin((l1 + l2)[idx])]
                t1, t2 = right_isosceles(float(e1[best])), right_isosceles(float(e2[best]))
                length = float(l1[best] + l2[best])
                dd1, dd2 = float(d1[best]), float(d2[best])
                names = {1: "right", -1: "left"}
                for mirror in (1, -1):
                    if d > 1e-12:
                        cos_delta = (dd1 * dd1 + d * d - dd2 * dd2) / (2 * dd1 * d)
                        delta = math.acos(max(-1.0, min(1.0, cos_delta)))
                        dir1 = gamma + mirror * delta
                    else:
                        dir1 = 0.0 if mirror == 1 else HALF_PI
                    ex, ey = dx - dd1 * math.cos(dir1), dy - dd1 * math.sin(dir1)
                    dir2 = math.atan2(ey, ex) if math.hypot(ex, ey) > 1e-12 else dir1 + math.pi
                    first, second = _place(t1, h1, dir1), _place(t2, h2, dir2)
                    side = "" if mirror == 1 else ", mirrored"
                    label = f"{names[h1]}- and {names[h2]}-handed triangles{side}"
                    out.append((length, label, [first, second]))
                    out.append((length, label + ", swapped order", [second, first]))
    out.sort(key=lambda item: item[0])
    return [(name, legs) for _, name, legs in out]


def triangle_segments(
    legs: Sequence[TriangleLeg], x0: float, y0: float, radius_m: float, steps: list[str], label: str
) -> list[GroundSegment]:
    """Ground segments (m) of the given triangles rolled one after another from (x0, y0)."""
    segs: list[GroundSegment] = []
    x, y = x0, y0
    for i, leg in enumerate(legs):
        tri = leg.triangle
        for side, rel in zip((tri.a, tri.b, tri.c), tri.leg_headings(leg.hand), strict=True):
            seg = GroundSegment(x, y, wrap(leg.heading_rad + rel), side * radius_m, 0.0, "roll")
            segs.append(seg)
            steps.append(f"{label} {i + 1}")
            x, y = seg.end
    return segs


def triangle_candidates(
    start_xy: tuple[float, float],
    q0: Quat,
    goal_xy: tuple[float, float],
    goal_heading: float | None,
    radius_m: float,
) -> list[Manoeuvre]:
    """Candidate spherical-triangle manoeuvres from (start_xy, q0) to goal_xy with P on top.

    With ``goal_heading`` (rad) it is a complete reconfiguration, otherwise partial. Shortest first.
    """
    R = radius_m
    preludes: list[tuple[str, list[GroundSegment], list[str]]] = []
    # (paper §3.2) roll straight to O, then roll P to the top.
    segs: list[GroundSegment] = []
    steps: list[str] = []
    sx, sy = start_xy
    gx, gy = goal_xy
    dist = math.hypot(gx - sx, gy - sy)
    q = q0
    if dist > 0:
        segs.append(GroundSegment(sx, sy, math.atan2(gy - sy, gx - sx), dist, 0.0, "straight"))
        steps.append("roll to the goal")
        q = roll_segment(q, segs[-1], R)
    theta_o, alpha_o, _ = tilt_from_quat(q)
    if theta_o > 0:
        segs.append(GroundSegment(gx, gy, wrap(alpha_o + math.pi), theta_o * R, 0.0, "a"))
        steps.append("roll P to the top")
    preludes.append(("paper §3.2: goal first", segs, steps))
    # Alternative: roll P to the top straight away, then triangles over the whole distance.
    theta0, alpha0, _ = tilt_from_quat(q0)
    segs2: list[GroundSegment] = []
    steps2: list[str] = []
    if theta0 > 0:
        segs2.append(GroundSegment(sx, sy, wrap(alpha0 + math.pi), theta0 * R, 0.0, "a"))
        steps2.append("roll P to the top")
    preludes.append(("P to the top first", segs2, steps2))

    out: list[Manoeuvre] = []
    for pname, psegs, psteps in preludes:
        qs = q0
        for seg in psegs:
            qs = roll_segment(qs, seg, R)
        x, y = psegs[-1].end if psegs else start_xy
        px, py = (gx - x) / R, (gy - y) / R
        if math.hypot(px, py) > 2 * MAX_FAMILY_DISTANCE * 0.999:
            continue
        yaw = None if goal_heading is None else wrap(goal_heading - tilt_from_quat(qs)[2])
        for tname, legs in solve_triangles(px, py, yaw):
            steps_all = list(psteps)
            tsegs = triangle_segments(legs, x, y, R, steps_all, "triangle")
            info = {
                "triangles": [
                    {
                        "a_rad": leg.triangle.a,
                        "b_rad": leg.triangle.b,
                        "c_rad": leg.triangle.c,
                        "A_rad": leg.triangle.A,
                        "B_rad": leg.triangle.B,
                        "C_rad": leg.triangle.C,
                        "excess_rad": leg.triangle.excess,
                        "hand": "right" if leg.hand == 1 else "left",
                        "yaw_rad": leg.triangle.yaw(leg.hand),
                        "first_leg_heading_rad": wrap(leg.heading_rad),
                    }
                    for leg in legs
                ],
            }
            out.append(
                Manoeuvre(
                    "triangle", f"{pname}; {tname}", tuple(psegs) + tuple(tsegs), tuple(steps_all), info
                )
            )
    out.sort(key=lambda m: m.length_m)
    return out


__all__ = [
    "MAX_FAMILY_DISTANCE",
    "SphericalTriangle",
    "TriangleLeg",
    "right_isosceles",
    "solve_triangles",
    "spherical_triangle",
    "triangle_candidates",
    "triangle_segments",
]
