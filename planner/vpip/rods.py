"""The VPIP rod driver: from the plane's two angles to the lengths of all 16 rods (paper 000 eq. 4–18).

Paper 000 §4 puts each rod of a DAEDALUS-type robot on a line from the centre of its side disc
``p_m`` (eq. 9) along a unit direction set by the rod angle ζ and the robot roll (eq. 12), and asks how
far the rod must extend to touch the Virtual Pose Instruction Plane (eq. 4). Solving the line–plane
intersection gives eq. 18, ``l = −r_s + N / D``. This module evaluates that for all rods at once.

Frames and signs
----------------
The equations are evaluated in the paper's frame: origin at the contact point, ``x`` to the right,
``y`` in the rolling direction, ``z`` up; the sphere centre is at ``(0, 0, r_m)``. The paper's roll
``φ_r > 0`` lowers the right disc (eq. 9). sphereplan's public convention is docs/contracts.md's (roll > 0
leans and turns left), so the public functions take

* ``roll_rad`` — robot roll, > 0 leans left; paper ``φ_r = −roll_rad``;
* ``phi_vpip_rad`` — plane roll "in the same direction as the robot's roll" (paper §4): > 0 lowers the
  plane on the left and extends the left rods; paper ``φ_VPIP = −phi_vpip_rad``;
* ``theta_vpip_rad`` — plane pitch, > 0 lowers the plane behind the robot and extends the rear rods,
  which drives the robot forward (paper §4 text, Fig. 3, and the positive angles of Fig. 7/8).
  As printed, eq. 4 (``… + tan θ·y + z = 0`` with ``y`` forward) lowers the *front* for θ > 0, and with
  eq. 12 (ζ > 0 behind the contact point) that would drive the robot backward; so the printed eq. 4 /
  eq. 18 are evaluated with ``θ = −theta_vpip_rad``. Tests check both the tip-on-plane identity and the
  physical meaning (rear rods extend for θ > 0, left rods for φ_VPIP > 0).

Rod angles
----------
ζ = 0 is a rod pointing straight down, ζ grows as the sphere rolls forward (a rod the robot has rolled
over points down and backwards, 0 < ζ < π/2; paper §2.1), so rod ``k`` of a side has
``ζ_k = pitch_phase + 2πk / rods_per_side`` where ``pitch_phase`` is how far the sphere has rolled (rad).
Both rings are taken aligned (no offset between the sides; paper Fig. 1 shows two parallel discs).
Rods ``0 … n−1`` are the left ring, ``n … 2n−1`` the right ring.

Clamping and skipping (paper §4)
--------------------------------
``l`` is clamped to ``[0, l_max]``; where ``|D|`` is (numerically) zero the line is parallel to the
plane and the rod holds its last length; rods with ζ in (π/2, 3π/2) point upwards and are skipped in
normal motion — the paper ignores them; here they are commanded fully retracted (0) so no rod is left
extended over the top.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.errors import InvalidInput, RobotProfileError

D_EPS = 1e-9
"""|D| below this counts as "line parallel to the plane" (eq. 18 has no solution): hold the last length."""

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class RodParams:
    """Geometry of a two-ring rod-driven sphere (paper 000 Table 1 and eq. 7).

    ``r_m`` sphere radius (m); ``r_s`` radius of the side disc in which a ring's rods lie (m; not in
    the paper, see docs/vpip.md for the default); ``l_max`` maximum extension (m); ``rod_speed_m_s``
    extension/retraction speed (m/s); ``rods_per_side`` rods per ring.
    """

    r_m: float = 0.232
    r_s: float = 0.12
    l_max: float = 0.21
    rod_speed_m_s: float = 0.1
    rods_per_side: int = 8

    def __post_init__(self) -> None:
        for name in ("r_m", "r_s", "l_max", "rod_speed_m_s"):
            value = getattr(self, name)
            if not math.isfinite(value) or value <= 0:
                raise RobotProfileError(f"vpip.{name}", f"must be a finite number > 0, got {value!r}")
        if self.r_s >= self.r_m:
            raise RobotProfileError(
                "vpip.r_s", f"must be smaller than r_m = {self.r_m} (eq. 7), got {self.r_s}"
            )
        if self.rods_per_side < 1:
            raise RobotProfileError("vpip.rods_per_side", f"must be >= 1, got {self.rods_per_side}")

    @property
    def d_m_s(self) -> float:
        """Distance (m) from the sphere centre to each side disc's centre, eq. 7: r_m·sin(arccos(r_s/r_m))."""
        return self.r_m * math.sin(math.acos(self.r_s / self.r_m))

    @property
    def n_rods(self) -> int:
        return 2 * self.rods_per_side

    @property
    def push_window_rad(self) -> float:
        """Largest ζ at which an upright robot's rod still reaches flat ground (eq. 1 for the disc layout).

        Eq. 18 with a flat plane gives the ground-contact length ``r_m / cos ζ − r_s``; it reaches
        ``l_max`` at ``ζ = arccos(r_m / (r_s + l_max))`` (eq. 1 is the special case r_s = r_m).
        """
        reach = self.r_s + self.l_max
        return math.acos(min(1.0, self.r_m / reach))

    def to_json(self) -> dict[str, Any]:
        return {
            "r_m": self.r_m,
            "r_s": self.r_s,
            "l_max": self.l_max,
            "rod_speed_m_s": self.rod_speed_m_s,
            "rods_per_side": self.rods_per_side,
            "d_m_s": self.d_m_s,
        }

    @classmethod
    def from_section(cls, section: Mapping[str, Any]) -> RodParams:
        """Build from a profile's ``[vpip]`` table (missing keys take Table 1 / documented defaults)."""
        kwargs: dict[str, Any] = {}
        for name in ("r_m", "r_s", "l_max", "rod_speed_m_s"):
            if name in section:
                value = section[name]
                if isinstance(value, bool) or not isinstance(value, int | float):
                    raise RobotProfileError(f"vpip.{name}", f"must be a number, got {value!r}")
                kwargs[name] = float(value)
        if "rods_per_side" in section:
            value = section["rods_per_side"]
            if isinstance(value, bool) or not isinstance(value, int):
                raise RobotProfileError("vpip.rods_per_side", f"must be an integer, got {value!r}")
            kwargs["rods_per_side"] = value
        return cls(**kwargs)


