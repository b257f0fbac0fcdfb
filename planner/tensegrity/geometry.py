"""Geometry of TeXploR, the two-arc tensegrity robot of paper 002 (Ervin & Vikas).

Two semicircular links of radius ``r`` share their centre O_b, the origin of the body frame {b}.
Link 1 lies in the body x–y plane (y ≥ 0), link 2 is link 1 turned by R12 (eq. 3) and lies in the y–z
plane (y ≤ 0). A point on link i at arc angle α (measured from x_i, α ∈ [0, π]) is r·[cα, sα, 0] in its
own frame (eq. 2) and, in {b} (eq. 4)::

    link 1: r [cα, sα, 0]        ends A1 (α = 0) = [r, 0, 0],  B1 (α = π) = [−r, 0, 0]
    link 2: r [0, −sα, cα]       ends A2 (α = 0) = [0, 0, r],  B2 (α = π) = [0, 0, −r]

The internal (slider) masses M1, M2 sit at arc angles θ1, θ2; the links' own centres of mass are at
[0, 2r/π, 0] in each link frame (paper §III-A). This module holds only geometry and mass data:
positions, tangents (eq. 5), the centre of mass, the depth of the body's lowest point below O_b for
any "up" direction (the support function of the two arcs, used by the energy check), and Rodrigues'
rotation taking the body's up vector to z_s (eq. 16).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.errors import InvalidInput, RobotProfileError
from planner.robot import RobotProfile

#: Rotation from link-2 coordinates to link-1 (= body) coordinates, paper 002 eq. 3.
R12 = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])

#: Standard gravity (m/s²).
G = 9.80665


@dataclass(frozen=True)
class TexplorParams:
    """Mass and size data of a two-arc robot (SI units).

    ``slider_mass_kg`` = (M1, M2), the internal masses; ``link_mass_kg`` = (m1, m2), the arcs.
    """

    radius_m: float
    slider_mass_kg: tuple[float, float]
    link_mass_kg: tuple[float, float]

    @property
    def total_mass_kg(self) -> float:
        return float(sum(self.slider_mass_kg) + sum(self.link_mass_kg))

    def masses_json(self) -> dict[str, float]:
        """The masses as the CLI prints them: {M1, M2, m1, m2} in kg."""
        (big1, big2), (small1, small2) = self.slider_mass_kg, self.link_mass_kg
        return {"M1": big1, "M2": big2, "m1": small1, "m2": small2}


def _positive_number(section: dict[str, Any], key: str, default: float) -> float:
    value = section.get(key, default)
    if (
        isinstance(value, bool)
        or not isinstance(value, int | float)
        or not math.isfinite(value)
        or value <= 0
    ):
        raise RobotProfileError(f"texplor.{key}", f"must be a finite number > 0, got {value!r}")
    return float(value)


def params_from_profile(profile: RobotProfile) -> TexplorParams:
    """Read a profile's ``[texplor]`` section (defaults: the paper's prototype, 431 g arcs, 427 g sliders).

    The arc radius is the profile's ``radius_m``. Keys: ``link_mass_kg``, ``slider_mass_kg`` (both arcs /
    both sliders alike) or the per-link ``link1_mass_kg`` … ``slider2_mass_kg``.
    """
    section = dict(profile.extra.get("texplor", {}))
    link = _positive_number(section, "link_mass_kg", 0.431)
    slider = _positive_number(section, "slider_mass_kg", 0.427)
    return TexplorParams(
        radius_m=profile.radius_m,
        slider_mass_kg=(
            _positive_number(section, "slider1_mass_kg", slider),
            _positive_number(section, "slider2_mass_kg", slider),
        ),
        link_mass_kg=(
            _positive_number(section, "link1_mass_kg", link),
            _positive_number(section, "link2_mass_kg", link),
        ),
    )


def check_mass_angle(name: str, value: float) -> float:
    """Validate a slider angle θ (rad): finite and on the arc, 0 ≤ θ ≤ π (a tiny overshoot is clipped)."""
    if not math.isfinite(value):
        raise InvalidInput(name, f"must be a finite angle, got {value!r}")
    if value < -1e-9 or value > math.pi + 1e-9:
        raise InvalidInput(name, f"must lie on the arc, 0..180 degrees (0..pi rad), got {value!r} rad")
    return min(max(value, 0.0), math.pi)


def link_point(link: int, angle_rad: float, radius_m: float) -> np.ndarray:
    """Body-frame point (m, shape (3,)) at arc angle ``angle_rad`` on link 1 or 2 (eq. 2, 4)."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    if link == 1:
        return radius_m * np.array([c, s, 0.0])
    return radius_m * np.array([0.0, -s, c])


