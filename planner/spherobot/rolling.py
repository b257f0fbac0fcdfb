"""Full SO(3) rolling of a sphere on the ground plane: the judge of every reconfiguration plan.

A sphere of radius R rolls without slipping and without spin about the vertical (paper 004 §2). Its
orientation is a unit quaternion ``q = (w, x, y, z)`` mapping body vectors to world vectors; the camera
point P is body +z. Moving the centre with ground velocity ``v`` (horizontal) forces the world angular
velocity ``ω = e_z × v / R``. This module rolls that constraint exactly:

* a straight roll of length ``s`` at heading ψ is the rotation about ``(−sin ψ, cos ψ, 0)`` by ``s / R``;
* an arc of signed curvature κ (left turns positive) is, in the frame turning with the heading, a rotation
  at the constant rate ``(0, 1/R, −κ)`` per metre, so
  ``q(s) = Rz(ψ0 + κs) · Exp(s·(0, 1/R, −κ)) · Rz(−ψ0) · q0`` (derived from ``Ṙ = [ω]× R``);
* any other ground path is rolled as a polyline (exact for polylines, converging to the curve).

It also carries the Spherobot model of paper 004 (eq. 1–4, state x, y, θ, α; controls ω'x, ω'y about the
axes x' = (cos α, sin α, 0), y' = (−sin α, cos α, 0)) and the conversions between (θ, α, spin) and
quaternions: ``q = Rot((−sin α, cos α, 0), θ) · Rz(spin)`` puts P at (sin θ cos α, sin θ sin α, cos θ).
The *heading* of an orientation is its spin: the azimuth of body +x once P is rolled straight to the top.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from planner.kinematics import wrap

Quat = tuple[float, float, float, float]

IDENTITY: Quat = (1.0, 0.0, 0.0, 0.0)


# ---------------------------------------------------------------------------------------------------------
# Quaternions (w, x, y, z), body -> world, Hamilton product.
# ---------------------------------------------------------------------------------------------------------
def quat_mul(a: Quat, b: Quat) -> Quat:
    """Hamilton product ``a ⊗ b`` (apply b first, then a)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


def quat_conj(q: Quat) -> Quat:
    return (q[0], -q[1], -q[2], -q[3])


def quat_normalize(q: Sequence[float]) -> Quat:
    n = math.sqrt(sum(c * c for c in q))
    if not n > 0:
        raise ValueError("zero quaternion")
    return (q[0] / n, q[1] / n, q[2] / n, q[3] / n)


def quat_axis_angle(axis: Sequence[float], angle_rad: float) -> Quat:
    """Rotation by ``angle_rad`` about the unit vector ``axis`` (right-hand rule)."""
    h = 0.5 * angle_rad
    s = math.sin(h)
    return (math.cos(h), axis[0] * s, axis[1] * s, axis[2] * s)


def quat_z(angle_rad: float) -> Quat:
    """Rotation about world +z."""
    return (math.cos(0.5 * angle_rad), 0.0, 0.0, math.sin(0.5 * angle_rad))


def quat_rotate(q: Quat, v: Sequence[float]) -> tuple[float, float, float]:
    """Rotate vector ``v`` by ``q`` (body vector -> world vector)."""
    w, x, y, z = q
    vx, vy, vz = v
    # t = 2 (q_vec × v); v' = v + w t + q_vec × t
    tx = 2.0 * (y * vz - z * vy)
    ty = 2.0 * (z * vx - x * vz)
    tz = 2.0 * (x * vy - y * vx)
    return (
        vx + w * tx + (y * tz - z * ty),
        vy + w * ty + (z * tx - x * tz),
        vz + w * tz + (x * ty - y * tx),
    )


def quat_to_matrix(q: Quat) -> np.ndarray:
    """3×3 rotation matrix of ``q`` (columns are the body axes in the world frame)."""
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def quat_angle(a: Quat, b: Quat) -> float:
    """Angle (rad, in [0, π]) of the rotation taking orientation ``a`` to ``b``."""
    rel = quat_mul(quat_conj(a), b)
    return 2.0 * math.atan2(math.sqrt(rel[1] ** 2 + rel[2] ** 2 + rel[3] ** 2), abs(rel[0]))