def rod_layout(pitch_phase_rad: float, rods_per_side: int) -> tuple[np.ndarray, np.ndarray]:
    """Rod angles ζ (rad, in [0, 2π)) and side factors s_f for all rods, shapes ``(2n,)``.

    Left ring first (paper s_f = −1), then the right ring (s_f = +1).
    """
    k = np.arange(rods_per_side, dtype=float)
    ring = np.mod(pitch_phase_rad + TWO_PI * k / rods_per_side, TWO_PI)
    zeta = np.concatenate([ring, ring])
    side = np.concatenate([-np.ones(rods_per_side), np.ones(rods_per_side)])
    return zeta, side


def skipped(zeta: np.ndarray) -> np.ndarray:
    """Rods pointing upwards, ζ in the open interval (π/2, 3π/2): skipped in normal motion (paper §4)."""
    z = np.mod(zeta, TWO_PI)
    return (z > 0.5 * math.pi) & (z < 1.5 * math.pi)


def disc_centre(params: RodParams, phi_r: float, side: np.ndarray) -> np.ndarray:
    """Side-disc centres ``p_m`` (paper frame, eq. 9); ``phi_r`` is the paper's roll. Shape ``(n, 3)``."""
    d = params.d_m_s
    s = np.asarray(side, dtype=float)
    return np.stack(
        [s * math.cos(phi_r) * d, np.zeros_like(s), params.r_m - s * math.sin(phi_r) * d], axis=-1
    )


def rod_direction(phi_r: float, zeta: np.ndarray) -> np.ndarray:
    """Unit rod directions in the paper frame, eq. 12 (``d_mt / r_s``). Shape ``(n, 3)``."""
    z = np.asarray(zeta, dtype=float)
    return np.stack([-np.cos(z) * math.sin(phi_r), -np.sin(z), -np.cos(z) * math.cos(phi_r)], axis=-1)


