"""Quasi-static rolling gaits of TeXploR: slider trajectories θ1(t), θ2(t) that roll it a distance.

The four hybrid states form a ring 1 → 3 → 2 → 4 → 1 (forward; the reverse ring 1 → 4 → 2 → 3 → 1);
neighbours share a corner where the body stands on two link ends, and 1↔2, 3↔4 never meet (paper 002
§II-E, Fig. 3). In the slider plane (θ1, θ2) ∈ [0, π]², the line c_y = 0 (the centre of mass in the
plane of both link ends; the diagonals sθ1 = sθ2 for equal masses) is the transition boundary of Fig. 9:
crossing it where the contact angles on both sides agree swaps the rolling link without a jump.

The planned slider path is the rectangle whose four corners lie on those boundaries, θ1 ∈ {a, π − a},
θ2 ∈ {b, π − b} with c_y(a, b) = 0 (``corner_deg`` = a, 45° by default, the Fig. 9 path x1 → x2). Each
edge lies in one state's region and drives that state's contact angle through the whole rolling link
(0 → π or back); one slider moves at a time. Walking the rectangle clockwise is the forward gait, the
other way the reverse gait.

Pose on the ground: in a state the pivot end stays put and the body rolls on the rolling link like a
cone on its apex (the contact segment, length r√2, is a generator). No slip means the body's angular
velocity lies along the contact segment, which fixes the yaw rate: dψ/dφ = (n · t)/|q − p| with e the
unit pivot→contact vector, n = z_b × e, t the arc tangent (eq. 5); |dψ/dφ| = 1/√2. The contact then
moves on the ground by r·|Δφ| (an arc of radius r√2 about the pivot), O_b stays r/√2 high.
The initial body pose is eq. 16 (Rodrigues) with O_b above the origin, turned about z_s so that a full
cycle advances along +x for a positive distance (forward ring) and along -x for a negative one.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.errors import InvalidInput, NoValidPathFound
from planner.robot import RobotProfile
from planner.tensegrity.geometry import (
    TexplorParams,
    link_point,
    link_tangent,
    params_from_profile,
    rodrigues_up,
    rot_z,
)
from planner.tensegrity.statics import (
    STATES,
    closed_form_angle,
    contact_angles,
    reaction_forces,
    surface_normal,
)

#: Forward and reverse state rings (paper 002 §II-E).
FORWARD_RING = (1, 3, 2, 4)
#: most samples a gait may hold (legs × samples per state): a gait's size is the request's distance
MAX_GAIT_SAMPLES = 1_000_000
REVERSE_RING = (1, 4, 2, 3)
#: Every hybrid transition the robot can make (no 1↔2, no 3↔4).
ALLOWED_TRANSITIONS = frozenset(
    {(FORWARD_RING[i], FORWARD_RING[(i + 1) % 4]) for i in range(4)}
    | {(REVERSE_RING[i], REVERSE_RING[(i + 1) % 4]) for i in range(4)}
)


def boundary_theta2(theta1: float, params: TexplorParams) -> float:
    """Lower branch θ2 ∈ [0, π/2] (rad) of the transition boundary c_y = 0 through θ1.

    c_y ∝ M1 sθ1 − M2 sθ2 + (m1 − m2)·2/π; the upper branch is π − θ2. NaN when no θ2 solves it.
    """
    (big1, big2), (small1, small2) = params.slider_mass_kg, params.link_mass_kg
    sine = (big1 * math.sin(theta1) + (small1 - small2) * 2.0 / math.pi) / big2
    return math.asin(sine) if 0.0 <= sine <= 1.0 else math.nan


@dataclass(frozen=True)
class Rectangle:
    """The slider path: corners (θ1, θ2) at θ1 ∈ {a, π − a}, θ2 ∈ {b, π − b} (rad), all on c_y = 0."""

    a: float
    b: float

    def edge(self, state: int, forward: bool) -> tuple[tuple[float, float], tuple[float, float]]:
        """Start and end (θ1, θ2) of the edge walked in ``state``."""
        a, b, pa, pb = self.a, self.b, math.pi - self.a, math.pi - self.b
        edges = {1: ((pa, b), (a, b)), 3: ((a, b), (a, pb)), 2: ((a, pb), (pa, pb)), 4: ((pa, pb), (pa, b))}
        start, end = edges[state]
        return (start, end) if forward else (end, start)


def make_rectangle(corner_rad: float, params: TexplorParams) -> Rectangle:
    """The rectangle with θ1 corners at ``corner_rad`` and π − ``corner_rad``; raises if impossible."""
    if not 0.0 < corner_rad < math.pi / 2:
        raise InvalidInput(
            "corner", f"must be strictly between 0 and 90 degrees, got {math.degrees(corner_rad):.3f}"
        )
    b = boundary_theta2(corner_rad, params)
    if not 0.0 <= b < math.pi / 2 - 1e-6:
        raise InvalidInput(
            "corner",
            f"no transition boundary point at theta1 = {math.degrees(corner_rad):.2f} deg for these masses "
            "(slider 2 cannot balance slider 1); choose a smaller corner angle",
        )
    return Rectangle(corner_rad, b)


@dataclass(frozen=True)
class Sample:
    """One step of a gait (SI units, radians; positions in the ground frame {s})."""

    t_s: float
    theta1: float
    theta2: float
    state: int
    phi1: float
    phi2: float
    r_sb: np.ndarray
    o_sb: np.ndarray
    rolled_m: float
    net_m: float
    forces_n: tuple[float, float]
    params: TexplorParams

    def contact_ground(self) -> tuple[np.ndarray, np.ndarray]:
        """Ground positions of Q1 and Q2 (m, shape (3,), z ≈ 0)."""
        r = self.params.radius_m
        q1 = self.o_sb + self.r_sb @ link_point(1, self.phi1, r)
        q2 = self.o_sb + self.r_sb @ link_point(2, self.phi2, r)
        return q1, q2

    def to_json(self) -> dict[str, Any]:
        q1, q2 = self.contact_ground()
        t_sb = np.eye(4)
        t_sb[:3, :3] = self.r_sb
        t_sb[:3, 3] = self.o_sb
        return {
            "t": self.t_s,
            "theta1_rad": self.theta1,
            "theta2_rad": self.theta2,
            "state": self.state,
            "pivot": STATES[self.state].pivot_name,
            "phi1_rad": self.phi1,
            "phi2_rad": self.phi2,
            "q1_ground_m": q1.tolist(),
            "q2_ground_m": q2.tolist(),
            "centre_m": self.o_sb.tolist(),
            "yaw_rad": math.atan2(self.r_sb[1, 0], self.r_sb[0, 0]),
            "T_sb": t_sb.tolist(),
            "F_r1": self.forces_n[0],
            "F_r2": self.forces_n[1],
            "rolled_m": self.rolled_m,
            "net_m": self.net_m,
        }


def _frame(state: int, phi: float, radius: float) -> tuple[np.ndarray, float]:
    """Body triad F = [e, n, z_b] of a state at rolling angle φ and the yaw rate dψ/dφ."""
    spec = STATES[state]
    phi1, phi2 = contact_angles(state, phi)
    pivot = link_point(spec.pivot_link, spec.pivot_angle_rad, radius)
    contact = link_point(spec.rolling_link, phi, radius)
    seg = contact - pivot
    e = seg / np.linalg.norm(seg)
    z_b = surface_normal(state, phi1, phi2)
    n = np.cross(z_b, e)
    rate = float(n @ link_tangent(spec.rolling_link, phi, radius)) / float(np.linalg.norm(seg))
    return np.column_stack([e, n, z_b]), rate


def _yaw_of(rotation: np.ndarray) -> float:
    return math.atan2(rotation[1, 0], rotation[0, 0])


class _Gait:
    """Closed-form evaluation of a gait at progress σ (integer part: leg index, fraction: along the leg)."""

    def __init__(
        self, params: TexplorParams, rect: Rectangle, start_state: int, forward: bool, yaw0_rad: float = 0.0
    ) -> None:
        self.params, self.rect, self.forward = params, rect, forward
        ring = FORWARD_RING if forward else REVERSE_RING
        k = ring.index(start_state)
        self.ring = ring[k:] + ring[:k]
        self._entries: list[tuple[float, np.ndarray]] = []  # (yaw ψ, pivot ground point) per leg
        r = params.radius_m
        state = self.ring[0]
        phi0 = self.leg_angle(0, 0.0)
        frame, _ = _frame(state, phi0, r)
        rotation = rot_z(yaw0_rad) @ rodrigues_up(surface_normal(state, *contact_angles(state, phi0)))
        spec = STATES[state]
        pivot = link_point(spec.pivot_link, spec.pivot_angle_rad, r)
        centre = np.array([0.0, 0.0, r / math.sqrt(2.0)])
        self._entries.append((_yaw_of(rotation @ frame), centre + rotation @ pivot))

    def leg_state(self, leg: int) -> int:
        return self.ring[leg % 4]

    def leg_thetas(self, leg: int, s: float) -> tuple[float, float]:
        (a1, a2), (b1, b2) = self.rect.edge(self.leg_state(leg), self.forward)
        return a1 + s * (b1 - a1), a2 + s * (b2 - a2)

    def leg_angle(self, leg: int, s: float) -> float:
        """Rolling-link contact angle (rad, clipped to [0, π]) on leg ``leg`` at fraction ``s``."""
        theta1, theta2 = self.leg_thetas(leg, s)
        return min(max(closed_form_angle(self.leg_state(leg), theta1, theta2, self.params), 0.0), math.pi)

    def _entry(self, leg: int) -> tuple[float, np.ndarray]:
        while len(self._entries) <= leg:
            prev = len(self._entries) - 1
            rotation, centre = self.pose(prev, 1.0)
            state = self.leg_state(prev + 1)
            frame, _ = _frame(state, self.leg_angle(prev + 1, 0.0), self.params.radius_m)
            spec = STATES[state]
            pivot = link_point(spec.pivot_link, spec.pivot_angle_rad, self.params.radius_m)
            self._entries.append((_yaw_of(rotation @ frame), centre + rotation @ pivot))
        return self._entries[leg]

    def pose(self, leg: int, s: float) -> tuple[np.ndarray, np.ndarray]:
        """R_sb and o_sb (m) on leg ``leg`` at fraction ``s``."""
        yaw0, pivot_ground = self._entry(leg)
        state, r = self.leg_state(leg), self.params.radius_m
        phi0, phi = self.leg_angle(leg, 0.0), self.leg_angle(leg, s)
        frame, rate = _frame(state, phi, r)
        rotation = rot_z(yaw0 + rate * (phi - phi0)) @ frame.T
        spec = STATES[state]
        centre = pivot_ground - rotation @ link_point(spec.pivot_link, spec.pivot_angle_rad, r)
        return rotation, centre

    def rolled(self, sigma: float) -> float:
        leg, s = self.split(sigma)
        return self.params.radius_m * (math.pi * leg + abs(self.leg_angle(leg, s) - self.leg_angle(leg, 0.0)))

    def centre(self, sigma: float) -> np.ndarray:
        return self.pose(*self.split(sigma))[1]

    @staticmethod
    def split(sigma: float) -> tuple[int, float]:
        leg = math.floor(sigma)
        if leg > 0 and sigma == leg:
            return leg - 1, 1.0
        return leg, sigma - leg


def _first_crossing(func: Any, target: float, hi: float, steps_per_leg: int = 64) -> float:
    """Smallest σ in [0, hi] with func(σ) = target (dense scan, then bisection)."""
    grid = np.linspace(0.0, hi, int(hi * steps_per_leg) + 1)
    values = [func(x) for x in grid]
    for i in range(1, len(grid)):
        if values[i] >= target:
            lo, up = grid[i - 1], grid[i]
            for _ in range(60):
                mid = 0.5 * (lo + up)
                if func(mid) >= target:
                    up = mid
                else:
                    lo = mid
            return float(up)
    raise NoValidPathFound(f"the gait does not reach {target} m within {hi / 4:.0f} cycles")


def _check_gait_request(distance_m: float, steps: int, start_state: int, measure: str) -> None:
    """Stage 0 of :func:`plan_gait`: every argument, as :class:`InvalidInput` naming the field."""
    if not math.isfinite(distance_m) or distance_m == 0.0:
        raise InvalidInput("distance", f"must be a finite non-zero number of metres, got {distance_m!r}")
    if steps < 2:
        raise InvalidInput("steps", f"must be at least 2 samples per state, got {steps}")
    if start_state not in STATES:
        raise InvalidInput("start_state", f"must be 1, 2, 3 or 4, got {start_state}")
    if measure not in ("net", "rolled"):
        raise InvalidInput("measure", f"must be 'net' or 'rolled', got {measure!r}")


def _oriented_gait(params: Any, rect: Any, start_state: int, forward: bool) -> _Gait:
    """Stage 1: the gait, turned about z_s so that a full cycle advances along +x (forward) or −x (reverse).

    Eq. 16 with no yaw sends a cycle some way off +x (forward: ~154°); a probe cycle measures by how much."""
    probe = _Gait(params, rect, start_state, forward)
    probe_cycle = probe.centre(4.0) - probe.centre(0.0)
    want = 0.0 if forward else math.pi
    return _Gait(params, rect, start_state, forward, want - math.atan2(probe_cycle[1], probe_cycle[0]))


def _sample_gait(gait: _Gait, params: Any, sigma_end: float, steps: int, speed: float,
                 net: Any) -> list[Sample]:
    """Stage 3: ``steps`` samples per leg up to σ = ``sigma_end``, timed by the sliders' speed (rad/s)."""
    samples: list[Sample] = []
    t_s = 0.0
    last: tuple[float, float] | None = None
    for leg, s in _sample_plan(sigma_end, steps):
        theta1, theta2 = gait.leg_thetas(leg, s)
        if last is not None:
            t_s += (abs(theta1 - last[0]) + abs(theta2 - last[1])) / speed
        last = (theta1, theta2)
        state = gait.leg_state(leg)
        phi1, phi2 = contact_angles(state, gait.leg_angle(leg, s))
        rotation, centre = gait.pose(leg, s)
        sigma = leg + s
        samples.append(
            Sample(
                t_s,
                theta1,
                theta2,
                state,
                phi1,
                phi2,
                rotation,
                centre,
                gait.rolled(sigma),
                net(sigma),
                reaction_forces(state, phi1, phi2, theta1, theta2, params),
                params,
            )
        )
    return samples