def quat_mul_array(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise Hamilton product of (N, 4) (or broadcastable) quaternion arrays."""
    aw, ax, ay, az = np.moveaxis(np.asarray(a, float), -1, 0)
    bw, bx, by, bz = np.moveaxis(np.asarray(b, float), -1, 0)
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


# ---------------------------------------------------------------------------------------------------------
# Tilt (θ, α, spin) <-> quaternion; the Spherobot model (paper 004 eq. 1–4).
# ---------------------------------------------------------------------------------------------------------
def p_world(q: Quat) -> tuple[float, float, float]:
    """World direction of P (body +z): the third column of the rotation matrix."""
    w, x, y, z = q
    return (2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y))


def quat_from_tilt(theta_rad: float, alpha_rad: float, spin_rad: float = 0.0) -> Quat:
    """Orientation with P at polar angle θ from the top and azimuth α (paper 004 Fig. 2).

    ``q = Rot((−sin α, cos α, 0), θ) · Rz(spin)``: rolling a P-on-top sphere with heading ``spin`` straight
    along direction α by ``θ·R`` gives exactly this orientation.
    """
    tilt = quat_axis_angle((-math.sin(alpha_rad), math.cos(alpha_rad), 0.0), theta_rad)
    return quat_mul(tilt, quat_z(spin_rad))


def tilt_from_quat(q: Quat) -> tuple[float, float, float]:
    """Inverse of :func:`quat_from_tilt`: (θ in [0, π], α in (−π, π], spin in (−π, π]).

    α is set to 0 when P is exactly on top (θ = 0), where it is undefined; at θ = π (P at the bottom)
    the decomposition is singular and α = 0 is used as well.
    """
    px, py, pz = p_world(q)
    horiz = math.hypot(px, py)
    theta = math.atan2(horiz, pz)
    alpha = math.atan2(py, px) if horiz > 1e-15 else 0.0
    rest = quat_mul(quat_conj(quat_axis_angle((-math.sin(alpha), math.cos(alpha), 0.0), theta)), q)
    spin = 2.0 * math.atan2(rest[3], rest[0])
    return theta, alpha, wrap(spin)


def heading_of(q: Quat) -> float:
    """Heading (rad, (−π, π]): azimuth of body +x after rolling P straight to the top (the spin)."""
    return tilt_from_quat(q)[2]


@dataclass(frozen=True)
class SpherobotState:
    """The paper's reduced state (eq. 1–4): centre (x, y) in m, θ and α in rad. It omits the spin about P."""

    x: float
    y: float
    theta: float
    alpha: float


def spherobot_rates(
    state: SpherobotState, omega_xp: float, omega_yp: float, radius_m: float = 1.0
) -> tuple[float, float, float, float]:
    """Paper 004 eq. 1–4, scaled to a sphere of radius ``radius_m``: (ẋ, ẏ, θ̇, α̇).

    ``omega_xp``/``omega_yp`` (rad/s) are the angular velocities about x' = (cos α, sin α, 0) and
    y' = (−sin α, cos α, 0). α̇ is singular at θ = 0 (α undefined there).
    """
    ca, sa = math.cos(state.alpha), math.sin(state.alpha)
    return (
        radius_m * (omega_yp * ca + omega_xp * sa),
        radius_m * (omega_yp * sa - omega_xp * ca),
        omega_yp,
        -omega_xp / math.tan(state.theta),
    )


def model_controls(
    heading_rad: float, speed_m_s: float, alpha_rad: float, radius_m: float
) -> tuple[float, float]:
    """(ω'x, ω'y) in rad/s moving the centre at ``speed_m_s`` along ``heading_rad`` (eq. 1–2 inverted)."""
    k = speed_m_s / radius_m
    return k * math.sin(alpha_rad - heading_rad), k * math.cos(heading_rad - alpha_rad)


# ---------------------------------------------------------------------------------------------------------
# Ground segments and exact rolling.
# ---------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class GroundSegment:
    """A straight line (``curvature == 0``) or circular arc travelled by the sphere's centre.

    Starts at (x0, y0) m with heading ``heading_rad``; ``length_m`` ≥ 0 of travel; ``curvature_1_m`` is
    signed (> 0 turns left, radius 1/|κ|). ``action`` labels the paper's control action: ``"a"``
    (straight roll along P's azimuth, §4.1), ``"b"`` (circle of radius R tan θ, §4.1), ``"roll"``
    (a straight leg of a spherical-triangle path, §3), ``"straight"`` (any other straight roll).
    """

    x0: float
    y0: float
    heading_rad: float
    length_m: float
    curvature_1_m: float = 0.0
    action: str = "straight"

    @property
    def kind(self) -> str:
        return "line" if self.curvature_1_m == 0.0 else "arc"

    def point_at(self, s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Centre position(s) after travelling ``s`` metres along the segment."""
        s = np.asarray(s, dtype=float)
        half = 0.5 * self.curvature_1_m * s
        chord = s * np.sinc(half / math.pi)  # 2 sin(κs/2)/κ, stable as κ → 0
        mid = self.heading_rad + half
        return self.x0 + chord * np.cos(mid), self.y0 + chord * np.sin(mid)

    @property
    def end(self) -> tuple[float, float]:
        x, y = self.point_at(self.length_m)
        return float(x), float(y)

    @property
    def center(self) -> tuple[float, float] | None:
        """Circle centre of an arc (None for a line)."""
        k = self.curvature_1_m
        if k == 0.0:
            return None
        return self.x0 - math.sin(self.heading_rad) / k, self.y0 + math.cos(self.heading_rad) / k


def roll_segment(q0: Quat, seg: GroundSegment, radius_m: float) -> Quat:
    """Orientation after rolling ``seg`` from orientation ``q0`` (closed form, exact)."""
    w, x, y, z = sample_segment(q0, seg, radius_m, np.array([seg.length_m]))[0].tolist()
    return (w, x, y, z)


def sample_segment(q0: Quat, seg: GroundSegment, radius_m: float, s: np.ndarray) -> np.ndarray:
    """Orientations (N, 4) at arc lengths ``s`` (m, shape (N,)) along ``seg`` starting from ``q0``."""
    s = np.asarray(s, dtype=float)
    h0, k = seg.heading_rad, seg.curvature_1_m
    if k == 0.0:
        half = 0.5 * s / radius_m
        sn = np.sin(half)
        rot = np.stack([np.cos(half), -math.sin(h0) * sn, math.cos(h0) * sn, np.zeros_like(s)], axis=-1)
        return quat_mul_array(rot, np.asarray(q0))
    # Rz(h0 + k s) · Exp(s (0, 1/R, −k)) · Rz(−h0) · q0
    wy, wz = 1.0 / radius_m, -k
    rate = math.hypot(wy, wz)
    half = 0.5 * rate * s
    sn = np.sin(half)
    expq = np.stack([np.cos(half), np.zeros_like(s), wy / rate * sn, wz / rate * sn], axis=-1)
    hz = 0.5 * (h0 + k * s)
    zq = np.stack([np.cos(hz), np.zeros_like(s), np.zeros_like(s), np.sin(hz)], axis=-1)
    base = quat_mul(quat_z(-h0), q0)
    return quat_mul_array(zq, quat_mul_array(expq, np.asarray(base)))


def roll_segments(q0: Quat, segments: Sequence[GroundSegment], radius_m: float) -> Quat:
    """Orientation after rolling every segment in turn (exact)."""
    q = q0
    for seg in segments:
        q = roll_segment(q, seg, radius_m)
    return q


def roll_polyline(q0: Quat, xy: np.ndarray, radius_m: float) -> np.ndarray:
    """Roll along any ground path given as a polyline of centre positions (N, 2) m.

    Returns the orientations (N, 4) at the vertices. Exact for the polyline itself (each piece is a straight
    roll, corners are pure turns with no spin about the vertical); a smooth path sampled finely converges to
    its exact rolling with an error O(step²).
    """
    xy = np.asarray(xy, dtype=float)
    d = np.diff(xy, axis=0)
    length = np.hypot(d[:, 0], d[:, 1])
    out = np.empty((len(xy), 4))
    q = q0
    out[0] = q
    for i in range(len(d)):
        ln = float(length[i])
        if ln > 0.0:
            axis = (-d[i, 1] / ln, d[i, 0] / ln, 0.0)
            q = quat_normalize(quat_mul(quat_axis_angle(axis, ln / radius_m), q))
        out[i + 1] = q
    return out