def eq18_terms(
    params: RodParams, phi_v: float, theta_v: float, phi_r: float, zeta: np.ndarray, side: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Numerator N and denominator D of eq. 17/18, in the paper's own symbols and signs.

    ``phi_v``, ``theta_v`` are the printed eq. 4 angles and ``phi_r`` the paper's roll; l = −r_s + N/D.
    """
    d = params.d_m_s
    s = np.asarray(side, dtype=float)
    z = np.asarray(zeta, dtype=float)
    tp, tt = math.tan(phi_v), math.tan(theta_v)
    n = tp * s * math.cos(phi_r) * d + params.r_m - s * math.sin(phi_r) * d
    den = tp * np.cos(z) * math.sin(phi_r) + tt * np.sin(z) + np.cos(z) * math.cos(phi_r)
    return n, den


def paper_angles(phi_vpip_rad: float, theta_vpip_rad: float, roll_rad: float) -> tuple[float, float, float]:
    """Map sphereplan's signed angles to the paper's (φ_VPIP, θ_VPIP of eq. 4, φ_r). See the module doc."""
    return -phi_vpip_rad, -theta_vpip_rad, -roll_rad


@dataclass(frozen=True)
class RodCommand:
    """One evaluation of the rod driver; every array has shape ``(2·rods_per_side,)``.

    ``raw_length_m`` is eq. 18 before clamping (NaN where |D| ≈ 0), ``length_m`` the command (clamped,
    held or retracted), ``active`` False for skipped rods, ``clamped`` −1 (at 0), +1 (at l_max), 0 (free).
    """

    zeta_rad: np.ndarray
    side: np.ndarray
    raw_length_m: np.ndarray
    length_m: np.ndarray
    active: np.ndarray
    clamped: np.ndarray
    held: np.ndarray


def rod_lengths(
    params: RodParams,
    phi_vpip_rad: float,
    theta_vpip_rad: float,
    roll_rad: float,
    pitch_phase_rad: float = 0.0,
    previous_m: np.ndarray | None = None,
) -> RodCommand:
    """Eq. 18 for every rod: the length that puts each rod's tip on the VPIP, clamped to [0, l_max].

    Angles in sphereplan's convention (module doc). ``previous_m`` (shape ``(2n,)``) are the last
    commanded lengths, held where |D| ≈ 0 (zero when not given).
    """
    for name, value in (
        ("phi_vpip", phi_vpip_rad),
        ("theta_vpip", theta_vpip_rad),
        ("roll", roll_rad),
        ("pitch_phase", pitch_phase_rad),
    ):
        if not math.isfinite(value):
            raise InvalidInput(name, f"must be finite, got {value!r}")
    for name, value in (("phi_vpip", phi_vpip_rad), ("theta_vpip", theta_vpip_rad), ("roll", roll_rad)):
        if abs(value) >= 0.5 * math.pi:
            raise InvalidInput(
                name, f"must be strictly between -90 and 90 degrees, got {math.degrees(value):.3g}"
            )
    zeta, side = rod_layout(pitch_phase_rad, params.rods_per_side)
    prev = np.zeros(params.n_rods) if previous_m is None else np.asarray(previous_m, dtype=float)
    if prev.shape != (params.n_rods,):
        raise InvalidInput("previous_m", f"needs shape ({params.n_rods},), got {prev.shape}")
    phi_v, theta_v, phi_r = paper_angles(phi_vpip_rad, theta_vpip_rad, roll_rad)
    n, den = eq18_terms(params, phi_v, theta_v, phi_r, zeta, side)
    parallel = np.abs(den) < D_EPS
    with np.errstate(divide="ignore", invalid="ignore"):
        raw = np.where(parallel, np.nan, -params.r_s + n / np.where(parallel, 1.0, den))
    active = ~skipped(zeta)
    clamped = np.where(raw < 0.0, -1, np.where(raw > params.l_max, 1, 0)).astype(int)
    length = np.clip(np.where(parallel, prev, raw), 0.0, params.l_max)
    held = parallel & active
    length = np.where(active, length, 0.0)
    clamped = np.where(active & ~parallel, clamped, 0)
    return RodCommand(zeta, side, raw, length, active, clamped, held)


def rod_tips(
    params: RodParams, roll_rad: float, zeta: np.ndarray, side: np.ndarray, length_m: np.ndarray
) -> np.ndarray:
    """Rod tip positions (paper frame, m), shape ``(n, 3)``: eq. 12 with λ = r_s + l."""
    phi_r = -roll_rad
    return disc_centre(params, phi_r, side) + (params.r_s + np.asarray(length_m))[:, None] * rod_direction(
        phi_r, zeta
    )


def rate_limit(target_m: np.ndarray, current_m: np.ndarray, max_step_m: float) -> np.ndarray:
    """Move each rod from ``current_m`` toward ``target_m`` by at most ``max_step_m`` (rod speed · dt)."""
    return current_m + np.clip(target_m - current_m, -max_step_m, max_step_m)


class RodDriver:
    """Stateful eq. 18 driver: remembers the last commands (held where |D| ≈ 0) and rate-limits them.

    ``step`` returns the :class:`RodCommand` for the targets and updates :attr:`lengths_m`, the commanded
    lengths after limiting each rod's change to ``rod_speed_m_s · dt_s``.
    """

    def __init__(self, params: RodParams, dt_s: float) -> None:
        self.params = params
        self.dt_s = dt_s
        self.lengths_m = np.zeros(params.n_rods)

    def reset(self) -> None:
        self.lengths_m = np.zeros(self.params.n_rods)

    def step(
        self, phi_vpip_rad: float, theta_vpip_rad: float, roll_rad: float, pitch_phase_rad: float
    ) -> RodCommand:
        cmd = rod_lengths(
            self.params, phi_vpip_rad, theta_vpip_rad, roll_rad, pitch_phase_rad, self.lengths_m
        )
        self.lengths_m = rate_limit(cmd.length_m, self.lengths_m, self.params.rod_speed_m_s * self.dt_s)
        return cmd


def equivalent_plane(
    params: RodParams,
    lengths_m: np.ndarray,
    roll_rad: float,
    pitch_phase_rad: float,
    limits_rad: tuple[float, float],
    steps: tuple[int, int] = (41, 41),
) -> tuple[float, float]:
    """The VPIP angles (φ_VPIP, θ_VPIP) whose eq. 18 lengths best match ``lengths_m`` (least squares).

    Used to drive the surrogate plant from rod commands that did not come from a plane (the simple
    baseline driver). Only the rods that can reach the ground count (ζ within the push window
    :attr:`RodParams.push_window_rad` of straight down); near-horizontal rods are left out because their
    eq. 18 length jumps between 0 and l_max as the plane tilts. Clamping makes the cost flat in places,
    so the minimum is found by brute force on a grid over ``|φ| ≤ limits_rad[0]``,
    ``|θ| ≤ limits_rad[1]`` (``steps`` points each; the default resolution is 1° × 2°); ties go to
    the flattest plane.
    """
    zeta, side = rod_layout(pitch_phase_rad, params.rods_per_side)
    window = params.push_window_rad + 1e-9
    use = (zeta <= window) | (zeta >= TWO_PI - window)
    target = np.asarray(lengths_m, dtype=float)[use]
    phis = np.linspace(-limits_rad[0], limits_rad[0], steps[0])
    thetas = np.linspace(-limits_rad[1], limits_rad[1], steps[1])
    pp, tt = np.meshgrid(phis, thetas, indexing="ij")
    # eq. 18 in the paper's signs (paper_angles), broadcast over (φ, θ, rod)
    phi_v, theta_v, phi_r = -pp[..., None], -tt[..., None], -roll_rad
    z, s = zeta[use], side[use]
    d = params.d_m_s
    n = np.tan(phi_v) * s * math.cos(phi_r) * d + params.r_m - s * math.sin(phi_r) * d
    den = (
        np.tan(phi_v) * np.cos(z) * math.sin(phi_r)
        + np.tan(theta_v) * np.sin(z)
        + np.cos(z) * math.cos(phi_r)
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        raw = np.where(np.abs(den) < D_EPS, 0.0, -params.r_s + n / np.where(np.abs(den) < D_EPS, 1.0, den))
    length = np.clip(raw, 0.0, params.l_max)
    cost = np.sum((length - target) ** 2, axis=-1) + 1e-9 * (pp**2 + tt**2)
    i, j = np.unravel_index(int(np.argmin(cost)), cost.shape)
    return float(phis[i]), float(thetas[j])