def _state_changes(samples: list[Sample]) -> tuple[list[int], list[dict[str, Any]]]:
    """Stage 4: the sequence of hybrid states the samples pass through, and each transition (when, where)."""
    sequence = [samples[0].state]
    transitions = []
    for prev, cur in itertools.pairwise(samples):
        if cur.state != prev.state:
            sequence.append(cur.state)
            transitions.append(
                {
                    "from": prev.state,
                    "to": cur.state,
                    "t": cur.t_s,
                    "theta1_rad": cur.theta1,
                    "theta2_rad": cur.theta2,
                }
            )
    return sequence, transitions


def plan_gait(
    distance_m: float,
    profile: RobotProfile,
    steps: int = 32,
    start_state: int = 1,
    corner_deg: float | None = None,
    measure: str = "net",
) -> dict[str, Any]:
    """What ``sphereplan tensegrity gait`` writes: slider trajectories that roll the robot ``distance_m``.

    ``distance_m`` > 0 walks the forward ring 1 → 3 → 2 → 4, < 0 the reverse ring. ``measure`` says what
    the distance counts: ``"net"`` (default), the advance of O_b along the gait's mean heading (the
    direction a full cycle moves it), or ``"rolled"``, the contact's ground travel Σ r·|Δφ|. ``steps``
    samples are taken on every leg (one leg = one state). Raises :class:`InvalidInput` naming the field.
    """
    _check_gait_request(distance_m, steps, start_state, measure)
    params = params_from_profile(profile)
    section = profile.extra.get("texplor", {})
    corner = math.radians(
        corner_deg if corner_deg is not None else float(section.get("gait_corner_deg", 45.0))
    )
    speed = float(section.get("slider_speed_rad_s", 0.5))
    rect = make_rectangle(corner, params)
    forward = distance_m > 0
    gait = _oriented_gait(params, rect, start_state, forward)
    start_centre = gait.centre(0.0)
    cycle = gait.centre(4.0) - start_centre
    heading = math.atan2(cycle[1], cycle[0])
    direction = np.array([math.cos(heading), math.sin(heading), 0.0])

    def net(sigma: float) -> float:
        return float((gait.centre(sigma) - start_centre) @ direction)

    # 2. how far along the ring (σ, in legs) the distance is reached
    target = abs(distance_m)
    per_cycle_net = float(np.linalg.norm(cycle[:2]))
    legs = 4.0 * (math.ceil(target / per_cycle_net) + 1)  # an upper bound on the legs the gait walks
    if legs * steps > MAX_GAIT_SAMPLES:
        field = "distance" if legs * 2 > MAX_GAIT_SAMPLES else "steps"
        raise InvalidInput(field, f"{distance_m:g} m at {steps} samples per state would need about "
                                  f"{legs * steps:.3g} samples; at most {MAX_GAIT_SAMPLES} are computed "
                                  f"(one cycle advances {per_cycle_net:.3g} m)")
    hi = legs
    sigma_end = _first_crossing(net if measure == "net" else gait.rolled, target, hi)
    samples = _sample_gait(gait, params, sigma_end, steps, speed, net)
    sequence, transitions = _state_changes(samples)
    return {
        "robot": profile.name,
        "radius_m": params.radius_m,
        "masses": params.masses_json(),
        "distance_m": distance_m,
        "measure": measure,
        "direction": "forward" if forward else "reverse",
        "ring": list(gait.ring),
        "start_state": start_state,
        "corner_rad": [rect.a, rect.b],
        "heading_rad": heading,
        "per_cycle": {"net_m": per_cycle_net, "rolled_m": 4.0 * math.pi * params.radius_m},
        "net_displacement_m": samples[-1].net_m,
        "rolled_distance_m": samples[-1].rolled_m,
        "duration_s": samples[-1].t_s,
        "state_sequence": sequence,
        "transitions": transitions,
        "steps": [sample.to_json() for sample in samples],
    }


def _sample_plan(sigma_end: float, steps: int) -> Iterator[tuple[int, float]]:
    """(leg, fraction) samples: ``steps`` + 1 per full leg, ends of consecutive legs both kept."""
    legs = math.ceil(sigma_end - 1e-12)
    for leg in range(max(legs, 1)):
        s_end = min(1.0, sigma_end - leg)
        count = max(2, math.ceil(steps * s_end))
        for s in np.linspace(0.0, s_end, count + 1):
            yield leg, float(s)