def link_tangent(link: int, angle_rad: float, radius_m: float) -> np.ndarray:
    """∂q/∂α on link ``link`` in {b} (m/rad, shape (3,)), eq. 5."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    if link == 1:
        return radius_m * np.array([-s, c, 0.0])
    return radius_m * np.array([0.0, -c, -s])


def mass_points(theta1: float, theta2: float, params: TexplorParams) -> tuple[np.ndarray, np.ndarray]:
    """Positions in {b} (m, shape (4, 3)) and masses (kg, (4,)) of slider 1, slider 2, link 1, link 2."""
    r = params.radius_m
    link_com = np.array([0.0, 2.0 * r / math.pi, 0.0])
    points = np.stack([link_point(1, theta1, r), link_point(2, theta2, r), link_com, R12 @ link_com])
    masses = np.array([*params.slider_mass_kg, *params.link_mass_kg], dtype=float)
    return points, masses


def centre_of_mass(theta1: float, theta2: float, params: TexplorParams) -> np.ndarray:
    """Centre of mass of the whole robot in {b} (m, shape (3,))."""
    points, masses = mass_points(theta1, theta2, params)
    return np.asarray(masses @ points / masses.sum())


def lowest_depth(up_b: np.ndarray, radius_m: float) -> np.ndarray:
    """Depth (m) of the lowest body point below O_b when ``up_b`` (unit, shape (..., 3), in {b}) points up.

    This is the support function of the two arcs in the direction w = −up: max over α ∈ [0, π] of
    w·q(α). For link 1, w·q = r(w_x cα + w_y sα) peaks inside the arc when w_y ≥ 0 (value r·|(w_x, w_y)|),
    otherwise at an end (r·|w_x|); link 2 alike with (w_z, −w_y). Resting on a plane, O_b sits this high.
    """
    w = -np.asarray(up_b, dtype=float)
    wx, wy, wz = w[..., 0], w[..., 1], w[..., 2]
    h1 = np.where(wy >= 0.0, np.hypot(wx, wy), np.abs(wx))
    h2 = np.where(-wy >= 0.0, np.hypot(wz, wy), np.abs(wz))
    return np.asarray(radius_m * np.maximum(h1, h2))


def hat(v: np.ndarray) -> np.ndarray:
    """so(3) hat operator: the skew matrix with hat(v) @ x = v × x."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rodrigues_up(z_b: np.ndarray) -> np.ndarray:
    """R_sb of eq. 16: the rotation about u = z_b × z_s / |·| by atan2(|z_b × z_s|, z_b·z_s).

    It maps the body's up vector ``z_b`` (unit, in {b}) to z_s with no extra turn about z_s.
    """
    z_s = np.array([0.0, 0.0, 1.0])
    z = np.asarray(z_b, dtype=float) / np.linalg.norm(z_b)
    axis = np.cross(z, z_s)
    sin_a = float(np.linalg.norm(axis))
    cos_a = float(z @ z_s)
    if sin_a < 1e-12:
        return np.eye(3) if cos_a > 0 else np.diag([1.0, -1.0, -1.0])
    u_hat = hat(axis / sin_a)
    angle = math.atan2(sin_a, cos_a)
    return np.eye(3) + math.sin(angle) * u_hat + (1.0 - math.cos(angle)) * (u_hat @ u_hat)


def rot_z(angle_rad: float) -> np.ndarray:
    """Rotation about z_s by ``angle_rad``."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
